"""BehaviorTreeError: every problem with a tree names the file, the line and the node."""

from __future__ import annotations

__all__ = ["BehaviorTreeError"]


class BehaviorTreeError(ValueError):
    """A tree that cannot be loaded or run as written.

    The message starts with ``file:line:`` and the node (``<MoveTo>``) when they are known.

    Attributes:
        source: The XML file (or ``"<string>"``).
        line: 1-based line of the element, or None.
        node: The element's tag (its ID for ``<Action ID=...>``), or None.
        reason: The message without the location.
    """

    def __init__(
        self,
        reason: str,
        *,
        source: str | None = None,
        line: int | None = None,
        node: str | None = None,
    ) -> None:
        self.source = source
        self.line = line
        self.node = node
        self.reason = reason
        where = ""
        if source is not None:
            where = f"{source}:{line}: " if line is not None else f"{source}: "
        element = f"<{node}> " if node else ""
        super().__init__(f"{where}{element}{reason}")
