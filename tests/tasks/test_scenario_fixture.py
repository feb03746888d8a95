"""The fleet_sim fixture from fleet_async.testing, used exactly as the README shows."""

from __future__ import annotations

import pytest

from fleet_async import Agent, Pose, ShapeParams


async def test_robot_arrives(fleet_sim):
    box = ShapeParams("box", half_extents=[0.2, 0.2, 0.1])
    pose = Pose.from_xyz(0, 0, 0.1)
    robot = Agent.from_mesh(box, box, pose, sim_core=fleet_sim, controller="omni")
    await robot.move(Pose.from_xyz(2, 0, 0.1))
    assert fleet_sim.step_count == 14  # 2 m: 1.4 s at 2 m/s, 5 m/s^2


def test_an_unfinished_test_mission_fails(pytester):
    pytester.makepyfile(
        """
        import pytest

        @pytest.fixture
        def fleet_sim_until():
            return 3.0

        async def test_forever(fleet_sim):
            while True:
                await fleet_sim.sleep(1.0)
        """
    )
    result = pytester.runpytest("-q")
    result.assert_outcomes(failed=2)
    result.stdout.fnmatch_lines(["*had not finished at sim time 3.0 s*"])


@pytest.mark.parametrize("fleet_backend", ["trio"])
async def test_backend_can_be_pinned(fleet_sim, fleet_backend):
    import trio

    await fleet_sim.sleep(0.2)
    assert trio.lowlevel.current_task() is not None
    assert fleet_sim.sim_time == pytest.approx(0.2)
