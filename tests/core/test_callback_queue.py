"""Per-object callbacks popped from a queue run exactly as a scan of every object did."""

from __future__ import annotations

import pytest

from fleet_async import MultiRobotSimulationCore, Pose, ShapeParams, SimObject
from tests.conftest import headless_params

BOX = ShapeParams("box", half_extents=[0.1, 0.1, 0.1])


def _run(scan: bool, skip: bool) -> list[tuple[int, int, float]]:
    sim = MultiRobotSimulationCore(headless_params())
    try:
        sim.world.scan_callbacks = scan
        log: list[tuple[int, int, float]] = []
        objs = [
            SimObject.from_mesh(BOX, BOX, Pose.from_xyz(float(i), 0.0, 0.1), sim_core=sim)
            for i in range(8)
        ]

        def make(tag):
            return lambda obj, dt: log.append((sim.step_count, tag, round(dt, 12)))

        late = make(99)
        first = make(0)
        objs[0].register_callback(first, frequency=1.0)
        for i, obj in enumerate(objs[1:], start=1):
            if i % 2 == 0:
                obj.register_callback(make(i), frequency=[1.0, 0.25, 3.0, 0.7][i // 2])
        while sim.step_count < 400:
            step = sim.step_count
            if step == 37:
                objs[5].register_callback(late, frequency=2.0)  # a new object joins the queue
            if step == 120:
                objs[0].unregister_callback(first)
            if step == 200:
                objs[5].unregister_callback(late)
                objs[5].register_callback(late, frequency=0.5)  # back, at the end of the order
            if skip and step not in (37, 120, 200):
                n = sim.idle_steps(min(400, 37 if step < 37 else 400) - step)
                if step < 120 <= step + n:
                    n = 120 - step
                if step < 200 <= step + n:
                    n = 200 - step
                if n:
                    sim.skip_steps(n)
                    continue
            sim.step_once()
        return log
    finally:
        sim.close()


@pytest.mark.parametrize("skip", [False, True])
def test_the_queue_calls_what_a_scan_calls_in_the_same_order(skip):
    reference = _run(scan=True, skip=False)
    assert _run(scan=False, skip=skip) == reference
    assert {tag for _, tag, _ in reference} == {0, 2, 4, 6, 99}
