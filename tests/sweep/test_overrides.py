"""--set keys: dotted paths into a scenario, entries addressed by name."""

from __future__ import annotations

import pytest
import yaml

from fleet_async.sweep import SweepKeyError, apply_overrides, settable_keys

SCENARIO = yaml.safe_load(
    """
simulation: {timestep: 0.1, duration: 10}
managers:
  - {name: pickers, type: agent, fleet_controller: {max_linear_vel: 1.5}}
entities:
  - name: picker
    manager: pickers
    controller: {type: omni, max_linear_vel: 1.0}
    grid: {count: 6, columns: 6, spacing: [1.5, 1.5]}
  - &tote {type: sim_object, name: tote, grid: {count: 4, offset: [0, 0, 0]}}
  - {<<: *tote, grid: {count: 2, offset: [5, 0, 0]}}
  - {type: sim_object, pose: [0, 0, 0]}
plugins:
  - {type: counter, config: {every: 2}}
"""
)


def test_keys_cover_simulation_fields_and_named_entries():
    keys = settable_keys(SCENARIO)
    assert "simulation.timestep" in keys and "simulation.physics" in keys  # any field
    assert "simulation.seed" not in keys  # --seeds sets it
    assert "entities.picker.grid.count" in keys
    assert "entities.picker.controller.max_linear_vel" in keys
    assert "managers.pickers.fleet_controller.max_linear_vel" in keys
    assert "plugins.counter.config.every" in keys
    assert not any(k.startswith("entities.tote") for k in keys)  # two entries share the name


def test_set_by_name_changes_only_that_entry():
    out = apply_overrides(
        SCENARIO,
        {
            "entities.picker.grid.count": 50,
            "simulation.physics": True,
            "managers.pickers.fleet_controller.max_linear_vel": 2.0,
        },
    )
    assert out["entities"][0]["grid"]["count"] == 50
    assert out["simulation"]["physics"] is True
    assert out["managers"][0]["fleet_controller"]["max_linear_vel"] == 2.0
    assert SCENARIO["entities"][0]["grid"]["count"] == 6  # the original is untouched


def test_unknown_key_names_it_the_nearest_and_the_valid_ones():
    with pytest.raises(SweepKeyError) as info:
        apply_overrides(SCENARIO, {"entities.picker.grid.cuont": 5})
    message = str(info.value)
    assert message.startswith("--set entities.picker.grid.cuont:")
    assert "did you mean 'entities.picker.grid.count'?" in message
    assert "valid keys: entities.picker.controller.max_linear_vel" in message
    with pytest.raises(SweepKeyError, match="no entities entry is named 'pickr'"):
        apply_overrides(SCENARIO, {"entities.pickr.grid.count": 5})
    with pytest.raises(SweepKeyError, match="not a mapping"):
        apply_overrides(SCENARIO, {"entities.picker.grid.count.x": 5})


def test_a_shared_name_is_refused_with_the_entries_that_share_it():
    with pytest.raises(SweepKeyError, match=r"entities\[1\], entities\[2\]"):
        apply_overrides(SCENARIO, {"entities.tote.grid.count": 1})


def test_the_seed_is_not_a_set_key():
    with pytest.raises(SweepKeyError, match="--seeds"):
        apply_overrides(SCENARIO, {"simulation.seed": 3})


def test_yaml_anchors_do_not_leak_a_change_into_other_entries():
    shared = {"count": 4}
    config = {"entities": [{"name": "a", "grid": shared}, {"name": "b", "grid": shared}]}
    out = apply_overrides(config, {"entities.a.grid.count": 9})
    assert out["entities"][0]["grid"]["count"] == 9
    assert out["entities"][1]["grid"]["count"] == 4


def test_flat_layout_keys_are_simulation_fields():
    flat = {"timestep": 0.1, "gui": False}
    assert "timestep" in settable_keys(flat) and "duration" in settable_keys(flat)
    assert apply_overrides(flat, {"duration": 5})["duration"] == 5
    with pytest.raises(SweepKeyError, match="not a simulation setting"):
        apply_overrides(flat, {"entities.x": 1})
