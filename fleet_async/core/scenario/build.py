"""Building a whole simulation from a scenario mapping or YAML file.

Two layouts. The flat (legacy) layout holds only SimulationParams keys at the top level. The
nested layout is recognised by any of these sections, applied in this order:

- ``simulation``: SimulationParams fields. With a ``world`` section and no explicit
  ``enable_floor``, the floor is off (the world geometry replaces it).
- ``entity_classes``: ``{type name: "package.module.Class"}``, registered before anything spawns.
- ``managers``: ``[{name, type: agent | sim_object, <constructor options>}]``, registered with the
  simulation (``sim.get_manager(name)``).
- ``world``: handed to ``sim.load_world(world, base_dir=...)``.
- ``traffic``: route graph, grid maps, deadlock time (``scenario/traffic.py``).
- ``entities``: entity mappings, see :meth:`ScenarioApi.spawn_robots_from_config`.
- ``plugins``: ``[{type: registered name | class: dotted.path, config: {...}, frequency: Hz}]``.
- ``missions``: ``["module:function" | {function, args, kwargs, name}]``, async functions that
  run the fleet, resolved at load (``scenario/missions.py``) and kept in
  ``sim.scenario_missions``; ``fleet_async.run_scenario`` / ``fleet-async run`` run them.
- ``trace``: ``OUT.fatrace`` or ``{path: OUT.fatrace, every_n_steps: N | fps: F}``; the built
  simulation records a trace from its first frame (``sim.start_trace``). ``path`` is relative
  to the working directory, as the command line's output files are.

Relative files (``urdf_path``, a shape's ``mesh_path``, world files) are looked up next to the
scenario file first (``base_dir``). Every error names the section and key (``entities[2].grid``),
the bad value or the nearest valid key, and the file. A simulation that fails to build is closed
before the error propagates, so no half-built simulation or PyBullet connection is left behind.
"""

from __future__ import annotations

import dataclasses
import difflib
import inspect
import os
from collections.abc import Mapping, Sequence
from pathlib import Path as FsPath
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, cast

from fleet_async.core.base.config_utils import load_yaml_config, register_class, resolve_class
from fleet_async.core.base.params import SimulationParams
from fleet_async.core.base.reprs import short_repr
from fleet_async.core.bodies.sim_object import SimObject
from fleet_async.core.devices import WorkcellPlugin
from fleet_async.core.managers.agent_manager import AgentManager
from fleet_async.core.managers.sim_object_manager import (
    SimObjectManager,
    get_entity_class,
    register_entity_class,
)
from fleet_async.core.scenario.entities import ACTION_TYPES, spawn_entities
from fleet_async.core.scenario.errors import (
    config_context,
    expect_type,
    reject_unknown_keys,
    where_prefix,
)
from fleet_async.core.scenario.missions import MissionSpec, parse_missions
from fleet_async.core.scenario.traffic import apply_traffic
from fleet_async.core.sim.plugins import SimPlugin

if TYPE_CHECKING:
    from collections.abc import Callable

    from typing_extensions import Self

    from fleet_async.core.scenario.host import BuiltSim

__all__ = [
    "ACTION_TYPES",
    "MANAGER_TYPES",
    "PLUGIN_KEYS",
    "SCENARIO_SECTIONS",
    "SIM_PLUGIN_REGISTRY",
    "TRACE_KEYS",
    "ScenarioApi",
    "register_sim_plugin",
]

SCENARIO_SECTIONS = (
    "simulation",
    "world",
    "entities",
    "managers",
    "entity_classes",
    "plugins",
    "missions",
    "trace",
    "serve",
    "traffic",
)
"""Top-level sections of the nested layout."""

SIM_PLUGIN_REGISTRY: dict[str, type[SimPlugin]] = {"workcell": WorkcellPlugin}
"""``plugins: [{type: ...}]`` names and their SimPlugin classes (:func:`register_sim_plugin`)."""

MANAGER_TYPES: dict[str, type[SimObjectManager[Any]]] = {
    "agent": AgentManager,
    "sim_object": SimObjectManager,
}
"""``managers: [{type: ...}]`` names and the manager classes they create."""
PLUGIN_KEYS = ("type", "class", "config", "frequency")
"""Keys of a ``plugins:`` entry."""
_SIMULATION_KEYS = frozenset(f.name for f in dataclasses.fields(SimulationParams))


def register_sim_plugin(name: str, cls: type[SimPlugin] | str) -> None:
    """Make ``cls`` usable as ``plugins: [{type: name}]`` in scenarios.

    Args:
        name: The ``type:`` value.
        cls: A SimPlugin subclass, or its dotted path.

    Raises:
        ValueError: for an empty name.
        TypeError: if ``cls`` is not a SimPlugin subclass.
    """
    register_class(SIM_PLUGIN_REGISTRY, name, cls, SimPlugin, "register_sim_plugin")


class ScenarioApi:
    """``from_dict`` / ``from_yaml`` / ``spawn_robots_from_config`` for MultiRobotSimulationCore."""

    scenario_missions: tuple[MissionSpec, ...] = ()
    """The missions the scenario names (its ``missions:`` section), resolved; empty for a
    simulation not built from a scenario. ``fleet_async.run_scenario(sim)`` runs them."""

    scenario_serve: Mapping[str, Any] = MappingProxyType({})
    """The scenario's ``serve:`` section (which robots ``fleet-async serve`` serves to fleet
    masters, and how), as written; ``fleet_async.interfaces`` reads and checks it."""

    @classmethod
    def from_dict(
        cls,
        config: Mapping[str, Any],
        *,
        source: str | None = None,
        base_dir: str | os.PathLike[str] | None = None,
    ) -> Self:
        """Create a simulation from a scenario mapping (flat or nested layout, see module doc).

        Args:
            config: The scenario.
            source: File the mapping came from, named in every error.
            base_dir: Directory relative files are looked up in first.

        Returns:
            The simulation with managers, world, entities, actions and plugins in place.

        Raises:
            ValueError: for an unknown section or key (naming it, the nearest valid one and
                ``source``) or a bad value (naming the expected type).
            FileNotFoundError: for a missing URDF, mesh or world file, naming the paths tried.
        """
        # Mixed into MultiRobotSimulationCore, a BuiltSim: the class called on is built.
        factory = cast("Callable[[SimulationParams], BuiltSim]", cls)
        return cast("Self", _build(factory, config, source, base_dir))

    @classmethod
    def from_yaml(cls, yaml_path: str | os.PathLike[str] = "config.yaml") -> Self:
        """Create a simulation from a YAML scenario file (see :meth:`from_dict`).

        Relative files in the scenario are looked up next to ``yaml_path`` first.

        Raises:
            FileNotFoundError: if ``yaml_path`` does not exist.
            ValueError: for malformed YAML (file, line and column), an empty file or a bad
                scenario.
        """
        config = load_yaml_config(yaml_path, allow_empty=False)
        return cls.from_dict(config, source=str(yaml_path), base_dir=FsPath(yaml_path).parent)

    def spawn_robots_from_config(
        self,
        robots_config: Sequence[Mapping[str, Any]],
        *,
        source: str | None = None,
        base_dir: str | os.PathLike[str] | None = None,
    ) -> list[SimObject]:
        """Spawn entities from config mappings; all or nothing.

        Each mapping is dispatched by ``type:`` (default "agent") to the registered class's
        ``from_dict``. Besides the class's own keys (``urdf_path``, shapes, ``pose`` + ``yaw``
        or ``pose: {position, orientation | yaw | rpy}``, ``controller``, ``plugins``, ...), an
        entry may have:

        - ``grid``: count-based ``{count, spacing, offset, columns}`` or range-based
          ``{x_min, x_max, y_min, y_max, spacing, offset}``; one entity per cell (``count`` of
          them), in a fresh manager registered with the simulation. ``yaw`` orients them all.
        - ``manager``: name of a registered manager to add the entities to instead.
        - ``batch_controller``: ``"batch_omni"`` / ``"batch_differential"`` / dotted path; the
          entities go to a fresh AgentManager with that batch mode.
        - ``actions``: ``[{type: move | wait | pick | drop, <fields of that Action>}]``, queued
          in order on each spawned agent, e.g. ``{type: move, path: [[x, y, z], ...]}``.

        Args:
            robots_config: The entity mappings.
            source: File they came from, named in errors.
            base_dir: Directory relative ``urdf_path`` / ``mesh_path`` are looked up in first.

        Returns:
            Every spawned object, in entry order (grid cells X fastest, then Y).

        Raises:
            ValueError, FileNotFoundError: for a bad entry, naming ``entities[i]`` and
                ``source``. Nothing this call spawned or registered is left behind.
        """
        sim = cast("BuiltSim", self)  # mixed into MultiRobotSimulationCore
        return spawn_entities(sim, robots_config, where_prefix(source), base_dir, declared=None)


def _section(config: Mapping[str, Any], name: str, kind: type, where: str) -> Any:
    value = config.get(name)
    if value is None:
        return kind()
    what = "a mapping" if kind is dict else "a list"
    return expect_type(value, kind, what, where, name)


# ----- the whole scenario ---------------------------------------------------------------------


def _build(
    factory: Callable[[SimulationParams], BuiltSim],
    config: Mapping[str, Any],
    source: str | None,
    base_dir: str | os.PathLike[str] | None,
) -> BuiltSim:
    where = where_prefix(source)
    expect_type(config, Mapping, "a mapping at the top level", where, "scenario")
    if not any(key in SCENARIO_SECTIONS for key in config):
        _check_flat_keys(config, where)
        return factory(SimulationParams.from_dict(dict(config), source=source))
    _check_sections(config, where)
    world = _section(config, "world", dict, where)
    simulation = dict(_section(config, "simulation", dict, where))
    if world and "enable_floor" not in simulation:
        simulation["enable_floor"] = False
    params = SimulationParams.from_dict(simulation, source=source)
    managers = _section(config, "managers", list, where)
    entities = _section(config, "entities", list, where)
    plugins = [
        _plugin_spec(e, f"plugins[{i}]", where)
        for i, e in enumerate(_section(config, "plugins", list, where))
    ]
    missions = parse_missions(_section(config, "missions", list, where), where, base_dir)
    for name, path in _section(config, "entity_classes", dict, where).items():
        label = f"entity_classes.{name}"
        expect_type(path, str, "a dotted path 'package.module.Class'", where, label)
        with config_context(where, label, resolving=True):
            register_entity_class(name, path)
    sim = factory(params)
    sim.scenario_missions = tuple(missions)
    sim.scenario_serve = MappingProxyType(dict(_section(config, "serve", dict, where)))
    try:
        declared = _create_managers(sim, managers, where)
        if world:
            with config_context(where, "world"):
                sim.load_world(world, base_dir=base_dir)
        if config.get("traffic") is not None:
            apply_traffic(sim, config["traffic"], where, base_dir)
        spawn_entities(sim, entities, where, base_dir, declared)
        _refuse_duplicate_names(sim, where)
        for label, cls, plugin_config, frequency in plugins:
            with config_context(where, label):
                sim.register_plugin(cls, config=plugin_config, frequency=frequency)
        # Frames the GUI window on the scene now, and finds a follow:NAME body or says not.
        with config_context(where, "simulation.camera_config"):
            sim.setup_camera()
        if config.get("trace") is not None:
            _start_trace(sim, config["trace"], where)
    except BaseException:
        sim.close()
        raise
    return sim


def _refuse_duplicate_names(sim: BuiltSim, where: str) -> None:
    """A scenario names each body once: the log, the summary, the trace and the viewer show
    those names, and two bodies called the same could not be told apart there.

    Raises:
        ValueError: naming the shared name, how many bodies (and their ids) carry it, and the
            file.
    """
    holders: dict[str, list[int]] = {}
    for obj in sim.sim_objects:
        if obj.name:
            holders.setdefault(obj.name, []).append(obj.object_id)
    shared = {name: ids for name, ids in holders.items() if len(ids) > 1}
    if shared:
        name, ids = next(iter(shared.items()))
        more = f" (and {len(shared) - 1} more shared names)" if len(shared) > 1 else ""
        raise ValueError(
            f"{where}entities: the name {name!r} is given to {len(ids)} bodies (object ids "
            f"{', '.join(map(str, ids))}){more}; a scenario's names must be unique: give "
            "each entry its own name (a grid entry numbers its bodies NAME_0, NAME_1, ...)"
        )


TRACE_KEYS = ("path", "every_n_steps", "fps")
"""Keys of the ``trace:`` section (``sim.start_trace``'s arguments)."""


def _start_trace(sim: BuiltSim, entry: Any, where: str) -> None:
    """The ``trace:`` section: a path, or ``{path, every_n_steps | fps}``."""
    options = {"path": entry} if isinstance(entry, str) else entry
    expect_type(options, dict, "a path or a mapping {path, every_n_steps | fps}", where, "trace")
    reject_unknown_keys(list(options), TRACE_KEYS, where, "trace")
    expect_type(options.get("path"), str, "a file path (string)", where, "trace.path")
    with config_context(where, "trace"):
        sim.start_trace(**options)


def _check_flat_keys(config: Mapping[str, Any], where: str) -> None:
    """In the flat layout, a key that is no SimulationParams field but looks like a section."""
    for key in config:
        close = difflib.get_close_matches(str(key), SCENARIO_SECTIONS, n=1, cutoff=0.75)
        if key not in _SIMULATION_KEYS and close:
            raise ValueError(
                f"{where}unknown top-level key {key!r} (did you mean section {close[0]!r}?); "
                f"sections: {', '.join(SCENARIO_SECTIONS)}"
            )


def _check_sections(config: Mapping[str, Any], where: str) -> None:
    for key in config:
        if key in SCENARIO_SECTIONS:
            continue
        if key in _SIMULATION_KEYS:
            raise ValueError(
                f"{where}unknown top-level section {key!r}: it is a simulation setting; "
                "put it under 'simulation:'"
            )
        reject_unknown_keys([key], SCENARIO_SECTIONS, where, "top-level section")


# ----- managers and plugins ---------------------------------------------------------------------


def _create_managers(sim: BuiltSim, entries: list[Any], where: str) -> list[str]:
    """Create, name and register each declared manager; return their names."""
    names: list[str] = []
    for i, entry in enumerate(entries):
        label = f"managers[{i}]"
        options = dict(expect_type(entry, dict, "a mapping", where, label))
        kind = options.pop("type", "agent")
        if kind not in MANAGER_TYPES:
            raise ValueError(
                f"{where}{label}.type: unknown manager type {kind!r}; valid: {list(MANAGER_TYPES)}"
            )
        cls = MANAGER_TYPES[kind]
        name = expect_type(
            options.pop("name", None), str, "a name (string)", where, f"{label}.name"
        )
        if name in names:
            raise ValueError(f"{where}{label}.name: manager {name!r} is declared twice")
        valid = [
            p for p in inspect.signature(cls.__init__).parameters if p not in ("self", "sim_core")
        ]
        reject_unknown_keys(list(options), ["type", *valid], where, label)
        if isinstance(options.get("object_class"), str):
            with config_context(where, f"{label}.object_class", resolving=True):
                options["object_class"] = _entity_class(options["object_class"])
        with config_context(where, label):
            cls(sim, name=name, **options)
        names.append(name)
    return names


def _entity_class(name_or_path: str) -> type[SimObject]:
    """A registered entity type name, or a dotted path to a SimObject subclass."""
    if "." not in name_or_path:
        return get_entity_class(name_or_path)
    cls = resolve_class(name_or_path)
    if not (isinstance(cls, type) and issubclass(cls, SimObject)):
        raise ValueError(f"{name_or_path!r} is not a SimObject subclass")
    return cls


def _plugin_spec(
    entry: Any, label: str, where: str
) -> tuple[str, type[SimPlugin], dict[str, Any] | None, float | None]:
    """(label, class, config, frequency) of one ``plugins:`` entry, checked."""
    expect_type(entry, dict, "a mapping", where, label)
    reject_unknown_keys(list(entry), PLUGIN_KEYS, where, label)
    if ("type" in entry) == ("class" in entry):
        raise ValueError(
            f"{where}{label}: give exactly one of 'type' or 'class', got {short_repr(entry)}"
        )
    if "type" in entry:
        name = entry["type"]
        if name not in SIM_PLUGIN_REGISTRY:
            raise ValueError(
                f"{where}{label}.type: unknown plugin {name!r}; registered: "
                f"{sorted(SIM_PLUGIN_REGISTRY)} (or give 'class: package.module.Class')"
            )
        cls = SIM_PLUGIN_REGISTRY[name]
    else:
        path = expect_type(entry["class"], str, "a dotted path", where, f"{label}.class")
        with config_context(where, f"{label}.class", resolving=True):
            cls = resolve_class(path)
        if not (isinstance(cls, type) and issubclass(cls, SimPlugin)):
            raise ValueError(f"{where}{label}.class: {path!r} is not a SimPlugin subclass")
    config = entry.get("config")
    if config is not None:
        expect_type(config, dict, "a mapping", where, f"{label}.config")
    frequency = entry.get("frequency")
    if frequency is not None and (
        isinstance(frequency, bool) or not isinstance(frequency, (int, float)) or frequency <= 0
    ):
        raise ValueError(
            f"{where}{label}.frequency: expected a number > 0 (Hz) or null, got {frequency!r}"
        )
    return label, cls, config, frequency


# ----- entities -------------------------------------------------------------------------------
