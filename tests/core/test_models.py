"""Model names, search paths, aliases, and the project's own robot URDFs."""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import pybullet as p
import pybullet_data
import pytest

from fleet_async.core.bodies.models import (
    PROJECT_ROBOTS_DIR,
    add_model_search_path,
    list_model_search_paths,
    list_models,
    register_model,
    remove_model_search_path,
    reset_model_registry,
    resolve_model,
)

PROJECT_MODELS = [
    "arm_robot",
    "mobile_manipulator",
    "mobile_robot",
    "rail_arm_robot",
    "simple_cube",
]
PYBULLET_MODELS = {
    "panda": "franka_panda/panda.urdf",
    "kuka_iiwa": "kuka_iiwa/model.urdf",
    "husky": "husky/husky.urdf",
    "racecar": "racecar/racecar.urdf",
    "r2d2": "r2d2.urdf",
    "kiva_shelf": "kiva_shelf/model.sdf",
    "table": "table/table.urdf",
    "tray": "tray/traybox.urdf",
    "cube": "cube.urdf",
    "sphere": "sphere2.urdf",
    "plane": "plane.urdf",
    "xarm": "xarm/xarm6_robot.urdf",
}
TINY_URDF = """<?xml version="1.0"?>
<robot name="tiny">
  <link name="base_link">
    <inertial><mass value="0.1"/>
      <inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial>
    <collision><geometry><sphere radius="0.05"/></geometry></collision>
  </link>
</robot>
"""


@pytest.fixture(autouse=True)
def _clean_registry() -> Iterator[None]:
    reset_model_registry()
    yield
    reset_model_registry()


@pytest.fixture
def robots_dir(tmp_path: Path) -> Path:
    """``tmp_path/models/robots/tiny_bot.urdf``; returns ``tmp_path/models``."""
    models = tmp_path / "models"
    (models / "robots").mkdir(parents=True)
    (models / "robots" / "tiny_bot.urdf").write_text(TINY_URDF)
    return models


@pytest.fixture
def client() -> Iterator[int]:
    cid = p.connect(p.DIRECT)
    yield cid
    p.disconnect(cid)


def _joints(body: int, cid: int) -> dict[str, tuple]:
    """Joint name -> the ``getJointInfo`` tuple."""
    infos = [p.getJointInfo(body, j, physicsClientId=cid) for j in range(p.getNumJoints(body, cid))]
    return {info[1].decode(): info for info in infos}


def _link_names(body: int, cid: int) -> list[str]:
    base = p.getBodyInfo(body, physicsClientId=cid)[0].decode()
    return [base, *(info[12].decode() for info in _joints(body, cid).values())]


# ----- known names -----------------------------------------------------------------------


def test_list_models_is_sorted_and_holds_every_default() -> None:
    names = list_models()

    assert names == sorted(names)
    assert set(names) == set(PROJECT_MODELS) | set(PYBULLET_MODELS)


@pytest.mark.parametrize("name", sorted(PYBULLET_MODELS))
def test_pybullet_names_resolve_into_pybullet_data(name: str) -> None:
    expected = Path(pybullet_data.getDataPath(), PYBULLET_MODELS[name]).resolve()

    assert resolve_model(name) == str(expected)
    assert Path(resolve_model(name)).is_file()


@pytest.mark.parametrize("name", PROJECT_MODELS)
@pytest.mark.parametrize("spelling", ["{}", "{}.urdf", "robots/{}.urdf"])
def test_project_names_resolve_in_every_spelling(name: str, spelling: str) -> None:
    path = resolve_model(spelling.format(name))

    assert path == str(Path(PROJECT_ROBOTS_DIR, f"{name}.urdf"))
    assert Path(path).is_absolute()
    assert Path(path).is_file()


def test_pybullet_name_with_extension() -> None:
    assert resolve_model("panda.urdf") == resolve_model("panda")
    assert resolve_model("kiva_shelf.sdf") == resolve_model("kiva_shelf")


def test_bare_name_of_a_pybullet_data_file() -> None:
    expected = Path(pybullet_data.getDataPath(), "duck_vhacd.urdf").resolve()

    assert resolve_model("duck_vhacd") == str(expected)


# ----- paths -----------------------------------------------------------------------------


def test_absolute_path_is_returned_resolved(robots_dir: Path) -> None:
    target = robots_dir / "robots" / "tiny_bot.urdf"

    assert resolve_model(str(target)) == str(target.resolve())


def test_path_relative_to_cwd(robots_dir: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(robots_dir)

    assert resolve_model("robots/tiny_bot.urdf") == str(
        (robots_dir / "robots" / "tiny_bot.urdf").resolve()
    )


def test_path_relative_to_a_search_path(robots_dir: Path) -> None:
    with pytest.raises(ValueError, match=r"unknown model 'robots/tiny_bot\.urdf'"):
        resolve_model("robots/tiny_bot.urdf")

    add_model_search_path(str(robots_dir))

    assert resolve_model("robots/tiny_bot.urdf") == str(
        (robots_dir / "robots" / "tiny_bot.urdf").resolve()
    )


def test_bare_name_found_in_a_search_path(robots_dir: Path) -> None:
    add_model_search_path(str(robots_dir / "robots"))

    assert resolve_model("tiny_bot") == str((robots_dir / "robots" / "tiny_bot.urdf").resolve())


def test_relative_path_in_pybullet_data() -> None:
    expected = Path(pybullet_data.getDataPath(), "kuka_iiwa", "model.urdf").resolve()

    assert resolve_model("kuka_iiwa/model.urdf") == str(expected)


# ----- search paths ----------------------------------------------------------------------


def test_default_search_paths() -> None:
    assert list_model_search_paths() == [
        PROJECT_ROBOTS_DIR,
        str(Path(pybullet_data.getDataPath()).resolve()),
    ]


def test_later_search_paths_are_searched_first(tmp_path: Path) -> None:
    first, second = tmp_path / "first", tmp_path / "second"
    for directory in (first, second):
        directory.mkdir()
        (directory / "bot.urdf").write_text(TINY_URDF)

    add_model_search_path(str(first))
    add_model_search_path(str(second))

    assert list_model_search_paths()[:2] == [str(second.resolve()), str(first.resolve())]
    assert list_model_search_paths()[-2:] == [
        PROJECT_ROBOTS_DIR,
        str(Path(pybullet_data.getDataPath()).resolve()),
    ]
    assert resolve_model("bot.urdf") == str((second / "bot.urdf").resolve())


def test_adding_a_path_twice_keeps_one_entry_at_the_front(tmp_path: Path) -> None:
    first, second = tmp_path / "first", tmp_path / "second"
    first.mkdir()
    second.mkdir()

    add_model_search_path(str(first))
    add_model_search_path(str(second))
    add_model_search_path(str(first) + os.sep)

    assert list_model_search_paths()[:3] == [
        str(first.resolve()),
        str(second.resolve()),
        PROJECT_ROBOTS_DIR,
    ]


def test_adding_a_builtin_path_changes_nothing() -> None:
    before = list_model_search_paths()

    add_model_search_path(PROJECT_ROBOTS_DIR)
    add_model_search_path(pybullet_data.getDataPath())

    assert list_model_search_paths() == before


def test_add_search_path_rejects_a_non_directory(tmp_path: Path) -> None:
    a_file = tmp_path / "file.urdf"
    a_file.write_text(TINY_URDF)

    with pytest.raises(ValueError, match="is not a directory"):
        add_model_search_path(str(tmp_path / "missing"))
    with pytest.raises(ValueError, match="is not a directory"):
        add_model_search_path(str(a_file))


def test_remove_search_path(robots_dir: Path) -> None:
    add_model_search_path(str(robots_dir))

    assert remove_model_search_path(str(robots_dir)) is True
    assert remove_model_search_path(str(robots_dir)) is False
    assert str(robots_dir.resolve()) not in list_model_search_paths()
    with pytest.raises(ValueError, match="unknown model"):
        resolve_model("robots/tiny_bot.urdf")


def test_builtin_search_paths_cannot_be_removed() -> None:
    assert remove_model_search_path(PROJECT_ROBOTS_DIR) is False
    assert PROJECT_ROBOTS_DIR in list_model_search_paths()


# ----- aliases ---------------------------------------------------------------------------


def test_register_model_adds_a_known_name(robots_dir: Path) -> None:
    target = robots_dir / "robots" / "tiny_bot.urdf"

    register_model("tiny", str(target))

    assert "tiny" in list_models()
    assert list_models() == sorted(list_models())
    assert resolve_model("tiny") == str(target.resolve())
    assert resolve_model("tiny.urdf") == str(target.resolve())


def test_register_model_shadows_a_builtin_name(robots_dir: Path) -> None:
    target = robots_dir / "robots" / "tiny_bot.urdf"

    register_model("panda", str(target))

    assert resolve_model("panda") == str(target.resolve())


def test_register_model_requires_an_existing_file(tmp_path: Path) -> None:
    missing = tmp_path / "nope.urdf"

    with pytest.raises(FileNotFoundError, match=r"nope\.urdf"):
        register_model("nope", str(missing))
    assert "nope" not in list_models()


@pytest.mark.parametrize("bad_name", ["", "robots/bot", "bot.urdf"])
def test_register_model_rejects_path_like_names(robots_dir: Path, bad_name: str) -> None:
    with pytest.raises(ValueError, match="bare name"):
        register_model(bad_name, str(robots_dir / "robots" / "tiny_bot.urdf"))


def test_reset_model_registry_restores_defaults(robots_dir: Path) -> None:
    defaults = (list_models(), list_model_search_paths())
    add_model_search_path(str(robots_dir))
    register_model("tiny", str(robots_dir / "robots" / "tiny_bot.urdf"))

    reset_model_registry()

    assert (list_models(), list_model_search_paths()) == defaults
    with pytest.raises(ValueError, match="unknown model"):
        resolve_model("tiny")


# ----- unknown names ---------------------------------------------------------------------


def test_unknown_name_lists_models_paths_and_closest_match() -> None:
    with pytest.raises(ValueError, match="unknown model 'pandaa'") as excinfo:
        resolve_model("pandaa")

    message = str(excinfo.value)
    assert "did you mean 'panda'?" in message
    assert f"known models: {list_models()}" in message
    assert f"search paths: {list_model_search_paths()}" in message


def test_unknown_name_without_a_close_match() -> None:
    with pytest.raises(ValueError, match="unknown model 'zzzzzz'") as excinfo:
        resolve_model("zzzzzz")

    assert "did you mean" not in str(excinfo.value)


def test_missing_absolute_path_is_unknown(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="unknown model"):
        resolve_model(str(tmp_path / "ghost.urdf"))


def test_empty_name_is_unknown() -> None:
    with pytest.raises(ValueError, match="unknown model ''"):
        resolve_model("")


# ----- project URDFs ---------------------------------------------------------------------


@pytest.mark.parametrize("name", PROJECT_MODELS)
def test_project_urdf_loads_with_positive_masses(name: str, client: int) -> None:
    body = p.loadURDF(resolve_model(name), physicsClientId=client)

    assert body >= 0
    for link in range(-1, p.getNumJoints(body, physicsClientId=client)):
        mass, _, inertia = p.getDynamicsInfo(body, link, physicsClientId=client)[:3]
        assert mass > 0.0
        assert all(value > 0.0 for value in inertia)


def test_simple_cube(client: int) -> None:
    body = p.loadURDF(resolve_model("simple_cube"), physicsClientId=client)

    assert p.getNumJoints(body, physicsClientId=client) == 0
    assert p.getBodyInfo(body, physicsClientId=client)[0] == b"base_link"
    assert p.getDynamicsInfo(body, -1, physicsClientId=client)[0] == pytest.approx(1.0)
    aabb_min, aabb_max = p.getAABB(body, -1, physicsClientId=client)
    assert [hi - lo for lo, hi in zip(aabb_min, aabb_max, strict=True)] == pytest.approx(
        [0.2] * 3, abs=0.01
    )


def test_mobile_robot(client: int) -> None:
    body = p.loadURDF(resolve_model("mobile_robot"), physicsClientId=client)
    joints = _joints(body, client)

    assert list(joints) == ["left_wheel_joint", "right_wheel_joint", "base_to_sensor_mast"]
    assert _link_names(body, client) == ["base_link", "left_wheel", "right_wheel", "sensor_mast"]
    for wheel in ("left_wheel_joint", "right_wheel_joint"):
        info = joints[wheel]
        # pybullet reports a continuous joint as revolute with lower > upper (no limits).
        assert info[2] == p.JOINT_REVOLUTE
        assert info[8] > info[9]
        assert info[10] > 0.0
        assert info[11] > 0.0
        assert info[13] == pytest.approx((0.0, 1.0, 0.0))
    assert joints["base_to_sensor_mast"][2] == p.JOINT_FIXED
    aabb_min, aabb_max = p.getAABB(body, -1, physicsClientId=client)
    assert aabb_max[0] - aabb_min[0] >= 0.5
    assert aabb_max[1] - aabb_min[1] == pytest.approx(0.4, abs=0.01)


def _assert_revolute(info: tuple, axis: tuple[float, float, float]) -> None:
    assert info[2] == p.JOINT_REVOLUTE
    assert (info[8], info[9]) == pytest.approx((-2.9, 2.9))
    assert info[10] > 0.0
    assert info[11] == pytest.approx(1.5)
    assert info[13] == pytest.approx(axis)


def test_arm_robot(client: int) -> None:
    body = p.loadURDF(resolve_model("arm_robot"), useFixedBase=True, physicsClientId=client)
    joints = _joints(body, client)

    assert list(joints) == [
        "base_to_shoulder",
        "shoulder_to_elbow",
        "elbow_to_wrist",
        "wrist_to_end",
    ]
    assert _link_names(body, client) == [
        "base_link",
        "shoulder",
        "upper_arm",
        "forearm",
        "end_effector",
    ]
    _assert_revolute(joints["base_to_shoulder"], (0.0, 0.0, 1.0))
    for name in ("shoulder_to_elbow", "elbow_to_wrist", "wrist_to_end"):
        _assert_revolute(joints[name], (0.0, 1.0, 0.0))


def test_arm_robot_reach(client: int) -> None:
    body = p.loadURDF(resolve_model("arm_robot"), useFixedBase=True, physicsClientId=client)
    shoulder = p.getLinkState(body, 1, computeForwardKinematics=True, physicsClientId=client)[4]
    end = p.getLinkState(body, 3, computeForwardKinematics=True, physicsClientId=client)
    aabb_top = p.getAABB(body, 3, physicsClientId=client)[1][2]

    # Straight up: the wrist frame sits 0.55 m above the shoulder pitch axis, the tip ~0.63 m.
    assert end[4][2] - shoulder[2] == pytest.approx(0.55)
    assert 0.6 <= aabb_top - shoulder[2] <= 0.8


def test_mobile_manipulator(client: int) -> None:
    body = p.loadURDF(resolve_model("mobile_manipulator"), physicsClientId=client)
    joints = _joints(body, client)

    assert {"left_wheel_joint", "right_wheel_joint"} <= set(joints)
    rail = joints["rail_joint"]
    assert rail[2] == p.JOINT_PRISMATIC
    assert (rail[8], rail[9]) == pytest.approx((0.0, 0.4))
    assert rail[10] > 0.0
    assert rail[11] == pytest.approx(0.2)
    assert rail[12] == b"mount"
    _assert_revolute(joints["mount_to_shoulder"], (0.0, 0.0, 1.0))
    for name in ("shoulder_to_elbow", "elbow_to_wrist", "wrist_to_end"):
        _assert_revolute(joints[name], (0.0, 1.0, 0.0))
    assert joints["wrist_to_end"][12] == b"end_effector"
    movable = [name for name, info in joints.items() if info[2] != p.JOINT_FIXED]
    assert movable == [
        "left_wheel_joint",
        "right_wheel_joint",
        "rail_joint",
        "mount_to_shoulder",
        "shoulder_to_elbow",
        "elbow_to_wrist",
        "wrist_to_end",
    ]
