"""Loggers that build their message only when the level is enabled.

The standard library evaluates an f-string argument before ``logger.debug`` can decide to drop
it. :class:`LazyLogger` accepts either a string or a zero-argument callable (typically a
``lambda``) and calls it only if the logger is enabled for that level, so formatting a NumPy
array for a debug line costs nothing when debug logging is off.

Usage policy: pass constants and cheap strings directly; wrap anything expensive (or with side
effects) in a ``lambda``. Both forms may be mixed freely, which eases migrating existing
``logging`` calls.

Every record reports the *caller's* file, function and line (``%(funcName)s``, ``%(lineno)d``),
not this module's: the wrappers pass the right ``stacklevel`` to :meth:`logging.Logger.log`.

Importing this module has no side effects: it configures no handlers and sets no levels.
"""

from __future__ import annotations

import functools
import logging
from collections.abc import Callable
from typing import Any

__all__ = [
    "LazyLogger",
    "NamedLazyLogger",
    "get_lazy_logger",
    "get_named_lazy_logger",
    "lazy_log",
    "wrap_existing_logger",
]

Message = str | Callable[[], object]
"""A log message: a string (or any object), or a zero-argument callable that returns one."""

# Frames between the user's call and ``Logger.log``: the public method (``debug`` ...) and
# ``_log_lazy``. ``stacklevel=1`` would name ``_log_lazy``; each extra level climbs one frame.
_WRAPPER_FRAMES = 2


class LazyLogger:
    """Logger wrapper that evaluates callable messages only when the level is enabled.

    Example:
        >>> log = LazyLogger(__name__)
        >>> log.debug(lambda: f"expensive array: {big_array}")  # doctest: +SKIP
        >>> log.info("cheap constant message")  # doctest: +SKIP

    Positional ``*args`` are %-style arguments and keyword arguments (``exc_info``,
    ``stack_info``, ``stacklevel``, ``extra``) are forwarded to :meth:`logging.Logger.log`, as
    with the standard logger. A user-supplied ``stacklevel`` counts from the caller of this
    wrapper, exactly as it would for a plain ``logging.Logger``.
    """

    def __init__(self, name: str | None = None, logger: logging.Logger | None = None) -> None:
        """Initialize LazyLogger.

        Args:
            name: Name passed to :func:`logging.getLogger` (typically ``__name__``); ``None``
                means the root logger. Ignored when ``logger`` is given.
            logger: Existing logger to wrap; takes precedence over ``name``.
        """
        self._logger = logger if logger is not None else logging.getLogger(name)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self._logger.name!r})"

    @property
    def logger(self) -> logging.Logger:
        """The underlying :class:`logging.Logger`."""
        return self._logger

    def isEnabledFor(self, level: int) -> bool:
        """Return whether a record at ``level`` would be processed by the underlying logger.

        Named like :meth:`logging.Logger.isEnabledFor` so a LazyLogger can stand in for one.

        Args:
            level: A logging level such as ``logging.DEBUG``.

        Returns:
            True if the underlying logger is enabled for ``level``.
        """
        return self._logger.isEnabledFor(level)

    def debug(self, msg_func: Message, *args: Any, **kwargs: Any) -> None:
        """Log at DEBUG, calling ``msg_func`` only if DEBUG is enabled.

        Args:
            msg_func: Message string, or a zero-argument callable returning it.
            *args: %-style arguments merged into the message by ``logging``.
            **kwargs: Forwarded to :meth:`logging.Logger.log`.
        """
        self._log_lazy(logging.DEBUG, msg_func, args, kwargs)

    def info(self, msg_func: Message, *args: Any, **kwargs: Any) -> None:
        """Log at INFO, calling ``msg_func`` only if INFO is enabled (see :meth:`debug`)."""
        self._log_lazy(logging.INFO, msg_func, args, kwargs)

    def warning(self, msg_func: Message, *args: Any, **kwargs: Any) -> None:
        """Log at WARNING, calling ``msg_func`` only if WARNING is enabled (see :meth:`debug`)."""
        self._log_lazy(logging.WARNING, msg_func, args, kwargs)

    def error(self, msg_func: Message, *args: Any, **kwargs: Any) -> None:
        """Log at ERROR, calling ``msg_func`` only if ERROR is enabled (see :meth:`debug`)."""
        self._log_lazy(logging.ERROR, msg_func, args, kwargs)

    def critical(self, msg_func: Message, *args: Any, **kwargs: Any) -> None:
        """Log at CRITICAL, calling ``msg_func`` only if CRITICAL is enabled (see :meth:`debug`)."""
        self._log_lazy(logging.CRITICAL, msg_func, args, kwargs)

    def _format(self, message: object, args: tuple[Any, ...]) -> object:
        """Hook for subclasses: adjust an evaluated message before it is logged."""
        return message

    def _log_lazy(
        self, level: int, msg_func: Message, args: tuple[Any, ...], kwargs: dict[str, Any]
    ) -> None:
        # Must be called directly from a public level method: _WRAPPER_FRAMES depends on it.
        if not self._logger.isEnabledFor(level):
            return
        message = msg_func() if callable(msg_func) else msg_func
        stacklevel = kwargs.pop("stacklevel", 1) + _WRAPPER_FRAMES
        self._logger.log(level, self._format(message, args), *args, stacklevel=stacklevel, **kwargs)


class NamedLazyLogger(LazyLogger):
    """LazyLogger that prepends a per-instance prefix such as ``"[Agent:3:robot_A] "``.

    The prefix can change at any time with :meth:`set_prefix` (e.g. once an object id is
    assigned). It is prepended only when the level is enabled, so a filtered-out call costs no
    string work. A ``%`` in the prefix is escaped when %-style arguments are given, so a prefix
    never breaks message formatting.

    Example:
        >>> log = NamedLazyLogger(__name__, prefix="[obj:7] ")
        >>> log.info("path complete")  # logs "[obj:7] path complete"  # doctest: +SKIP
    """

    def __init__(
        self, name: str | None = None, logger: logging.Logger | None = None, prefix: str = ""
    ) -> None:
        """Initialize NamedLazyLogger.

        Args:
            name: Logger name (typically ``__name__``); ignored when ``logger`` is given.
            logger: Existing logger to wrap; takes precedence over ``name``.
            prefix: Text prepended to every message (include a trailing space if wanted).
        """
        super().__init__(name, logger)
        self._prefix = prefix

    @property
    def prefix(self) -> str:
        """The current prefix string."""
        return self._prefix

    def set_prefix(self, prefix: str) -> None:
        """Replace the prefix prepended to every message.

        Args:
            prefix: New prefix (include a trailing space if wanted).
        """
        self._prefix = prefix

    def _format(self, message: object, args: tuple[Any, ...]) -> object:
        if not self._prefix:
            return message
        prefix = self._prefix.replace("%", "%%") if args else self._prefix
        return f"{prefix}{message}"


def get_lazy_logger(name: str) -> LazyLogger:
    """Return a :class:`LazyLogger` for ``logging.getLogger(name)``.

    Args:
        name: Logger name, typically ``__name__``.

    Returns:
        A new LazyLogger wrapping the named logger.
    """
    return LazyLogger(name)


def get_named_lazy_logger(name: str, prefix: str = "") -> NamedLazyLogger:
    """Return a :class:`NamedLazyLogger`, the usual logger for entity and action instances.

    Args:
        name: Logger name, typically ``__name__``.
        prefix: Text prepended to every message, e.g. ``f"[Agent:{object_id}] "``.

    Returns:
        A new NamedLazyLogger wrapping the named logger.
    """
    return NamedLazyLogger(name, prefix=prefix)


def wrap_existing_logger(logger: logging.Logger) -> LazyLogger:
    """Wrap an existing :class:`logging.Logger` with lazy evaluation.

    Args:
        logger: The logger to wrap; its handlers, level and name are used unchanged.

    Returns:
        A LazyLogger writing to ``logger``.
    """
    return LazyLogger(logger=logger)


def lazy_log(func: Callable[..., logging.Logger]) -> Callable[..., LazyLogger]:
    """Decorate a function returning a :class:`logging.Logger` so it returns a LazyLogger.

    A LazyLogger returned by the wrapped function is passed through unchanged.

    Example:
        >>> @lazy_log
        ... def my_logger():
        ...     return logging.getLogger(__name__)
        >>> my_logger().debug(lambda: "built only if DEBUG is on")

    Args:
        func: Callable returning a logger.

    Returns:
        A callable with the same signature returning a LazyLogger.
    """

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> LazyLogger:
        logger = func(*args, **kwargs)
        return logger if isinstance(logger, LazyLogger) else LazyLogger(logger=logger)

    return wrapper
