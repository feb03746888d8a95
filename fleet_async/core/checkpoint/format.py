"""The checkpoint file: a zip of numpy arrays holding a JSON header, a JSON state and arrays.

Format 2 (this one) is an ``.npz`` archive (``numpy.savez``) read with ``allow_pickle=False``:
``header`` (JSON text, as bytes: format name, version, timestep, every object's id and type),
``state`` (the state tree as ``codec.py`` writes it, JSON text) and ``a0``, ``a1``, ... (the
tree's numeric arrays). Nothing in it can run code when read. The header is read and checked
first, so a restore can refuse a simulation built differently before it decodes the state.
Format 1 was a pickle; it is read only with ``unsafe=True`` (``legacy.py``).
"""

from __future__ import annotations

import dataclasses
import io
import json
import os
import zipfile
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from fleet_async.core.actions.action_queue import ActionQueue
    from fleet_async.core.base.scheduling import PeriodicSchedule
    from fleet_async.core.collision.system import CollisionSystem
    from fleet_async.core.motion.joints import JointMotion
    from fleet_async.core.motion.kinematics import KinematicEngine

__all__ = [
    "FORMAT",
    "PICKLE_VERSION",
    "ROW_COLUMNS",
    "VERSION",
    "CheckpointError",
    "CheckpointFile",
    "CheckpointParts",
    "is_pickle",
    "read_file",
    "type_name",
    "typed_states",
    "write_file",
]

FORMAT = "fleet_async checkpoint"
VERSION = 2
PICKLE_VERSION = 1
ROW_COLUMNS = ("position", "orientation", "velocity", "angular_velocity", "moved")
"""Columns of the state store saved for every object's row."""


class CheckpointError(ValueError):
    """A simulation that cannot be saved, or a checkpoint that cannot be restored into it."""


@dataclasses.dataclass(frozen=True)
class CheckpointParts:
    """What the simulation hands the checkpoint: its clock and its collaborators."""

    step_count: int
    collision_count: int
    paused: bool
    engine: KinematicEngine
    actions: ActionQueue
    callbacks: PeriodicSchedule
    plugin_schedule: PeriodicSchedule
    collision: CollisionSystem
    joint_motion: JointMotion
    other_motion: tuple[object, ...] = ()
    """Motion systems added with ``sim.add_motion_system`` (the devices' one, say): a
    checkpoint does not capture them, so saving refuses while there are any."""


@dataclasses.dataclass(frozen=True)
class CheckpointFile:
    """A checkpoint file read but not yet decoded: the header, the state document, arrays."""

    header: dict[str, Any]
    document: Any
    arrays: list[np.ndarray]


def type_name(obj: object) -> str:
    """``module.QualName`` of ``obj``'s type (how the header and typed states name types)."""
    return f"{type(obj).__module__}.{type(obj).__qualname__}"


def typed_states(items: list[Any]) -> list[tuple[str, dict[str, Any]]]:
    """``(type name, item.get_state())`` for each controller or plugin, in order."""
    return [(type_name(item), item.get_state()) for item in items]


def is_pickle(data: bytes) -> bool:
    """Whether ``data`` starts like a pickle (a format-1 checkpoint)."""
    return data[:1] == b"\x80"


def write_file(
    path: str | os.PathLike[str], header: dict[str, Any], document: Any, arrays: list[np.ndarray]
) -> None:
    """Write a checkpoint atomically (a temporary file, then renamed over ``path``)."""
    members = {f"a{i}": array for i, array in enumerate(arrays)}
    members["header"] = np.frombuffer(json.dumps(header).encode(), dtype=np.uint8)
    members["state"] = np.frombuffer(json.dumps(document).encode(), dtype=np.uint8)
    buffer = io.BytesIO()
    np.savez(buffer, allow_pickle=False, **members)
    tmp = Path(f"{os.fspath(path)}.tmp")
    tmp.write_bytes(buffer.getvalue())
    os.replace(tmp, path)


def _json_member(archive: Any, name: str, path: str | os.PathLike[str]) -> Any:
    raw = archive[name]
    if raw.dtype != np.uint8 or raw.ndim != 1:
        raise CheckpointError(f"restore_state: {path}: member {name!r} is not JSON text")
    return json.loads(raw.tobytes().decode())


def read_file(path: str | os.PathLike[str], data: bytes) -> CheckpointFile:
    """The header, state document and arrays of the checkpoint ``data`` read from ``path``.

    Raises:
        CheckpointError: for a file that is not a format-2 checkpoint, naming it and why.
    """
    try:
        with np.load(io.BytesIO(data), allow_pickle=False) as archive:
            header = _json_member(archive, "header", path)
            if not isinstance(header, dict) or header.get("format") != FORMAT:
                raise CheckpointError(f"restore_state: {path} is not a fleet_async checkpoint")
            if header.get("version") != VERSION:
                raise CheckpointError(
                    f"restore_state: {path} has checkpoint format {header.get('version')!r}; "
                    f"this fleet_async reads format {VERSION}"
                )
            document = _json_member(archive, "state", path)
            count = sum(1 for name in archive.files if name.startswith("a"))
            arrays = [archive[f"a{i}"] for i in range(count)]
    except CheckpointError:
        raise
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile, RecursionError) as exc:
        raise CheckpointError(
            f"restore_state: {path} is not a readable checkpoint ({type(exc).__name__}: {exc})"
        ) from exc
    return CheckpointFile(header, document, arrays)
