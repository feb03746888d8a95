"""Loading world geometry: Gazebo ``.world`` files, single SDF files, mesh directories.

``sim.load_world(world_config)`` turns static scenery into STATIC SimObjects (mass 0), so the
collision system checks moving objects against them and they never move. A call loads
everything it can into PyBullet first and wraps the bodies into SimObjects only at the end: if
anything failed and ``on_error`` is ``"raise"`` (the default), the bodies already created are
removed and :class:`WorldLoadError` lists every failure; nothing half-loaded remains and no
spawn event was emitted. With ``on_error: "warn"`` each failure is logged and the rest loads.

Models that Open-RMF marks as doors, lifts and workcells become Door, Elevator and Workcell
devices instead of static bodies (``devices/rmf_world.py``). The ``world_config``
mapping is checked in ``world_config.py``; file-format work (``model://``
lookup, SDF rewriting for PyBullet) lives in ``gazebo_world.py`` and ``sdf_rewriter.py``.
"""

from __future__ import annotations

import logging
import os
import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path as FsPath
from typing import TYPE_CHECKING, Any, cast

import pybullet as p

from fleet_async.core.base.types import CollisionMode
from fleet_async.core.bodies.sim_object import SimObject
from fleet_async.core.devices.rmf_world import (
    device_class,
    rmf_device_params,
    rmf_workcell_params,
)
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.scenario.gazebo_world import (
    AssetProblem,
    ModelSearch,
    WorldEntry,
    inline_model_sdf,
    model_sdf_file,
    parse_xml,
    read_world,
    remove_models,
    sdf_models,
    unsupported_world_elements,
)
from fleet_async.core.scenario.sdf_rewriter import SdfRewriter
from fleet_async.core.scenario.world_config import (
    MESH_SUFFIXES,
    WorldOptions,
    model_search_dirs,
    read_world_config,
)
from fleet_async.core.world.backend import native_output_logged
from fleet_async.core.world.link_colours import one_colour_per_link
from fleet_async.core.world.shapes import forget_body_shape, record_body_shape

if TYPE_CHECKING:
    from fleet_async.core.sim.kernel import SimulationKernel

__all__ = ["WorldLoadError", "WorldLoadFailure", "WorldLoadingApi"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class WorldLoadFailure:
    """One model or file that could not be loaded.

    Attributes:
        name: The model's name (include ``<name>``, model name, or mesh file stem).
        reason: What went wrong.
        paths: The paths tried or involved (absolute).
    """

    name: str
    reason: str
    paths: tuple[str, ...] = ()

    def __str__(self) -> str:
        tried = f" [paths: {', '.join(self.paths)}]" if self.paths else ""
        return f"{self.name!r}: {self.reason}{tried}"


class WorldLoadError(RuntimeError):
    """Raised by ``load_world`` when some models could not be loaded; nothing stays loaded.

    Attributes:
        source: The world file, SDF file or mesh directory (absolute).
        failures: Every failure, in the order met.
    """

    def __init__(self, source: str, failures: Sequence[WorldLoadFailure]) -> None:
        self.source = source
        self.failures = list(failures)
        lines = "\n".join(f"  - {failure}" for failure in self.failures)
        super().__init__(
            f"load_world({source}): {len(self.failures)} model(s) could not be loaded, so "
            f"nothing was loaded (set world_config on_error: 'warn' to load the rest):\n{lines}"
        )


# ----- loading bodies into PyBullet -----------------------------------------------------------


@dataclass
class LoadedBody:
    """A body created by this load, not yet wrapped in a SimObject."""

    name: str
    body: int
    user_data: dict[str, Any]
    collision_shape: int = -1  # a shape this load created for the body (mesh_dir)


class BodyLoader:
    """Creates static bodies in one PyBullet client and collects failures by name.

    Args:
        client: PyBullet physics client id.
        rewriter: Prepares SDF trees and mesh files for PyBullet.
        skip: Model names not to load.
    """

    def __init__(self, client: int, rewriter: SdfRewriter, skip: set[str]) -> None:
        self.client = client
        self.rewriter = rewriter
        self.skip = skip
        self.skipped: set[str] = set()
        self.bodies: list[LoadedBody] = []
        self.failures: list[WorldLoadFailure] = []
        self.devices: list[Any] = []  # spawn params of Open-RMF doors, lifts and workcells

    def fail(self, name: str, problem: AssetProblem) -> None:
        """Record that ``name`` could not be loaded."""
        self.failures.append(WorldLoadFailure(name, problem.reason, problem.paths))

    def skips(self, *names: str) -> bool:
        """Whether any of ``names`` is in ``skip_models`` (remembering which matched)."""
        hits = self.skip.intersection(names)
        self.skipped |= hits
        return bool(hits)

    def load_sdf_tree(
        self, root: ET.Element, sdf_file: FsPath, name: str, force_copy: bool = False
    ) -> list[int] | None:
        """Prepare and load an SDF tree whose relative paths are relative to ``sdf_file``.

        Returns:
            The new static body ids (none for a file without models, e.g. a light), or None
            if it failed; every problem is then recorded under ``name``.
        """
        changed, problems = self.rewriter.prepare(root, sdf_file.parent)
        for problem in problems:
            self.fail(name, problem)
        if problems:
            return None
        if not sdf_models(root):
            logger.info("load_world: %r (%s) holds no <model>; nothing to load", name, sdf_file)
            return []
        path = self.rewriter.write(root, name) if changed or force_copy else sdf_file
        try:
            with native_output_logged(logger):
                bodies = [int(b) for b in p.loadSDF(str(path), physicsClientId=self.client)]
        except p.error as exc:
            paths = dict.fromkeys([sdf_file, path])
            self.fail(name, AssetProblem(f"PyBullet could not load the SDF ({exc})", paths))
            return None
        if not bodies:
            self.fail(name, AssetProblem("PyBullet loaded no body from the SDF", [sdf_file]))
            return None
        for body in bodies:
            for link in range(-1, p.getNumJoints(body, physicsClientId=self.client)):
                p.changeDynamics(body, link, mass=0.0, physicsClientId=self.client)
            one_colour_per_link(self.client, body)  # the GUI and recordings show it alike
        return bodies

    def add(self, name: str, body: int, user_data: dict[str, Any], shape: int = -1) -> None:
        """Keep a created body for wrapping (or removal on failure)."""
        self.bodies.append(LoadedBody(name, body, user_data, shape))

    def place(self, body: int, pose: Pose) -> None:
        """Move ``body`` by ``pose`` (applied on top of the pose its SDF gave it)."""
        pos, orn = p.getBasePositionAndOrientation(body, physicsClientId=self.client)
        new_pos, new_orn = pose.compose(Pose(pos, orn)).as_position_orientation()
        p.resetBasePositionAndOrientation(body, new_pos, new_orn, physicsClientId=self.client)

    def body_model_name(self, body: int) -> str:
        """The model name PyBullet recorded for ``body``."""
        return str(p.getBodyInfo(body, physicsClientId=self.client)[1].decode("utf-8"))

    def load_mesh(self, name: str, path: FsPath) -> None:
        """One static body at the origin from a mesh file (collision as a concave trimesh).

        Raises:
            AssetProblem: for a missing or invalid mesh, or one PyBullet rejects.
        """
        mesh = str(self.rewriter.mesh_file(path))
        shape = -1
        try:
            # Building geometry is concave: a convex hull would fill every room.
            shape = p.createCollisionShape(
                p.GEOM_MESH,
                fileName=mesh,
                flags=p.GEOM_FORCE_CONCAVE_TRIMESH,
                physicsClientId=self.client,
            )
            visual = p.createVisualShape(p.GEOM_MESH, fileName=mesh, physicsClientId=self.client)
        except p.error as exc:
            if shape >= 0:
                p.removeCollisionShape(shape, physicsClientId=self.client)
            raise AssetProblem(f"PyBullet could not read the mesh ({exc})", [path]) from None
        body = p.createMultiBody(0.0, shape, visual, [0.0, 0.0, 0.0], physicsClientId=self.client)
        record_body_shape(self.client, body, shape)
        self.add(name, body, {"world_source": str(path.parent), "model_file": str(path)}, shape)

    def discard(self, start: int = 0) -> None:
        """Remove the bodies from index ``start`` on (and shapes created for them)."""
        for item in reversed(self.bodies[start:]):
            p.removeBody(item.body, physicsClientId=self.client)
            forget_body_shape(self.client, item.body)
            if item.collision_shape >= 0:
                p.removeCollisionShape(item.collision_shape, physicsClientId=self.client)
        del self.bodies[start:]


# ----- the three sources ----------------------------------------------------------------------


def _entry_sdf(loader: BodyLoader, entry: WorldEntry, world_file: FsPath) -> FsPath:
    """The SDF file an ``<include>`` refers to."""
    target = loader.rewriter.search.resolve(str(entry.uri), world_file.parent)
    return model_sdf_file(target) if target.is_dir() else target


def _load_entry(loader: BodyLoader, entry: WorldEntry, world: FsPath, version: str) -> None:
    if entry.element is not None:
        root, sdf_file, force = inline_model_sdf(entry.element, version), world, True
    else:
        sdf_file, force = _entry_sdf(loader, entry, world), False
        root = parse_xml(sdf_file)
    bodies = loader.load_sdf_tree(root, sdf_file, entry.name, force_copy=force) or []
    for body in bodies:
        loader.place(body, entry.pose)
        name = entry.name if len(bodies) == 1 else f"{entry.name}/{loader.body_model_name(body)}"
        data = {"world_source": str(world), "model_file": str(sdf_file)}
        loader.add(name, body, data | ({"uri": entry.uri} if entry.uri else {}))


def _load_world_file(loader: BodyLoader, world: FsPath) -> None:
    try:
        root = parse_xml(world)
        entries, problems = read_world(root)
    except AssetProblem as problem:
        loader.fail(world.name, problem)
        return
    for name, issue in problems:
        loader.fail(name, issue)
    for element in unsupported_world_elements(root):
        logger.warning("load_world(%s): %s is not loaded (not supported)", world, element)
    version = root.get("version", "1.6")
    for entry in entries:
        if loader.skips(entry.name, entry.model_name):
            continue
        try:
            device: Any = rmf_workcell_params(entry.model_name, entry.name, entry.pose)
            if entry.element is not None:
                device = rmf_device_params(entry.element, f"model {entry.name!r}")
            if device is not None:
                loader.devices.append(device)
                continue
            _load_entry(loader, entry, world, version)
        except ValueError as exc:
            loader.fail(entry.name, AssetProblem(str(exc), [world]))
        except AssetProblem as problem:
            loader.fail(entry.name, problem)


def _load_sdf_file(loader: BodyLoader, sdf_file: FsPath) -> None:
    try:
        root = parse_xml(sdf_file)
    except AssetProblem as problem:
        loader.fail(sdf_file.stem, problem)
        return
    names = [model.get("name", "") for model in sdf_models(root)]
    removed = remove_models(root, {n for n in names if loader.skips(n)})
    label = ", ".join(n for n in names if n not in removed) or sdf_file.stem
    bodies = loader.load_sdf_tree(root, sdf_file, label, force_copy=bool(removed))
    for body in bodies or []:
        data = {"world_source": str(sdf_file), "model_file": str(sdf_file)}
        loader.add(loader.body_model_name(body), body, data)


def _load_mesh_dir(loader: BodyLoader, mesh_dir: FsPath) -> None:
    files = sorted(f for f in mesh_dir.iterdir() if f.suffix.lower() in MESH_SUFFIXES)
    if not files:
        raise ValueError(f"load_world: mesh_dir {mesh_dir} holds no .obj or .stl file")
    for path in files:
        if loader.skips(path.stem):
            continue
        try:
            loader.load_mesh(path.stem, path)
        except AssetProblem as problem:
            loader.fail(path.stem, problem)


_LOADERS: dict[str, Callable[[BodyLoader, FsPath], None]] = {
    "world_file": _load_world_file,
    "sdf": _load_sdf_file,
    "mesh_dir": _load_mesh_dir,
}


class WorldLoadingApi:
    """``load_world`` for MultiRobotSimulationCore."""

    def load_world(
        self,
        world_config: Mapping[str, Any],
        skip_models: Sequence[str] | None = None,
        *,
        base_dir: str | os.PathLike[str] | None = None,
    ) -> list[SimObject]:
        """Load static world geometry; every body becomes a STATIC SimObject (mass 0).

        Args:
            world_config: One source, checked in this order: ``world_file`` (a Gazebo
                ``.world``: its ``<include>`` models, placed at their ``<pose>`` composed with
                the pose their SDF gives them, and inline ``<model>`` elements), ``sdf`` (an
                SDF file; a relative path is also searched in ``model_paths`` and
                pybullet_data) or ``mesh_dir`` (each ``.obj`` / ``.stl`` file in it becomes a
                body at the origin, collision as a concave triangle mesh). Options:
                ``skip_models`` (names), ``model_paths`` (directories searched for
                ``model://NAME`` before ``GAZEBO_MODEL_PATH``, the file's directory and its
                ``models`` subdirectory), ``on_error`` ("raise" or "warn").
            skip_models: More model names to skip: an include's ``<name>`` or the model name
                of its URI, an SDF model's name, or a mesh file's stem.
            base_dir: Directory relative paths in ``world_config`` are relative to (default:
                the working directory); scenario files pass their own directory.

        Returns:
            The new objects in load order (Open-RMF doors, lifts and workcells last, as
            devices; an empty config loads nothing: ``[]``), named after their include
            ``<name>`` (else the URI's model name), SDF model name or mesh file stem. Their
            ``user_data`` holds ``world_source`` (the source path), ``model_file`` (the SDF or
            mesh file the body came from) and, for includes, ``uri``.

        Raises:
            WorldLoadError: listing every model that failed (name, reason, paths), after
                removing what this call loaded; unless ``on_error`` is "warn", which logs one
                warning per failure and returns what loaded.
            FileNotFoundError: if the source or a ``model_paths`` directory does not exist.
            ValueError / TypeError: for a bad ``world_config`` (unknown key, no source...).
        """
        sim = cast("SimulationKernel", self)
        if isinstance(world_config, Mapping) and not world_config:
            logger.info("load_world({}): an empty world config; nothing to load")
            return []  # as the reference implementation: nothing asked, nothing loaded
        opts = read_world_config(world_config, skip_models, base_dir)
        loader = _load_bodies(sim, opts)
        if loader.failures and opts.on_error == "raise":
            loader.discard()
            raise WorldLoadError(str(opts.source), loader.failures)
        for failure in loader.failures:
            logger.warning("load_world(%s): not loaded: %s", opts.source, failure)
        unmatched = sorted(opts.skip - loader.skipped)
        if unmatched:
            logger.warning("load_world(%s): skip_models %s matched nothing", opts.source, unmatched)
        objects = _wrap(sim, loader)
        try:
            for params in loader.devices:
                objects.append(device_class(params).from_params(params, sim))
        except BaseException:
            for obj in reversed(objects):
                sim.remove_object(obj)
            raise
        return objects


def _load_bodies(sim: SimulationKernel, opts: WorldOptions) -> BodyLoader:
    """Create the bodies of ``opts.source`` in PyBullet (not yet SimObjects)."""
    search = ModelSearch(model_search_dirs(opts.model_paths, opts.source, opts.key))
    # Rewritten SDF copies and converted meshes are only read during loadSDF / shape creation.
    with tempfile.TemporaryDirectory(prefix="fleet_async_world_") as workdir:
        loader = BodyLoader(sim.client, SdfRewriter(search, FsPath(workdir)), opts.skip)
        try:
            with sim.batch_spawn():
                _LOADERS[opts.key](loader, opts.source)
        except BaseException:
            loader.discard()
            raise
    return loader


def _wrap(sim: SimulationKernel, loader: BodyLoader) -> list[SimObject]:
    """Register every loaded body as a STATIC SimObject; on error, leave nothing behind."""
    objects: list[SimObject] = []
    try:
        for item in loader.bodies:
            objects.append(
                SimObject(
                    item.body,
                    sim_core=sim,
                    pickable=False,
                    mass=0.0,
                    collision_mode=CollisionMode.STATIC,
                    name=item.name,
                    user_data=item.user_data,
                )
            )
    except BaseException:
        for obj in reversed(objects):
            sim.remove_object(obj)
        loader.discard(start=len(objects))
        raise
    logger.info("load_world: %d static object(s) loaded", len(objects))
    return objects
