"""Fenced code blocks of Markdown files, for the tests that run the docs and the README."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

NO_RUN = "<!-- no-run -->"
"""An HTML comment on the line before a fence: the block is shown, not run."""

_FENCE = re.compile(r"^(`{3,})\s*([\w+-]*)\s*$")


@dataclasses.dataclass(frozen=True)
class Block:
    """One fenced block.

    Attributes:
        path: The Markdown file.
        line: Line number of the opening fence (1-based).
        language: The fence's info string (``python``, ``bash``, ...), "" if none.
        code: The block's text.
        runs: False when the line before the fence is ``<!-- no-run -->``.
    """

    path: Path
    line: int
    language: str
    code: str
    runs: bool

    @property
    def id(self) -> str:
        return f"{self.path.name}:{self.line}"


def fenced_blocks(path: Path) -> list[Block]:
    """Every fenced block of the Markdown file ``path``, in order."""
    lines = path.read_text(encoding="utf-8").splitlines()
    blocks: list[Block] = []
    i = 0
    while i < len(lines):
        opening = _FENCE.match(lines[i])
        if opening is None:
            i += 1
            continue
        fence, language, start = opening[1], opening[2], i
        before = next((lines[j].strip() for j in range(start - 1, -1, -1) if lines[j].strip()), "")
        i += 1
        body: list[str] = []
        while i < len(lines) and lines[i].strip() != fence:
            body.append(lines[i])
            i += 1
        i += 1
        blocks.append(Block(path, start + 1, language, "\n".join(body) + "\n", before != NO_RUN))
    return blocks
