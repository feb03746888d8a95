"""Deterministic scenario tests in sim time: a pytest plugin.

Write a test as an ``async def`` that takes the ``fleet_sim`` fixture; it runs as a mission
under ``fleet_async.run`` on both anyio backends (asyncio and trio), so it can ``await``
``agent.move(...)``, ``fleet_sim.sleep(...)`` and the rest, and assert exact sim times::

    async def test_robot_arrives(fleet_sim):
        robot = Agent.from_mesh(box, box, Pose.from_xyz(0, 0, 0.1), sim_core=fleet_sim,
                                controller="omni")
        await robot.move(Pose.from_xyz(2, 0, 0.1))
        assert fleet_sim.step_count == 14  # 2 m at 2 m/s and 5 m/s^2: 1.4 s

The simulation is headless (``pybullet.DIRECT``), unpaced, with timestep 0.1 s and seed 0;
override the ``fleet_sim_params`` fixture to change that. Limit backends with
``@pytest.mark.parametrize("fleet_backend", ["asyncio"])``. The plugin is registered through
the ``pytest11`` entry point, so installing fleet-async is enough; the trio variant needs trio
(``pip install "fleet-async[trio]"``) and is skipped, with that reason, without it.
"""

from __future__ import annotations

import importlib.util
import inspect
from collections.abc import Iterator
from typing import Any

import pytest

from fleet_async.core.base.params import SimulationParams
from fleet_async.core.simulation import MultiRobotSimulationCore
from fleet_async.tasks.run import run

__all__ = ["fleet_backend", "fleet_sim", "fleet_sim_params", "fleet_sim_until", "run_mission_test"]


_NO_TRIO = pytest.mark.skipif(
    importlib.util.find_spec("trio") is None,
    reason='trio is not installed: pip install "fleet-async[trio]" to run the trio variant',
)


@pytest.fixture(params=["asyncio", pytest.param("trio", marks=_NO_TRIO)])
def fleet_backend(request: pytest.FixtureRequest) -> str:
    """The anyio backend a ``fleet_sim`` test runs on (both, by default; the trio variant is
    skipped, saying so, where trio is not installed)."""
    return str(request.param)


@pytest.fixture
def fleet_sim_params() -> SimulationParams:
    """Params of the ``fleet_sim`` simulation: headless, unpaced, dt = 0.1 s, seed 0."""
    return SimulationParams(gui=False, monitor=False, target_rtf=0.0, timestep=0.1, seed=0)


@pytest.fixture
def fleet_sim_until() -> float:
    """Sim seconds a ``fleet_sim`` test may run before it fails as unfinished (600 s)."""
    return 600.0


@pytest.fixture
def fleet_sim(
    fleet_sim_params: SimulationParams, fleet_backend: str, fleet_sim_until: float
) -> Iterator[MultiRobotSimulationCore]:
    """A fresh simulation; an ``async def`` test using it runs as a mission on ``fleet_backend``."""
    sim = MultiRobotSimulationCore(fleet_sim_params)
    yield sim
    sim.close()


def run_mission_test(test: Any, kwargs: dict[str, Any], backend: str, until: float = 600.0) -> Any:
    """Run an async test function as the main mission of its ``fleet_sim``.

    Raises:
        AssertionError: if the test has not finished by sim time ``until``.
    """
    sim = kwargs["fleet_sim"]
    finished: list[bool] = []

    async def main() -> Any:
        result = await test(**kwargs)
        finished.append(True)
        return result

    result = run(sim, main, backend=backend, until=until, then="cancel")
    if not finished:
        raise AssertionError(f"the test mission had not finished at sim time {until} s")
    return result


@pytest.hookimpl(tryfirst=True)
def pytest_pyfunc_call(pyfuncitem: pytest.Function) -> bool | None:
    """Run ``async def`` tests that use ``fleet_sim`` through ``fleet_async.run``."""
    test = pyfuncitem.obj
    if not inspect.iscoroutinefunction(test) or "fleet_sim" not in pyfuncitem.funcargs:
        return None
    names = inspect.signature(test).parameters
    kwargs = {name: pyfuncitem.funcargs[name] for name in names if name in pyfuncitem.funcargs}
    backend = str(pyfuncitem.funcargs.get("fleet_backend", "asyncio"))
    until = float(str(pyfuncitem.funcargs.get("fleet_sim_until", 600.0)))
    run_mission_test(test, kwargs, backend, until)
    return True
