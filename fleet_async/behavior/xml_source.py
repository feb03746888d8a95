"""Reading a BehaviorTree.CPP XML file into elements that remember their line numbers.

The standard library's expat parser is used directly (``xml.etree`` forgets line numbers).
Trees are trusted local files, as a Python script is, so ``defusedxml`` is not needed; expat
does not fetch external entities.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

from fleet_async.behavior.errors import BehaviorTreeError

__all__ = ["Element", "parse_xml"]


@dataclass
class Element:
    """One XML element: tag, attributes in document order, 1-based line, children."""

    tag: str
    attrs: dict[str, str]
    line: int
    children: list[Element] = field(default_factory=list)


def parse_xml(text: str, source: str) -> Element:
    """Parse ``text`` (from ``source``, for messages) and return its root element.

    Raises:
        BehaviorTreeError: for malformed XML, naming the file, line and column.
    """
    parser = expat.ParserCreate()
    stack: list[Element] = []
    roots: list[Element] = []

    def start(tag: str, attrs: dict[str, str]) -> None:
        element = Element(tag, dict(attrs), parser.CurrentLineNumber)
        (stack[-1].children if stack else roots).append(element)
        stack.append(element)

    def end(tag: str) -> None:
        stack.pop()

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(text, True)
    except expat.ExpatError as exc:
        reason = expat.errors.messages.get(exc.code, str(exc))
        raise BehaviorTreeError(
            f"malformed XML: {reason} (column {exc.offset + 1})", source=source, line=exc.lineno
        ) from None
    return roots[0]


def read_xml_file(path: str | Path) -> tuple[str, str]:
    """(text, source name) of an XML file.

    Raises:
        FileNotFoundError: naming the absolute path.
    """
    file = Path(path)
    if not file.is_file():
        raise FileNotFoundError(f"behaviour tree file not found: {file} ({file.resolve()})")
    return file.read_text(encoding="utf-8"), str(file)
