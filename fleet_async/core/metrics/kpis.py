"""Fleet KPIs: one summary row per run, and a per-robot table on request.

``sim.kpis()`` returns the simulation's :class:`KpiCollector`, subscribed to the event bus on
first call; it counts from that moment on (a first call after steps have run is an error unless
it says ``from_now=True``). Counts (actions, tasks, collisions, mission errors)
come from events. Time and distance come from one vectorised pass over the robots' rows of the
state store after every step: each robot's step is classified as *moving* (its linear or
angular velocity over the step is non-zero), *waiting* (not moving while an action of its
queue is in progress) or *idle* (neither), and the distance it drove is ``|v| * dt``. Time is
counted in whole steps (``steps * dt``), never accumulated as floats. The definitions are
documented in ``docs/sweeps.md``; wall time is not a KPI (it differs between machines).

Robots are the agents whose class says ``is_robot`` (doors, lifts and workcells are agents
too, but not robots: their actions and time are not fleet figures). The bus runs handlers lower
priority first; the collector takes each event first (:data:`OBSERVE_FIRST`), before any
handler can react to it, and lets robots go, and stops, last (:data:`OBSERVE_LAST`).
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from fleet_async.core.base.events import SimEvents
from fleet_async.core.base.types import ActionStatus
from fleet_async.core.metrics.rows import FleetKpis, RobotKpis
from fleet_async.core.metrics.traffic import TrafficCounts

if sys.version_info < (3, 11):  # anyio depends on the backport there
    from exceptiongroup import BaseExceptionGroup

if TYPE_CHECKING:
    from fleet_async.core.agents.agent import Agent
    from fleet_async.core.bodies.sim_object import SimObject
    from fleet_async.core.sim.kernel import SimulationKernel

__all__ = ["OBSERVE_FIRST", "OBSERVE_LAST", "KpiApi", "KpiCollector"]

OBSERVE_FIRST = -1_000_000
"""Priority of the collector's handlers that see an event before anyone reacts to it: the
per-step pass reads the state store as the step's phases left it (not as a POST_STEP handler
moved it afterwards), a spawned robot joins before a handler can report a task for it, and the
counts take the payload as it was emitted."""
OBSERVE_LAST = 1_000_000
"""Priority of the collector's handlers that run after everyone else's: a removed robot leaves
once the handlers of its removal have reported on it, and ``stop_after_step`` stops once every
handler of that step's POST_STEP has run."""

_STILL = 1e-18  # (m/s)^2 and (rad/s)^2: below this a robot did not move in the step
_EPS_TIME = 1e-9  # s


class _Robot:
    """Event counts and identity of one robot (time and distance live in the arrays)."""

    __slots__ = (
        "actions",
        "agent",
        "battery_base",
        "battery_final",
        "collisions",
        "index",
        "joined_step",
        "left_step",
        "name",
        "object_id",
        "tasks",
    )

    def __init__(self, agent: SimObject, index: int, step: int) -> None:
        self.agent: SimObject | None = agent
        self.index = index
        self.name = agent.name if agent.name else f"#{agent.object_id}"
        self.object_id = agent.object_id
        self.joined_step = step
        self.left_step: int | None = None
        self.actions = [0, 0, 0]  # completed, failed, cancelled
        self.tasks = [0, 0]  # completed, failed
        self.collisions = 0
        self.battery_base = _battery_used(agent)
        self.battery_final: tuple[float, float] | None = None  # (used, soc) when it left

    def label(self) -> str:
        """Its name as it is now (missions often name robots after they spawn), else the last
        name it had in the simulation, else ``#object_id``."""
        if self.agent is not None and self.agent.name:
            self.name = self.agent.name
        return self.name


def _as_slice(index: np.ndarray) -> slice | np.ndarray:
    """``index`` as a slice when it is a run of consecutive ascending integers."""
    n = len(index)
    if n and int(index[-1]) - int(index[0]) == n - 1 and bool(np.all(np.diff(index) == 1)):
        return slice(int(index[0]), int(index[0]) + n)
    return index


def _leaves(error: BaseException) -> list[BaseException]:
    """The exceptions inside (nested) exception groups, or ``[error]``."""
    if isinstance(error, BaseExceptionGroup):
        return [leaf for inner in error.exceptions for leaf in _leaves(inner)]
    return [error]


def _battery(agent: SimObject) -> Any:
    return getattr(agent, "battery_plugin", None)


def _battery_used(agent: SimObject) -> float:
    battery = _battery(agent)
    return 0.0 if battery is None else float(battery.used)


class KpiCollector:
    """Counts one simulation's fleet KPIs from its events and its state store.

    Get it with ``sim.kpis()`` (one per simulation, subscribed on first call) rather than
    constructing it yourself.

    Args:
        sim: The simulation to observe.
    """

    def __init__(self, sim: SimulationKernel) -> None:
        self._sim = sim
        self._dt = sim.params.timestep
        self._steps = 0
        self._stopped = False
        self._tasks = [0, 0]
        self._actions = [0, 0, 0]
        self._collisions = 0
        self._mission_errors = 0
        self._traffic = TrafficCounts(sim)
        self._errors_seen: list[BaseException] = []
        self._robots: list[_Robot] = []
        self._by_id: dict[int, _Robot] = {}  # id(agent) -> robot, while it is in the sim
        # Per robot index: busy (an action of its queue is in progress), and whether an action
        # ended during the current step after it began (the step still counts as busy).
        self._busy = np.zeros(16, dtype=bool)
        self._ended = np.zeros(16, dtype=bool)
        self._any_ended = False
        self._speed_sum = np.zeros(16)  # m/s, summed over steps
        self._moving = np.zeros(16, dtype=np.int64)
        self._waiting = np.zeros(16, dtype=np.int64)
        self._live_count = 0
        self._linked = True  # the live selectors below are up to date
        self._live_index: slice | np.ndarray = slice(0, 0)
        self._live_rows: slice | np.ndarray = slice(0, 0)
        # event -> (handler, priority); every handler takes the payload keys it reads and
        # **_ for the rest (the bus passes a handler only the keys it names).
        self._handlers: dict[str, tuple[Callable[..., Any], int]] = {
            SimEvents.STEPS_SKIPPED: (self._on_skipped, OBSERVE_FIRST),
            SimEvents.AGENT_SPAWNED: (self._on_spawned, OBSERVE_FIRST),
            # OBJECT_REMOVED, not AGENT_REMOVED: sim.reset() emits only the former.
            SimEvents.OBJECT_REMOVED: (self._on_removed, OBSERVE_LAST),
            SimEvents.ACTION_STARTED: (self._on_action_started, OBSERVE_FIRST),
            SimEvents.ACTION_COMPLETED: (self._on_action_ended, OBSERVE_FIRST),
            SimEvents.ACTION_FAILED: (self._on_action_ended, OBSERVE_FIRST),
            SimEvents.TASK_COMPLETED: (self._on_task_completed, OBSERVE_FIRST),
            SimEvents.TASK_FAILED: (self._on_task_failed, OBSERVE_FIRST),
            SimEvents.COLLISION_STARTED: (self._on_collision, OBSERVE_FIRST),
            SimEvents.MISSION_FAILED: (self._on_mission_failed, OBSERVE_FIRST),
        }
        for agent in sim.agents:
            self._on_spawned(cast("Agent", agent))
        for event, (handler, priority) in self._handlers.items():
            sim.events.on(event, handler, priority=priority)
        # A step observer, not a POST_STEP handler: it sees the step before any handler (as
        # OBSERVE_FIRST did) and does not stop idle steps from being skipped.
        sim.add_step_observer(self._on_step, before_handlers=True)
        self._stop_step: int | None = None

    # ----- reading --------------------------------------------------------------------------

    @property
    def stopped(self) -> bool:
        """Whether :meth:`stop` was called (the figures no longer change)."""
        return self._stopped

    def stop(self) -> None:
        """Stop counting: unsubscribe, and keep the figures as they are now."""
        if self._stopped:
            return
        self._stopped = True
        self._traffic.freeze()
        for event, (handler, _) in self._handlers.items():
            self._sim.events.off(event, handler)
        self._sim.remove_step_observer(self._on_step)
        self._sim.remove_step_observer(self._check_stop)

    def stop_after_step(self, step: int) -> None:
        """Stop counting once the simulation's step number ``step`` (``sim.step_count``) has
        run (at once if it already has).

        A run that ends at a known step (``fleet_async.run(..., until=...)``) cancels its
        missions, and with them their actions, after that step: stopping there leaves out what
        the ending itself does, so the figures are those of the run's last step.
        """
        sim = self._sim
        if sim.step_count >= step:
            self.stop()
            return
        self._stop_step = step
        # After every POST_STEP handler of the step (an observer, so idle steps still skip).
        sim.add_step_observer(self._check_stop)

    def _check_stop(self, step: int) -> None:
        if self._stop_step is not None and step >= self._stop_step:
            self.stop()

    def summary(self) -> FleetKpis:
        """The fleet's figures since the collector started (see :class:`FleetKpis`)."""
        robots = self.per_robot()
        n = len(robots)
        sim_time = self._steps * self._dt
        distance = math.fsum(r.distance_m for r in robots)
        moving, waiting, idle = self._step_totals()
        batteries = [r for r in robots if r.battery_used is not None]
        used = math.fsum(r.battery_used for r in batteries if r.battery_used is not None)
        return FleetKpis(
            robot_count=n,
            steps=self._steps,
            sim_time_s=sim_time,
            tasks_completed=self._tasks[0],
            tasks_failed=self._tasks[1],
            throughput_per_hour=self._tasks[0] * 3600.0 / sim_time if sim_time > 0 else 0.0,
            actions_completed=self._actions[0],
            actions_failed=self._actions[1],
            actions_cancelled=self._actions[2],
            distance_total_m=distance,
            distance_mean_m=distance / n if n else 0.0,
            moving_time_total_s=moving * self._dt,
            moving_time_mean_s=moving * self._dt / n if n else 0.0,
            waiting_time_total_s=waiting * self._dt,
            waiting_time_mean_s=waiting * self._dt / n if n else 0.0,
            idle_time_total_s=idle * self._dt,
            idle_time_mean_s=idle * self._dt / n if n else 0.0,
            collisions=self._collisions,
            mission_errors=self._mission_errors,
            battery_robots=len(batteries),
            battery_used_total=used if batteries else None,
            battery_used_mean=used / len(batteries) if batteries else None,
            battery_min_soc=min(r.battery_soc for r in batteries if r.battery_soc is not None)
            if batteries
            else None,
            safety_stops=sum(r.safety_stops for r in robots),
            safety_stopped_time_total_s=math.fsum(r.safety_stopped_time_s for r in robots),
            deadlocks_suspected=self._traffic.deadlocks(),
        )

    def per_robot(self) -> list[RobotKpis]:
        """One row per robot counted (present now or removed meanwhile), in join order."""
        return [self._robot_row(robot) for robot in self._robots]

    # ----- robots joining and leaving -------------------------------------------------------

    def _join(self, agent: SimObject) -> None:
        index = len(self._robots)
        robot = _Robot(agent, index, self._steps)
        self._robots.append(robot)
        self._by_id[id(agent)] = robot
        if index >= len(self._busy):
            self._grow(2 * len(self._busy))
        self._linked = False  # rebuilt before the next step: a spawn of N robots costs O(N)

    def _grow(self, capacity: int) -> None:
        for name in ("_busy", "_ended", "_speed_sum", "_moving", "_waiting"):
            old = getattr(self, name)
            new = np.zeros(capacity, dtype=old.dtype)
            new[: len(old)] = old
            setattr(self, name, new)

    def _relink(self) -> None:
        """Rebuild the (robot index, state row) selectors of the robots in the simulation.

        Slices where they can be (every robot still present; robots on consecutive rows, as a
        batch spawn leaves them): a slice reads a view, an index array copies.
        """
        live = [r for r in self._robots if r.agent is not None]
        index = np.array([r.index for r in live], dtype=np.int64)
        rows = np.array([r.agent.state_row for r in live if r.agent is not None], dtype=np.int64)
        self._live_count = len(live)
        self._live_index = _as_slice(index)
        self._live_rows = _as_slice(rows)

    def _on_spawned(self, agent: Agent, **_: Any) -> None:
        if agent.is_robot and id(agent) not in self._by_id:
            self._join(agent)

    def _on_removed(self, obj: SimObject, **_: Any) -> None:
        robot = self._by_id.pop(id(obj), None)
        if robot is None:
            return
        battery = _battery(obj)
        if battery is not None:
            robot.battery_final = (float(battery.used) - robot.battery_base, float(battery.soc))
        robot.label()  # keep the name it left with
        robot.agent = None
        robot.left_step = self._steps
        self._busy[robot.index] = False
        self._linked = False

    # ----- events ---------------------------------------------------------------------------

    def _on_action_started(self, agent: SimObject, **_: Any) -> None:
        robot = self._by_id.get(id(agent))
        if robot is not None:
            self._busy[robot.index] = True

    def _on_action_ended(self, agent: Agent, action: Any, status: ActionStatus, **_: Any) -> None:
        if not agent.is_robot:
            return  # a door's or a lift's action is no fleet figure
        which = {ActionStatus.COMPLETED: 0, ActionStatus.CANCELLED: 2}.get(status, 1)
        self._actions[which] += 1
        if which == 2:  # a cancelled action also counts as failed (ACTION_FAILED)
            self._actions[1] += 1
        robot = self._by_id.get(id(agent))
        if robot is None:
            return
        robot.actions[which] += 1
        if which == 2:
            robot.actions[1] += 1
        if not self._busy[robot.index]:
            return  # a queued action that never started
        self._busy[robot.index] = False
        end = action.end_time
        if self._sim.in_step and end is not None and end > self._sim.sim_time + _EPS_TIME:
            self._ended[robot.index] = True  # it ended at the step's end: the step was busy
            self._any_ended = True

    def _on_task(self, which: int, agent: SimObject | None) -> None:
        self._tasks[which] += 1
        robot = self._by_id.get(id(agent)) if agent is not None else None
        if robot is not None:
            robot.tasks[which] += 1

    def _on_task_completed(self, agent: SimObject | None = None, **_: Any) -> None:
        self._on_task(0, agent)

    def _on_task_failed(self, agent: SimObject | None = None, **_: Any) -> None:
        self._on_task(1, agent)

    def _on_collision(self, obj_a: SimObject, obj_b: SimObject, **_: Any) -> None:
        self._collisions += 1
        for obj in (obj_a, obj_b):
            robot = self._by_id.get(id(obj))
            if robot is not None:
                robot.collisions += 1

    def _on_mission_failed(self, error: BaseException, **_: Any) -> None:
        # An error that ends a child mission reaches its parent again inside an exception
        # group: count each exception once. The list keeps them alive so ids stay unique.
        for leaf in _leaves(error):
            if all(leaf is not seen for seen in self._errors_seen):
                self._errors_seen.append(leaf)
                self._mission_errors += 1

    # ----- the per-step pass (hot path: numpy only) -------------------------------------------

    def _on_step(self, _step: int = 0) -> None:
        self._steps += 1
        if not self._linked:
            self._relink()
            self._linked = True
        if not self._live_count:
            return
        speed2, moving = self._motion()
        index = self._live_index
        busy = self._busy[index]
        if self._any_ended:
            busy = busy | self._ended[index]
            self._ended[:] = False
            self._any_ended = False
        self._speed_sum[index] += np.sqrt(speed2)  # times dt at read: the distance
        self._moving[index] += moving
        self._waiting[index] += busy > moving  # busy and not moving

    def _motion(self) -> tuple[np.ndarray, np.ndarray]:
        """Squared speed and whether each live robot moved, from the store."""
        store = self._sim.state
        rows = self._live_rows
        vel = store.velocity[rows]
        spin = store.angular_velocity[rows]
        speed2 = np.einsum("ij,ij->i", vel, vel)
        return speed2, speed2 + np.einsum("ij,ij->i", spin, spin) > _STILL

    def _on_skipped(self, step: int, count: int, **_: Any) -> None:
        """``count`` empty steps from ``step`` were skipped: count them as if they ran."""
        if self._stop_step is not None:
            count = min(count, self._stop_step - step)
        if count <= 0:
            return
        if not self._linked:
            self._relink()
            self._linked = True
        if self._live_count and bool(self._motion()[1].any()):
            for _i in range(count):  # a still velocity left over: step the pass itself
                self._on_step()
        else:
            self._steps += count
            if self._live_count:
                index = self._live_index
                self._waiting[index] += self._busy[index] * count  # busy, and nothing moves
        if self._stop_step is not None and step + count >= self._stop_step:
            self.stop()

    # ----- rows -----------------------------------------------------------------------------

    def _alive_steps(self, robot: _Robot) -> int:
        end = self._steps if robot.left_step is None else robot.left_step
        return end - robot.joined_step

    def _step_totals(self) -> tuple[int, int, int]:
        n = len(self._robots)
        moving = int(self._moving[:n].sum())
        waiting = int(self._waiting[:n].sum())
        alive = sum(self._alive_steps(r) for r in self._robots)
        return moving, waiting, alive - moving - waiting

    def _robot_row(self, robot: _Robot) -> RobotKpis:
        i, dt = robot.index, self._dt
        moving, waiting = int(self._moving[i]), int(self._waiting[i])
        idle = self._alive_steps(robot) - moving - waiting
        used: float | None = None
        soc: float | None = None
        if robot.battery_final is not None:
            used, soc = robot.battery_final
        elif robot.agent is not None and _battery(robot.agent) is not None:
            battery = _battery(robot.agent)
            used, soc = float(battery.used) - robot.battery_base, float(battery.soc)
        return RobotKpis(
            robot=robot.label(),
            object_id=robot.object_id,
            distance_m=float(self._speed_sum[i]) * dt,
            moving_time_s=moving * dt,
            waiting_time_s=waiting * dt,
            idle_time_s=idle * dt,
            actions_completed=robot.actions[0],
            actions_failed=robot.actions[1],
            actions_cancelled=robot.actions[2],
            tasks_completed=robot.tasks[0],
            tasks_failed=robot.tasks[1],
            collisions=robot.collisions,
            battery_used=used,
            battery_soc=soc,
            safety_stops=self._traffic.robot(robot.object_id)[0],
            safety_stopped_time_s=self._traffic.robot(robot.object_id)[1],
        )


class KpiApi:
    """``sim.kpis()`` (mixed into ``MultiRobotSimulationCore``)."""

    _kpis: KpiCollector | None = None

    def kpis(self, *, from_now: bool = False) -> KpiCollector:
        """The fleet KPI collector (``.summary()``, ``.per_robot()``); it subscribes on the
        first call and counts from then on, so call it before running.

        Args:
            from_now: Allow the first call after steps have run (a warm-up left uncounted, a
                restored checkpoint); the figures count from this call on.

        Raises:
            RuntimeError: if this first call comes after steps have run and ``from_now`` is
                False: the collector would have missed them, and its figures for a finished
                run would be all zeros.
        """
        if self._kpis is None:
            sim = cast("SimulationKernel", self)
            if sim.step_count > 0 and not from_now:
                raise RuntimeError(
                    f"sim.kpis(): first called after {sim.step_count} steps "
                    f"({sim.sim_time:g} s of sim time) had run; the collector counts from its "
                    "first call, so it would leave them out (all zeros after a finished run). "
                    "Call sim.kpis() before running, or sim.kpis(from_now=True) to count from "
                    "here on"
                )
            self._kpis = KpiCollector(sim)
        return self._kpis
