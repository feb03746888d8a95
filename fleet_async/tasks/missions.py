"""Missions: coroutines the kernel runs, their handles, and the dispatch loop.

A :class:`Mission` is both the running coroutine and its handle: ``await mission`` (or
``await mission.join()``) waits for it and returns its result, ``mission.cancel()`` cancels it,
``mission.interrupt(cause)`` raises :class:`~fleet_async.tasks.errors.Interrupt` inside it at
its current await. It is also a :class:`~fleet_async.tasks.kernel.SimEvent`, so it composes
with ``sim.any_of`` / ``sim.all_of``.
"""

from __future__ import annotations

import copy
import heapq
import inspect
import logging
import sys
import time
import types
from collections.abc import Awaitable, Callable, Generator
from typing import TYPE_CHECKING, Any

from fleet_async.tasks.errors import Cancelled, Interrupt, MissionCancelledError
from fleet_async.tasks.kernel import PARKED, PENDING, URGENT, EventRun, Kernel, SimEvent
from fleet_async.tasks.scopes import CancelScope, Delivery

if TYPE_CHECKING:
    from fleet_async.tasks.groups import Nursery

__all__ = ["Mission", "dispatch", "start_mission"]

logger = logging.getLogger(__name__)


class Mission(SimEvent):
    """One mission: a coroutine run by the kernel, and the handle to it.

    Attributes:
        name: For messages and traces.
        key: Its place in the spawn tree: the run's first mission is ``(0,)``, the n-th
            mission it starts ``(0, n)``, and so on (seeds ``sim.mission_rng()``).
    """

    __slots__ = (
        "_children",
        "_coro",
        "_kept",
        "_nursery",
        "_owned",
        "_root_scope",
        "cancelled",
        "key",
        "name",
        "scope",
        "target",
    )

    def __init__(
        self, kernel: Kernel, coro: Any, name: str, key: tuple[int, ...], nursery: Nursery
    ) -> None:
        super().__init__(kernel)
        self._coro = coro
        self.name = name
        self.key = key
        self._nursery = nursery
        self._children = 0
        self._owned: dict[Any, None] | None = None  # ActionWaits of its unfinished actions
        self._kept: list[Any] | None = None  # requests it was interrupted from
        self.cancelled = False
        """Whether it ended by cancellation."""
        self.target: SimEvent | None = None
        """The event it is parked on (None while it runs or once it ended)."""
        self._root_scope = CancelScope(kernel, owner=self, parent=nursery.cancel_scope, root=True)
        self.scope = self._root_scope
        """Its innermost cancel scope (its own root scope while it is in no other)."""

    fails_run_unhandled = False  # a mission's failure reaches its group (or the run) itself

    def __repr__(self) -> str:
        state = "alive" if self.raw_value is PENDING else "ended"
        return f"<Mission {self.name!r} {state}>"

    # ----- what it leaves behind ------------------------------------------------------------

    def own(self, wait: Any) -> None:
        """An action it queued (an ActionWait): cancelled if unfinished when it ends (see
        :meth:`disown`)."""
        owned = self._owned
        if owned is None:
            self._owned = {wait: None}
        else:
            owned[wait] = None

    def disown(self, wait: Any) -> None:
        """An action it queued has ended: forget it at once, so that the finished action is
        freed now rather than kept until the mission ends (objects that outlive a few
        allocations get promoted by the garbage collector, whose full passes then grow with
        the fleet)."""
        owned = self._owned
        if owned is not None:
            owned.pop(wait, None)

    def keep_request(self, request: Any) -> None:
        """A request it was interrupted from: it stays for the mission to await again, and is
        withdrawn if the mission ends without doing so."""
        if self._kept is None:
            self._kept = []
        if request not in self._kept:
            self._kept.append(request)

    def drop_kept_request(self, request: Any) -> bool:
        """Forget ``request`` as kept; return whether it was."""
        kept = self._kept
        if kept and request in kept:
            kept.remove(request)
            return True
        return False

    def _leave_behind(self) -> None:
        """It ended: cancel its unfinished actions, withdraw the requests it left."""
        owned, self._owned = self._owned, None
        if owned:
            for wait in owned:
                wait.drop_owned()
        kept, self._kept = self._kept, None
        if kept:
            for request in kept:
                request.withdraw()

    # ----- the handle ---------------------------------------------------------------------

    @property
    def is_alive(self) -> bool:
        """Whether it has not ended yet."""
        return self.raw_value is PENDING

    def result(self) -> Any:
        """What it returned.

        Raises:
            RuntimeError: if it is still running.
            MissionCancelledError: if it was cancelled.
            BaseException: the exception it ended with.
        """
        if self.raw_value is PENDING:
            raise RuntimeError(f"mission {self.name!r} is still running")
        if not self.ok:
            raise self.raw_value
        return self.raw_value

    def join(self) -> Mission:
        """``await mission.join()`` waits until it ends and returns its result (as
        ``await mission``)."""
        return self

    def cancel(self) -> None:
        """Cancel it: it raises Cancelled at its current (or next) sim await, its awaited action
        is cancelled, and it ends unless it catches the cancellation in a shielded scope."""
        if self.raw_value is PENDING:
            self._root_scope.cancel()

    def interrupt(self, cause: Any = None) -> None:
        """Raise ``Interrupt(cause)`` inside it at its current await (an URGENT event at the
        current step); an awaited action is cancelled first. It may catch it and go on.

        Raises:
            RuntimeError: if it has ended, or if a mission interrupts itself.
        """
        if self.raw_value is not PENDING:
            raise RuntimeError(f"mission {self.name!r} has ended and cannot be interrupted")
        if self is self.kernel.current:
            raise RuntimeError(f"mission {self.name!r} cannot interrupt itself")
        self.kernel.schedule(Delivery(self.kernel, self, Interrupt(cause)), URGENT)

    def _stray_scope_error(self, outcome: Any) -> RuntimeError:
        """The mission ended inside a cancel scope it never left (an async generator left
        suspended inside ``with sim.move_on_after(...)``): leave them, and say so."""
        scope: CancelScope | None = self.scope
        while scope is not None and scope is not self._root_scope:
            scope.detach()
            scope = scope.parent
        self.scope = self._root_scope
        error = RuntimeError(
            f"mission {self.name!r} ended inside a cancel scope it entered and never left: an "
            "async generator suspended inside 'with sim.move_on_after(...)' (or another sim "
            "scope)? Close the generator ('await agen.aclose()') before leaving it"
        )
        if isinstance(outcome, BaseException):
            error.__context__ = outcome
        return error

    def close(self) -> None:
        """End it without resuming it (the run stops): its ``finally`` blocks run, without
        sim awaits. Counts as cancelled."""
        if self.raw_value is not PENDING:
            return
        target = self.target
        if target is not None and target.callbacks is not None and self in target.callbacks:
            target.callbacks.remove(self)
            if target.abandon is not None:
                target.abandon(self, True)
        try:
            self._coro.close()
        except BaseException:  # a finally block that awaits cannot run any more
            logger.exception("mission %r failed to clean up while the run stopped", self.name)
        kernel = self.kernel
        kernel.missions.pop(self, None)
        self.target = None
        self._root_scope.detach()
        self._leave_behind()
        self.cancelled = True
        self.ok = False
        self.raw_value = MissionCancelledError(f"mission {self.name!r} was stopped with the run")
        self._nursery.child_done(self, None)

    def child_key(self) -> tuple[int, ...]:
        """The key of the next mission this one starts."""
        self._children += 1
        return (*self.key, self._children)

    # ----- running --------------------------------------------------------------------------

    def step(self, throw: bool, value: Any) -> Any:
        """Run the coroutine until it parks on a sim event or ends (then PARKED), or until it
        awaits something else, which is returned for the host loop to serve."""
        kernel = self.kernel
        kernel.current = self
        kernel.resumes += 1
        self.target = None
        coro = self._coro
        swallowed = 0
        while True:
            try:
                request = coro.throw(value) if throw else coro.send(value)
            except StopIteration as stop:
                self._end(True, stop.value)
                return PARKED
            except BaseException as exc:
                if kernel.is_host_cancel(exc):
                    self._end(False, exc, quietly=True)
                    raise  # the host cancelled the run; not this mission's failure
                self._end(False, exc)
                return PARKED
            if not isinstance(request, SimEvent):
                kernel.current = None
                return request
            if request.kernel is not kernel:
                throw, value = True, RuntimeError(f"{request!r} belongs to another run")
                continue
            if self._kept is not None:
                self.drop_kept_request(request)  # awaited again: it is the mission's once more
            if kernel.cancelled_open and not request.uncancellable and self.scope.cancelled():
                if request.abandon is not None:  # it never waits: undo what the wait set up
                    request.abandon(self, True)
                swallowed += 1
                if swallowed > _SWALLOW_LIMIT:
                    self._end(False, self._swallow_error())
                    return PARKED
                throw, value = True, kernel.cancelled_exc()
                continue
            callbacks = request.callbacks
            if callbacks is None:  # processed already: its value is ready
                throw, value = not request.ok, request.raw_value
                if throw and not request.per_waiter:
                    value = waiter_copy(value)
                continue
            callbacks.append(self)
            self.target = request
            kernel.current = None
            return PARKED

    def _swallow_error(self) -> RuntimeError:
        """It caught its cancellation and awaited sim time again, over and over, at once: it
        would keep the run busy forever. End it (its ``finally`` blocks run) and say so."""
        try:
            self._coro.close()
        except BaseException:  # it ignored even GeneratorExit: its frames are gone anyway
            logger.exception("mission %r did not close cleanly", self.name)
        return RuntimeError(
            f"mission {self.name!r} caught its cancellation and awaited sim time again "
            f"{_SWALLOW_LIMIT} times in a row: a mission must let Cancelled propagate (clean "
            "up in 'finally', or await in 'with sim.cancel_scope(shield=True)'); it was ended"
        )

    def _end(self, ok: bool, value: Any, quietly: bool = False) -> None:
        kernel = self.kernel
        kernel.current = None
        del kernel.missions[self]
        self.target = None
        if self._owned is not None or self._kept is not None:
            self._leave_behind()
        if self.scope is not self._root_scope and not quietly:
            ok, value = False, self._stray_scope_error(value)
        self._root_scope.detach()
        if quietly:
            self.ok, self.raw_value = False, value
            return
        error: BaseException | None = None
        if ok:
            self.ok, self.raw_value = True, value
        elif isinstance(value, Cancelled):
            self.cancelled = True
            self.ok = False
            self.raw_value = MissionCancelledError(f"mission {self.name!r} was cancelled")
        else:
            error = value
            notes = getattr(value, "__notes__", ())
            if sys.version_info >= (3, 11) and not any(n.startswith("in mission ") for n in notes):
                value.add_note(
                    f"in mission {self.name!r} at sim time {kernel.now * kernel.timestep:.3f} s"
                )
            self.ok, self.raw_value = False, value
            if kernel.on_failure is not None:
                kernel.on_failure(self, value)
        kernel.schedule(self)  # whoever joins it resumes
        self._nursery.child_done(self, error)


_SWALLOW_LIMIT = 1000
"""Cancellations a mission may catch in a row, awaiting again at once each time, before it
is ended as one that would never stop."""


def waiter_copy(error: BaseException) -> BaseException:
    """The failure one waiter of a shared failed event raises: a copy chained to the original
    (SimPy's rule), so that waiters' tracebacks do not mix; the original if it cannot be
    copied."""
    try:
        twin = copy.copy(error)
    except Exception:  # an exception type whose arguments do not rebuild it
        return error
    if type(twin) is not type(error) or twin is error:
        return error
    twin.__cause__ = error
    return twin


def start_mission(
    kernel: Kernel,
    fn: Callable[..., Awaitable[Any]] | Awaitable[Any],
    args: tuple[Any, ...],
    name: str | None,
    key: tuple[int, ...],
    nursery: Nursery,
) -> Mission:
    """Create a mission that starts at the current step (URGENT, in spawn order).

    Raises:
        TypeError: if ``fn(*args)`` is not a coroutine (or ``fn`` is not an awaitable).
    """
    coro = _as_coroutine(fn, args)
    label = name or getattr(coro, "__qualname__", None) or "mission"
    mission = Mission(kernel, coro, label, key, nursery)
    start = SimEvent(kernel)
    start.callbacks = [mission]
    start.raw_value = None
    mission.target = start
    kernel.missions[mission] = None
    kernel.schedule(start, URGENT)
    return mission


def _as_coroutine(fn: Any, args: tuple[Any, ...]) -> Any:
    if callable(fn) and not inspect.isawaitable(fn):
        made = fn(*args)
        if inspect.iscoroutine(made):
            return made
        if inspect.isawaitable(made):
            return _await(made)
        if inspect.isgenerator(made):
            raise TypeError(
                f"{fn!r} returned a generator: missions are async functions (async def), "
                "not SimPy generators; write 'await sim.timeout(d)' for 'yield env.timeout(d)'"
            )
        raise TypeError(f"a mission must be an async function; {fn!r} returned {made!r}")
    if inspect.isgenerator(fn):
        raise TypeError(
            f"{fn!r} is a generator: missions are async functions (async def), not SimPy "
            "generators; write 'await sim.timeout(d)' for 'yield env.timeout(d)'"
        )
    if args:
        raise TypeError(f"arguments were given, but {fn!r} is not callable")
    if inspect.iscoroutine(fn):
        return fn
    if inspect.isawaitable(fn):
        return _await(fn)
    raise TypeError(f"expected an async function or a coroutine, got {fn!r}")


async def _await(awaitable: Awaitable[Any]) -> Any:
    return await awaitable


@types.coroutine
def dispatch(kernel: Kernel) -> Generator[Any, Any, None]:
    """Process every event due now, in queue order, resuming waiting missions one at a time.

    A generator-based coroutine: a mission's non-sim await is forwarded to the host event loop
    through it (the mission holds the clock meanwhile), and the answer is sent back.

    Raises:
        The host loop's cancellation, when the host cancelled a forwarded await.
    """
    queue = kernel.queue
    heappop = heapq.heappop
    after = kernel.after_event
    run: EventRun | None = None  # a run of events being taken (kernel.EventRun)
    run_entry: Any = None  # and its queue entry
    try:
        while True:
            if run is not None:  # its next event, unless something scheduled since comes first
                if run.next < len(run.events) and not (queue and queue[0] < run_entry):
                    event = run.events[run.next]
                    run.next += 1
                else:
                    if run.next < len(run.events):
                        heapq.heappush(queue, run_entry)  # the rest waits its turn
                    run = None
                    continue
            elif queue and queue[0][0] <= kernel.now:
                entry = heappop(queue)
                event = entry[3]
                if event.__class__ is EventRun:
                    run, run_entry = event, entry
                    continue
            else:
                return
            callbacks = event.callbacks
            if callbacks is None:  # a disarmed timer
                kernel.dead -= 1
                continue
            event.callbacks = None
            if not callbacks:
                unhandled = not event.ok and event.fails_run_unhandled and not event.defused
                if unhandled and kernel.on_unhandled is not None:
                    kernel.on_unhandled(event)
                continue
            for callback in callbacks:
                if callback.__class__ is not Mission:
                    callback(event)
                    continue
                guard = event.guard
                if guard is not None and not guard(callback):
                    continue
                value = event.raw_value
                if not event.ok and not event.per_waiter:
                    value = waiter_copy(value)
                answer = callback.step(not event.ok, value)
                while answer is not PARKED:  # a non-sim await: the host loop serves it
                    answer = yield from _forward(kernel, callback, answer)
            if after is not None:
                after()
    finally:  # stopped mid-run (the host cancelled a forwarded await): the rest stays queued
        if run is not None and run.next < len(run.events):
            heapq.heappush(queue, run_entry)


@types.coroutine
def _forward(kernel: Kernel, mission: Mission, request: Any) -> Generator[Any, Any, Any]:
    kernel.holding = mission
    kernel.holding_what = request
    kernel.holding_since = time.perf_counter()
    try:
        reply = yield request
    except BaseException as exc:
        kernel.holding = None
        return mission.step(True, exc)
    kernel.holding = None
    return mission.step(False, reply)
