"""Entities of a scenario: planning each entry, grids, managers, files, and queued actions.

Every entry is checked before anything spawns (``spawn_entities`` is all or nothing); see
:meth:`fleet_async.core.scenario.build.ScenarioApi.spawn_robots_from_config` for the entry format.
"""

from __future__ import annotations

import dataclasses
import os
import typing
from collections.abc import Callable, Mapping
from pathlib import Path as FsPath
from typing import TYPE_CHECKING, Any

import numpy as np

from fleet_async.core.actions.action import Action, MoveAction, WaitAction
from fleet_async.core.actions.arm_actions import JointAction, PoseAction
from fleet_async.core.actions.pick_drop import DropAction, PickAction
from fleet_async.core.agents.agent import Agent
from fleet_async.core.agents.agent_params import AgentSpawnParams
from fleet_async.core.base.config_utils import dataclass_from_dict
from fleet_async.core.base.memory import check_spawn_fits
from fleet_async.core.base.paths import resolve_data_file
from fleet_async.core.base.reprs import short_repr
from fleet_async.core.bodies.models import resolve_model
from fleet_async.core.bodies.sim_object import SimObject
from fleet_async.core.bodies.spawn_params import SimObjectSpawnParams
from fleet_async.core.devices import (
    Door,
    DoorParams,
    Elevator,
    ElevatorParams,
    Workcell,
    WorkcellParams,
)
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.geometry.pose_config import pose_from_config
from fleet_async.core.geometry.waypoints import Path
from fleet_async.core.managers.agent_manager import AgentManager
from fleet_async.core.managers.grid_spawn import GridSpawnParams
from fleet_async.core.managers.sim_object_manager import SimObjectManager, get_entity_class
from fleet_async.core.scenario.errors import (
    config_context,
    expect_type,
    reject_unknown_keys,
)
from fleet_async.core.world.shapes import ShapeParams

if TYPE_CHECKING:
    from fleet_async.core.scenario.host import EntityHost

__all__ = ["ACTION_TYPES", "SCENARIO_ENTITY_KEYS", "spawn_entities"]

ACTION_TYPES: dict[str, type[Action]] = {
    "move": MoveAction,
    "wait": WaitAction,
    "pick": PickAction,
    "drop": DropAction,
    "joint": JointAction,
    "pose": PoseAction,
}
"""``actions: [{type: ...}]`` names and the Action dataclasses they build (add your own)."""

# Keys of an entity mapping that the scenario handles itself; the rest go to the class.
SCENARIO_ENTITY_KEYS = ("type", "grid", "manager", "batch_controller", "actions")
# Classes whose spawn params are known, so their entries are checked before anything spawns
# and their grids take the bulk spawn path. Other classes spawn one by one via ``from_dict``.
_KNOWN_PARAMS: dict[type[SimObject], type[SimObjectSpawnParams]] = {
    Agent: AgentSpawnParams,
    SimObject: SimObjectSpawnParams,
    Door: DoorParams,
    Elevator: ElevatorParams,
    Workcell: WorkcellParams,
}


@dataclasses.dataclass
class _EntityPlan:
    """One checked ``entities[i]`` entry, ready to spawn."""

    label: str
    type_name: str
    cls: type[SimObject]
    config: dict[str, Any]
    params: SimObjectSpawnParams | None  # known classes only
    grid: GridSpawnParams | None
    count: int
    manager: SimObjectManager[Any] | None
    batch_controller: str | None
    actions: list[_ActionSpec]


def spawn_entities(
    sim: EntityHost,
    entries: Any,
    where: str,
    base_dir: str | os.PathLike[str] | None,
    declared: list[str] | None,
) -> list[SimObject]:
    """Check every entry, then spawn them; on an error remove what this call added."""
    expect_type(entries, (list, tuple), "a list of mappings", where, "entities")
    plans = [
        _plan_entity(sim, entry, f"entities[{i}]", where, base_dir, declared)
        for i, entry in enumerate(entries)
    ]
    share = sim.params.memory_share
    for plan in plans:  # the entry that cannot fit by itself is named first
        if plan.grid is not None:
            check_spawn_fits(plan.count, share, f"{where}{plan.label}.grid")
    total = sum(p.count if p.grid is not None else 1 for p in plans)
    check_spawn_fits(total, share, f"{where}entities")
    before = {obj.object_id for obj in sim.sim_objects}
    fresh: list[SimObjectManager[Any]] = []
    spawned: list[SimObject] = []
    try:
        for plan in plans:
            with config_context(where, plan.label):
                spawned.extend(_spawn_plan(sim, plan, fresh, where))
    except BaseException:
        for obj in [o for o in sim.sim_objects if o.object_id not in before]:
            sim.remove_object(obj)
        for manager in fresh:
            sim.unregister_manager(manager)
        raise
    return spawned


def _plan_entity(
    sim: EntityHost,
    entry: Any,
    label: str,
    where: str,
    base_dir: str | os.PathLike[str] | None,
    declared: list[str] | None,
) -> _EntityPlan:
    config = dict(expect_type(entry, dict, "a mapping", where, label))
    type_name = config.pop("type", "agent")
    with config_context(where, f"{label}.type"):
        cls = get_entity_class(type_name)
    scenario = {key: config.pop(key) for key in SCENARIO_ENTITY_KEYS[1:] if key in config}
    params_cls = _KNOWN_PARAMS.get(cls)
    if params_cls is not None:
        valid = [*params_cls.field_names(), "pose", "yaw", *SCENARIO_ENTITY_KEYS]
        reject_unknown_keys(list(config), valid, where, label)
    is_agent = issubclass(cls, Agent)
    for key in ("batch_controller", "actions"):
        if key in scenario and not is_agent:
            raise ValueError(
                f"{where}{label}.{key}: only agents take {key!r}; type {type_name!r} is "
                f"{cls.__name__}"
            )
    grid, count = _plan_grid(scenario.get("grid"), config, where, label)
    manager = _plan_manager(sim, scenario, cls, where, label, declared)
    _resolve_files(config, sim, base_dir, where, label)
    if isinstance(config.get("pose"), Mapping):
        with config_context(where, f"{label}.pose"):
            config["pose"] = pose_from_config(config["pose"])
    params = None
    if params_cls is not None:
        with config_context(where, label):
            params = params_cls.from_dict(config)
    actions = _plan_actions(scenario.get("actions"), where, f"{label}.actions")
    batch = scenario.get("batch_controller")
    if batch is not None:
        expect_type(batch, str, "a batch controller name", where, f"{label}.batch_controller")
    return _EntityPlan(label, type_name, cls, config, params, grid, count, manager, batch, actions)


def _plan_grid(
    grid_config: Any, config: dict[str, Any], where: str, label: str
) -> tuple[GridSpawnParams | None, int]:
    if grid_config is None:
        return None, 1
    for key in ("pose", "initial_pose"):
        if key in config:
            raise ValueError(
                f"{where}{label}: {key!r} cannot be combined with 'grid' (the grid places each "
                "entity; use 'yaw' to orient them)"
            )
    try:
        grid = GridSpawnParams.from_dict(grid_config)
    except ValueError as exc:
        message = str(exc)
        message = message if message.startswith("grid") else f"grid: {message}"
        raise ValueError(f"{where}{label}.{message}") from exc
    count = grid_config.get("count", grid.total_cells)
    return grid, int(count)


def _plan_manager(
    sim: EntityHost,
    scenario: dict[str, Any],
    cls: type[SimObject],
    where: str,
    label: str,
    declared: list[str] | None,
) -> SimObjectManager[Any] | None:
    name = scenario.get("manager")
    if name is None:
        return None
    expect_type(name, str, "a manager name", where, f"{label}.manager")
    if "batch_controller" in scenario:
        raise ValueError(
            f"{where}{label}: give 'manager' or 'batch_controller', not both (set the batch "
            f"controller on manager {name!r} instead)"
        )
    manager = sim.get_manager(name)
    if manager is None:
        known = (
            f"declared managers: {declared}"
            if declared is not None
            else ("declare it under 'managers:' or register it with sim.register_manager")
        )
        raise ValueError(f"{where}{label}.manager: no manager named {name!r}; {known}")
    if not isinstance(manager, SimObjectManager):
        raise ValueError(f"{where}{label}.manager: {name!r} is not a SimObjectManager")
    if isinstance(manager, AgentManager) and not issubclass(cls, Agent):
        raise ValueError(
            f"{where}{label}.manager: {name!r} is an agent manager; {cls.__name__} is not an Agent"
        )
    return manager


def _spawn_plan(
    sim: EntityHost,
    plan: _EntityPlan,
    fresh: list[SimObjectManager[Any]],
    where: str,
) -> list[SimObject]:
    manager = plan.manager
    if manager is None and (plan.grid is not None or plan.batch_controller is not None):
        if issubclass(plan.cls, Agent):
            manager = AgentManager(sim, object_class=plan.cls)
        else:
            manager = SimObjectManager(sim, object_class=plan.cls)
        fresh.append(manager)
        if plan.batch_controller is not None:
            assert isinstance(manager, AgentManager)
            manager.enable_batch(plan.batch_controller)
    objects = _spawn_objects(sim, plan, manager, where)
    for obj in objects:
        if plan.actions and isinstance(obj, Agent):
            for spec in plan.actions:
                obj.add_action(spec.build())
    return objects


def _spawn_objects(
    sim: EntityHost,
    plan: _EntityPlan,
    manager: SimObjectManager[Any] | None,
    where: str,
) -> list[SimObject]:
    """Known classes in bulk (grid) or from their params; other classes one by one."""
    if plan.params is not None and (manager is None or manager.object_class is plan.cls):
        if manager is None:
            return [plan.cls.from_params(plan.params, sim)]
        if plan.grid is not None:
            prefix = plan.params.name  # a named grid entry: <name>_0, <name>_1, ...
            return list(
                manager.spawn_objects_grid(plan.count, plan.grid, plan.params, name_prefix=prefix)
            )
        return list(manager.spawn_objects_batch([plan.params]))
    configs = [plan.config]
    if plan.grid is not None:
        cells = plan.grid.cell_positions(np.arange(plan.count)).tolist()
        name = plan.config.get("name")
        configs = [
            {**plan.config, "pose": cell, **({} if name is None else {"name": f"{name}_{k}"})}
            for k, cell in enumerate(cells)
        ]
    labels = [
        f"{where}{plan.label}" + (f".grid[{k}]" if plan.grid is not None else "")
        for k in range(len(configs))
    ]
    if manager is None:
        return [plan.cls.from_dict(configs[0], sim)]
    with sim.batch_spawn():
        return [
            manager.spawn_entity({**config, "type": plan.type_name}, label=label)
            for config, label in zip(configs, labels, strict=True)
        ]


# ----- files and poses ------------------------------------------------------------------------


def _resolve_files(
    config: dict[str, Any],
    sim: EntityHost,
    base_dir: str | os.PathLike[str] | None,
    where: str,
    label: str,
) -> None:
    """Replace relative ``urdf_path`` / ``mesh_path`` values by the files they name."""
    base = FsPath(base_dir) if base_dir is not None else None
    if isinstance(config.get("urdf_path"), str):
        config["urdf_path"] = _find_urdf(config["urdf_path"], base, f"{where}{label}.urdf_path")
    search = list(sim.params.model_paths or [])
    for key in ("visual_shape", "collision_shape"):
        shape = config.get(key)
        mesh = (
            shape.get("mesh_path") if isinstance(shape, dict) else getattr(shape, "mesh_path", None)
        )
        if not isinstance(mesh, str):
            continue
        found = _find_mesh(mesh, base, search, f"{where}{label}.{key}.mesh_path")
        if isinstance(shape, dict):
            config[key] = {**shape, "mesh_path": found}
        elif isinstance(shape, ShapeParams):
            config[key] = dataclasses.replace(shape, mesh_path=found)


def _next_to(value: str, base: FsPath | None) -> tuple[str | None, list[str]]:
    """(the file ``value`` names relative to ``base`` if it exists, [candidate tried])."""
    if base is None or FsPath(value).expanduser().is_absolute():
        return None, []
    candidate = base / value
    return (str(candidate.resolve()), []) if candidate.is_file() else (None, [str(candidate)])


def _find_urdf(value: str, base: FsPath | None, label: str) -> str:
    found, tried = _next_to(value, base)
    if found is not None:
        return found
    try:
        return resolve_model(value)
    except ValueError as exc:
        first = f"tried {tried[0]}, then " if tried else ""
        raise FileNotFoundError(
            f"{label}: file not found: {short_repr(value)} ({first}{exc})"
        ) from exc


def _find_mesh(value: str, base: FsPath | None, search: list[str], label: str) -> str:
    found, tried = _next_to(value, base)
    if found is not None:
        return found
    try:
        return resolve_data_file(value, search, label)
    except FileNotFoundError as exc:
        first = f"; first tried {tried[0]}" if tried else ""
        raise FileNotFoundError(f"{exc}{first}") from exc


def _path_value(value: Any) -> Path:
    if isinstance(value, Path):
        return value
    if not isinstance(value, list):
        raise ValueError(f"expected a list of waypoints [[x, y, z], ...], got {short_repr(value)}")
    waypoints = []
    for k, point in enumerate(value):
        try:
            waypoints.append(pose_from_config(point))
        except ValueError as exc:
            raise ValueError(f"[{k}]: {exc}") from exc
    return Path(waypoints)


# ----- actions --------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class _ActionSpec:
    """One checked ``actions[j]`` entry; :meth:`build` makes a fresh Action for each agent."""

    cls: type[Action]
    config: dict[str, Any]
    converters: dict[str, Callable[[Any], Any]]

    def build(self, section: str | None = None) -> Action:
        return dataclass_from_dict(
            self.cls, self.config, converters=self.converters, section=section
        )


def _plan_actions(entries: Any, where: str, label: str) -> list[_ActionSpec]:
    """Check each action entry by building it once."""
    if entries is None:
        return []
    expect_type(entries, list, "a list of action mappings", where, label)
    plans = []
    for j, entry in enumerate(entries):
        item = f"{label}[{j}]"
        config = dict(expect_type(entry, dict, "a mapping", where, item))
        name = config.pop("type", None)
        if name not in ACTION_TYPES:
            raise ValueError(
                f"{where}{item}.type: unknown action type {name!r}; valid: {sorted(ACTION_TYPES)}"
            )
        spec = _ActionSpec(ACTION_TYPES[name], config, _pose_converters(ACTION_TYPES[name]))
        with config_context(where, item):
            spec.build(section=item)
        plans.append(spec)
    return plans


def _pose_converters(cls: type[Action]) -> dict[str, Callable[[Any], Any]]:
    """Converters for the Pose and Path fields of an Action dataclass, found by introspection."""
    try:
        hints = typing.get_type_hints(cls, localns={"Agent": Agent, "SimObject": SimObject})
    except (NameError, TypeError):
        hints = {}
    converters: dict[str, Callable[[Any], Any]] = {}
    for field in dataclasses.fields(cls):
        hint = hints.get(field.name)
        kinds = {hint, *typing.get_args(hint)}
        if field.init and Path in kinds:
            converters[field.name] = _path_value
        elif field.init and Pose in kinds:
            converters[field.name] = lambda v: None if v is None else pose_from_config(v)
    return converters
