"""Finding data files (meshes, SDF, URDF) on the user's search paths."""

from __future__ import annotations

from pathlib import Path as FsPath

import pybullet_data

__all__ = ["resolve_data_file"]


def resolve_data_file(path: str, search_paths: list[str] | None = None, field: str = "path") -> str:
    """Find a file: as given, then under each search path, then in pybullet_data.

    Args:
        path: Absolute or relative file path.
        search_paths: Directories tried, in order, for a relative ``path``.
        field: Name of the setting, for the error message.

    Returns:
        The absolute path of the first match.

    Raises:
        FileNotFoundError: naming ``field``, ``path`` and every location tried.
    """
    candidate = FsPath(path).expanduser()
    tried = [candidate]
    if not candidate.is_absolute():
        tried += [
            FsPath(base) / candidate
            for base in [*(search_paths or []), pybullet_data.getDataPath()]
        ]
    for option in tried:
        if option.is_file():
            return str(option.resolve())
    raise FileNotFoundError(f"{field} {path!r} not found; tried: " + ", ".join(map(str, tried)))
