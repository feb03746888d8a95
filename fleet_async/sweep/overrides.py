"""Dotted paths into a scenario mapping: what ``--set KEY=...`` may change, and changing it.

A key walks the scenario's nesting with dots. Entries of the list sections (``entities``,
``managers``, ``plugins``) are addressed by their ``name`` (a plugin by its ``type`` when it
has no name), never by position, so a key survives edits of the file:

- ``simulation.timestep``: any SimulationParams field, even one the file does not set
  (except ``seed``, which ``--seeds`` sets);
- ``entities.pickers.grid.count``, ``entities.restocker.controller.max_linear_vel``: a value the
  entry named ``pickers`` / ``restocker`` sets, at any depth of mappings;
- ``managers.pickers.fleet_controller.max_linear_vel``, ``world.world_file``, ...

A key must name a value the scenario already has (lists are values: ``entities.r0.pose``), so
a typo is an error rather than a silently ignored setting; :func:`settable_keys` lists them.
In the flat layout (SimulationParams keys at the top level), the keys are the field names.
"""

from __future__ import annotations

import dataclasses
import difflib
from collections.abc import Mapping
from typing import Any

from fleet_async.core import SimulationParams
from fleet_async.core.scenario.build import SCENARIO_SECTIONS

__all__ = ["SweepKeyError", "apply_overrides", "is_nested", "settable_keys", "unshared"]

_SIM_FIELDS = tuple(f.name for f in dataclasses.fields(SimulationParams) if f.name != "seed")
_LIST_SECTIONS = ("entities", "managers", "plugins")
_LABEL_KEYS = {"entities": ("name",), "managers": ("name",), "plugins": ("name", "type")}
_SHOWN = 40  # keys listed in an error message; settable_keys() has them all


class SweepKeyError(ValueError):
    """A ``--set`` key the scenario does not have; the message names it and the valid ones."""


def is_nested(config: Mapping[str, Any]) -> bool:
    """Whether the scenario uses the nested layout (``simulation:``, ``entities:``, ...)."""
    return any(key in SCENARIO_SECTIONS for key in config)


def unshared(value: Any) -> Any:
    """A deep copy of mappings and lists that shares nothing, not even what YAML anchors
    (``<<: *tote``) made one object: a change under one entry never shows in another."""
    if isinstance(value, Mapping):
        return {k: unshared(v) for k, v in value.items()}
    if isinstance(value, list):
        return [unshared(v) for v in value]
    return value


def _labels(section: str, items: list[Any]) -> dict[str, list[int]]:
    """``{label: [positions]}`` of a list section's mapping entries that have a label."""
    found: dict[str, list[int]] = {}
    for i, item in enumerate(items):
        if not isinstance(item, Mapping):
            continue
        for key in _LABEL_KEYS[section]:
            label = item.get(key)
            if isinstance(label, str) and label:
                found.setdefault(label, []).append(i)
                break
    return found


def _leaves(prefix: str, value: Any) -> list[str]:
    if isinstance(value, Mapping) and value:
        return [leaf for k, v in value.items() for leaf in _leaves(f"{prefix}.{k}", v)]
    return [prefix]


def settable_keys(config: Mapping[str, Any]) -> list[str]:
    """Every key ``--set`` accepts for this scenario, sorted."""
    if not is_nested(config):
        return sorted(_SIM_FIELDS)
    keys = {f"simulation.{name}" for name in _SIM_FIELDS}
    for section, value in config.items():
        if section == "simulation":
            continue
        if section in _LIST_SECTIONS and isinstance(value, list):
            for label, positions in _labels(section, value).items():
                if len(positions) == 1:
                    item = value[positions[0]]
                    keys.update(_leaves(f"{section}.{label}", item))
        else:
            keys.update(_leaves(str(section), value))
    return sorted(keys)


def _unknown(key: str, config: Mapping[str, Any], why: str) -> SweepKeyError:
    valid = settable_keys(config)
    close = difflib.get_close_matches(key, valid, n=1, cutoff=0.6)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    shown = ", ".join(valid[:_SHOWN])
    more = (
        f", ... ({len(valid) - _SHOWN} more: --keys lists them all)" if len(valid) > _SHOWN else ""
    )
    return SweepKeyError(f"--set {key}: {why}{hint}; valid keys: {shown}{more}")


def _entry(config: Mapping[str, Any], section: str, label: str, key: str) -> dict[str, Any]:
    items = config.get(section)
    positions = _labels(section, items).get(label, []) if isinstance(items, list) else []
    if len(positions) > 1:
        where = ", ".join(f"{section}[{i}]" for i in positions)
        raise SweepKeyError(
            f"--set {key}: {section} named {label!r} are several ({where}); give the one to "
            "sweep a name of its own"
        )
    if not positions:
        raise _unknown(key, config, f"no {section} entry is named {label!r}")
    assert isinstance(items, list)
    entry = items[positions[0]]
    assert isinstance(entry, dict)
    return entry


def _set_one(config: dict[str, Any], key: str, value: Any) -> None:
    parts = key.split(".")
    if any(not p for p in parts):
        raise _unknown(key, config, "empty part in the key")
    if not is_nested(config):
        if len(parts) != 1 or parts[0] not in _SIM_FIELDS:
            raise _unknown(key, config, "not a simulation setting")
        config[parts[0]] = value
        return
    section = parts[0]
    if section == "simulation" and len(parts) == 2 and parts[1] in _SIM_FIELDS:
        if not isinstance(config.get("simulation"), dict):
            config["simulation"] = {}
        config["simulation"][parts[1]] = value
        return
    if section in _LIST_SECTIONS and len(parts) >= 3:
        node: Any = _entry(config, section, parts[1], key)
        path = parts[2:]
    else:
        node, path = config, parts
    for i, part in enumerate(path[:-1]):
        node = node.get(part) if isinstance(node, dict) else None
        if not isinstance(node, dict):
            raise _unknown(
                key,
                config,
                f"{'.'.join(parts[: len(parts) - len(path) + i + 1])} "
                "is not a mapping in the scenario",
            )
    if not isinstance(node, dict) or path[-1] not in node:
        raise _unknown(key, config, "the scenario sets no such value")
    node[path[-1]] = value


def apply_overrides(config: Mapping[str, Any], values: Mapping[str, Any]) -> dict[str, Any]:
    """A copy of ``config`` with each ``{dotted key: value}`` set (see the module doc).

    Raises:
        SweepKeyError: for a key the scenario does not have, naming it, the nearest valid key
            and the valid ones; for an entry name that several entries share.
    """
    out = unshared(config)
    for key, value in values.items():
        if key in ("seed", "simulation.seed"):
            raise SweepKeyError(f"--set {key}: the seed is swept with --seeds, not --set")
        _set_one(out, key, unshared(value))
    return out
