"""The scenario reference: every YAML key a scenario takes, generated from the code.

The keys come from the objects the scenario loader maps YAML onto: the parameter dataclasses
(``SimulationParams``, ``AgentSpawnParams``, ``ShapeParams``, ``ControllerParams``, the Action
dataclasses, ...) by field introspection, the constructors of managers and controllers by
signature, and the loader's own key lists (``SCENARIO_SECTIONS``, ``MISSION_KEYS``, ...).
Descriptions come from the docstrings (Google style ``Attributes:`` / ``Args:`` sections). So
the page cannot drift from the loader: a new field shows up by itself, and
``tests/test_docs.py`` fails when a key has no description.

Run at every docs build by the MkDocs hook in ``docs/hooks/mkdocs_hooks.py``, which puts the
output where ``docs/scenarios.md`` says ``<!-- scenario-reference -->``. Run by hand with
``python docs/hooks/scenario_reference.py`` to print the Markdown.
"""

from __future__ import annotations

import dataclasses
import inspect
import re
from collections.abc import Callable, Iterable
from typing import Any

from fleet_async.core.actions.action import Action
from fleet_async.core.agents.agent_params import AgentSpawnParams
from fleet_async.core.agents.agent_plugins import AGENT_PLUGIN_REGISTRY
from fleet_async.core.base.params import SimulationParams
from fleet_async.core.bodies.spawn_params import SimObjectSpawnParams
from fleet_async.core.managers.grid_spawn import GridSpawnParams
from fleet_async.core.motion.controllers import CONTROLLER_REGISTRY, ControllerParams
from fleet_async.core.motion.ik import IKParams
from fleet_async.core.collision.safety_params import SafetyFieldParams
from fleet_async.core.scenario import build, entities, missions, traffic, world_config
from fleet_async.core.world.shapes import ShapeParams

MARKER = "<!-- scenario-reference -->"

# Keys the loader handles itself (no dataclass field behind them): described here, and
# tests/test_docs.py checks that this list and the loader's own key lists stay equal.
SECTION_TEXT = {
    "simulation": "SimulationParams fields (below). With a `world` and no `enable_floor`, "
    "the floor is off.",
    "world": "The world geometry: one source key and options (below).",
    "entities": "A list of robots and objects (below).",
    "managers": "A list of named managers that `entities` entries join with `manager:`.",
    "entity_classes": "`{type name: package.module.Class}`: your own SimObject / Agent "
    "classes, usable as an entity's `type:`.",
    "plugins": "A list of simulation plugins (SimPlugin subclasses) (below).",
    "missions": "A list of async functions that run the fleet (below).",
    "trace": "`OUT.fatrace` or a mapping (below): record a trace of the run for "
    "`fleet-async view`, from the first frame (`sim.start_trace`).",
    "serve": "What `fleet-async serve` serves to fleet software: `robots` (default all), "
    "`broker` and the VDA 5050 settings (`version`, `manufacturer`, `serial_numbers`, ...; "
    "[Fleet interfaces](fleet-interfaces.md)). Other commands ignore it.",
    "traffic": "A route graph, grid maps and the deadlock time (below; "
    "[Traffic](traffic.md)).",
}
TRAFFIC_TEXT = {
    "route_graph": "A YAML route graph or a LIF layout (`.json` / `.lif`), or "
    "`{path, layout_id, vehicle_type}`; robots plan `go_to_node` on it.",
    "maps": "A list of map_server `.yaml` or MovingAI `.map` files, or "
    "`{path, resolution, height, tile}` mappings: static obstacles (`sim.load_map`).",
    "deadlock_after": "Seconds robots held by each other's safety fields wait before "
    "`deadlock_suspected` (default 10).",
}
WORLD_TEXT = {
    "world_file": "A Gazebo `.world` file (its `model://` includes are resolved).",
    "sdf": "An SDF file.",
    "mesh_dir": "A directory of `.obj` / `.stl` meshes, one static body each.",
    "skip_models": "Model names not to load.",
    "model_paths": "Directories searched first for `model://` URIs.",
    "on_error": '`"raise"` (default) or `"warn"`: what a model that fails to load does.',
}
ENTITY_TEXT = {
    "type": '`"agent"` (default), `"sim_object"`, or a name from `entity_classes`.',
    "grid": "Spawn one entity per grid cell into a fresh manager: count-based "
    "`{count, columns, spacing, offset}` or range-based (GridSpawnParams, below).",
    "manager": "Name of a manager from `managers:` to add the entities to.",
    "batch_controller": '`"batch_omni"`, `"batch_differential"` or a dotted path: the '
    "entities go to a fresh AgentManager that moves them in one vectorised controller.",
    "actions": "Agents only: a list of actions queued in order when the agent spawns (below).",
    "pose": "`[x, y, z]` (with `yaw`), or `{position, orientation | yaw | rpy}`; instead of "
    "`initial_pose`.",
    "yaw": "Heading in radians, with a `pose: [x, y, z]` or a `grid`.",
}
MANAGER_TEXT = {
    "name": "The manager's name (`sim.get_manager(name)`, an entity's `manager:`).",
    "type": '`"agent"` (default) or `"sim_object"`.',
}
PLUGIN_TEXT = {
    "type": "A name registered with `register_sim_plugin`.",
    "class": "Or a dotted path to a SimPlugin subclass.",
    "config": "A mapping handed to the plugin.",
    "frequency": "How often it runs, in Hz of sim time (default: every step).",
}
MISSION_TEXT = {
    "function": '`"module:function"`: an `async def function(sim, ...)`; `module` is found '
    "beside the scenario file first, then on the Python path, or is a `.py` path relative to "
    "the scenario file. A bare string entry is this key alone.",
    "args": "Positional arguments after `sim`.",
    "kwargs": "Keyword arguments.",
    "name": "The mission's name (default: the function's name).",
}
TRACE_TEXT = {
    "path": "The trace file, relative to the working directory (as the command line's output "
    "files are). A bare string is this key alone.",
    "every_n_steps": "Record a frame every N steps (default 1).",
    "fps": "Instead of `every_n_steps`: frames per sim second, rounded to whole steps.",
}


@dataclasses.dataclass(frozen=True)
class Key:
    """One documented key."""

    name: str
    type: str
    default: str
    text: str


# ----- docstrings -------------------------------------------------------------------------------

_SECTION = re.compile(r"^(\s*)(Attributes|Args|Arguments|Config keys[^:]*):\s*$")
_ENTRY = re.compile(r"^\s*([A-Za-z_]\w*(?:\s*/\s*[A-Za-z_]\w*)*)(?:\s*\([^)]*\))?:\s*(.*)$")


def docstring_entries(obj: Any) -> dict[str, str]:
    """``name: text`` entries of the ``Attributes:`` / ``Args:`` / ``Config keys:`` sections
    of ``obj``'s docstring and, for a class, of its bases' docstrings (nearest first wins)."""
    entries: dict[str, str] = {}
    owners = inspect.getmro(obj) if inspect.isclass(obj) else (obj,)
    for owner in owners:
        for name, text in _parse(inspect.getdoc(owner) or "").items():
            entries.setdefault(name, text)
    return entries


def _parse(doc: str) -> dict[str, str]:
    entries: dict[str, str] = {}
    lines = doc.splitlines()
    i = 0
    while i < len(lines):
        match = _SECTION.match(lines[i])
        i += 1
        if match is None:
            continue
        indent: int | None = None
        current: str | None = None
        shared: list[str] = []
        while i < len(lines) and (not lines[i].strip() or _indent(lines[i]) > len(match[1])):
            line = lines[i]
            i += 1
            if not line.strip():
                continue
            if indent is None:
                indent = _indent(line)
            entry = _ENTRY.match(line)
            if _indent(line) == indent and entry:
                names = [n.strip() for n in entry[1].split("/")]  # "a / b / c: shared text"
                current = names[-1]
                for name in names:
                    entries[name] = entry[2].strip()
                shared = names
            elif current is not None:
                for name in shared:
                    entries[name] = f"{entries[name]} {line.strip()}".strip()
    return entries


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip())


# ----- keys from code ---------------------------------------------------------------------------


def _show(value: Any) -> str:
    if hasattr(value, "value") and hasattr(value, "name"):  # an Enum member: its YAML value
        value = value.value
    return "`" + repr(value).replace("|", "\\|") + "`"


def _type(annotation: Any) -> str:
    text = annotation if isinstance(annotation, str) else getattr(annotation, "__name__", "")
    return f"`{text}`".replace("|", "\\|") if text else ""


def dataclass_keys(cls: type, skip: Iterable[str] = ()) -> list[Key]:
    """One Key per constructor field of the dataclass ``cls``."""
    docs = docstring_entries(cls)
    keys = []
    for field in dataclasses.fields(cls):
        if not field.init or field.name in skip:
            continue
        if field.default is not dataclasses.MISSING:
            default = _show(field.default)
        elif field.default_factory is not dataclasses.MISSING:
            default = _show(field.default_factory())
        else:
            default = "required"
        keys.append(Key(field.name, _type(field.type), default, docs.get(field.name, "")))
    return keys


def signature_keys(function: Callable[..., Any], skip: Iterable[str] = ()) -> list[Key]:
    """One Key per keyword parameter of ``function`` (a class: its constructor)."""
    docs = docstring_entries(function)
    target = function.__init__ if inspect.isclass(function) else function  # type: ignore[misc]
    keys = []
    for name, parameter in inspect.signature(target).parameters.items():
        if name in ("self", *skip) or parameter.kind in (
            parameter.VAR_POSITIONAL,
            parameter.VAR_KEYWORD,
        ):
            continue
        empty = parameter.default is inspect.Parameter.empty
        default = "required" if empty else _show(parameter.default)
        keys.append(Key(name, _type(parameter.annotation), default, docs.get(name, "")))
    return keys


def text_keys(texts: dict[str, str], names: Iterable[str]) -> list[Key]:
    return [Key(name, "", "", texts[name]) for name in names]


# ----- the page -------------------------------------------------------------------------------


def table(keys: list[Key]) -> str:
    rows = ["| key | type | default | what it sets |", "|---|---|---|---|"]
    for key in keys:
        text = " ".join(key.text.split()).replace("|", "\\|")
        rows.append(f"| `{key.name}` | {key.type} | {key.default} | {text} |")
    return "\n".join(rows)


def sections() -> list[tuple[str, str, list[Key]]]:
    """(heading, introduction, keys) of every part of the reference, in page order."""
    manager_skip = ("sim_core", "name")
    parts: list[tuple[str, str, list[Key]]] = [
        (
            "Top level",
            "A scenario in the nested layout has these sections; every one is optional. (The "
            "flat layout, SimulationParams keys at the top level, is still read.)",
            text_keys(SECTION_TEXT, build.SCENARIO_SECTIONS),
        ),
        ("simulation", "`SimulationParams`.", dataclass_keys(SimulationParams)),
        (
            "world",
            "One source key (the first present of "
            + ", ".join(f"`{k}`" for k in world_config.SOURCE_KEYS)
            + ") and options. Relative paths are taken from the scenario file's folder.",
            text_keys(WORLD_TEXT, (*world_config.SOURCE_KEYS, *world_config.OPTION_KEYS)),
        ),
    ]
    for kind, cls in build.MANAGER_TYPES.items():
        parts.append(
            (
                f"managers (type: {kind})",
                f"`{cls.__name__}` constructor options.",
                text_keys(MANAGER_TEXT, ("name", "type")) + signature_keys(cls, manager_skip),
            )
        )
    parts += [
        (
            "entities",
            "Keys the scenario handles for every entry, then the spawn parameters of the "
            "entry's class.",
            text_keys(ENTITY_TEXT, (*entities.SCENARIO_ENTITY_KEYS, "pose", "yaw")),
        ),
        (
            "entities (type: sim_object)",
            "`SimObjectSpawnParams`.",
            dataclass_keys(SimObjectSpawnParams),
        ),
        (
            "entities (type: agent)",
            "`AgentSpawnParams`: everything of `sim_object`, plus these.",
            [
                key
                for key in dataclass_keys(AgentSpawnParams)
                if key.name not in {f.name for f in dataclasses.fields(SimObjectSpawnParams)}
            ],
        ),
        ("visual_shape, collision_shape", "`ShapeParams`.", dataclass_keys(ShapeParams)),
        (
            "grid",
            "Range-based: `GridSpawnParams`. Count-based instead: `count` (entities), optional "
            "`columns`, `spacing`, `offset`.",
            dataclass_keys(GridSpawnParams),
        ),
        (
            "controller",
            "A name (" + ", ".join(f"`{n}`" for n in CONTROLLER_REGISTRY) + "), a mapping "
            "`{type: name, ...}` or `{class: dotted.path, ...}`, or a list of them (one base "
            "controller, then high-level ones such as `patrol`). Limits are "
            "`ControllerParams`:",
            dataclass_keys(ControllerParams),
        ),
    ]
    seen: set[type] = set()
    for name, cls in CONTROLLER_REGISTRY.items():
        keys = signature_keys(cls, ("params",))
        if cls in seen or not keys:
            continue
        seen.add(cls)
        parts.append((f"controller (type: {name})", f"`{cls.__name__}` options.", keys))
    parts.append(("ik_params", "`IKParams` (arms).", dataclass_keys(IKParams)))
    for name, plugin in AGENT_PLUGIN_REGISTRY.items():
        docs = docstring_entries(plugin)
        defaults = getattr(plugin, "DEFAULTS", {})
        keys = [Key(k, "", _show(v), docs.get(k, "")) for k, v in defaults.items()]
        parts.append(
            (
                f"plugins of an agent (type: {name})",
                f"`{{type: {name}, config: {{...}}}}`: `{plugin.__name__}` config keys.",
                keys,
            )
        )
    for name, action in entities.ACTION_TYPES.items():
        parts.append(
            (
                f"actions (type: {name})",
                f"`{action.__name__}`.",
                dataclass_keys(action, _action_state_fields()),
            )
        )
    parts += [
        ("plugins", "Simulation plugins.", text_keys(PLUGIN_TEXT, build.PLUGIN_KEYS)),
        (
            "missions",
            'Each entry is `"module:function"` or a mapping; the function is called as '
            "`function(sim, *args, **kwargs)` by `fleet-async run` / `fleet_async.run_scenario`.",
            text_keys(MISSION_TEXT, missions.MISSION_KEYS),
        ),
        (
            "trace",
            "`sim.start_trace(**trace)`; `fleet-async run --trace` / `--view` replace it.",
            text_keys(TRACE_TEXT, build.TRACE_KEYS),
        ),
        (
            "traffic",
            "Relative paths are taken from the scenario file's folder.",
            text_keys(TRAFFIC_TEXT, traffic.TRAFFIC_KEYS),
        ),
        (
            "safety_field",
            "An agent's `safety_field`: `SafetyFieldParams` (`true` for the defaults).",
            dataclass_keys(SafetyFieldParams),
        ),
    ]
    return parts


def _action_state_fields() -> set[str]:
    """Fields every Action has that are run-time state or set by the queue, not config."""
    return {f.name for f in dataclasses.fields(Action) if not f.init}


def render() -> str:
    """The reference as Markdown (level-3 headings, one table per part)."""
    out = []
    for heading, intro, keys in sections():
        out += [f"### {heading}", "", intro, "", table(keys), ""]
    return "\n".join(out)


if __name__ == "__main__":
    print(render())
