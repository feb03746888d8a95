"""Robot and object models by name: known names, user aliases and model search paths.

``resolve_model`` turns what a user writes in a config or a spawn call (``"panda"``,
``"mobile_robot"``, ``"robots/arm_robot.urdf"``, ``"/abs/path/to/bot.urdf"``) into the absolute
path of a URDF or SDF file. Lookup order:

1. an existing file, absolute or relative to the working directory;
2. a relative path under a model search path (user paths, latest added first, then the
   project's own robots directory, then ``pybullet_data``);
3. a known model name: a user alias (``register_model``), a project robot or a
   ``pybullet_data`` model, optionally written with its ``.urdf``/``.sdf`` extension or as
   ``robots/<name>.urdf``;
4. a bare name ``<name>`` found as ``<name>.urdf`` or ``<name>.sdf`` under a search path.

The only module state is the user's search paths and aliases; ``reset_model_registry`` restores
the defaults.
"""

from __future__ import annotations

import difflib
import functools
import os
from pathlib import Path as FsPath

import pybullet_data

__all__ = [
    "PROJECT_ROBOTS_DIR",
    "add_model_search_path",
    "list_model_search_paths",
    "list_models",
    "register_model",
    "remove_model_search_path",
    "reset_model_registry",
    "resolve_model",
]

PROJECT_ROBOTS_DIR: str = str(FsPath(__file__).resolve().parents[2] / "data" / "robots")
"""The directory holding the project's own robot URDFs."""

_PROJECT_MODELS: dict[str, str] = {
    name: f"{name}.urdf"
    for name in ("simple_cube", "mobile_robot", "arm_robot", "mobile_manipulator", "rail_arm_robot")
}
"""Project model name -> file relative to ``PROJECT_ROBOTS_DIR``."""

_PYBULLET_MODELS: dict[str, str] = {
    "panda": "franka_panda/panda.urdf",
    "kuka_iiwa": "kuka_iiwa/model.urdf",
    "husky": "husky/husky.urdf",
    "racecar": "racecar/racecar.urdf",
    "r2d2": "r2d2.urdf",
    "kiva_shelf": "kiva_shelf/model.sdf",
    "table": "table/table.urdf",
    "tray": "tray/traybox.urdf",
    "cube": "cube.urdf",
    "sphere": "sphere2.urdf",
    "plane": "plane.urdf",
    "xarm": "xarm/xarm6_robot.urdf",
}
"""pybullet_data model name -> file relative to ``pybullet_data.getDataPath()``; a name whose file
is missing from the installed pybullet_data is not offered."""

_MODEL_SUFFIXES = (".urdf", ".sdf")

# User state, in the order the user added it; reset_model_registry() empties both.
_user_search_paths: list[str] = []
_user_models: dict[str, str] = {}


@functools.cache
def _pybullet_data_dir() -> str:
    return str(FsPath(pybullet_data.getDataPath()).resolve())


def _builtin_search_paths() -> list[str]:
    return [PROJECT_ROBOTS_DIR, _pybullet_data_dir()]


@functools.cache
def _builtin_models() -> dict[str, str]:
    """Built-in name -> absolute file, for the files installed (read once: a loop of spawns
    by model name must not stat every model each time)."""
    models: dict[str, str] = {}
    for base, table in (
        (pybullet_data.getDataPath(), _PYBULLET_MODELS),
        (PROJECT_ROBOTS_DIR, _PROJECT_MODELS),
    ):
        for name, relative in table.items():
            candidate = FsPath(base) / relative
            if candidate.is_file():
                models[name] = str(candidate.resolve())
    return models


def _known_models() -> dict[str, str]:
    """Every known name -> absolute file; user aliases shadow built-in names."""
    models = dict(_builtin_models())
    models.update(_user_models)
    return models


def _model_key(name_or_path: str) -> str:
    """The model name a spelling refers to: ``robots/arm_robot.urdf`` and ``arm_robot.urdf``
    both mean ``arm_robot``; anything else is returned unchanged."""
    as_path = FsPath(name_or_path)
    if as_path.suffix.lower() in _MODEL_SUFFIXES and str(as_path.parent) in (".", "robots"):
        return as_path.stem
    return name_or_path


def _find_under(relative: str, search_paths: list[str]) -> str | None:
    # os.path, not pathlib: a spawn loop resolves its model once per robot.
    for base in search_paths:
        candidate = os.path.join(base, relative)
        if os.path.isfile(candidate):
            return os.path.realpath(candidate)
    return None


def resolve_model(name_or_path: str) -> str:
    """Find the URDF/SDF file for a model name or path.

    Args:
        name_or_path: A file path (absolute, or relative to the working directory or to a
            model search path), a known model name (see ``list_models``), a known name with
            its extension (``"arm_robot.urdf"``) or as ``"robots/<name>.urdf"``, or a bare
            name whose ``.urdf``/``.sdf`` file lies in a search path.

    Returns:
        The absolute path of the model file.

    Raises:
        ValueError: if nothing matches; the message names the closest known model, every
            known model (sorted) and the search paths tried (in search order).
    """
    expanded = os.path.expanduser(name_or_path)
    if name_or_path and os.path.isfile(expanded):
        return os.path.realpath(expanded)
    search_paths = list_model_search_paths()
    relative = bool(name_or_path) and not os.path.isabs(expanded)
    if relative:
        found = _find_under(expanded, search_paths)
        if found is not None:
            return found
    known = _known_models()
    key = _model_key(name_or_path)
    if key in known:
        return known[key]
    if relative and not os.path.splitext(expanded)[1]:
        for suffix in _MODEL_SUFFIXES:
            found = _find_under(expanded + suffix, search_paths)
            if found is not None:
                return found
    raise ValueError(_unknown_model_message(name_or_path, key, sorted(known), search_paths))


def _unknown_model_message(
    name_or_path: str, key: str, known: list[str], search_paths: list[str]
) -> str:
    close = difflib.get_close_matches(key, known, n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    return (
        f"unknown model {name_or_path!r}{hint}; known models: {known}; search paths: {search_paths}"
    )


def add_model_search_path(path: str) -> None:
    """Search a directory for models, before every directory added earlier.

    Adding a directory already on the list moves it to the front; adding a built-in directory
    (the project robots or pybullet_data) changes nothing, since those are always searched last.

    Args:
        path: Directory, absolute or relative to the working directory.

    Raises:
        ValueError: if ``path`` is not a directory.
    """
    directory = FsPath(path).expanduser()
    if not directory.is_dir():
        raise ValueError(f"model search path {path!r} is not a directory")
    resolved = str(directory.resolve())
    if resolved in _builtin_search_paths():
        return
    if resolved in _user_search_paths:
        _user_search_paths.remove(resolved)
    _user_search_paths.insert(0, resolved)


def remove_model_search_path(path: str) -> bool:
    """Stop searching a directory added with ``add_model_search_path``.

    Args:
        path: The directory, spelled as when added or any spelling resolving to it.

    Returns:
        True if it was removed; False if it was not a user search path (built-in paths
        cannot be removed).
    """
    resolved = str(FsPath(path).expanduser().resolve())
    if resolved in _user_search_paths:
        _user_search_paths.remove(resolved)
        return True
    return False


def list_model_search_paths() -> list[str]:
    """The model search paths, in search order.

    Returns:
        User paths (latest added first), then the project robots directory, then pybullet_data;
        all absolute.
    """
    return [*_user_search_paths, *_builtin_search_paths()]


def list_models() -> list[str]:
    """The known model names.

    Returns:
        Sorted names: pybullet_data models present in the installed package, the project's
        robots and the user's aliases.
    """
    return sorted(_known_models())


def register_model(name: str, path: str) -> None:
    """Make ``name`` a known model, shadowing a built-in model of the same name.

    Args:
        name: Model name; non-empty, and not itself a path or file name.
        path: The model file, absolute or relative to the working directory; stored absolute.

    Raises:
        ValueError: if ``name`` is empty, contains a path separator or ends in ``.urdf``/``.sdf``.
        FileNotFoundError: naming ``path`` if it is not a file.
    """
    if not name or _model_key(name) != name or FsPath(name).name != name:
        raise ValueError(f"model name {name!r} must be a non-empty bare name, not a path")
    model_file = FsPath(path).expanduser()
    if not model_file.is_file():
        raise FileNotFoundError(f"model file {path!r} for model {name!r} not found")
    _user_models[name] = str(model_file.resolve())


def reset_model_registry() -> None:
    """Forget every user search path and alias, restoring the built-in defaults."""
    _user_search_paths.clear()
    _user_models.clear()
