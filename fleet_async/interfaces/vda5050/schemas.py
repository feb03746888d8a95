"""The standard's JSON schemas (MIT, shipped in ``schemas/``) and validation against them.

The schemas are the VDA5050/VDA5050 repository's ``json_schemas`` at tags 2.0.0 and 2.1.0,
byte for byte; where they contradict the standard's own text (which wins, its section 6 says),
a patched copy in ``schemas/fixed/`` is used instead (its README says what and why).
"""

from __future__ import annotations

import itertools
import json
from functools import cache
from importlib import resources
from typing import Any

__all__ = ["MESSAGES", "schema", "validation_errors"]

MESSAGES = ("order", "instantActions", "state", "visualization", "connection", "factsheet")
"""Messages with a schema."""

_EXTRA_MISSING = (
    'VDA 5050 message validation needs the vda5050 extra: python -m pip install -e ".[vda5050]"'
)


@cache
def schema(version: str, message: str) -> dict[str, Any]:
    """The JSON schema of ``message`` in protocol ``version``."""
    if message not in MESSAGES:
        raise ValueError(f"VDA 5050 schema: unknown message {message!r} (expected {MESSAGES})")
    root = resources.files("fleet_async.interfaces.vda5050") / "schemas"
    fixed = root / "fixed" / version / f"{message}.schema"
    path = fixed if fixed.is_file() else root / version / f"{message}.schema"
    if not path.is_file():
        raise ValueError(f"VDA 5050 schema: no schema for version {version!r}")
    data: dict[str, Any] = json.loads(path.read_text(encoding="utf-8"))
    return data


@cache
def _validator(version: str, message: str) -> Any:
    try:
        import jsonschema
    except ModuleNotFoundError as exc:  # pragma: no cover - the extra pulls it in
        raise ModuleNotFoundError(_EXTRA_MISSING) from exc
    return jsonschema.Draft202012Validator(
        schema(version, message), format_checker=jsonschema.FormatChecker()
    )


def validation_errors(version: str, message: str, data: Any, limit: int = 3) -> list[str]:
    """What is wrong with ``data`` as a ``message`` (at most ``limit`` problems; [] if valid).

    Each problem names the field's path (``nodes[0].nodePosition.x``) and what was expected.
    """
    # The first few errors only: sorting them all would let one large bad message hold the
    # network thread for as long as it takes to list a million of them.
    errors = itertools.islice(_validator(version, message).iter_errors(data), limit)
    problems = []
    for error in errors:
        where = "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in error.path)
        problems.append(f"{where.lstrip('.') or '(message)'}: {_short(error.message)}")
    return problems


def _short(text: str, limit: int = 160) -> str:
    return text if len(text) <= limit else text[: limit - 3] + "..."
