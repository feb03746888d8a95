"""Managers: bookkeeping and bulk operations over a group of objects or agents.

:class:`SimObjectManager` tracks a group of SimObjects (``objects``, ``body_ids``,
``object_ids``, always the same length and order) and spawns them on grids, in batches or from
config. ``AgentManager`` (in ``agent_manager.py``) adds goals, actions, callbacks and
fleet-wide controller settings for agents. A manager with a simulation registers itself there
(``sim.register_manager``), so ``sim.remove_object`` and ``sim.reset`` keep its lists in sync.

Randomised grid spawning draws from the simulation's generator (``sim.rng``), so a run is
reproduced by its seed. Grid and batch spawns of the standard classes go through the bulk path
(``spawn_batch``), which leaves nothing behind when it fails; a class that overrides
``from_params`` spawns one object at a time, and a failure keeps what was already spawned.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Callable, Iterable, Sequence
from contextlib import AbstractContextManager, nullcontext
from pathlib import Path as FsPath
from typing import TYPE_CHECKING, Any, ClassVar, Generic, TypeVar, cast

import numpy as np

from fleet_async.core.agents.agent import Agent
from fleet_async.core.base.config_utils import load_yaml_config, register_class
from fleet_async.core.base.memory import check_spawn_fits
from fleet_async.core.bodies.sim_object import SimObject
from fleet_async.core.bodies.spawn_params import SimObjectSpawnParams
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.managers.grid_spawn import (
    GridSpawnParams,
    assign_by_counts,
    assign_by_probability,
    assign_first_cells,
)

if TYPE_CHECKING:
    from fleet_async.core.managers.host import ManagerHost

__all__ = [
    "ENTITY_REGISTRY",
    "GridSpawnParams",
    "SimObjectManager",
    "get_entity_class",
    "register_entity_class",
]

logger = logging.getLogger(__name__)

T = TypeVar("T", bound=SimObject)

ENTITY_REGISTRY: dict[str, type[SimObject]] = {"agent": Agent, "sim_object": SimObject}
"""Entity ``type:`` names and the classes ``spawn_from_config`` builds for them."""


def register_entity_class(name: str, cls: type[SimObject] | str) -> None:
    """Make ``cls`` spawnable as ``type: name`` in entity configs.

    Args:
        name: The ``type:`` value.
        cls: A SimObject subclass, or its dotted path ``"package.module.ClassName"``.

    Raises:
        ValueError: for an empty name.
        TypeError: if ``cls`` is not a SimObject subclass.
    """
    register_class(ENTITY_REGISTRY, name, cls, SimObject, "register_entity_class")


def get_entity_class(name: str) -> type[SimObject]:
    """The class registered as ``type: name``.

    Raises:
        ValueError: for an unknown name, listing the known ones.
    """
    cls = ENTITY_REGISTRY.get(name) if isinstance(name, str) else None
    if cls is None:
        raise ValueError(f"unknown entity type {name!r}; known types: {sorted(ENTITY_REGISTRY)}")
    return cls


def _check_params(params: Any, what: str) -> SimObjectSpawnParams:
    if not isinstance(params, SimObjectSpawnParams):
        raise TypeError(f"{what}: expected spawn params, got {params!r}")
    return params


class SimObjectManager(Generic[T]):
    """Tracks a group of simulation objects and spawns them in bulk.

    Args:
        sim_core: The simulation; None until an object of a simulation is added.
        object_class: Class the spawn methods instantiate (SimObject or a subclass).
        enable_profiling: Log each spawn call's elapsed time at INFO.
        name: Name under which ``sim_core.get_manager(name)`` finds this manager.

    Attributes:
        name: The manager's name, or None.
        objects: Managed objects, in the order added.
        body_ids: ``objects[i].body_id``.
        object_ids: ``objects[i].object_id``.
        sim_core: The simulation, or None.
        object_class: Class the spawn methods instantiate.
        enable_profiling: Whether spawn calls log their elapsed time.
    """

    _managed_type: ClassVar[type[SimObject]] = SimObject
    name: str | None = None

    def __init__(
        self,
        sim_core: ManagerHost | None = None,
        object_class: type[SimObject] = SimObject,
        enable_profiling: bool = False,
        *,
        name: str | None = None,
    ) -> None:
        if name is not None:  # None keeps a name a subclass has already set
            if not isinstance(name, str):
                raise ValueError(
                    f"{type(self).__name__}.name: expected a string or None, got {name!r}"
                )
            self.name = name
        if not (isinstance(object_class, type) and issubclass(object_class, self._managed_type)):
            raise TypeError(
                f"{type(self).__name__}.object_class: expected a "
                f"{self._managed_type.__name__} subclass, got {object_class!r}"
            )
        self.object_class = object_class
        self.enable_profiling = bool(enable_profiling)
        self.objects: list[T] = []
        self.body_ids: list[int] = []
        self.object_ids: list[int] = []
        self._by_object_id: dict[int, T] = {}
        self.sim_core: ManagerHost | None = None
        if sim_core is not None:
            self._attach(sim_core)

    def __repr__(self) -> str:
        return f"{type(self).__name__}(objects={len(self.objects)})"

    def _attach(self, sim: ManagerHost) -> None:
        """Join ``sim`` so its removals and resets reach this manager."""
        other = None if self.name is None else sim.get_manager(self.name)
        if other is not None and other is not self:
            raise ValueError(
                f"{type(self).__name__}.name: a manager named {self.name!r} is already registered"
            )
        sim.register_manager(self)  # sets self.sim_core

    # ----- bookkeeping --------------------------------------------------------------------

    def add_object(self, obj: T) -> None:
        """Track ``obj``; it must already be part of the simulation.

        An object with ``object_id < 0`` (created without a simulation) is skipped with a
        warning; one already tracked is ignored. A manager without a simulation joins the
        object's simulation.

        Raises:
            TypeError: for an object this manager cannot manage.
            ValueError: for an object of another simulation than the manager's.
        """
        if not isinstance(obj, self._managed_type):
            raise TypeError(
                f"{type(self).__name__}.add_object: expected a {self._managed_type.__name__}, "
                f"got {obj!r}"
            )
        if obj.object_id < 0 or obj.sim_core is None:
            logger.warning("add_object: skipping %r, it is not part of a simulation", obj)
            return
        if self._by_object_id.get(obj.object_id) is obj:
            return
        if self.sim_core is None:
            self._attach(cast("ManagerHost", obj.sim_core))  # an object's is the whole sim
        elif obj.sim_core is not self.sim_core:
            raise ValueError(f"add_object: {obj!r} belongs to another simulation")
        self.objects.append(obj)
        self.body_ids.append(obj.body_id)
        self.object_ids.append(obj.object_id)
        self._by_object_id[obj.object_id] = obj

    def remove_object(self, obj: T) -> bool:
        """Stop tracking ``obj`` (the simulation and PyBullet are not touched).

        ``sim.remove_object`` calls this on every registered manager.

        Returns:
            True if ``obj`` was tracked, False otherwise.
        """
        if self._by_object_id.get(obj.object_id) is not obj:
            return False
        i = self.object_ids.index(obj.object_id)
        del self.objects[i], self.body_ids[i], self.object_ids[i]
        del self._by_object_id[obj.object_id]
        return True

    def clear(self) -> None:
        """Stop tracking every object (``sim.reset`` calls this); the simulation is untouched."""
        self.objects.clear()
        self.body_ids.clear()
        self.object_ids.clear()
        self._by_object_id.clear()

    def get_object_count(self) -> int:
        """Number of managed objects."""
        return len(self.objects)

    # ----- poses --------------------------------------------------------------------------

    def _at(self, index: int, what: str) -> T:
        if not -len(self.objects) <= index < len(self.objects):
            raise IndexError(f"{what}: index {index} out of range for {len(self.objects)} objects")
        return self.objects[index]

    def get_pose(self, object_index: int) -> Pose:
        """Current pose of ``objects[object_index]``.

        Raises:
            IndexError: for an index out of range.
        """
        return self._at(object_index, "get_pose").get_pose()

    def get_all_poses(self) -> list[Pose]:
        """Current poses of every object, in ``objects`` order."""
        return [obj.get_pose() for obj in self.objects]

    def get_poses_dict(self) -> dict[int, Pose]:
        """``{object_id: pose}`` for every object."""
        return {obj.object_id: obj.get_pose() for obj in self.objects}

    def set_pose_all(self, pose_factory: Callable[[T], Pose]) -> None:
        """``obj.set_pose(pose_factory(obj))`` for every object, in order."""
        for obj in list(self.objects):
            obj.set_pose(pose_factory(obj))

    # ----- spawning -----------------------------------------------------------------------

    def spawn_objects_grid(
        self,
        num_objects: int,
        grid_params: GridSpawnParams,
        spawn_params: SimObjectSpawnParams,
        *,
        name_prefix: str | None = None,
    ) -> list[T]:
        """Spawn ``num_objects`` copies of ``spawn_params`` on the first cells of the grid.

        Object ``i`` goes to cell ``i`` (X fastest, then Y, then Z) with the orientation of
        ``spawn_params.initial_pose``; with ``name_prefix`` it is named ``<prefix>_<i>``.

        Raises:
            ValueError: if ``num_objects`` is negative or exceeds ``grid_params.total_cells``.
        """
        _check_params(spawn_params, "spawn_objects_grid.spawn_params")
        cells, kinds = assign_first_cells(grid_params, num_objects)
        return self._spawn_on_cells(
            grid_params, cells, kinds, [spawn_params], "spawn_objects_grid", name_prefix
        )

    def spawn_grid_mixed(
        self,
        num_objects: int,
        grid_params: GridSpawnParams,
        spawn_params_list: Sequence[tuple[SimObjectSpawnParams, float]],
        *,
        name_prefix: str | None = None,
    ) -> list[T]:
        """Fill the first ``num_objects`` cells, each with a type drawn by probability.

        One uniform draw from ``sim_core.rng`` per cell picks type ``i`` with probability
        ``p_i``; a cell whose draw falls past the sum of the probabilities stays empty, so at
        most ``num_objects`` objects spawn.

        Args:
            num_objects: Cells to visit (<= ``grid_params.total_cells``).
            grid_params: The grid.
            spawn_params_list: ``(spawn_params, probability)`` pairs; each probability in
                [0, 1], their sum <= 1.

        Raises:
            ValueError: for bad probabilities, too many objects, or no simulation.
        """
        what = "spawn_grid_mixed"
        params, probs = self._unpack(spawn_params_list, what)
        cells, kinds = assign_by_probability(
            grid_params, num_objects, probs, lambda: self._rng(what)
        )
        return self._spawn_on_cells(grid_params, cells, kinds, params, what, name_prefix)

    def spawn_grid_counts(
        self,
        grid_params: GridSpawnParams,
        spawn_params_count_list: Sequence[tuple[SimObjectSpawnParams, int]],
        *,
        name_prefix: str | None = None,
    ) -> list[T]:
        """Spawn exactly ``count`` objects of each type on cells shuffled with ``sim_core.rng``.

        Objects are returned (and tracked) in cell order; cells left over stay empty.

        Raises:
            ValueError: if the total count exceeds ``grid_params.total_cells``, for a negative
                count, or without a simulation.
        """
        what = "spawn_grid_counts"
        params, counts = self._unpack(spawn_params_count_list, what)
        cells, kinds = assign_by_counts(grid_params, counts, lambda: self._rng(what))
        return self._spawn_on_cells(grid_params, cells, kinds, params, what, name_prefix)

    def spawn_objects_batch(self, params_list: Sequence[SimObjectSpawnParams]) -> list[T]:
        """Spawn one object per params with GUI rendering suspended (``sim_core.batch_spawn``)."""
        prepared = [
            self._prepare_params(_check_params(prm, f"spawn_objects_batch[{i}]"))
            for i, prm in enumerate(params_list)
        ]
        return self._spawn_params(prepared, "spawn_objects_batch")

    def spawn_from_config(
        self, entities_yaml: Sequence[dict[str, Any]], *, source: str | None = None
    ) -> list[T]:
        """Spawn entities from config mappings, dispatching on their ``type:`` (default "agent").

        Each mapping (without ``type``) goes to ``cls.from_dict(mapping, sim_core)`` of the
        registered class (see :func:`register_entity_class`). Types are checked for every entry
        before anything spawns.

        Raises:
            ValueError: for an unknown type (listing the known ones), a type this manager cannot
                manage, or a bad entry, naming ``entities[i]`` and ``source``.
        """
        return self._spawn_entities(entities_yaml, "entities", source)

    def spawn_entity(self, config: dict[str, Any], *, label: str = "entity") -> T:
        """Spawn and track one entity from a config mapping, like one entry of
        :meth:`spawn_from_config`.

        Args:
            config: The entity mapping; its ``type:`` (default "agent") picks the class.
            label: Where the entry came from, prefixed to error messages (e.g.
                ``"scenario.yaml: entities[2]"``).

        Raises:
            ValueError: for an unknown type, a type this manager cannot manage, or a bad entry,
                prefixed with ``label``.
        """
        cls, prepared = self._plan_entity(config, label)
        return self._spawn_each([self._entity_maker(label, cls, prepared)], "spawn_entity")[0]

    def spawn_from_yaml(self, yaml_path: str | FsPath, key: str = "entities") -> list[T]:
        """Spawn the entities listed under ``key`` in a YAML file (``[]`` if it has no ``key``).

        Raises:
            FileNotFoundError: if ``yaml_path`` does not exist.
            ValueError: as :meth:`spawn_from_config`, naming the file.
        """
        entries = load_yaml_config(yaml_path).get(key)
        if entries is None:
            return []
        return self._spawn_entities(entries, key, str(yaml_path))

    # ----- spawning internals -------------------------------------------------------------

    def _prepare_params(self, params: SimObjectSpawnParams) -> SimObjectSpawnParams:
        """Adjust spawn params before use (AgentManager merges its fleet controller)."""
        return params

    def _prepare_config(self, cls: type[SimObject], config: dict[str, Any]) -> dict[str, Any]:
        """Adjust an entity config before ``cls.from_dict`` (AgentManager hook)."""
        return config

    def _rng(self, what: str) -> np.random.Generator:
        if self.sim_core is None:
            raise ValueError(
                f"{what}: needs the simulation's random generator; give the manager a sim_core"
            )
        return self.sim_core.rng

    @staticmethod
    def _unpack(pairs: Sequence[tuple[Any, Any]], what: str) -> tuple[list[Any], list[Any]]:
        if not pairs:
            raise ValueError(f"{what}: expected at least one (spawn_params, value) pair")
        params, values = [], []
        for i, pair in enumerate(pairs):
            if not (isinstance(pair, (tuple, list)) and len(pair) == 2):
                raise ValueError(f"{what}: entry {i} is not a (spawn_params, value) pair: {pair!r}")
            params.append(_check_params(pair[0], f"{what}: entry {i}"))
            values.append(pair[1])
        return params, values

    def _maker(self, params: SimObjectSpawnParams) -> Callable[[], SimObject]:
        return lambda: self.object_class.from_params(params, self.sim_core)

    def _spawn_on_cells(
        self,
        grid: GridSpawnParams,
        cells: np.ndarray,
        kinds: np.ndarray,
        params: list[SimObjectSpawnParams],
        what: str,
        name_prefix: str | None = None,
    ) -> list[T]:
        """Spawn ``params[kinds[k]]`` at ``cells[k]`` in its orientation (``<name_prefix>_<k>``)."""
        if self.sim_core is not None:
            check_spawn_fits(len(cells), self.sim_core.params.memory_share, what)
        positions = grid.cell_positions(cells)
        prepared = [self._prepare_params(prm) for prm in params]
        placed = [
            dataclasses.replace(
                prepared[kind],
                initial_pose=Pose(positions[k], prepared[kind].initial_pose.orientation),
                **({} if name_prefix is None else {"name": f"{name_prefix}_{k}"}),
            )
            for k, kind in enumerate(kinds.tolist())
        ]
        return self._spawn_params(placed, what)

    def _spawn_params(self, params_list: list[SimObjectSpawnParams], what: str) -> list[T]:
        """Spawn from params: in bulk when the class spawns the standard way, else one by one.

        The bulk path (``object_class.spawn_batch``) is all-or-nothing: on an error nothing it
        created is left behind. A class that overrides ``from_params`` is honoured by spawning
        one by one, where what was spawned before an error stays tracked.
        """
        cls = self.object_class
        standard = getattr(cls.from_params, "__func__", None) in (
            SimObject.from_params.__func__,  # type: ignore[attr-defined]  # a classmethod's
            Agent.from_params.__func__,  # type: ignore[attr-defined]  # function
        )
        if self.sim_core is None or not standard:
            return self._spawn_each((self._maker(prm) for prm in params_list), what)
        start = time.perf_counter()
        spawned = cast(list[T], cls.spawn_batch(params_list, self.sim_core))
        for obj in spawned:
            self.add_object(obj)
        if self.enable_profiling:
            elapsed_ms = (time.perf_counter() - start) * 1e3
            logger.info("%s: spawned %d objects in %.1f ms", what, len(spawned), elapsed_ms)
        return spawned

    def _spawn_entities(self, entries: Any, key: str, source: str | None) -> list[T]:
        where = f"{source}: " if source else ""
        if not isinstance(entries, list):
            raise ValueError(f"{where}{key}: expected a list of mappings, got {entries!r}")
        plan: list[tuple[str, type[SimObject], dict[str, Any]]] = []
        for i, entry in enumerate(entries):
            label = f"{where}{key}[{i}]"
            plan.append((label, *self._plan_entity(entry, label)))
        return self._spawn_each(
            (self._entity_maker(label, cls, config) for label, cls, config in plan),
            "spawn_from_config",
        )

    def _plan_entity(self, entry: Any, label: str) -> tuple[type[SimObject], dict[str, Any]]:
        """The class and prepared config for one entity mapping, checked before spawning."""
        if not isinstance(entry, dict):
            raise ValueError(f"{label}: expected a mapping, got {entry!r}")
        config = dict(entry)
        type_name = config.pop("type", "agent")
        try:
            cls = get_entity_class(type_name)
        except ValueError as exc:
            raise ValueError(f"{label}: {exc}") from None
        if not issubclass(cls, self._managed_type):
            raise ValueError(
                f"{label}: type {type_name!r} ({cls.__name__}) cannot join a "
                f"{type(self).__name__}, which manages {self._managed_type.__name__} objects"
            )
        return cls, self._prepare_config(cls, config)

    def _entity_maker(
        self, label: str, cls: type[SimObject], config: dict[str, Any]
    ) -> Callable[[], SimObject]:
        def make() -> SimObject:
            try:
                return cls.from_dict(config, self.sim_core)
            except ValueError as exc:
                raise ValueError(f"{label}: {exc}") from exc

        return make

    def _spawn_each(self, makers: Iterable[Callable[[], SimObject]], what: str) -> list[T]:
        """Create and track objects one by one; on an error the ones made so far stay tracked."""
        start = time.perf_counter()
        spawned: list[T] = []
        batch: AbstractContextManager[Any] = (
            self.sim_core.batch_spawn() if self.sim_core is not None else nullcontext()
        )
        with batch:
            for make in makers:
                obj = cast(T, make())
                self.add_object(obj)
                spawned.append(obj)
        if self.enable_profiling:
            elapsed_ms = (time.perf_counter() - start) * 1e3
            logger.info("%s: spawned %d objects in %.1f ms", what, len(spawned), elapsed_ms)
        return spawned
