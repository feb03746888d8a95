"""Synchronous publish/subscribe with priorities.

One :class:`EventBus` belongs to the simulation (``sim.events``) and each entity gets its own on
first access (``obj.events``). Handlers run in ascending priority (lower first, as in the
reference API); handlers of equal priority run in the order they were registered, so dispatch
order never depends on object identity or hashing.

Handlers are called with the event's payload as keyword arguments. A handler that takes
``**kwargs`` gets the whole payload; one that names its parameters gets only those it names,
so a handler written to the reference API's payload (``def on_bump(other)``) works although
fleet_async's payloads carry more (``sim``, ``obj_a``, ``obj_b``). A named parameter the
payload lacks is still an error.

A handler that raises propagates its exception to whoever emitted the event, unless the bus was
created with ``on_error="log"``. Errors are never swallowed silently.
"""

from __future__ import annotations

import inspect
import logging
from collections.abc import Callable
from typing import Any

__all__ = ["EventBus", "SimEvents"]

logger = logging.getLogger(__name__)

Handler = Callable[..., Any]


class SimEvents:
    """Names of the events the simulator emits, with the payload keys each carries."""

    PRE_STEP = "pre_step"
    """Start of ``step_once``; payload ``sim``, ``step`` (the step about to run), ``dt``,
    ``sim_time``."""
    POST_STEP = "post_step"
    """End of ``step_once``, after the clock advanced; same payload as PRE_STEP (``step`` and
    ``sim_time`` are the new ones)."""
    STEPS_SKIPPED = "steps_skipped"
    """``sim.skip_steps(n)`` advanced the clock over ``n`` empty steps; payload ``sim``,
    ``step`` (the first skipped step), ``count`` (n), ``sim_time`` (after the span)."""
    PAUSED = "paused"
    """``sim.pause()``; payload ``sim``."""
    RESUMED = "resumed"
    """``sim.resume()``; payload ``sim``."""
    OBJECT_SPAWNED = "object_spawned"
    """An object joined the simulation; payload ``sim``, ``obj`` (also on the object's own bus,
    if it has one)."""
    OBJECT_REMOVED = "object_removed"
    """An object left the simulation; payload ``sim``, ``obj`` (also on its own bus)."""
    AGENT_SPAWNED = "agent_spawned"
    """An agent joined (emitted after OBJECT_SPAWNED); payload ``sim``, ``agent``."""
    AGENT_REMOVED = "agent_removed"
    """An agent left (emitted after OBJECT_REMOVED); payload ``sim``, ``agent``."""
    COLLISION_STARTED = "collision_started"
    """A pair began touching; payload ``sim``, ``obj_a``, ``obj_b`` (entity buses: ``other``)."""
    COLLISION_ENDED = "collision_ended"
    """A pair stopped touching; same payload as COLLISION_STARTED."""
    PRE_UPDATE = "pre_update"
    """Before the motion phase moves agents; payload ``sim``, ``dt``. On an object's own bus:
    ``dt``, before that object is moved (only objects whose bus has a handler pay for it)."""
    POST_UPDATE = "post_update"
    """After the motion phase; payload ``sim``, ``dt``. On an object's own bus: ``dt`` and
    ``moved`` (whether its pose changed during the motion phase)."""
    ACTION_STARTED = "action_started"
    """An action began; payload ``agent``, ``action``."""
    ACTION_COMPLETED = "action_completed"
    """An action finished successfully; payload ``agent``, ``action``, ``status``."""
    ACTION_FAILED = "action_failed"
    """An action failed or was cancelled; payload ``agent``, ``action``, ``status``."""
    TASK_COMPLETED = "task_completed"
    """Fleet code finished one unit of work (an order, a delivery): emitted by *your* missions
    or callbacks, counted by ``sim.kpis()``; payload ``sim``, ``agent`` (or None), ``task``."""
    TASK_FAILED = "task_failed"
    """Fleet code gave up on a unit of work; same payload as TASK_COMPLETED."""
    MISSION_FAILED = "mission_failed"
    """A mission ended with an exception (not a cancellation), emitted by the mission runtime
    when it ends; payload ``sim``, ``mission`` (its name), ``error``."""
    SAFETY_STOP_STARTED = "safety_stop_started"
    """Something entered an agent's protective field: it stops in this step, its action stays
    active; payload ``sim``, ``agent``, ``obstacles`` (the objects in the field; a map's
    walls are not objects)."""
    SAFETY_STOP_ENDED = "safety_stop_ended"
    """An agent's protective field cleared (or its path ended): it drives on; payload ``sim``,
    ``agent``, ``duration`` (s stopped)."""
    DEADLOCK_SUSPECTED = "deadlock_suspected"
    """A set of agents, each stopped by another member in its protective field, has lasted
    ``sim.safety.deadlock_after`` seconds; payload ``sim``, ``agents``, ``sim_time``."""

    @classmethod
    def all(cls) -> tuple[str, ...]:
        """Return every event name, in declaration order."""
        return tuple(v for k, v in vars(cls).items() if k.isupper() and isinstance(v, str))


def _named_parameters(handler: Handler) -> frozenset[str] | None:
    """Keyword names ``handler`` accepts, or None when it takes ``**kwargs`` (or has no
    signature Python can read): None means "pass the whole payload"."""
    try:
        params = inspect.signature(handler).parameters.values()
    except (TypeError, ValueError):
        return None
    names = []
    for param in params:
        if param.kind is inspect.Parameter.VAR_KEYWORD:
            return None
        if param.kind in (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY):
            names.append(param.name)
    return frozenset(names)


class EventBus:
    """Dispatch named events to handlers ordered by priority (lower first).

    Args:
        on_error: ``"raise"`` (default) re-raises a handler's exception to the emitter, with a
            note naming the handler and the event; ``"log"`` logs it with the traceback and goes on
            with the remaining handlers.
        on_change: Called with the event name whenever a handler of that event is added or
            removed (lets an owner notice that someone listens).

    Raises:
        ValueError: if ``on_error`` is neither ``"raise"`` nor ``"log"``.
    """

    __slots__ = ("_handlers", "_on_change", "_on_error", "_seq")

    def __init__(
        self, on_error: str = "raise", on_change: Callable[[str], None] | None = None
    ) -> None:
        if on_error not in ("raise", "log"):
            raise ValueError(f"EventBus.on_error: expected 'raise' or 'log', got {on_error!r}")
        self._on_error = on_error
        self._on_change = on_change
        # event -> (priority, registration sequence, handler, accepted names), sorted; rebuilt
        # on change so that emit() is a plain loop.
        self._handlers: dict[str, list[tuple[int, int, Handler, frozenset[str] | None]]] = {}
        self._seq = 0

    def on(self, event: str, handler: Handler, priority: int = 0) -> Handler:
        """Subscribe ``handler`` to ``event``; lower ``priority`` runs first.

        Returns the handler, so ``on`` can be used as a decorator factory's inner call.

        Raises:
            TypeError: if ``handler`` is not callable.
            ValueError: if ``event`` is not a non-empty string.
        """
        if not isinstance(event, str) or not event:
            raise ValueError(f"EventBus.on: event must be a non-empty string, got {event!r}")
        if not callable(handler):
            raise TypeError(f"EventBus.on: handler for {event!r} is not callable: {handler!r}")
        self._seq += 1
        entry = (int(priority), self._seq, handler, _named_parameters(handler))
        entries = [*self._handlers.get(event, ()), entry]
        entries.sort(key=lambda e: (e[0], e[1]))
        self._handlers[event] = entries
        if self._on_change is not None:
            self._on_change(event)
        return handler

    def subscribe(self, event: str, priority: int = 0) -> Callable[[Handler], Handler]:
        """Decorator form of :meth:`on`."""

        def decorator(handler: Handler) -> Handler:
            return self.on(event, handler, priority)

        return decorator

    def off(self, event: str, handler: Handler) -> bool:
        """Unsubscribe ``handler`` from ``event``; return whether it was subscribed."""
        entries = self._handlers.get(event)
        if not entries:
            return False
        kept = [e for e in entries if e[2] != handler]
        if len(kept) == len(entries):
            return False
        if kept:
            self._handlers[event] = kept
        else:
            del self._handlers[event]
        if self._on_change is not None:
            self._on_change(event)
        return True

    def has_handlers(self, event: str) -> bool:
        """Return whether anyone listens to ``event`` (lets emitters skip building payloads)."""
        return event in self._handlers

    def handler_count(self, event: str | None = None) -> int:
        """Number of handlers for ``event``, or across all events when ``event`` is None."""
        if event is not None:
            return len(self._handlers.get(event, ()))
        return sum(len(v) for v in self._handlers.values())

    def emit(self, event: str, **payload: Any) -> int:
        """Call every handler of ``event`` with (its share of) ``payload`` as keywords.

        Returns:
            The number of handlers called.
        """
        entries = self._handlers.get(event)
        if not entries:
            return 0
        # Iterate over a snapshot: handlers may subscribe or unsubscribe while we dispatch.
        for _, _, handler, names in tuple(entries):
            try:
                if names is None:
                    handler(**payload)
                else:
                    handler(**{k: v for k, v in payload.items() if k in names})
            except Exception as exc:
                if self._on_error == "raise":
                    if hasattr(exc, "add_note"):  # Python >= 3.11
                        exc.add_note(f"raised by handler {handler!r} for event {event!r}")
                    raise
                logger.exception("handler %r for event %r raised; continuing", handler, event)
        return len(entries)

    def clear(self, event: str | None = None) -> None:
        """Drop the handlers of ``event``, or of every event when ``event`` is None."""
        cleared = list(self._handlers) if event is None else [event]
        if event is None:
            self._handlers.clear()
        else:
            self._handlers.pop(event, None)
        if self._on_change is not None:
            for name in cleared:
                self._on_change(name)
