"""Synchronous publish/subscribe with priorities.

One :class:`EventBus` belongs to the simulation (``sim.events``) and each entity gets its own on
first access (``obj.events``). Handlers are called with the event's payload as keyword
arguments, in descending priority; handlers of equal priority run in the order they were
registered, so dispatch order never depends on object identity or hashing.

A handler that raises propagates its exception to whoever emitted the event, unless the bus was
created with ``on_error="log"``. Errors are never swallowed silently.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

__all__ = ["EventBus", "SimEvents"]

logger = logging.getLogger(__name__)

Handler = Callable[..., Any]


class SimEvents:
    """Names of the events the simulator emits, with the payload keys each carries."""

    PRE_STEP = "pre_step"
    """Start of ``step_once``; payload ``sim``, ``step`` (the step about to run), ``sim_time``."""
    POST_STEP = "post_step"
    """End of ``step_once``, after the clock advanced; same payload as PRE_STEP."""
    STEPS_SKIPPED = "steps_skipped"
    """``sim.skip_steps(n)`` advanced the clock over ``n`` empty steps; payload ``sim``,
    ``step`` (the first skipped step), ``count`` (n), ``sim_time`` (after the span)."""
    PAUSED = "paused"
    """``sim.pause()``; payload ``sim``."""
    RESUMED = "resumed"
    """``sim.resume()``; payload ``sim``."""
    OBJECT_SPAWNED = "object_spawned"
    """An object joined the simulation; payload ``sim``, ``obj``."""
    OBJECT_REMOVED = "object_removed"
    """An object left the simulation; payload ``sim``, ``obj``."""
    AGENT_SPAWNED = "agent_spawned"
    """An agent joined (emitted after OBJECT_SPAWNED); payload ``sim``, ``agent``."""
    AGENT_REMOVED = "agent_removed"
    """An agent left (emitted after OBJECT_REMOVED); payload ``sim``, ``agent``."""
    COLLISION_STARTED = "collision_started"
    """A pair began touching; payload ``sim``, ``obj_a``, ``obj_b`` (entity buses: ``other``)."""
    COLLISION_ENDED = "collision_ended"
    """A pair stopped touching; same payload as COLLISION_STARTED."""
    PRE_UPDATE = "pre_update"
    """Before the motion phase moves agents; payload ``sim``, ``dt``."""
    POST_UPDATE = "post_update"
    """After the motion phase; payload ``sim``, ``dt``."""
    ACTION_STARTED = "action_started"
    """An action began; payload ``agent``, ``action``."""
    ACTION_COMPLETED = "action_completed"
    """An action finished successfully; payload ``agent``, ``action``."""
    ACTION_FAILED = "action_failed"
    """An action failed or was cancelled; payload ``agent``, ``action``."""

    @classmethod
    def all(cls) -> tuple[str, ...]:
        """Return every event name, in declaration order."""
        return tuple(v for k, v in vars(cls).items() if k.isupper() and isinstance(v, str))


class EventBus:
    """Dispatch named events to handlers ordered by priority.

    Args:
        on_error: ``"raise"`` (default) re-raises a handler's exception to the emitter, with a
            note naming the handler and the event; ``"log"`` logs it with the traceback and goes on
            with the remaining handlers.

    Raises:
        ValueError: if ``on_error`` is neither ``"raise"`` nor ``"log"``.
    """

    __slots__ = ("_handlers", "_on_error", "_seq")

    def __init__(self, on_error: str = "raise") -> None:
        if on_error not in ("raise", "log"):
            raise ValueError(f"EventBus.on_error: expected 'raise' or 'log', got {on_error!r}")
        self._on_error = on_error
        # event -> handlers sorted by (-priority, registration sequence); rebuilt on change so
        # that emit() is a plain loop.
        self._handlers: dict[str, list[tuple[int, int, Handler]]] = {}
        self._seq = 0

    def on(self, event: str, handler: Handler, priority: int = 0) -> Handler:
        """Subscribe ``handler`` to ``event``; higher ``priority`` runs first.

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
        entries = [*self._handlers.get(event, ()), (-int(priority), self._seq, handler)]
        entries.sort(key=lambda e: (e[0], e[1]))
        self._handlers[event] = entries
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
        """Call every handler of ``event`` with ``payload`` as keyword arguments.

        Returns:
            The number of handlers called.
        """
        entries = self._handlers.get(event)
        if not entries:
            return 0
        # Iterate over a snapshot: handlers may subscribe or unsubscribe while we dispatch.
        for _, _, handler in tuple(entries):
            try:
                handler(**payload)
            except Exception as exc:
                if self._on_error == "raise":
                    if hasattr(exc, "add_note"):  # Python >= 3.11
                        exc.add_note(f"raised by handler {handler!r} for event {event!r}")
                    raise
                logger.exception("handler %r for event %r raised; continuing", handler, event)
        return len(entries)

    def clear(self, event: str | None = None) -> None:
        """Drop the handlers of ``event``, or of every event when ``event`` is None."""
        if event is None:
            self._handlers.clear()
        else:
            self._handlers.pop(event, None)
