"""EventBus priority order, payloads: pre/post_step, per-entity pre/post_update, action events."""

import pybullet
from parity_trace import Trace, call_safely
from pybullet_fleet.action import MoveAction, WaitAction
from pybullet_fleet.agent import Agent
from pybullet_fleet.core_simulation import MultiRobotSimulationCore, SimulationParams
from pybullet_fleet.events import EventBus, SimEvents
from pybullet_fleet.geometry import Path, Pose
from pybullet_fleet.sim_object import ShapeParams

T = Trace()
BOX = ShapeParams(shape_type="box", half_extents=[0.2, 0.15, 0.1])


def describe(kw):
    return {
        k: (
            v
            if isinstance(v, (int, float, str, bool, type(None)))
            else getattr(v, "value", type(v).__name__)
        )
        for k, v in kw.items()
    }


with T.probe("priority_order") as out:
    bus = EventBus()
    order = []
    bus.on("e", lambda: order.append("p0_first"), priority=0)
    bus.on("e", lambda: order.append("p10"), priority=10)
    bus.on("e", lambda: order.append("p-5"), priority=-5)
    bus.on("e", lambda: order.append("p0_second"))
    out["emit_returns"] = repr(bus.emit("e"))
    out["order"] = order
    out["has_handlers"] = [bus.has_handlers("e"), bus.has_handlers("nope")]
with T.probe("handler_raises") as out:
    bus = EventBus()
    seen = []
    bus.on("e", lambda: 1 / 0)
    bus.on("e", lambda: seen.append("second"), priority=5)
    out["emit"] = call_safely(bus.emit, "e")
    out["second_ran"] = seen
with T.probe("off") as out:
    bus = EventBus()
    h = lambda: None  # noqa: E731
    bus.on("e", h)
    out["off_returns"] = repr(bus.off("e", h))
    out["after"] = bus.has_handlers("e")
    out["off_unknown"] = call_safely(lambda: repr(bus.off("zzz", h)))
with T.probe("sim_events_values") as out:
    out["names"] = {k: getattr(SimEvents, k) for k in dir(SimEvents) if k.isupper()}

sim = MultiRobotSimulationCore(SimulationParams(gui=False, monitor=False, target_rtf=0))
agent = Agent.from_mesh(
    visual_shape=BOX,
    collision_shape=BOX,
    pose=Pose.from_xyz(0, 0, 0.1),
    sim_core=sim,
    motion_mode="omnidirectional",
    name="r",
)
log = []
for ev in (
    SimEvents.PRE_STEP,
    SimEvents.POST_STEP,
    SimEvents.ACTION_STARTED,
    SimEvents.ACTION_COMPLETED,
    SimEvents.PRE_UPDATE,
    SimEvents.POST_UPDATE,
):
    sim.events.on(ev, lambda _ev=ev, **kw: log.append(["sim", _ev, sim.step_count, describe(kw)]))
    agent.events.on(
        ev, lambda _ev=ev, **kw: log.append(["agent", _ev, sim.step_count, describe(kw)])
    )
move = MoveAction(path=Path.from_positions([[0.3, 0, 0.1]]))
agent.add_action_sequence([move, WaitAction(duration=0.2)])
sim.initialize_simulation()
for _ in range(12):
    sim.step_once()
with T.probe("step_events") as out:
    first = {}
    for who, ev, step, kw in log:
        first.setdefault(f"{who}.{ev}", {"first_step": step, "payload": kw})
    out["first_of_each"] = first
    out["counts"] = {k: sum(1 for w, e, *_ in log if f"{w}.{e}" == k) for k in first}
with T.probe("action_events_in_order") as out:
    out["log"] = [[w, e, s, kw] for w, e, s, kw in log if "action" in e]
pybullet.disconnect(physicsClientId=sim.client)
T.dump()
