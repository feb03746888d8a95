"""What a sweep runs: a scenario YAML, or a Python function of a seed and parameters.

Both build a simulation for one (parameters, seed) pair; :func:`execute_run` then attaches the
KPI collector, runs it, and returns the row. That function is what the engines ship to their
workers, so everything here pickles: a YAML scenario travels as its (already parsed) mapping,
a function as a reference (``"pkg.module:name"`` or ``"path/to/file.py:name"``, loaded in the
worker) or as the function object itself (importable, or picklable by value).
"""

from __future__ import annotations

import dataclasses
import hashlib
import importlib
import importlib.util
import inspect
import re
import sys
import time
from abc import ABC, abstractmethod
from collections.abc import Awaitable, Callable, Mapping
from pathlib import Path
from typing import Any

from fleet_async.core import MultiRobotSimulationCore, load_yaml_config
from fleet_async.core.base.steps import steps_for
from fleet_async.scenario_runner import DEFAULT_MAX_DURATION, run_scenario
from fleet_async.sweep.overrides import (
    SweepKeyError,
    apply_overrides,
    is_nested,
    settable_keys,
)
from fleet_async.sweep.table import round_sim_times
from fleet_async.tasks import run as run_missions

if sys.version_info < (3, 11):  # anyio depends on the backport there
    from exceptiongroup import BaseExceptionGroup

__all__ = [
    "FunctionScenario",
    "RunResult",
    "RunSpec",
    "Scenario",
    "YamlScenario",
    "describe_error",
    "execute_run",
    "load_function",
]

Mission = Callable[[], Awaitable[Any]]
_ADDRESS = re.compile(r" at 0x[0-9a-fA-F]+")


class Scenario(ABC):
    """A family of simulations, one per (parameters, seed)."""

    label: str
    """How tables and messages name the scenario (a file name, a function reference)."""

    @abstractmethod
    def settable_keys(self) -> list[str] | None:
        """The keys ``--set`` accepts, or None when any key is accepted."""

    @abstractmethod
    def check_keys(self, keys: list[str]) -> None:
        """Raise SweepKeyError for a key the scenario does not take, naming the valid ones."""

    @abstractmethod
    def build(
        self, params: Mapping[str, Any], seed: int
    ) -> tuple[MultiRobotSimulationCore, Mission | None]:
        """A fresh simulation (headless) for ``params`` and ``seed``, and its main mission."""


class YamlScenario(Scenario):
    """A scenario mapping (as a YAML file holds it); ``--set`` keys are dotted paths into it.

    Every run is headless and unpaced, with ``seed`` as the simulation's seed.

    Args:
        config: The scenario mapping (nested or flat layout).
        source: The file it came from, named in errors.
        base_dir: Where its relative files (worlds, meshes, URDFs) are looked up first.
    """

    def __init__(
        self, config: Mapping[str, Any], source: str = "<scenario>", base_dir: str | None = None
    ) -> None:
        self.config = dict(config)
        self.source = source
        self.base_dir = base_dir
        self.label = Path(source).name

    @classmethod
    def from_file(cls, path: str | Path) -> YamlScenario:
        """Load a scenario YAML file."""
        path = Path(path)
        config = load_yaml_config(path, allow_empty=False)
        return cls(config, str(path), str(path.resolve().parent))

    def settable_keys(self) -> list[str]:
        """Dotted paths into the scenario (see :mod:`fleet_async.sweep.overrides`)."""
        return settable_keys(self.config)

    def check_keys(self, keys: list[str]) -> None:
        """Raise SweepKeyError for a key the scenario does not have."""
        apply_overrides(self.config, dict.fromkeys(keys))

    def build(
        self, params: Mapping[str, Any], seed: int
    ) -> tuple[MultiRobotSimulationCore, Mission | None]:
        """The simulation of the scenario with ``params`` set; no main mission (the run starts
        the scenario's own ``missions:``, as ``fleet-async run`` does)."""
        config = apply_overrides(self.config, params)
        if is_nested(config):
            if not isinstance(config.get("simulation"), dict):
                config["simulation"] = {}
            settings = config["simulation"]
        else:
            settings = config
        settings.update(gui=False, monitor=False, target_rtf=0.0, seed=seed)
        sim = MultiRobotSimulationCore.from_dict(config, source=self.source, base_dir=self.base_dir)
        return sim, None


def load_function(reference: str) -> Callable[..., Any]:
    """The function named by ``"pkg.module:name"`` or ``"path/to/file.py:name"``.

    Raises:
        ValueError: for a malformed reference, a missing file or module, or a missing name.
    """
    target, sep, name = reference.rpartition(":")
    if not sep or not target or not name.isidentifier():
        raise ValueError(
            f"{reference!r}: expected MODULE:FUNCTION or FILE.py:FUNCTION "
            "(e.g. examples/sweep_fleet.py:scenario)"
        )
    if target.endswith(".py"):
        path = Path(target).resolve()
        if not path.is_file():
            raise ValueError(f"{reference!r}: no file {path}")
        # A stable module name per file, so the module's own classes pickle by reference.
        module_name = f"_fleet_sweep_{path.stem}_{hashlib.sha1(str(path).encode()).hexdigest()[:8]}"
        module = sys.modules.get(module_name)
        if module is None:
            spec = importlib.util.spec_from_file_location(module_name, path)
            if spec is None or spec.loader is None:
                raise ValueError(f"{reference!r}: cannot load {path} as Python")
            module = importlib.util.module_from_spec(spec)
            sys.modules[module_name] = module
            try:
                spec.loader.exec_module(module)
            except BaseException:
                del sys.modules[module_name]
                raise
    else:
        try:
            module = importlib.import_module(target)
        except ImportError as exc:
            raise ValueError(f"{reference!r}: cannot import {target!r}: {exc}") from exc
    function = getattr(module, name, None)
    if not callable(function):
        raise ValueError(f"{reference!r}: {target} has no function {name!r}")
    return function


class FunctionScenario(Scenario):
    """A Python function ``fn(seed, **params)`` that builds a simulation.

    It returns the simulation, or ``(sim, main)`` with ``main`` an async function (no
    arguments) that the run starts as its main mission (``fleet_async.run(sim, main)``). It
    should build, not run: the KPIs count from the moment it returns. Parameters the sweep does
    not set keep the function's defaults; ``--set`` keys are its keyword parameters.

    Args:
        function: The function, or a reference to it (see :func:`load_function`), which each
            worker loads itself.
    """

    def __init__(self, function: Callable[..., Any] | str) -> None:
        self.reference = function if isinstance(function, str) else None
        self._function = function if callable(function) else None
        if self.reference is not None:
            self.label = self.reference
        else:
            self.label = (
                f"{getattr(function, '__module__', '?')}:{getattr(function, '__name__', '?')}"
            )

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        if self.reference is not None:
            state["_function"] = None  # the worker loads it from the reference
        return state

    @property
    def function(self) -> Callable[..., Any]:
        """The function (loaded on first use when given as a reference)."""
        if self._function is None:
            assert self.reference is not None
            self._function = load_function(self.reference)
        return self._function

    def settable_keys(self) -> list[str] | None:
        """The function's parameters after the seed; None if it takes ``**kwargs``."""
        parameters = list(inspect.signature(self.function).parameters.values())[1:]
        if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters):
            return None
        return [
            p.name
            for p in parameters
            if p.kind in (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)
        ]

    def check_keys(self, keys: list[str]) -> None:
        """Raise SweepKeyError for a key the function does not take."""
        valid = self.settable_keys()
        if valid is None:
            return
        for key in keys:
            if key not in valid:
                raise SweepKeyError(
                    f"--set {key}: {self.label} takes no parameter {key!r}; valid keys: "
                    f"{', '.join(valid) if valid else '(none: it takes only the seed)'}"
                )

    def build(
        self, params: Mapping[str, Any], seed: int
    ) -> tuple[MultiRobotSimulationCore, Mission | None]:
        """Call the function; check what it returned."""
        built = self.function(seed, **params)
        sim, main = (
            (built[0], built[1]) if isinstance(built, tuple) and len(built) == 2 else (built, None)
        )
        if not isinstance(sim, MultiRobotSimulationCore):
            raise TypeError(
                f"{self.label} returned {built!r}; expected a MultiRobotSimulationCore or "
                "(sim, main) with main an async function"
            )
        if main is not None and not callable(main):
            sim.close()
            raise TypeError(f"{self.label}: the main mission it returned is not callable: {main!r}")
        return sim, main


@dataclasses.dataclass(frozen=True)
class RunSpec:
    """One run of a sweep, as sent to a worker.

    Attributes:
        index: The run number (its row's place in the table).
        params: The swept values, ``{key: value}``.
        seed: The seed.
        scenario: What to build.
        duration: Sim seconds to run; None: the scenario's ``simulation.duration``, else until
            its work is done: the main mission has returned or, without one, the scenario's
            ``missions:`` have returned and its actions are done (at most 600 s).
        per_robot: Also return the per-robot table.
        checkpoint: Branch from this checkpoint (``sim.save_state``): restore it into the
            freshly built simulation and reseed it with ``seed`` (``sim.reseed``: ``sim.rng``
            and every stream of ``sim.rng_for``, controllers' among them) before running.
        unsafe: Also read a format-1 (pickle) checkpoint, which runs code it names.
    """

    index: int
    params: dict[str, Any]
    seed: int
    scenario: Scenario
    duration: float | None = None
    per_robot: bool = False
    checkpoint: str | None = None
    unsafe: bool = False


@dataclasses.dataclass(frozen=True)
class RunResult:
    """What a run produced: its KPI row, or its error (never both).

    Attributes:
        index, params, seed: As in the RunSpec.
        kpis: ``FleetKpis.as_dict()``, or None if the run failed.
        robots: ``[RobotKpis.as_dict(), ...]`` when asked for and the run succeeded.
        error: ``"Type: message"`` of what the run raised, or None.
        wall_time_s: Wall seconds the run took in its worker (not part of what must be
            identical between engines).
    """

    index: int
    params: dict[str, Any]
    seed: int
    kpis: dict[str, Any] | None
    robots: list[dict[str, Any]] | None
    error: str | None
    wall_time_s: float


def _leaves(error: BaseException) -> list[BaseException]:
    if isinstance(error, BaseExceptionGroup):
        return [leaf for inner in error.exceptions for leaf in _leaves(inner)]
    return [error]


def describe_error(error: BaseException) -> str:
    """``"Type: message (notes)"`` per exception (groups flattened, joined by ``" | "``), on
    one line, with memory addresses removed so that the text is the same in every process."""
    parts = []
    for leaf in _leaves(error):
        text = f"{type(leaf).__name__}: {leaf}"
        notes = getattr(leaf, "__notes__", None)
        if notes:
            text += f" ({'; '.join(str(n) for n in notes)})"
        parts.append(_ADDRESS.sub("", " / ".join(text.splitlines())))
    return " | ".join(parts)


def _run_missions(sim: MultiRobotSimulationCore, main: Mission, duration: float) -> None:
    kpis = sim.kpis(from_now=True)
    if duration <= 0:
        run_missions(sim, main)
        return
    until = sim.sim_time + duration
    # The runner cancels the missions at `until`, and with them their actions: count the run up
    # to its last step, not the cancellations that end it.
    kpis.stop_after_step(steps_for(until, sim.params.timestep))
    run_missions(sim, main, until=until)


def _run_scenario(sim: MultiRobotSimulationCore, duration: float | None) -> None:
    """The scenario's own work, as ``fleet-async run`` runs it: its ``missions:`` and queued
    actions, for the duration or until done (at most ``DEFAULT_MAX_DURATION``)."""
    kpis = sim.kpis(from_now=True)
    if duration is None and sim.params.duration > 0:
        duration = float(sim.params.duration)
    limit = duration if duration is not None else DEFAULT_MAX_DURATION
    kpis.stop_after_step(steps_for(sim.sim_time + limit, sim.params.timestep))
    run_scenario(sim, duration)


def _run_built(
    sim: MultiRobotSimulationCore, main: Mission | None, spec: RunSpec
) -> tuple[dict[str, Any], list[dict[str, Any]] | None]:
    kpis = sim.kpis(from_now=True)
    if main is not None:
        duration = spec.duration if spec.duration is not None else sim.params.duration
        _run_missions(sim, main, duration)
    else:
        _run_scenario(sim, spec.duration)
    kpis.stop()
    dt = sim.params.timestep
    robots = (
        [round_sim_times(r.as_dict(), dt) for r in kpis.per_robot()] if spec.per_robot else None
    )
    return round_sim_times(kpis.summary().as_dict(), dt), robots


def execute_run(spec: RunSpec) -> RunResult:
    """Build, run and summarise one run; an exception becomes the result's ``error``."""
    t0 = time.perf_counter()
    kpis: dict[str, Any] | None = None
    robots: list[dict[str, Any]] | None = None
    error: str | None = None
    try:
        sim, main = spec.scenario.build(spec.params, spec.seed)
        try:
            if spec.checkpoint is not None:
                sim.restore_state(spec.checkpoint, unsafe=spec.unsafe)
                sim.reseed(spec.seed)  # every stream: branches differ from here on
            kpis, robots = _run_built(sim, main, spec)
        finally:
            sim.close()
    except Exception as exc:
        kpis, robots, error = None, None, describe_error(exc)
    return RunResult(
        index=spec.index,
        params=dict(spec.params),
        seed=spec.seed,
        kpis=kpis,
        robots=robots,
        error=error,
        wall_time_s=time.perf_counter() - t0,
    )
