"""One served robot: takes orders and instant tasks, drives them, says how it stands.

A :class:`Vehicle` changes the simulation only at step boundaries, when the fleet interface
calls :meth:`Vehicle.apply` (a command) and :meth:`Vehicle.advance` (progress of what it is
doing); both are synchronous and deterministic, so a run replays exactly from its recorded
commands. Driving goes through the robot's own motion (``set_path``, with an edge's speed
limit as a cap); picks and drops run as ``PickAction`` / ``DropAction`` on its action queue.

What it does with an order (docs/fleet-interfaces.md has the whole contract):
- The order's released nodes and edges (the base) are driven in sequence; the vehicle stops at
  the last released node and waits there for an update that releases more.
- On reaching a node it runs the node's tasks in order, then enters the next edge (running the
  edge's tasks first) and drives on.
- Rejections leave everything as it was and add an error to the state.
"""

from __future__ import annotations

import logging
import math
from collections import deque
from collections.abc import Callable
from typing import Any

from fleet_async.core.actions.action import Action
from fleet_async.core.base.types import ActionStatus, MotionMode
from fleet_async.core.geometry.pose import Pose
from fleet_async.interfaces.commands import (
    Command,
    Edge,
    InstantTasks,
    Node,
    Order,
    Rejection,
    Task,
)
from fleet_async.interfaces.driving import Drive, plan_drive
from fleet_async.interfaces.host import ServedAgent, ServingHost
from fleet_async.interfaces.loads import load_action, loads_of
from fleet_async.interfaces.order_check import check_order
from fleet_async.interfaces.snapshot import (
    TaskProgress,
    TaskStatus,
    VehicleError,
    VehicleSnapshot,
)

__all__ = ["INSTANT_TASKS", "Vehicle"]

logger = logging.getLogger(__name__)

INSTANT_TASKS = frozenset(
    {
        "cancel_order",
        "start_pause",
        "stop_pause",
        "state_request",
        "factsheet_request",
        "init_position",
        "start_charging",
        "stop_charging",
    }
)
"""Task kinds an instant command may carry."""

_ORDER_ERRORS = frozenset({"validation", "order", "order_update", "no_order_to_cancel"})


class Vehicle:
    """A robot that a master drives through orders.

    Args:
        agent: The robot (an ``Agent``).
        host: Its simulation.
        default_deviation_xy: m within which a node counts as reached when the order does not
            say (also how close the first node of a new order must be).
        on_change: Called with a reason (``"order_accepted"``, ``"node_reached"`` ...) each
            time the state changes in a way the master must hear of.
        name: The vehicle's name (default: the robot's).
    """

    def __init__(
        self,
        agent: ServedAgent,
        host: ServingHost,
        default_deviation_xy: float = 0.5,
        on_change: Callable[[str], None] | None = None,
        name: str | None = None,
    ) -> None:
        self.agent = agent
        self.name: str = name or agent.name or f"#{agent.object_id}"
        self._host = host
        self._default_deviation = float(default_deviation_xy)
        self._notify = on_change if on_change is not None else (lambda reason: None)
        self.order_id = ""
        self.order_update = 0
        self.last_node_id = ""
        self.last_node_sequence = 0
        self.map_id: str | None = None  # the map of the last node reached (or initPosition)
        self._nodes: deque[Node] = deque()  # still to reach (base, then horizon)
        self._edges: deque[Edge] = deque()  # still to drive
        self._tasks: dict[str, list[Any]] = {}  # task_id -> [Task, TaskStatus, description]
        self._pending: deque[Task] = deque()  # tasks to run before driving on
        self._running: tuple[Task, Action] | None = None
        self._drive: Drive | None = None
        self.paused = False
        self.errors: list[VehicleError] = []
        self._last_xy = self._xy()
        self._distance = 0.0
        self.factsheet_requested = False
        self._rest_heights: dict[int, float] = {}  # loads carried: where they stood (z, m)

    # ----- reading --------------------------------------------------------------------------

    @property
    def has_order(self) -> bool:
        """Whether an order is in progress: nodes to reach or tasks not done."""
        return bool(self._nodes or self._pending or self._running or self._drive)

    @property
    def busy(self) -> bool:
        """Whether :meth:`advance` has anything to do: a drive, a task, or a released edge to
        take (and no pause)."""
        if self._drive is not None or self._running is not None or self._pending:
            return True
        return not self.paused and bool(self._edges) and self._edges[0].released

    def snapshot(self) -> VehicleSnapshot:
        """The vehicle's state now (immutable)."""
        agent = self.agent
        pose = agent.get_pose()
        yaw = pose.yaw
        v = agent.velocity
        c, s = math.cos(yaw), math.sin(yaw)
        host = self._host
        stopped = host.safety.is_stopped(agent)  # by its protective field: not driving
        return VehicleSnapshot(
            field_violation=stopped,
            name=self.name,
            step=host.step_count,
            sim_time=host.sim_time,
            x=pose.x,
            y=pose.y,
            theta=yaw,
            vx=float(c * v[0] + s * v[1]),
            vy=float(-s * v[0] + c * v[1]),
            omega=float(agent.angular_velocity),
            driving=bool(agent.is_moving) and not stopped,
            paused=self.paused,
            battery_charge=float(agent.battery_soc) * 100.0,
            charging=bool(agent.is_charging),
            order_id=self.order_id,
            order_update=self.order_update,
            last_node_id=self.last_node_id,
            last_node_sequence=self.last_node_sequence,
            nodes=tuple((n.node_id, n.sequence, n.released) for n in self._nodes),
            edges=tuple((e.edge_id, e.sequence, e.released) for e in self._edges),
            tasks=tuple(
                TaskProgress(t.task_id, t.kind, st, d) for t, st, d in self._tasks.values()
            ),
            loads=loads_of(agent),
            errors=tuple(self.errors),
            distance_since_last_node=self._distance,
            node_positions=tuple((float(n.x or 0.0), float(n.y or 0.0)) for n in self._nodes),
        )

    # ----- commands ---------------------------------------------------------------------------

    def apply(self, command: Command) -> None:
        """Take one command (at a step boundary)."""
        if isinstance(command, Order):
            self._take_order(command)
        elif isinstance(command, InstantTasks):
            for task in command.tasks:
                self._instant(task)
        elif isinstance(command, Rejection):
            self._error(command.kind, command.description, command.references)
        else:  # pragma: no cover - the fleet interface only queues the three
            raise TypeError(f"Vehicle.apply: not a command: {command!r}")

    def _error(
        self, kind: str, description: str, references: tuple[tuple[str, str], ...] = ()
    ) -> None:
        self.errors.append(VehicleError(kind, description, False, references))
        logger.info("%s: %s error: %s", self.name, kind, description)
        self._notify("error")

    def _take_order(self, order: Order) -> None:
        problem = check_order(order, self.agent.motion_mode is MotionMode.DIFFERENTIAL)
        if problem is not None:
            self._error(problem.kind, problem.description, problem.references)
            return
        if order.order_id == self.order_id:
            self._update_order(order)
        elif self.has_order:
            self._refuse_busy(order)
        else:
            self._start_order(order)

    def _refuse(self, kind: str, order: Order, message: str) -> None:
        refs = (("order_id", order.order_id), ("order_update", str(order.update)))
        self._error(kind, f"order {order.order_id!r} update {order.update}: {message}", refs)

    def _start_order(self, order: Order) -> None:
        first = order.nodes[0]
        limit = first.deviation_xy if first.deviation_xy else self._default_deviation
        x, y = self._xy()
        assert first.x is not None
        assert first.y is not None
        away = math.hypot(first.x - x, first.y - y)
        if away > limit:
            self._refuse(
                "order",
                order,
                f"its first node {first.node_id!r} is {away:.3f} m from the vehicle "
                f"(allowed {limit:g} m): a new order must start where the vehicle is",
            )
            return
        self._accept(order)
        self._reach(first)

    def _refuse_busy(self, order: Order) -> None:
        self._refuse(
            "order",
            order,
            f"the vehicle is still on order {self.order_id!r} (nodes or tasks left): update "
            "that order, or cancel it first",
        )

    def _update_order(self, order: Order) -> None:
        if order.update < self.order_update:
            self._refuse(
                "order_update",
                order,
                f"is older than the update {self.order_update} being run",
            )
            return
        if order.update == self.order_update:
            logger.info("%s: order %r update %d received again: ignored", self.name,
                        order.order_id, order.update)  # fmt: skip
            return
        end = self._base_end()
        first = order.nodes[0]
        if end is None or (first.node_id, first.sequence) != end:
            self._refuse(
                "order_update",
                order,
                f"must start at the last released node {end!r}, not "
                f"({first.node_id!r}, {first.sequence})",
            )
            return
        self._append(order)

    def _base_end(self) -> tuple[str, int] | None:
        """(node id, sequence) of the last released node of the current order."""
        released = [n for n in self._nodes if n.released]
        if released:
            return released[-1].node_id, released[-1].sequence
        if self.order_id:
            return self.last_node_id, self.last_node_sequence
        return None

    def _drop_horizon(self) -> None:
        self._nodes = deque(n for n in self._nodes if n.released)
        self._edges = deque(e for e in self._edges if e.released)

    def _accept(self, order: Order, keep_tasks: bool = False) -> None:
        self.order_id, self.order_update = order.order_id, order.update
        self.errors = [e for e in self.errors if e.kind not in _ORDER_ERRORS]
        if not keep_tasks:
            self._tasks = {}
        owners: list[Node | Edge] = [*order.nodes, *order.edges]
        for item in owners:
            for task in item.tasks:
                if task.task_id not in self._tasks:
                    self._tasks[task.task_id] = [task, TaskStatus.WAITING, ""]
        self._nodes = deque(order.nodes)
        self._edges = deque(order.edges)
        self._notify("order_accepted")

    def _append(self, order: Order) -> None:
        """Take an update: the old horizon goes, the new route follows the stitching node (the
        old base's last node, reached or not, whose tasks stay those first sent)."""
        self._drop_horizon()
        base_nodes, base_edges = list(self._nodes), list(self._edges)
        self._accept(order, keep_tasks=True)
        self._nodes = deque([*base_nodes, *order.nodes[1:]])
        self._edges = deque([*base_edges, *order.edges])

    # ----- instant tasks ---------------------------------------------------------------------

    def _instant(self, task: Task) -> None:
        self._tasks[task.task_id] = [task, TaskStatus.RUNNING, ""]
        handler = getattr(self, f"_do_{task.kind}", None)
        if task.kind not in INSTANT_TASKS or handler is None:
            self._finish(task, False, f"{task.kind!r} is not an instant task this vehicle runs")
            self._error(
                "order",
                f"instant task {task.task_id!r}: kind {task.kind!r} is not supported "
                f"(supported: {', '.join(sorted(INSTANT_TASKS))})",
                (("task_id", task.task_id), ("task_kind", task.kind)),
            )
            return
        problem = handler(task)
        self._finish(task, problem is None, problem or "")

    def _finish(self, task: Task, ok: bool, description: str = "") -> None:
        self._tasks[task.task_id] = [task, TaskStatus.FINISHED if ok else TaskStatus.FAILED,
                                     description]  # fmt: skip
        self._notify("task_state")

    def _do_cancel_order(self, task: Task) -> str | None:
        if not self.has_order:
            self._error(
                "no_order_to_cancel",
                f"cancel {task.task_id!r}: there is no order to cancel",
                (("task_id", task.task_id),),
            )
            return "no order to cancel"
        self.agent.stop()
        self._drive = None
        if self._running is not None:
            running, action = self._running
            action.cancel()
            self._set(running, TaskStatus.FAILED, "cancelled by cancel_order")
            self._running = None
        for waiting in [t for t, st, _ in self._tasks.values() if st is TaskStatus.WAITING]:
            self._set(waiting, TaskStatus.FAILED, "cancelled by cancel_order")
        self._pending.clear()
        self._nodes.clear()
        self._edges.clear()
        self._notify("order_cancelled")
        return None

    def _do_start_pause(self, task: Task) -> str | None:
        if not self.paused:
            self.paused = True
            if self._drive is not None:
                self.agent.stop()
            self._notify("paused")
        return None

    def _do_stop_pause(self, task: Task) -> str | None:
        if self.paused:
            self.paused = False
            if self._drive is not None:
                self._drive.resume(self.agent, self._host)
            self._notify("resumed")
        return None

    def _do_state_request(self, task: Task) -> str | None:
        self._notify("state_request")
        return None

    def _do_factsheet_request(self, task: Task) -> str | None:
        self.factsheet_requested = True
        self._notify("factsheet_request")
        return None

    def _do_init_position(self, task: Task) -> str | None:
        if self.has_order:
            return "the vehicle is on an order: cancel it first"
        p = task.params
        try:
            x, y, theta = float(p["x"]), float(p["y"]), float(p["theta"])
        except (KeyError, TypeError, ValueError):
            return f"needs numbers x, y and theta, got {dict(p)!r}"
        if not all(math.isfinite(v) for v in (x, y, theta)):
            return f"x, y and theta must be finite, got {dict(p)!r}"
        z = self.agent.get_pose().z
        self.agent.set_pose(Pose.from_yaw(x, y, z, theta))
        self._last_xy = (x, y)
        self.last_node_id = str(p.get("last_node_id", ""))
        self.last_node_sequence = 0
        if p.get("map_id"):
            self.map_id = str(p["map_id"])
        self._notify("position_initialized")
        return None

    def _do_start_charging(self, task: Task) -> str | None:
        return self._charging(True)

    def _do_stop_charging(self, task: Task) -> str | None:
        return self._charging(False)

    def _charging(self, on: bool) -> str | None:
        if self.agent.battery_plugin is None:
            return "the vehicle has no battery (add a BatteryPlugin)"
        if self.agent.is_charging != on:
            self.agent.set_charging(on)
            self._notify("charging")
        return None

    # ----- progress ---------------------------------------------------------------------------

    def advance(self) -> None:
        """Follow up on what the vehicle is doing (at a step boundary)."""
        if not self.busy:
            return
        if self._drive is not None:
            x, y = self._xy()
            self._distance += math.hypot(x - self._last_xy[0], y - self._last_xy[1])
            self._last_xy = (x, y)
        if self._running is not None and not self._check_running():
            return
        if self._drive is not None:
            for node in self._drive.reached(self.agent):
                self._reach(node)
            if not self._drive.done:
                return
            self._drive = None
            self._host.fleet.cap_speed(self.agent, None)
        if self.paused:
            return
        self._next()

    def _next(self) -> None:
        """Start the next thing: a pending task, else the next released edge."""
        while self._running is None and self._pending:
            self._start_task(self._pending.popleft())
        if self._running is not None or not self._edges or not self._edges[0].released:
            return
        if self._drive is None and self._edges[0].tasks and not self._edge_tasks_started():
            self._pending.extend(self._edges[0].tasks)
            self._next()
            return
        drive = plan_drive(self._edges, self._nodes, self.agent)
        self._drive = drive
        self._last_xy = self._xy()
        drive.start(self.agent, self._host)
        self._notify("driving")

    def _edge_tasks_started(self) -> bool:
        first = self._edges[0].tasks[0].task_id
        return self._tasks[first][1] is not TaskStatus.WAITING

    def _reach(self, node: Node) -> None:
        """``node`` is reached: it and the edge before it are done; its tasks are next."""
        if self._nodes and self._nodes[0].sequence == node.sequence:
            self._nodes.popleft()
        if self._edges and self._edges[0].sequence < node.sequence:
            self._edges.popleft()
        self.last_node_id, self.last_node_sequence = node.node_id, node.sequence
        self.map_id = node.map_id or self.map_id
        self._distance = 0.0
        self._pending.extend(node.tasks)
        self._notify("node_reached")

    def _start_task(self, task: Task) -> None:
        if task.kind in ("start_charging", "stop_charging"):
            problem = self._charging(task.kind == "start_charging")
            self._set(task, TaskStatus.FINISHED if problem is None else TaskStatus.FAILED,
                      problem or "")  # fmt: skip
            return
        action = load_action(task, self.agent, self._host.objects, self._rest_heights)
        if isinstance(action, str):
            self._set(task, TaskStatus.FAILED, action)
            return
        self.agent.add_action(action)
        self._running = (task, action)
        self._set(task, TaskStatus.RUNNING)

    def _check_running(self) -> bool:
        """Whether the running task has ended (its state updated)."""
        assert self._running is not None
        task, action = self._running
        if not action.is_complete():
            return False
        self._running = None
        if action.status is ActionStatus.COMPLETED:
            self._set(task, TaskStatus.FINISHED)
            self._notify("load_changed")
        else:
            self._set(task, TaskStatus.FAILED, action.error_message or action.status.value)
        return True

    def _set(self, task: Task, status: TaskStatus, description: str = "") -> None:
        self._tasks[task.task_id] = [task, status, description]
        self._notify("task_state")

    def _xy(self) -> tuple[float, float]:
        pose = self.agent.get_pose()
        return pose.x, pose.y
