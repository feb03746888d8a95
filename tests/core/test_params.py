from __future__ import annotations

import math
import re

import pytest

from fleet_async import CollisionDetectionMethod, SimulationParams, SpatialHashCellSizeMode


def test_defaults_match_reference():
    prm = SimulationParams()
    assert prm.target_rtf == 1.0 and prm.timestep == 0.1 and prm.duration == 0
    assert prm.gui is True and prm.physics is False and prm.monitor is True
    assert prm.collision_check_frequency is None and prm.log_level == "warn"
    assert prm.max_steps_per_frame == 10 and prm.gui_min_fps == 30
    assert prm.ignore_static_collision is True and prm.profiling_interval == 100
    assert prm.spatial_hash_cell_size_mode is SpatialHashCellSizeMode.AUTO_INITIAL
    assert SimulationParams.__dataclass_fields__["collision_detection_method"].default is None
    assert prm.collision_detection_method is CollisionDetectionMethod.CLOSEST_POINTS  # picked
    assert prm.collision_margin == 0.02
    assert prm.multi_cell_threshold == 1.5 and prm.enable_floor is True
    assert (prm.window_width, prm.window_height) == (1024, 768)
    assert (prm.monitor_width, prm.monitor_height, prm.monitor_x, prm.monitor_y) == (
        200,
        290,
        -1,
        -1,
    )


def test_collision_method_resolves_from_physics():
    assert (
        SimulationParams().resolved_collision_detection_method
        is CollisionDetectionMethod.CLOSEST_POINTS
    )
    assert (
        SimulationParams(physics=True).resolved_collision_detection_method
        is CollisionDetectionMethod.CONTACT_POINTS
    )
    explicit = SimulationParams(collision_detection_method="hybrid")
    assert explicit.collision_detection_method is CollisionDetectionMethod.HYBRID


@pytest.mark.parametrize(
    ("field", "value", "match"),
    [
        ("timestep", -0.1, "timestep.*-0.1"),
        ("timestep", 0, "timestep"),
        ("target_rtf", -1, "target_rtf"),
        ("collision_check_frequency", -2.0, "collision_check_frequency"),
        ("log_level", "loud", "log_level.*loud"),
        ("max_steps_per_frame", 0, "max_steps_per_frame"),
        ("spatial_hash_cell_size_mode", "huge", "spatial_hash_cell_size_mode.*huge"),
        ("collision_margin", -0.01, "collision_margin"),
        ("gui", "yes", "gui.*yes"),
        ("model_paths", "not-a-list", "model_paths"),
        (
            "duration",
            -5,
            r"duration: expected a finite number >= 0 \(0: run until .*got -5",
        ),
        ("duration", math.inf, r"duration.*inf"),
    ],
)
def test_bad_values_name_field_and_value(field, value, match):
    with pytest.raises(ValueError, match=match):
        SimulationParams(**{field: value})


def test_a_negative_duration_in_a_file_is_refused_naming_the_file(tmp_path):
    path = tmp_path / "scenario.yaml"
    path.write_text("simulation:\n  duration: -5\n")
    with pytest.raises(
        ValueError, match=rf"^{re.escape(str(path))}: SimulationParams\.duration.*-5"
    ):
        SimulationParams.from_config(str(path))


def test_from_dict_converts_enums_and_rejects_unknown_keys():
    prm = SimulationParams.from_dict({"timestep": 0.05, "spatial_hash_cell_size_mode": "constant"})
    assert prm.timestep == 0.05
    assert prm.spatial_hash_cell_size_mode is SpatialHashCellSizeMode.CONSTANT
    with pytest.raises(ValueError, match=r"timestap.*timestep"):
        SimulationParams.from_dict({"timestap": 0.05})


def test_from_config_reads_nested_and_flat_files(tmp_path):
    nested = tmp_path / "nested.yaml"
    nested.write_text("simulation:\n  timestep: 0.02\n  gui: false\n")
    assert SimulationParams.from_config(str(nested)).timestep == 0.02
    flat = tmp_path / "flat.yaml"
    flat.write_text("timestep: 0.25\nphysics: true\n")
    prm = SimulationParams.from_config(str(flat))
    assert prm.timestep == 0.25 and prm.physics is True


def test_from_config_errors_name_the_file(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("simulation:\n  timestepp: 0.02\n")
    with pytest.raises(ValueError, match=r"bad.yaml"):
        SimulationParams.from_config(str(bad))
    with pytest.raises(FileNotFoundError, match=r"missing.yaml"):
        SimulationParams.from_config(str(tmp_path / "missing.yaml"))
