"""The ``world_config`` of ``load_world``: its keys, checked, with every path resolved.

A world comes from one source key, in priority order ``world_file`` (Gazebo ``.world``),
``sdf`` (an SDF file) or ``mesh_dir`` (a directory of ``.obj`` / ``.stl`` meshes); options are
``skip_models``, ``model_paths`` and ``on_error``. Unknown keys are errors naming the nearest
valid one; relative paths are taken from ``base_dir`` (the scenario file's directory).
"""

from __future__ import annotations

import difflib
import logging
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path as FsPath
from typing import Any

import pybullet_data

from fleet_async.core.base.reprs import short_repr

__all__ = [
    "MESH_SUFFIXES",
    "OPTION_KEYS",
    "SOURCE_KEYS",
    "WorldOptions",
    "model_search_dirs",
    "read_world_config",
]

logger = logging.getLogger(__name__)

SOURCE_KEYS = ("world_file", "sdf", "mesh_dir")
"""World sources, in priority order: the first one present is loaded."""
OPTION_KEYS = ("skip_models", "model_paths", "on_error")
MESH_SUFFIXES = (".obj", ".stl")


@dataclass
class WorldOptions:
    """A checked ``world_config``.

    Attributes:
        key: The source key used ("world_file", "sdf" or "mesh_dir").
        source: Absolute path of that source.
        skip: Model names not to load.
        model_paths: Absolute directories searched first for ``model://`` URIs.
        on_error: "raise" or "warn".
    """

    key: str
    source: FsPath
    skip: set[str] = field(default_factory=set)
    model_paths: list[FsPath] = field(default_factory=list)
    on_error: str = "raise"


def _absolute(value: Any, key: str, base: FsPath) -> FsPath:
    if not isinstance(value, (str, os.PathLike)) or not os.fspath(value):
        raise ValueError(
            f"load_world: world_config[{key!r}] must be a path, got {short_repr(value)}"
        )
    path = FsPath(os.fspath(value)).expanduser()
    return path if path.is_absolute() else base / path


def _names(value: Any, key: str) -> set[str]:
    if value is None:
        return set()
    if not isinstance(value, (list, tuple, set)) or not all(isinstance(v, str) for v in value):
        raise ValueError(
            f"load_world: {key} must be a list of model names, got {short_repr(value)}"
        )
    return set(value)


def _source_key(world_config: Mapping[str, Any]) -> str:
    """The source key to load; unknown keys and a missing source are errors."""
    valid = (*SOURCE_KEYS, *OPTION_KEYS)
    for key in world_config:
        if key not in valid:
            nearest = difflib.get_close_matches(str(key), valid, n=1, cutoff=0.0)[0]
            raise ValueError(
                f"load_world: unknown world_config key {key!r} (nearest valid key: {nearest!r}); "
                f"valid keys: {', '.join(valid)}"
            )
    sources = [key for key in SOURCE_KEYS if key in world_config]
    if not sources:
        raise ValueError(
            "load_world: world_config needs one of 'world_file' (Gazebo .world), 'sdf' (SDF "
            "file) or 'mesh_dir' (directory of .obj/.stl meshes); accepted keys: "
            f"{', '.join(valid)}; got {sorted(map(str, world_config))}"
        )
    if len(sources) > 1:
        logger.warning(
            "load_world: loading %r; ignoring lower-priority %s", sources[0], sources[1:]
        )
    return sources[0]


def _model_paths(value: Any, base: FsPath) -> list[FsPath]:
    if value is None:
        return []
    if not isinstance(value, (list, tuple)):
        raise ValueError(
            f"load_world: model_paths must be a list of directories, got {short_repr(value)}"
        )
    paths = [_absolute(d, "model_paths", base) for d in value]
    for directory in paths:
        if not directory.is_dir():
            raise FileNotFoundError(
                f"load_world: model_paths directory not found: {directory.absolute()}"
            )
    return [d.resolve() for d in paths]


def _source_path(key: str, value: Any, base: FsPath, model_paths: list[FsPath]) -> FsPath:
    path = _absolute(value, key, base)
    tried = [path]
    if key == "sdf" and not FsPath(os.fspath(value)).expanduser().is_absolute():
        rel = FsPath(os.fspath(value))
        tried += [d / rel for d in (*model_paths, FsPath(pybullet_data.getDataPath()))]
    for candidate in tried:
        if candidate.is_dir() if key == "mesh_dir" else candidate.is_file():
            return candidate.resolve()
    kind = "directory" if key == "mesh_dir" else "file"
    raise FileNotFoundError(
        f"load_world: world_config[{key!r}] {kind} not found: "
        + ", ".join(str(c.absolute()) for c in tried)
    )


def read_world_config(
    world_config: Mapping[str, Any],
    skip_models: Sequence[str] | None = None,
    base_dir: str | os.PathLike[str] | None = None,
) -> WorldOptions:
    """Check ``world_config`` and resolve its paths (see ``load_world``).

    Raises:
        TypeError: if ``world_config`` is not a mapping.
        ValueError: for an unknown key (naming the nearest valid one), no source key, or a
            bad value.
        FileNotFoundError: for a source or model path that does not exist (absolute path).
    """
    if not isinstance(world_config, Mapping):
        raise TypeError(f"load_world: world_config must be a mapping, got {world_config!r}")
    key = _source_key(world_config)
    on_error = world_config.get("on_error", "raise")
    if on_error not in ("raise", "warn"):
        raise ValueError(f"load_world: on_error must be 'raise' or 'warn', got {on_error!r}")
    base = FsPath(os.fspath(base_dir)).expanduser() if base_dir is not None else FsPath.cwd()
    model_paths = _model_paths(world_config.get("model_paths"), base)
    return WorldOptions(
        key=key,
        source=_source_path(key, world_config[key], base, model_paths),
        skip=_names(world_config.get("skip_models"), "skip_models")
        | _names(skip_models, "skip_models"),
        model_paths=model_paths,
        on_error=on_error,
    )


def model_search_dirs(model_paths: Sequence[FsPath], source: FsPath, key: str) -> list[FsPath]:
    """Where ``model://`` URIs are looked up, in order.

    ``model_paths``, then ``GAZEBO_MODEL_PATH`` (read now), then the source's directory and its
    ``models`` subdirectory; for an ``sdf`` source also the directory above, so a model's own
    SDF finds ``model://<itself>/meshes/...``.
    """
    env = [
        FsPath(d).absolute()
        for d in os.environ.get("GAZEBO_MODEL_PATH", "").split(os.pathsep)
        if d.strip()
    ]
    here = source if key == "mesh_dir" else source.parent
    above = [here.parent] if key == "sdf" else []
    return [*model_paths, *env, here, here / "models", *above]
