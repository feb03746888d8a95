"""Reading Gazebo worlds and finding their models, before PyBullet sees a file.

PyBullet's ``loadSDF`` knows neither ``<include>`` nor ``model://`` URIs, ignores the pose of a
model's root link, silently drops nested models and crashes (segfault) on a model with more
than one root link or on an ASCII STL mesh. Everything that must happen before PyBullet sees a
file is done in pure Python, here and in ``sdf_rewriter.py``:

- finding ``model://NAME`` models on the model search path (``NAME/model.config`` naming the
  SDF file, highest ``version`` first, or ``NAME/model.sdf``);
- reading the ``<include>`` and inline ``<model>`` entries of a ``.world`` file;
- rewriting an SDF tree so PyBullet loads it as Gazebo would (``sdf_rewriter.py``).

Problems are raised or returned as :class:`AssetProblem` (a reason and the paths tried); the
loader (``world_loader.py``) turns them into named failures.
"""

from __future__ import annotations

import copy
import math
import os
import re
import xml.etree.ElementTree as ET
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path as FsPath

from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.quaternions import quat_from_euler

__all__ = [
    "AssetProblem",
    "ModelSearch",
    "WorldEntry",
    "format_pose",
    "inline_model_sdf",
    "model_sdf_file",
    "parse_pose",
    "parse_xml",
    "read_world",
    "remove_models",
    "sdf_models",
    "unsupported_world_elements",
]


class AssetProblem(Exception):
    """Something about one model or file that stops it from loading.

    Attributes:
        reason: What is wrong, for a person to act on.
        paths: Every path tried or involved (absolute).
    """

    def __init__(self, reason: str, paths: Iterable[str | os.PathLike[str]] = ()) -> None:
        super().__init__(reason)
        self.reason = reason
        self.paths = tuple(str(path) for path in paths)


def parse_xml(path: FsPath) -> ET.Element:
    """Parse an XML file and return its root element.

    Raises:
        AssetProblem: for malformed XML (naming the file, line and column) or an unreadable file.
    """
    try:
        return ET.parse(path).getroot()
    except ET.ParseError as exc:
        line, column = exc.position
        raise AssetProblem(
            f"malformed XML in {path} at line {line}, column {column}: {exc}", [path]
        ) from None
    except OSError as exc:
        raise AssetProblem(f"cannot read {path}: {exc.strerror or exc}", [path]) from None


# ----- poses --------------------------------------------------------------------------------


def parse_pose(element: ET.Element | None, where: str) -> Pose:
    """Read an SDF ``<pose>``: ``x y z roll pitch yaw`` (metres, radians; fixed-axis XYZ).

    ``degrees="true"`` and ``rotation_format="quat_xyzw"`` (``x y z qx qy qz qw``) are
    understood. A missing or empty element is the identity.

    Raises:
        AssetProblem: for a pose relative to another frame or with the wrong number of values.
    """
    if element is None or not (element.text or "").strip():
        return Pose([0.0, 0.0, 0.0])
    frame = element.get("relative_to") or element.get("frame") or ""
    if frame.strip() not in ("", "world"):
        raise AssetProblem(f"{where}: <pose> relative to frame {frame!r} is not supported")
    text = str(element.text)
    try:
        values = [float(v) for v in text.split()]
    except ValueError:
        raise AssetProblem(f"{where}: <pose> {text.strip()!r} is not a list of numbers") from None
    if not all(math.isfinite(v) for v in values):
        raise AssetProblem(f"{where}: <pose> {text.strip()!r} has non-finite values")
    if element.get("rotation_format", "euler_rpy") == "quat_xyzw":
        if len(values) != 7:
            raise AssetProblem(f"{where}: <pose> quat_xyzw needs 7 numbers, got {text.strip()!r}")
        return Pose(values[:3], values[3:])
    if len(values) != 6:
        raise AssetProblem(
            f"{where}: <pose> needs 6 numbers 'x y z roll pitch yaw', got {text.strip()!r}"
        )
    angles = values[3:]
    if element.get("degrees", "false").strip().lower() in ("true", "1"):
        angles = [math.radians(a) for a in angles]
    return Pose(values[:3], quat_from_euler(*angles))


def format_pose(pose: Pose) -> str:
    """``x y z roll pitch yaw`` text for an SDF ``<pose>`` (full float precision)."""
    return " ".join(repr(float(v)) for v in (*pose.position.tolist(), *pose.as_euler()))


# ----- finding models and files ------------------------------------------------------------


def _sdf_version(text: str | None) -> tuple[int, ...]:
    try:
        return tuple(int(part) for part in (text or "").strip().split("."))
    except ValueError:
        return ()


def model_sdf_file(model_dir: FsPath) -> FsPath:
    """The SDF file of a Gazebo model directory.

    ``model.config``'s ``<sdf>`` elements name the candidates; the highest ``version`` wins
    (the first listed on a tie). Without ``model.config`` (or with no ``<sdf>`` in it),
    ``model.sdf`` is used.

    Raises:
        AssetProblem: if ``model.config`` is malformed or names a missing file, or there is no SDF.
    """
    config = model_dir / "model.config"
    if config.is_file():
        entries = [
            (_sdf_version(e.get("version")), -i, (e.text or "").strip())
            for i, e in enumerate(parse_xml(config).iter("sdf"))
            if (e.text or "").strip()
        ]
        if entries:
            version, _, name = max(entries)
            chosen = model_dir / name
            if not chosen.is_file():
                label = ".".join(map(str, version)) or "?"
                raise AssetProblem(
                    f"{config} names SDF file {name!r} (version {label}), which does not exist",
                    [chosen],
                )
            return chosen
    fallback = model_dir / "model.sdf"
    if fallback.is_file():
        return fallback
    raise AssetProblem(
        f"model directory {model_dir} has no SDF file (no <sdf> in model.config, no model.sdf)",
        [config, fallback],
    )


def _is_model_dir(path: FsPath) -> bool:
    return path.is_dir() and ((path / "model.config").is_file() or (path / "model.sdf").is_file())


class ModelSearch:
    """Resolves ``model://NAME[/sub/path]`` URIs on an ordered list of model directories.

    Args:
        dirs: Directories searched in order (absolute).
    """

    def __init__(self, dirs: Sequence[FsPath]) -> None:
        self.dirs = list(dirs)

    def model_dir(self, name: str) -> FsPath:
        """The first ``<dir>/<name>`` holding ``model.config`` or ``model.sdf``.

        Raises:
            AssetProblem: naming every directory tried.
        """
        tried = [base / name for base in self.dirs]
        for candidate in tried:
            if _is_model_dir(candidate):
                return candidate
        raise AssetProblem(
            f"model {name!r} not found: no {name}/ with model.config or model.sdf on the model "
            "path (world_config model_paths, GAZEBO_MODEL_PATH, the file's directory and its "
            "models/ subdirectory)",
            tried,
        )

    def model_file(self, uri: str) -> FsPath:
        """The file or directory a ``model://NAME/sub/path`` URI points to.

        Raises:
            AssetProblem: naming every path tried.
        """
        name, _, sub = uri[len("model://") :].partition("/")
        if not sub:
            return self.model_dir(name)
        tried = [base / name / sub for base in self.dirs]
        for candidate in tried:
            if candidate.exists():
                return candidate
        raise AssetProblem(f"{uri!r} not found on the model path", tried)

    def resolve(self, uri: str, relative_to: FsPath, fallback: Sequence[FsPath] = ()) -> FsPath:
        """Resolve a ``model://``, ``file://``, absolute or relative URI to an existing path.

        Args:
            uri: The URI text.
            relative_to: Directory for relative paths.
            fallback: Further directories tried for a relative path.

        Raises:
            AssetProblem: for an unsupported scheme or a path that does not exist.
        """
        text = uri.strip()
        if text.startswith("model://"):
            return self.model_file(text)
        if text.startswith("file://"):
            text = text[len("file://") :]
        elif re.match(r"^[A-Za-z][A-Za-z0-9+.-]*://", text):
            raise AssetProblem(f"URI {uri!r}: only model://, file:// and file paths are supported")
        path = FsPath(text).expanduser()
        tried = (
            [path] if path.is_absolute() else [relative_to / path, *(d / path for d in fallback)]
        )
        for candidate in tried:
            if candidate.exists():
                return candidate.resolve()
        raise AssetProblem(f"{uri!r} not found", tried)


# ----- world files --------------------------------------------------------------------------


@dataclass
class WorldEntry:
    """One ``<include>`` or inline ``<model>`` of a world file.

    Attributes:
        name: Include ``<name>``, else the model name from the URI; the inline model's name.
        model_name: The model the URI names (``NAME`` of ``model://NAME``); the inline name.
        pose: Include ``<pose>`` in the world frame (identity for inline models, whose own
            ``<pose>`` stays in their SDF).
        uri: The include ``<uri>``; None for an inline model.
        element: The inline ``<model>`` element; None for an include.
    """

    name: str
    model_name: str
    pose: Pose
    uri: str | None = None
    element: ET.Element | None = None


def _uri_model_name(uri: str) -> str:
    text = uri.strip().rstrip("/")
    if text.startswith("model://"):
        return text[len("model://") :].split("/")[0]
    path = FsPath(text.removeprefix("file://"))
    return path.parent.name if path.suffix.lower() == ".sdf" and path.stem == "model" else path.stem


def _read_include(element: ET.Element, index: int) -> WorldEntry:
    label = (element.findtext("name") or "").strip()
    uri = (element.findtext("uri") or "").strip()
    if not uri:
        raise AssetProblem(f"<include> #{index} of the world has no <uri>")
    model_name = _uri_model_name(uri)
    name = label or model_name
    return WorldEntry(name, model_name, parse_pose(element.find("pose"), f"include {name!r}"), uri)


def read_world(root: ET.Element) -> tuple[list[WorldEntry], list[tuple[str, AssetProblem]]]:
    """Read the ``<include>`` and ``<model>`` entries of a world, in document order.

    Args:
        root: Root of the parsed ``.world`` file (``<sdf><world>`` or ``<world>``).

    Returns:
        (entries, problems): problems are ``(entry name, problem)`` for entries that could not
        be read (no ``<uri>``, a bad ``<pose>``, an inline model without a name).

    Raises:
        AssetProblem: if there is no ``<world>`` element.
    """
    world = root if root.tag == "world" else root.find("world")
    if world is None:
        raise AssetProblem(
            f"no <world> element (root is <{root.tag}>); to load a single model file use the "
            "'sdf' key instead of 'world_file'"
        )
    entries: list[WorldEntry] = []
    problems: list[tuple[str, AssetProblem]] = []
    for index, element in enumerate(world, start=1):
        try:
            if element.tag == "include":
                entries.append(_read_include(element, index))
            elif element.tag == "model":
                name = element.get("name", "").strip()
                if not name:
                    raise AssetProblem(f"inline <model> #{index} has no name attribute")
                entries.append(WorldEntry(name, name, Pose([0.0, 0.0, 0.0]), element=element))
        except AssetProblem as problem:
            label = (element.findtext("name") or element.get("name") or "").strip()
            problems.append((label or f"<{element.tag}> #{index}", problem))
    return entries, problems


def unsupported_world_elements(root: ET.Element) -> list[str]:
    """Names of world children that describe things this loader does not load (actors...)."""
    world = root if root.tag == "world" else root.find("world")
    if world is None:
        return []
    return [
        f"<{e.tag} name={e.get('name', '')!r}>" for e in world if e.tag in ("actor", "population")
    ]


def inline_model_sdf(element: ET.Element, version: str) -> ET.Element:
    """A standalone ``<sdf>`` tree holding a copy of an inline world ``<model>``."""
    root = ET.Element("sdf", {"version": version})
    root.append(copy.deepcopy(element))
    return root


# ----- rewriting SDF trees for PyBullet ----------------------------------------------------


def sdf_models(root: ET.Element) -> list[ET.Element]:
    """Top-level ``<model>`` elements of an SDF tree (under ``<sdf>`` or ``<sdf><world>``)."""
    holders = [root, *root.findall("world")]
    return [model for holder in holders for model in holder.findall("model")]


def remove_models(root: ET.Element, names: set[str]) -> list[str]:
    """Remove top-level models whose name is in ``names``; return the names removed."""
    removed = []
    for holder in (root, *root.findall("world")):
        for model in holder.findall("model"):
            if model.get("name", "") in names:
                holder.remove(model)
                removed.append(model.get("name", ""))
    return removed


# ----- mesh files -----------------------------------------------------------------------------
