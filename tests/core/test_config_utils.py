"""Config loading, merging, class resolution and dataclass mapping."""

from __future__ import annotations

import collections
import enum
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional, Union

import pytest

from fleet_async.core.base.config_utils import (
    dataclass_from_dict,
    forward_spawn_params,
    load_config,
    load_yaml_config,
    merge_configs,
    resolve_class,
)


class Mode(str, enum.Enum):
    FAST = "fast"
    SAFE_STOP = "safe_stop"


class Level(enum.IntEnum):
    LOW = 1
    HIGH = 2


@dataclass
class Inner:
    gain: float = 1.0


@dataclass
class Params:
    speed: float = 1.0
    count: int = 3
    enabled: bool = True
    name: str = "robot"
    mode: Mode = Mode.FAST
    level: Level = Level.LOW
    limit: float | None = None
    legacy_limit: Optional[float] = None  # noqa: UP045 - typing.Optional must keep working
    either: Union[int, str] = 0  # noqa: UP007 - typing.Union must keep working
    waypoints: list[float] = field(default_factory=list)
    tags: dict[str, int] = field(default_factory=dict)
    extra: Any = None
    inner: Inner = field(default_factory=Inner)
    camera_config: dict[str, Any] | None = None


@dataclass
class Required:
    robot_id: str
    speed: float = 0.5


@dataclass
class Validated:
    speed: float = 1.0

    def __post_init__(self) -> None:
        if self.speed < 0:
            raise ValueError(f"Validated.speed: expected >= 0, got {self.speed}")


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


# ----- load_yaml_config ------------------------------------------------------------------


def test_load_yaml_config_parses_mapping(tmp_path: Path) -> None:
    path = _write(tmp_path, "c.yaml", "simulation:\n  timestep: 0.05\n  gui: false\n")

    assert load_yaml_config(path) == {"simulation": {"timestep": 0.05, "gui": False}}
    assert load_yaml_config(str(path)) == {"simulation": {"timestep": 0.05, "gui": False}}


def test_load_yaml_config_missing_file_names_the_path(tmp_path: Path) -> None:
    missing = tmp_path / "nope.yaml"

    with pytest.raises(FileNotFoundError, match=r"nope\.yaml"):
        load_yaml_config(missing)


def test_load_yaml_config_empty_file_is_empty_dict(tmp_path: Path) -> None:
    assert load_yaml_config(_write(tmp_path, "empty.yaml", "")) == {}
    assert load_yaml_config(_write(tmp_path, "comment.yaml", "# nothing\n")) == {}


def test_load_yaml_config_syntax_error_names_file_line_and_column(tmp_path: Path) -> None:
    path = _write(tmp_path, "bad.yaml", "a: 1\nb: [1, 2\nc: 3\n")

    with pytest.raises(ValueError, match="invalid YAML") as info:
        load_yaml_config(path)

    message = str(info.value)
    assert str(path) in message
    assert "line 3" in message
    assert "column 2" in message


def test_load_yaml_config_non_mapping_top_level(tmp_path: Path) -> None:
    path = _write(tmp_path, "list.yaml", "- 1\n- 2\n")

    with pytest.raises(ValueError, match="must be a mapping, got list") as info:
        load_yaml_config(path)
    assert str(path) in str(info.value)


# ----- merge_configs / load_config -------------------------------------------------------


def test_merge_configs_recursive_override_wins_and_lists_replaced() -> None:
    base = {"sim": {"dt": 0.1, "gui": True, "paths": ["a", "b"]}, "keep": 1}
    override = {"sim": {"dt": 0.05, "paths": ["c"]}, "new": {"x": 1}}

    merged = merge_configs(base, override)

    assert merged == {
        "sim": {"dt": 0.05, "gui": True, "paths": ["c"]},
        "keep": 1,
        "new": {"x": 1},
    }


def test_merge_configs_does_not_mutate_or_alias_inputs() -> None:
    base = {"sim": {"dt": 0.1, "paths": ["a"]}}
    override = {"sim": {"gui": False}, "new": {"list": [1]}}

    merged = merge_configs(base, override)
    merged["sim"]["paths"].append("z")
    merged["new"]["list"].append(2)

    assert base == {"sim": {"dt": 0.1, "paths": ["a"]}}
    assert override == {"sim": {"gui": False}, "new": {"list": [1]}}


def test_merge_configs_non_mapping_replaces_mapping() -> None:
    assert merge_configs({"a": {"b": 1}}, {"a": None}) == {"a": None}
    assert merge_configs({"a": 1}, {"a": {"b": 2}}) == {"a": {"b": 2}}


def test_load_config_later_files_override_earlier(tmp_path: Path) -> None:
    base = _write(tmp_path, "base.yaml", "sim:\n  dt: 0.1\n  gui: true\nrobots: [a, b]\n")
    big = _write(tmp_path, "big.yaml", "sim:\n  dt: 0.01\nrobots: [c]\n")

    assert load_config([str(base), str(big)]) == {"sim": {"dt": 0.01, "gui": True}, "robots": ["c"]}
    assert load_config(str(base)) == {"sim": {"dt": 0.1, "gui": True}, "robots": ["a", "b"]}
    assert load_config(base) == load_config(str(base))
    assert load_config([]) == {}


def test_load_config_missing_file_raises(tmp_path: Path) -> None:
    base = _write(tmp_path, "base.yaml", "a: 1\n")

    with pytest.raises(FileNotFoundError, match=r"missing\.yaml"):
        load_config([base, tmp_path / "missing.yaml"])


# ----- resolve_class ---------------------------------------------------------------------


def test_resolve_class_returns_the_class() -> None:
    assert resolve_class("collections.OrderedDict") is collections.OrderedDict
    assert resolve_class("pathlib.Path") is Path


@pytest.mark.parametrize("bad", ["NoDots", "", ".Leading", "trailing.", "a..b"])
def test_resolve_class_rejects_non_dotted(bad: str) -> None:
    with pytest.raises(ValueError, match="dotted path"):
        resolve_class(bad)


def test_resolve_class_missing_module_names_the_path() -> None:
    with pytest.raises(ModuleNotFoundError, match=r"no_such_pkg_xyz\.Thing"):
        resolve_class("no_such_pkg_xyz.Thing")


def test_resolve_class_missing_attribute_names_the_path() -> None:
    with pytest.raises(AttributeError, match=r"collections\.NoSuchClass"):
        resolve_class("collections.NoSuchClass")


# ----- dataclass_from_dict: reading values ---------------------------------------------


def test_dataclass_from_dict_reads_fields_and_keeps_defaults() -> None:
    params = dataclass_from_dict(Params, {"speed": 2.5, "count": 7, "name": "r2"})

    assert params == Params(speed=2.5, count=7, name="r2")
    assert params.enabled is True


def test_dataclass_from_dict_int_for_float_becomes_float() -> None:
    params = dataclass_from_dict(Params, {"speed": 2, "limit": 3, "waypoints": [1, 2.5]})

    assert params.speed == 2.0
    assert type(params.speed) is float
    assert type(params.limit) is float
    assert params.waypoints == [1.0, 2.5]
    assert [type(v) for v in params.waypoints] == [float, float]


@pytest.mark.parametrize(
    ("raw", "expected"),
    [
        ("fast", Mode.FAST),
        ("FAST", Mode.FAST),
        ("Safe_Stop", Mode.SAFE_STOP),
        ("SAFE_STOP", Mode.SAFE_STOP),
        (Mode.SAFE_STOP, Mode.SAFE_STOP),
    ],
)
def test_dataclass_from_dict_converts_enum_strings(raw: object, expected: Mode) -> None:
    params = dataclass_from_dict(Params, {"mode": raw})

    assert params.mode is expected


def test_dataclass_from_dict_converts_int_enum_by_value_and_name() -> None:
    assert dataclass_from_dict(Params, {"level": 2}).level is Level.HIGH
    assert dataclass_from_dict(Params, {"level": "high"}).level is Level.HIGH


def test_dataclass_from_dict_bad_enum_lists_accepted_values() -> None:
    with pytest.raises(ValueError, match="'fast', 'safe_stop'") as info:
        dataclass_from_dict(Params, {"mode": "turbo"}, source="robots.yaml")

    assert "turbo" in str(info.value)
    assert "robots.yaml" in str(info.value)
    assert "mode" in str(info.value)


def test_dataclass_from_dict_optional_accepts_none_and_value() -> None:
    assert dataclass_from_dict(Params, {"limit": None}).limit is None
    assert dataclass_from_dict(Params, {"legacy_limit": 1.5}).legacy_limit == 1.5
    assert dataclass_from_dict(Params, {"either": "x"}).either == "x"
    assert dataclass_from_dict(Params, {"either": 4}).either == 4


def test_dataclass_from_dict_any_and_dict_fields() -> None:
    params = dataclass_from_dict(
        Params, {"extra": [1, "two"], "tags": {"a": 1}, "camera_config": {"fov": 60}}
    )

    assert params.extra == [1, "two"]
    assert params.tags == {"a": 1}
    assert params.camera_config == {"fov": 60}


def test_dataclass_from_dict_builds_nested_dataclass_from_mapping() -> None:
    params = dataclass_from_dict(Params, {"inner": {"gain": 3}})

    assert params.inner == Inner(gain=3.0)


def test_dataclass_from_dict_nested_unknown_key_names_the_path() -> None:
    with pytest.raises(ValueError, match=r"Params\.inner: unknown key 'gian'") as info:
        dataclass_from_dict(Params, {"inner": {"gian": 3}}, source="w.yaml")

    assert "did you mean 'gain'" in str(info.value)
    assert str(info.value).startswith("w.yaml: ")


def test_dataclass_from_dict_string_annotations_resolved() -> None:
    # This module uses `from __future__ import annotations`: every annotation is a string.
    assert isinstance(Params.__dataclass_fields__["speed"].type, str)

    with pytest.raises(ValueError, match="expected float"):
        dataclass_from_dict(Params, {"speed": "fast"})


# ----- dataclass_from_dict: errors -------------------------------------------------------


def test_dataclass_from_dict_unknown_key_names_key_suggestion_section_and_file() -> None:
    with pytest.raises(ValueError, match="unknown key") as info:
        dataclass_from_dict(Params, {"sped": 1.0}, source="fleet.yaml", section="simulation")

    message = str(info.value)
    assert "'sped'" in message
    assert "did you mean 'speed'?" in message
    assert "simulation" in message
    assert message.startswith("fleet.yaml: ")


def test_dataclass_from_dict_unknown_key_without_section_names_the_class() -> None:
    with pytest.raises(ValueError, match=r"Params: unknown key 'zzz_qqq'"):
        dataclass_from_dict(Params, {"zzz_qqq": 1})


def test_dataclass_from_dict_reports_every_unknown_key() -> None:
    with pytest.raises(ValueError, match="unknown keys") as info:
        dataclass_from_dict(Params, {"sped": 1, "cont": 2})

    assert "'sped'" in str(info.value)
    assert "'cont'" in str(info.value)


def test_dataclass_from_dict_missing_required_field_is_named() -> None:
    with pytest.raises(ValueError, match="missing required key 'robot_id'"):
        dataclass_from_dict(Required, {"speed": 1.0})

    assert dataclass_from_dict(Required, {"robot_id": "r1"}) == Required("r1")


@pytest.mark.parametrize(
    ("key", "value", "expected"),
    [
        ("speed", "fast", "float"),
        ("speed", True, "float"),
        ("speed", [1.0], "float"),
        ("speed", None, "float"),
        ("count", 2.5, "int"),
        ("count", "3", "int"),
        ("count", False, "int"),
        ("enabled", "yes", "bool"),
        ("enabled", 1, "bool"),
        ("name", 12, "str"),
        ("name", ["a"], "str"),
        ("waypoints", 1.0, "list"),
        ("tags", [1], "dict"),
        ("either", 1.5, "int | str"),
    ],
)
def test_dataclass_from_dict_type_mismatch_names_key_value_type_and_file(
    key: str, value: object, expected: str
) -> None:
    with pytest.raises(ValueError, match="expected") as info:
        dataclass_from_dict(Params, {key: value}, source="cfg.yaml")

    message = str(info.value)
    assert message.startswith("cfg.yaml: ")
    assert f"Params.{key}" in message
    assert repr(value) in message
    assert expected in message


def test_dataclass_from_dict_checks_container_items_and_names_them() -> None:
    with pytest.raises(ValueError, match=r"Params\.waypoints\[1\]: expected float, got 'x'"):
        dataclass_from_dict(Params, {"waypoints": [1.0, "x"]})
    with pytest.raises(ValueError, match=r"Params\.tags\['a'\]: expected int, got 'b'"):
        dataclass_from_dict(Params, {"tags": {"a": "b"}})


def test_dataclass_from_dict_hints_at_yaml_exponent_strings() -> None:
    with pytest.raises(ValueError, match=r"1\.0e-3"):
        dataclass_from_dict(Params, {"speed": "1e-3"})


def test_dataclass_from_dict_non_mapping_config() -> None:
    with pytest.raises(ValueError, match="expected a mapping"):
        dataclass_from_dict(Params, ["speed", 1.0])  # type: ignore[arg-type]


def test_dataclass_from_dict_requires_a_dataclass_type() -> None:
    with pytest.raises(TypeError, match="dataclass"):
        dataclass_from_dict(dict, {})
    with pytest.raises(TypeError, match="dataclass"):
        dataclass_from_dict(Params(), {})  # type: ignore[arg-type]


def test_dataclass_from_dict_post_init_error_gets_the_file() -> None:
    with pytest.raises(ValueError, match=r"^v\.yaml: Validated\.speed: expected >= 0"):
        dataclass_from_dict(Validated, {"speed": -1.0}, source="v.yaml")
    with pytest.raises(ValueError, match=r"^Validated\.speed"):
        dataclass_from_dict(Validated, {"speed": -1.0})


def test_dataclass_from_dict_does_not_mutate_config() -> None:
    config = {"speed": 2, "waypoints": [1, 2], "mode": "fast"}

    dataclass_from_dict(Params, config)

    assert config == {"speed": 2, "waypoints": [1, 2], "mode": "fast"}


# ----- dataclass_from_dict: aliases, converters, strict_keys -----------------------------


def test_dataclass_from_dict_alias_reads_alternative_key() -> None:
    aliases = {"camera_config": "camera"}

    params = dataclass_from_dict(Params, {"camera": {"fov": 90}}, aliases=aliases)
    plain = dataclass_from_dict(Params, {"camera_config": {"fov": 45}}, aliases=aliases)

    assert params.camera_config == {"fov": 90}
    assert plain.camera_config == {"fov": 45}
    with pytest.raises(ValueError, match="not both"):
        dataclass_from_dict(Params, {"camera": {}, "camera_config": {}}, aliases=aliases)


def test_dataclass_from_dict_converter_applies_and_none_skips() -> None:
    converters = {"count": lambda v: None if v == "auto" else int(v) * 10}

    assert dataclass_from_dict(Params, {"count": "2"}, converters=converters).count == 20
    assert dataclass_from_dict(Params, {"count": "auto"}, converters=converters).count == 3


def test_dataclass_from_dict_converter_error_names_the_key() -> None:
    with pytest.raises(ValueError, match=r"^c\.yaml: Params\.count: .*invalid literal"):
        dataclass_from_dict(Params, {"count": "many"}, converters={"count": int}, source="c.yaml")


def test_dataclass_from_dict_strict_keys_reads_only_listed_fields() -> None:
    config = {"speed": 9.0, "count": 9, "unrelated_key": "ignored"}

    params = dataclass_from_dict(Params, config, strict_keys=["speed"])

    assert params.speed == 9.0
    assert params.count == 3


def test_dataclass_from_dict_rejects_unknown_field_names_in_options() -> None:
    with pytest.raises(ValueError, match="'nope' is not a field"):
        dataclass_from_dict(Params, {}, strict_keys=["nope"])
    with pytest.raises(ValueError, match="'nope' is not a field"):
        dataclass_from_dict(Params, {}, aliases={"nope": "x"})


# ----- forward_spawn_params --------------------------------------------------------------


@dataclass
class Spawn:
    urdf_path: str = "robot.urdf"
    initial_pose: tuple[float, float, float] = (0.0, 0.0, 0.0)
    mass: float = 1.0
    color: str = "red"


class Factory:
    @classmethod
    def from_urdf(
        cls, urdf_path: str, pose: object = None, mass: float = 0.0, sim_core: object = None
    ) -> dict[str, object]:
        return {"urdf_path": urdf_path, "pose": pose, "mass": mass, "sim_core": sim_core}


def test_forward_spawn_params_matches_signature_with_aliases_and_extras() -> None:
    spawn = Spawn(urdf_path="r2d2.urdf", initial_pose=(1.0, 2.0, 0.0), mass=3.0)
    sim = object()

    kwargs = forward_spawn_params(
        Factory.from_urdf,
        spawn,
        aliases={"initial_pose": "pose"},
        extra_kwargs={"sim_core": sim},
    )

    assert kwargs == {
        "urdf_path": "r2d2.urdf",
        "pose": (1.0, 2.0, 0.0),
        "mass": 3.0,
        "sim_core": sim,
    }
    assert Factory.from_urdf(**kwargs)["pose"] == (1.0, 2.0, 0.0)


def test_forward_spawn_params_without_alias_drops_unmatched_fields() -> None:
    kwargs = forward_spawn_params(Factory.from_urdf, Spawn())

    assert kwargs == {"urdf_path": "robot.urdf", "mass": 1.0}


def test_forward_spawn_params_var_kwargs_receives_every_field() -> None:
    def factory(urdf_path: str, **kwargs: object) -> None:
        del urdf_path, kwargs

    kwargs = forward_spawn_params(factory, Spawn(), extra_kwargs={"mass": 5.0})

    assert kwargs == {
        "urdf_path": "robot.urdf",
        "initial_pose": (0.0, 0.0, 0.0),
        "mass": 5.0,
        "color": "red",
    }


def test_forward_spawn_params_errors() -> None:
    with pytest.raises(TypeError, match="dataclass instance"):
        forward_spawn_params(Factory.from_urdf, Spawn)
    with pytest.raises(ValueError, match="'pose_typo' is not a field of Spawn"):
        forward_spawn_params(Factory.from_urdf, Spawn(), aliases={"pose_typo": "pose"})


def test_forward_spawn_params_skips_positional_only_parameters() -> None:
    def factory(urdf_path: str, /, mass: float = 0.0) -> None:
        del urdf_path, mass

    assert forward_spawn_params(factory, Spawn()) == {"mass": 1.0}


def test_dataclass_from_dict_missing_aliased_field_names_key_and_field() -> None:
    with pytest.raises(ValueError, match=r"missing required key 'id' \(field 'robot_id'\)"):
        dataclass_from_dict(Required, {}, aliases={"robot_id": "id"}, source="r.yaml")
    assert dataclass_from_dict(Required, {"id": "r7"}, aliases={"robot_id": "id"}).robot_id == "r7"
