"""Task groups of missions (anyio's shape), and gather / race built on them.

``async with sim.task_group() as tg:`` starts missions with ``tg.start_soon(fn, *args)`` (which
returns the :class:`~fleet_async.tasks.missions.Mission` handle) and waits for all of them on
exit. If a mission fails, the group's scope is cancelled (the other missions and the body get
Cancelled) and the exit raises an ExceptionGroup of every failure, as anyio's task groups do.
"""

from __future__ import annotations

import sys
from collections.abc import Awaitable, Callable
from types import TracebackType
from typing import TYPE_CHECKING, Any

from fleet_async.tasks.errors import Cancelled, Interrupt
from fleet_async.tasks.kernel import Kernel, SimEvent
from fleet_async.tasks.missions import start_mission
from fleet_async.tasks.scopes import CancelScope

if sys.version_info < (3, 11):  # pragma: no cover  # anyio brings the backport
    from exceptiongroup import BaseExceptionGroup

if TYPE_CHECKING:
    from fleet_async.tasks.missions import Mission

__all__ = ["Nursery", "TaskGroup", "gather", "lone_error", "race"]


class _Join(SimEvent):
    """What a task group's exit waits on: the last of its missions ending. Cancellation does
    not end this wait (the missions are cancelled instead, and the exit waits for them)."""

    __slots__ = ()
    uncancellable = True


class Nursery:
    """The missions started under one cancel scope: counts them, collects their failures,
    and cancels the scope at the first one.

    Args:
        kernel: The run's kernel.
        scope: The scope the missions' root scopes hang under.
        owner: The mission that owns the group (None for the run's root).
    """

    def __init__(self, kernel: Kernel, scope: CancelScope, owner: Mission | None) -> None:
        self.kernel = kernel
        self.cancel_scope = scope
        self._owner = owner
        self._keys = 0
        self.live = 0
        self.errors: list[BaseException] = []
        self.closed = False
        self._join: _Join | None = None

    def start(
        self,
        fn: Callable[..., Awaitable[Any]] | Awaitable[Any],
        args: tuple[Any, ...] = (),
        name: str | None = None,
    ) -> Mission:
        """Start a mission in this group at the current step.

        Raises:
            RuntimeError: if the group has closed.
        """
        if self.closed:
            raise RuntimeError("this task group has closed; start missions while it is open")
        if self._owner is not None:
            key = self._owner.child_key()
        else:
            key = (self._keys,)
            self._keys += 1
        if name is None and self._owner is not None:
            fn_name = getattr(fn, "__name__", None) or getattr(fn, "__qualname__", "mission")
            name = f"{self._owner.name}/{fn_name}#{key[-1]}"
        mission = start_mission(self.kernel, fn, args, name, key, self)
        self.live += 1
        return mission

    def child_done(self, mission: Mission, error: BaseException | None) -> None:
        """A mission of this group ended (``error``: what it failed with, or None).

        In a task group a failure cancels the group at once (anyio's rule). In the run's root
        group (``sim.spawn``, SimPy's ``env.process``) it is first offered to whoever joins the
        mission: it fails the run only if nobody awaited the mission when its end came.
        """
        self.live -= 1
        if error is not None:
            if self._owner is None:
                self._fail_unless_joined(mission, error)
            else:
                self.fail(error)
        if self.live == 0 and self._join is not None and not self._join.triggered:
            self._join.succeed()

    def fail(self, error: BaseException) -> None:
        """Record ``error`` and cancel the group's scope (the run's, for the root group)."""
        self.errors.append(error)
        self.cancel_scope.cancel()

    def _fail_unless_joined(self, mission: Mission, error: BaseException) -> None:
        waiters = mission.callbacks  # its end is scheduled: whoever joins it is in this list

        def unless_joined(_: SimEvent) -> None:
            if waiters is not None and len(waiters) == 1:  # nobody but this check
                self.fail(error)

        if waiters is not None:
            waiters.append(unless_joined)

    def joined(self) -> SimEvent:
        """An event that triggers when no mission of the group is left."""
        self._join = _Join(self.kernel)
        if self.live == 0:
            self._join.succeed()
        return self._join


class TaskGroup:
    """A group of missions: ``async with sim.task_group() as tg: tg.start_soon(fn, *args)``."""

    def __init__(self, kernel: Kernel) -> None:
        self.kernel = kernel
        self._nursery: Nursery | None = None
        self._scope = CancelScope(kernel)

    @property
    def cancel_scope(self) -> CancelScope:
        """The group's cancel scope (``tg.cancel_scope.cancel()`` cancels every mission in it
        and the body)."""
        return self._scope

    def start_soon(
        self, fn: Callable[..., Awaitable[Any]], *args: Any, name: str | None = None
    ) -> Mission:
        """Start ``fn(*args)`` as a mission of this group; it runs once the current mission
        parks (URGENT, in the order started). Returns its handle."""
        if self._nursery is None:
            raise RuntimeError("use 'async with sim.task_group() as tg:' before start_soon")
        return self._nursery.start(fn, args, name)

    async def __aenter__(self) -> TaskGroup:
        owner = self.kernel.require_current("sim.task_group")
        self._scope.__enter__()
        self._nursery = Nursery(self.kernel, self._scope, owner)
        return self

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> bool:
        nursery = self._nursery
        assert nursery is not None
        if isinstance(exc, GeneratorExit):  # the run is stopping: its missions are closed
            nursery.closed = True
            self._scope.__exit__(None, None, None)
            return False
        body_error = exc if exc is not None and not isinstance(exc, Cancelled) else None
        if body_error is not None:
            self._scope.cancel()
        interrupted: Interrupt | None = None
        while nursery.live:
            try:
                await nursery.joined()
            except Interrupt as raised:  # interrupted while waiting: stop the missions first
                self._scope.cancel()
                interrupted = interrupted or raised
        nursery.closed = True
        errors = [
            *([body_error] if body_error is not None else []),
            *([interrupted] if interrupted is not None else []),
            *nursery.errors,
        ]
        if errors:  # an interrupt while waiting counts as the body's, as in the body itself
            self._scope.__exit__(None, None, None)
            raise BaseExceptionGroup("errors in a sim task group", errors)
        swallowed = self._scope.__exit__(exc_type, exc, tb)
        owner = self.kernel.current
        if exc is None and owner is not None and owner.scope.cancelled():
            # Leaving the group is a checkpoint: an outer scope was cancelled meanwhile.
            raise self.kernel.cancelled_exc()
        return swallowed


def lone_error(exc: BaseException) -> BaseException:
    """``exc`` without the exception groups that wrap it alone.

    Notes on the groups move to the error (a task group's body that raises fails its
    mission with the group, which gets the "in mission ..." note), except a mission note
    when the error already names the mission it failed in.
    """
    notes: list[str] = []
    while isinstance(exc, BaseExceptionGroup) and len(exc.exceptions) == 1:
        notes += getattr(exc, "__notes__", ())
        exc = exc.exceptions[0]
    if notes and hasattr(exc, "add_note"):
        have = list(getattr(exc, "__notes__", ()))
        named = any(note.startswith("in mission ") for note in have)
        for note in notes:
            if note in have or (named and note.startswith("in mission ")):
                continue
            exc.add_note(note)
            have.append(note)
            named = named or note.startswith("in mission ")
    return exc


def _as_item(item: Any) -> tuple[Callable[..., Awaitable[Any]] | Awaitable[Any], str]:
    name = getattr(item, "__qualname__", None) or getattr(item, "__name__", None)
    if isinstance(item, SimEvent) or callable(item) or hasattr(item, "__await__"):
        return item, name or type(item).__name__
    raise TypeError(f"expected a coroutine, an async function or a sim event, got {item!r}")


async def gather(kernel: Kernel, *items: Any) -> list[Any]:
    """Run missions (async functions, coroutines or sim events) concurrently; results in
    argument order. A lone failure is raised as itself; several as an ExceptionGroup."""
    checked = [_as_item(item) for item in items]
    results: list[Any] = [None] * len(items)

    async def slot(i: int, item: Any) -> None:
        results[i] = await (item() if callable(item) and not isinstance(item, SimEvent) else item)

    try:
        async with TaskGroup(kernel) as tg:
            for i, (item, name) in enumerate(checked):
                tg.start_soon(slot, i, item, name=f"gather[{i}]:{name}")
    except BaseExceptionGroup as group:
        raise lone_error(group) from None
    return results


async def race(kernel: Kernel, *items: Any) -> tuple[int, Any]:
    """Run missions concurrently; return (index, result) of the first to finish and cancel the
    others (and the actions they await). The first to finish is the first whose end the
    kernel processes: at equal sim time, by the event order (an action that ended in the step
    beats a timer due at its end)."""
    if not items:
        raise ValueError("race: expected at least one contender")
    checked = [_as_item(item) for item in items]
    winner: list[tuple[int, Any]] = []

    async def contender(i: int, item: Any, tg: TaskGroup) -> None:
        result = await (item() if callable(item) and not isinstance(item, SimEvent) else item)
        if not winner:
            winner.append((i, result))
            tg.cancel_scope.cancel()

    try:
        async with TaskGroup(kernel) as tg:
            for i, (item, name) in enumerate(checked):
                tg.start_soon(contender, i, item, tg, name=f"race[{i}]:{name}")
    except BaseExceptionGroup as group:
        raise lone_error(group) from None
    if not winner:
        raise RuntimeError("race: every contender was cancelled")
    return winner[0]
