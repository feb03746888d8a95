"""The mission kernel: a discrete-event scheduler that drives mission coroutines itself.

Every resumption of a mission is an event in one queue, ordered by
``(step, class, sequence)``: the step it is due at, its class (URGENT: a mission's start, an
interrupt, a cancel delivery; STEP: an action that ended during the step that ends at this
step, in agent order; NORMAL: everything else) and a sequence number taken when the event was
scheduled. The kernel pops events in that order and resumes their waiting missions one at a
time, each until it parks again, so the order is the same on every anyio backend and in every
run: the event loop never decides who runs next.

A mission is a coroutine that the kernel steps with ``send`` / ``throw`` (as SimPy steps its
generators). When it awaits a :class:`SimEvent` it yields the event to the kernel and parks.
When it awaits anything else (real I/O, ``anyio.sleep``), the kernel forwards that yield to the
host event loop and sends the answer back: the mission holds the clock meanwhile, and no other
mission runs (``fleet_async.tasks.missions.dispatch``).
"""

from __future__ import annotations

import collections.abc
import heapq
import itertools
import threading
from collections.abc import Callable, Generator
from typing import TYPE_CHECKING, Any, NoReturn

from fleet_async.tasks.errors import Cancelled, NoMissionRuntimeError

if TYPE_CHECKING:
    from fleet_async.tasks.missions import Mission

__all__ = [
    "NORMAL",
    "PENDING",
    "STEP",
    "URGENT",
    "EventRun",
    "Kernel",
    "SimEvent",
    "Timeout",
    "kernel_of",
]

URGENT = 0
"""Class of a mission's start, an interrupt and a cancel delivery (SimPy's URGENT)."""
STEP = 1
"""Class of an action outcome: the action ended during the step that ends at this step."""
NORMAL = 2
"""Class of everything else: timers, event triggers, grants, joins."""

PENDING: Any = object()
"""The value of an event that has not been triggered."""

PARKED: Any = object()
"""What stepping a mission returns when it parked on a sim event or finished."""


class SimEvent:
    """Something a mission can await in sim time, SimPy style.

    An event is *pending*, then *triggered* (``succeed`` / ``fail`` schedule it, with a value),
    then *processed* (the kernel popped it and resumed whoever waited). ``await event`` returns
    its value or raises its exception; awaiting an event that was already processed returns at
    once, awaiting one that is merely triggered waits until the kernel processes it (as SimPy's
    ``yield event`` does). ``a | b`` and ``a & b`` wait for either or both.

    The kernel's protocol, for the mission layer's own event types: ``kernel``, ``callbacks``
    (None once processed; missions and plain callables), ``ok`` and ``raw_value`` (PENDING
    until triggered), and three hooks, ``guard``, ``uncancellable`` and ``abandon``.
    """

    __slots__ = ("_defused", "callbacks", "kernel", "ok", "raw_value")

    fails_run_unhandled = True
    """A failure of this event that nobody waits on fails the run unless it is defused
    (SimPy's rule); False for events whose failures are reported another way (missions)."""
    per_waiter = False
    """The failure is made for one waiter (an interrupt, a cancellation): thrown as is. Other
    failures are thrown as a copy per waiter, chained to the original."""
    guard: Callable[[Mission], bool] | None = None
    """Checked before the kernel resumes a mission from this event (deliveries only)."""
    uncancellable = False
    """A park on this event is not ended by cancellation (a task group's join)."""
    abandon: Callable[[Mission, bool], None] | None = None
    """Called as ``abandon(mission, cancelled)`` when a mission stops waiting on this event
    because it was cancelled (``cancelled`` True) or interrupted (False), after it left
    ``callbacks``: undo what the wait set up (a cancellation withdraws a request; an interrupt
    leaves it queued, as SimPy does, for the mission to await again)."""

    def __init__(self, kernel: Kernel) -> None:
        self.kernel = kernel
        self.callbacks: list[Any] | None = []
        self.raw_value: Any = PENDING
        self.ok = True
        """Whether the event succeeded (meaningful once triggered)."""

    @property
    def defused(self) -> bool:
        """Whether a failure of this event nobody waits on is accepted (does not fail the
        run). Set it to True to let an event fail unobserved."""
        return bool(getattr(self, "_defused", False))

    @defused.setter
    def defused(self, value: bool) -> None:
        self._defused = bool(value)

    @property
    def triggered(self) -> bool:
        """Whether the event has a value (it may not be processed yet)."""
        return self.raw_value is not PENDING

    @property
    def processed(self) -> bool:
        """Whether the kernel has processed the event (its waiters were resumed)."""
        return self.callbacks is None

    @property
    def value(self) -> Any:
        """The event's value (its exception, if it failed).

        Raises:
            AttributeError: if the event has not been triggered yet.
        """
        if self.raw_value is PENDING:
            raise AttributeError(f"{self!r} has no value yet (it has not been triggered)")
        return self.raw_value

    def succeed(self, value: Any = None) -> SimEvent:
        """Trigger the event with ``value``; its waiters resume when the kernel gets to it.

        Raises:
            RuntimeError: if it was triggered already.
        """
        if self.raw_value is not PENDING:
            raise RuntimeError(f"{self!r} has already been triggered")
        self.ok = True
        self.raw_value = value
        self.kernel.schedule(self)
        return self

    def fail(self, exception: BaseException) -> SimEvent:
        """Trigger the event with an exception, which its waiters raise.

        Raises:
            TypeError: if ``exception`` is not an exception.
            RuntimeError: if it was triggered already.
        """
        if not isinstance(exception, BaseException):
            raise TypeError(f"fail() expects an exception, got {exception!r}")
        if self.raw_value is not PENDING:
            raise RuntimeError(f"{self!r} has already been triggered")
        self.ok = False
        self.raw_value = exception
        self.kernel.schedule(self)
        return self

    def trigger(self, event: SimEvent) -> None:
        """Trigger with the outcome of another event (a callback for chaining events)."""
        self.ok = event.ok
        self.raw_value = event.raw_value
        self.kernel.schedule(self)

    def rebind(self, kernel: Kernel) -> bool:
        """Join ``kernel``'s run if this event may (an Event made before the run); return
        whether it belongs to ``kernel`` now."""
        return self.kernel is kernel

    def __await__(self) -> Generator[Any, Any, Any]:
        kernel = self.kernel
        if kernel.current is None or _thread() != kernel.thread:
            raise kernel.outside_error("awaiting a sim event")
        return (yield self)

    # A host event loop that is handed a sim event as a task (anyio's start_soon(sim.sleep,
    # 1) in a task group of anyio's, asyncio.create_task(sim.sleep(1))) steps it as a
    # coroutine: say what happened instead of failing somewhere inside that library.
    def send(self, value: Any) -> NoReturn:
        """Refuse to run as a task of the host event loop (see the class doc)."""
        raise NoMissionRuntimeError(_host_task_message(self))

    def throw(self, *args: Any) -> NoReturn:
        """Refuse to run as a task of the host event loop (see the class doc)."""
        raise NoMissionRuntimeError(_host_task_message(self))

    def __and__(self, other: SimEvent) -> SimEvent:
        from fleet_async.tasks.conditions import AllOf  # conditions build on events

        return AllOf(self.kernel, (self, other))

    def __or__(self, other: SimEvent) -> SimEvent:
        from fleet_async.tasks.conditions import AnyOf  # conditions build on events

        return AnyOf(self.kernel, (self, other))

    def __repr__(self) -> str:
        state = "processed" if self.callbacks is None else "pending"
        if self.callbacks is not None and self.raw_value is not PENDING:
            state = "triggered"
        return f"<{type(self).__name__} {state}>"


class Timeout(SimEvent):
    """An event that succeeds ``steps`` steps from now (scheduled when created, like SimPy's
    ``env.timeout``: its sequence number is taken at the call)."""

    __slots__ = ("due_step",)

    def __init__(self, kernel: Kernel, steps: int, value: Any = None) -> None:
        self.kernel = kernel
        self.callbacks = []
        self.raw_value = value
        self.ok = True
        self.due_step = kernel.now + kernel.in_step + steps
        kernel.seq += 1
        heapq.heappush(kernel.queue, (self.due_step, NORMAL, kernel.seq, self))


class EventRun:
    """Events that share a class and a step, in their order, as one queue entry: what one
    simulation step caused (the STEP class; ``Kernel.schedule_run``). The dispatch loop takes
    them one at a time and, when something it scheduled meanwhile comes first, puts the rest
    back under the same key: the order is exactly that of one entry per event, without a heap
    push and pop for each."""

    __slots__ = ("callbacks", "events", "next")

    def __init__(self, events: list[SimEvent]) -> None:
        self.events = events
        self.next = 0
        """Index of the first event not taken yet."""
        self.callbacks = events  # never None: the entry is live (``Kernel.drop_due``)


class Kernel:
    """The event queue, the clock it reads, and the mission being run.

    Args:
        now: The step the kernel starts at (the simulation's step count).
        timestep: Sim seconds per step.
        what_is_outside: How the message of a misuse error names the right way in.
    """

    def __init__(
        self,
        now: int = 0,
        timestep: float = 1.0,
        what_is_outside: str = "fleet_async.run(sim, main)",
    ) -> None:
        self.now = now
        self.timestep = timestep
        self.thread = threading.get_ident()
        """The thread the run drives missions on; sim awaits from any other are errors."""
        """Sim seconds per step."""
        """The current step (the clock); only the driver advances it."""
        self.queue: list[tuple[int, int, int, SimEvent]] = []
        self.seq = 0
        self.current: Mission | None = None
        """The mission being run now (None between missions and while one holds the clock
        on a non-sim await)."""
        self.holding: Mission | None = None
        """The mission holding the clock on a non-sim await, if any."""
        self.holding_since = 0.0
        """Wall time (perf_counter) at which ``holding`` started its non-sim await."""
        self.holding_what: Any = None
        """What ``holding`` awaits (the object forwarded to the host loop)."""
        self.resumes = 0
        """Resumptions of missions so far (the watchdog thread tells a mission that runs on
        from one that was resumed again)."""
        self.on_unhandled: Callable[[SimEvent], None] | None = None
        """Told about a failed event that nobody waited on and nobody defused."""
        self.after_event: Callable[[], None] | None = None
        """Called after each processed event (invariant checks in tests; None in runs)."""
        self.in_step = 0
        """1 while the simulation runs a step (events it triggers are due at the step's end),
        else 0."""
        self.cancelled_open = 0
        """Cancel scopes that are cancelled and not yet exited (0: skip the level check)."""
        self.missions: dict[Mission, None] = {}
        """Missions alive, in start order."""
        self.on_failure: Callable[[Mission, BaseException], None] | None = None
        """Told about every mission that ends with an exception (not a cancellation)."""
        self.is_host_cancel: Callable[[BaseException], bool] = _never
        """Whether an exception out of a mission is the host loop cancelling the run (which
        ends the run, not just the mission); the driver installs its own test."""
        self.dead = 0
        """Queue entries that will resume nobody (timers of scopes that were left)."""
        self._what_is_outside = what_is_outside
        self._mission_ids = itertools.count()

    @property
    def alive(self) -> int:
        """How many missions are alive."""
        return len(self.missions)

    # ----- scheduling ---------------------------------------------------------------------

    def schedule(self, event: SimEvent, cls: int = NORMAL, delay: int = 0) -> None:
        """Put ``event`` in the queue ``delay`` steps from now, with class ``cls``. During a
        step, "now" is the step's end: what the step causes happens when it ends."""
        self.seq += 1
        heapq.heappush(self.queue, (self.now + self.in_step + delay, cls, self.seq, event))

    def schedule_run(self, events: list[SimEvent], cls: int) -> None:
        """Put ``events`` in the queue now, with class ``cls``, in this order, as if each
        were scheduled in turn (see :class:`EventRun`)."""
        self.seq += 1
        run: Any = EventRun(events)  # the dispatch loop tells it from a SimEvent
        heapq.heappush(self.queue, (self.now + self.in_step, cls, self.seq, run))

    def next_step(self) -> int | None:
        """The step of the earliest queued event, or None when the queue is empty."""
        return self.queue[0][0] if self.queue else None

    def due(self) -> bool:
        """Whether an event is due now."""
        return bool(self.queue) and self.queue[0][0] <= self.now

    def steps_to_next(self) -> int | None:
        """Steps until the earliest queued event (None if the queue is empty)."""
        return self.queue[0][0] - self.now if self.queue else None

    def nothing_due(self) -> bool:
        """Whether no queued event will ever resume anything."""
        return len(self.queue) == self.dead

    def disarm(self, timer: SimEvent) -> None:
        """A timer nobody will wait on any more (a scope left before its deadline)."""
        if timer.callbacks is not None and not timer.callbacks:
            timer.callbacks = None  # the dispatch loop skips it and counts it off
            self.dead += 1

    def drop_due(self) -> None:
        """Forget the events due now (``run(until=t)`` does not process those due at t)."""
        kept = []
        for entry in self.queue:
            if entry[0] > self.now:
                kept.append(entry)
            elif entry[3].callbacks is None:
                self.dead -= 1
        heapq.heapify(kept)
        self.queue[:] = kept

    def next_mission_id(self) -> int:
        """A fresh number for a new mission (its place in creation order)."""
        return next(self._mission_ids)

    # ----- running missions ----------------------------------------------------------------

    def require_current(self, what: str) -> Mission:
        """The mission running now.

        Raises:
            NoMissionRuntimeError: outside a mission of this kernel.
        """
        mission = self.current
        if mission is None:
            raise self.outside_error(what)
        return mission

    def outside_error(self, what: str) -> NoMissionRuntimeError:
        """The error for a sim-time await made outside a mission."""
        if _thread() != self.thread:
            return NoMissionRuntimeError(
                f"{what} from another thread than the run's: sim events belong to the thread "
                "that runs fleet_async.run; hand work over with anyio.from_thread.run_sync "
                "(e.g. to set an Event)"
            )
        if self.holding is not None:
            return NoMissionRuntimeError(
                f"{what} was called from outside the missions while mission "
                f"{self.holding.name!r} holds the clock on a non-sim await; a task started "
                "with anyio.create_task_group() inside a mission is a plain task: start "
                "missions with sim.task_group() or sim.spawn() instead"
            )
        return NoMissionRuntimeError(
            f"{what} must be awaited inside a mission started by fleet_async "
            f"({self._what_is_outside}, sim.task_group(), sim.spawn(), sim.gather() or "
            "sim.race())"
        )

    def cancelled_exc(self) -> Cancelled:
        """A fresh cancellation to throw into a mission."""
        return Cancelled(f"cancelled at step {self.now}")


_thread = threading.get_ident


def _host_task_message(event: SimEvent) -> str:
    return (
        f"{event!r} was started as a task of the host event loop (anyio.create_task_group()"
        ".start_soon, asyncio.create_task, a trio nursery): such tasks run outside sim time "
        "and cannot wait on it. Inside missions start missions instead: "
        "'async with sim.task_group() as tg: tg.start_soon(...)', or sim.spawn(...)"
    )


collections.abc.Coroutine.register(SimEvent)  # so that the host loop steps it and hears why


def _never(_: BaseException) -> bool:
    return False


def kernel_of(sim: Any, what: str) -> Kernel:
    """The kernel of ``sim``'s mission runtime (made on first use).

    Raises:
        NoMissionRuntimeError: when called from another thread than the runtime's.
    """
    kernel: Kernel = sim.ensure_mission_runtime().kernel
    if _thread() != kernel.thread:
        raise kernel.outside_error(what)
    return kernel
