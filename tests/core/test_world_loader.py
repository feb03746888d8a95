from __future__ import annotations

import logging
import math
import re
import struct
from pathlib import Path

import numpy as np
import pybullet as p
import pybullet_data
import pytest

from fleet_async import (
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimEvents,
    SimObject,
    WorldLoadError,
)
from fleet_async.core.scenario import world_loader
from fleet_async.core.world.shapes import body_collision_shape
from tests.conftest import headless_params

ROOT = Path(__file__).resolve().parent.parent.parent
DATA = ROOT / "tests" / "data" / "worlds"
WORLD = DATA / "test.world"
WAREHOUSE = ROOT / "examples" / "worlds" / "warehouse.world"
KIVA = Path(pybullet_data.getDataPath()) / "kiva_shelf" / "model.sdf"

BOX_MODEL = """<?xml version="1.0"?>
<sdf version="1.6"><model name="{name}"><static>true</static>
  <link name="body"><collision name="c"><geometry><box><size>{size} {size} {size}</size></box>
  </geometry></collision></link></model></sdf>
"""


def aabb(sim, obj, link=-1):
    lo, hi = p.getAABB(obj.body_id, link, physicsClientId=sim.client)
    return np.array(lo), np.array(hi)


def body_count(sim):
    return p.getNumBodies(physicsClientId=sim.client)


def world_xml(*children: str) -> str:
    return (
        '<?xml version="1.0"?>\n<sdf version="1.6"><world name="w">\n'
        + "\n".join(children)
        + "\n</world></sdf>\n"
    )


def include(uri: str, name: str | None = None, pose: str | None = None) -> str:
    parts = [f"<uri>{uri}</uri>"]
    if name is not None:
        parts.append(f"<name>{name}</name>")
    if pose is not None:
        parts.append(f"<pose>{pose}</pose>")
    return "<include>" + "".join(parts) + "</include>"


def write_model(models_dir: Path, name: str, sdf_text: str, filename: str = "model.sdf") -> Path:
    model_dir = models_dir / name
    model_dir.mkdir(parents=True, exist_ok=True)
    (model_dir / filename).write_text(sdf_text)
    return model_dir


def box_at(sim, x, y, z, half=0.2):
    shape = ShapeParams("box", half_extents=[half, half, half])
    return SimObject.from_mesh(
        visual_shape=shape, collision_shape=shape, pose=Pose.from_xyz(x, y, z), sim_core=sim
    )


def pairs_with(sim, obj):
    sim.step_once()
    return [pair for pair in sim.get_active_collision_pairs() if obj.object_id in pair]


# ----- Gazebo world files -----------------------------------------------------------------


def test_world_file_loads_includes_and_inline_models_as_static_objects(sim):
    objs = sim.load_world({"world_file": str(WORLD), "skip_models": ["robot_spot"]})
    assert [o.name for o in objs] == ["box_a", "test_box", "pair", "meshy", "inline_wall"]
    assert sim.sim_objects == objs
    for obj in objs:
        assert obj.is_static and obj.mass == 0.0 and not obj.pickable
        links = range(-1, p.getNumJoints(obj.body_id, physicsClientId=sim.client))
        assert [
            p.getDynamicsInfo(obj.body_id, i, physicsClientId=sim.client)[0] for i in links
        ] == [0.0] * len(links)
    assert objs[0].user_data["uri"] == "model://test_box"
    assert objs[0].user_data["model_file"] == str(DATA / "models" / "test_box" / "model.sdf")


def test_include_pose_is_composed_with_the_pose_the_sdf_gives_the_model(sim):
    box_a, plain, *_ = sim.load_world({"world_file": str(WORLD)}, skip_models=["robot_spot"])
    # include (1, 2, 0, yaw pi/2) * model pose (0.5, 0, 0.2) = (1, 2.5, 0.2), yaw pi/2
    pose = box_a.get_pose()
    assert np.allclose(pose.position, [1.0, 2.5, 0.2], atol=1e-9)
    assert math.isclose(pose.yaw, math.pi / 2, abs_tol=1e-9)
    # model.sdf (version 1.6, a 1.0 x 0.5 x 0.4 box) was chosen over model-1_5.sdf (0.1 m cube);
    # turned by 90 degrees it spans 0.5 in x and 1.0 in y.
    lo, hi = aabb(sim, box_a)
    assert np.allclose(lo, [0.75, 2.0, 0.0], atol=1e-6)
    assert np.allclose(hi, [1.25, 3.0, 0.4], atol=1e-6)
    assert np.allclose(plain.get_pose().position, [-2.5, 0.0, 0.2], atol=1e-9)
    assert np.allclose(plain.get_pose().orientation, [0, 0, 0, 1], atol=1e-12)


def test_model_with_two_root_links_and_a_root_link_pose_loads_as_gazebo_places_it(sim):
    objs = sim.load_world({"world_file": str(WORLD), "skip_models": ["robot_spot"]})
    pair = next(o for o in objs if o.name == "pair")
    assert p.getNumJoints(pair.body_id, physicsClientId=sim.client) == 1  # one body, tied
    assert np.allclose(pair.get_pose().position, [1.0, -4.0, 0.0], atol=1e-9)  # "left" link
    lo, hi = aabb(sim, pair, 0)  # "right" link at model x = 3
    assert np.allclose((lo + hi) / 2, [3.0, -4.0, 0.0], atol=1e-6)
    assert np.allclose(hi - lo, [0.5, 0.5, 0.5], atol=1e-6)


def test_model_uri_and_relative_meshes_inside_a_model_sdf_resolve(sim):
    objs = sim.load_world({"world_file": str(WORLD), "skip_models": ["robot_spot"]})
    meshy = next(o for o in objs if o.name == "meshy")
    lo, hi = aabb(sim, meshy)
    # tetra.obj (model://) at the origin plus the ASCII STL wedge (relative path) at x + 2
    assert np.allclose(lo, [0.0, 6.0, 0.0], atol=0.01)
    assert np.allclose(hi, [3.0, 7.0, 1.0], atol=0.01)


def test_skip_models_by_include_name_or_uri_model_name(sim, caplog):
    objs = sim.load_world({"world_file": str(WORLD), "skip_models": ["meshy"]}, ["test_box"])
    assert [o.name for o in objs] == ["pair", "inline_wall"]  # test_box skipped all 3 includes
    sim.reset()
    with caplog.at_level(logging.WARNING, logger="fleet_async.core.scenario.world_loader"):
        objs = sim.load_world({"world_file": str(WORLD)}, ["inline_wall", "robot_spot", "nobody"])
    assert [o.name for o in objs] == ["box_a", "test_box", "pair", "meshy"]
    assert "skip_models ['nobody'] matched nothing" in caplog.text


def test_model_search_order(sim, tmp_path, monkeypatch):
    first, env_dir, world_dir = tmp_path / "first", tmp_path / "env", tmp_path / "world"
    for size, base in ((0.5, first), (1.0, env_dir), (2.0, world_dir / "models")):
        write_model(base, "crate", BOX_MODEL.format(name="crate", size=size))
    world = world_dir / "crates.world"
    world.write_text(world_xml(include("model://crate")))

    def loaded_size(config):
        (obj,) = sim.load_world(config)
        lo, hi = aabb(sim, obj)
        sim.remove_object(obj)
        return round(float(hi[0] - lo[0]), 6)

    monkeypatch.setenv("GAZEBO_MODEL_PATH", f"/no/such/dir:{env_dir}")
    assert loaded_size({"world_file": str(world), "model_paths": [str(first)]}) == 0.5
    assert loaded_size({"world_file": str(world)}) == 1.0
    monkeypatch.delenv("GAZEBO_MODEL_PATH")
    assert loaded_size({"world_file": str(world)}) == 2.0


def test_relative_paths_resolve_against_base_dir_or_the_working_directory(
    sim, tmp_path, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    objs = sim.load_world({"world_file": "test.world", "model_paths": ["models"]}, base_dir=DATA)
    assert len(objs) == 6
    with pytest.raises(FileNotFoundError, match=str(tmp_path / "test.world")):
        sim.load_world({"world_file": "test.world"})
    monkeypatch.chdir(DATA)
    assert [o.name for o in sim.load_world({"mesh_dir": "meshes"})] == [
        "tetra",
        "tetra_binary",
        "wedge_ascii",
    ]


# ----- single SDF files and mesh directories ----------------------------------------------


def test_sdf_key_loads_pybullet_data_kiva_shelf_named_after_its_model(sim):
    (shelf,) = sim.load_world({"sdf": str(KIVA)})
    assert shelf.name == "Amazon Pod" and shelf.is_static and shelf.mass == 0.0
    assert np.allclose(shelf.get_pose().position, [0.0, 1.0, 1.2045], atol=1e-9)
    (again,) = sim.load_world({"sdf": "kiva_shelf/model.sdf"})  # relative: pybullet_data
    assert np.allclose(aabb(sim, again)[0], aabb(sim, shelf)[0])


def test_sdf_key_skips_models_by_name(sim, tmp_path):
    sdf = tmp_path / "two.sdf"
    models = [
        f'<model name="{n}"><static>true</static><pose>{x} 0 0 0 0 0</pose><link name="l">'
        '<collision name="c"><geometry><box><size>1 1 1</size></box></geometry></collision>'
        "</link></model>"
        for n, x in (("keep", 1), ("drop", 5))
    ]
    sdf.write_text('<sdf version="1.6"><world name="w">' + "".join(models) + "</world></sdf>")
    assert [o.name for o in sim.load_world({"sdf": str(sdf)})] == ["keep", "drop"]
    (kept,) = sim.load_world({"sdf": str(sdf), "skip_models": ["drop"]})
    assert kept.name == "keep" and np.allclose(kept.get_pose().position, [1, 0, 0])


def test_mesh_dir_makes_one_static_trimesh_body_per_obj_and_stl_file(sim):
    objs = sim.load_world({"mesh_dir": str(DATA / "meshes")}, skip_models=None)
    assert [o.name for o in objs] == ["tetra", "tetra_binary", "wedge_ascii"]
    assert all(o.is_static and o.mass == 0.0 for o in objs)
    boxes = {o.name: aabb(sim, o) for o in objs}
    assert np.allclose(boxes["tetra"], [[0, 0, 0], [1, 1, 1]], atol=1e-6)
    assert np.allclose(boxes["tetra_binary"], [[5, 0, 0], [7, 2, 2]], atol=1e-6)
    assert np.allclose(boxes["wedge_ascii"], [[0, 0, 0], [1, 1, 1]], atol=1e-6)  # converted
    assert all(body_collision_shape(sim.client, o.body_id) >= 0 for o in objs)
    assert objs[1].user_data == {
        "world_source": str(DATA / "meshes"),
        "model_file": str(DATA / "meshes" / "tetra_binary.stl"),
    }
    assert [o.name for o in sim.load_world({"mesh_dir": str(DATA / "meshes")}, ["tetra"])] == [
        "tetra_binary",
        "wedge_ascii",
    ]


# ----- collisions with loaded geometry ----------------------------------------------------


def test_loaded_shelf_takes_part_in_collision_checks_only_when_static_collisions_count():
    with MultiRobotSimulationCore(headless_params(ignore_static_collision=False)) as sim:
        (shelf,) = sim.load_world({"sdf": str(KIVA)})
        box = box_at(sim, 0.0, 1.0, 1.2)  # through the middle board
        assert pairs_with(sim, box) == [tuple(sorted((shelf.object_id, box.object_id)))]
        box.set_pose(Pose.from_xyz(4.0, 4.0, 1.2))
        assert pairs_with(sim, box) == []
        assert shelf.get_pose().position.tolist() == [0.0, 1.0, 1.2045]  # never moved
    with MultiRobotSimulationCore(headless_params()) as sim:  # ignore_static_collision=True
        sim.load_world({"sdf": str(KIVA)})
        assert pairs_with(sim, box_at(sim, 0.0, 1.0, 1.2)) == []


def test_mesh_dir_body_collides_through_its_triangle_mesh():
    with MultiRobotSimulationCore(headless_params(ignore_static_collision=False)) as sim:
        objs = sim.load_world({"mesh_dir": str(DATA / "meshes")})
        tetra = next(o for o in objs if o.name == "tetra_binary")
        box = box_at(sim, 5.1, 0.5, 0.5)  # crosses the x = 5 face
        assert pairs_with(sim, box) == [(tetra.object_id, box.object_id)]
        box.set_pose(Pose.from_xyz(10.0, 10.0, 0.5))
        assert pairs_with(sim, box) == []


# ----- the example warehouse --------------------------------------------------------------

SHELVES = {
    f"shelf_{row}{col}": (x, y)
    for row, y in (("A", 4.0), ("B", 8.0), ("C", 12.0))
    for col, x in ((1, 4.0), (2, 10.0), (3, 16.0))
}
STATIONS = {"station_1": (5.0, 17.0), "station_2": (15.0, 17.0)}
AISLES_Y = (2.0, 6.0, 10.0, 14.0)


def test_example_warehouse_world_loads_with_four_free_aisles():
    with MultiRobotSimulationCore(headless_params(ignore_static_collision=False)) as sim:
        objs = sim.load_world({"world_file": str(WAREHOUSE)})
        assert {o.name: tuple(o.get_pose().position) for o in objs} == {
            name: (x, y, 0.0) for name, (x, y) in {**SHELVES, **STATIONS}.items()
        }
        boxes = sim.get_aabbs()
        for obj in objs:
            lo, hi = boxes[obj.object_id]
            assert min(lo[0], lo[1]) >= 0.0 and max(hi[0], hi[1]) <= 20.0
            for y in AISLES_Y:  # no rack or table reaches into a 2 m aisle
                assert hi[1] <= y - 1.0 or lo[1] >= y + 1.0, (obj.name, y)
        size = {o.name: np.subtract(*boxes[o.object_id][::-1]) for o in objs}
        assert np.allclose(size["shelf_B2"], [4.0, 1.0, 2.0], atol=0.005)
        assert np.allclose(size["station_1"], [1.2, 0.8, 0.75], atol=0.005)
        robot = box_at(sim, 0.5, 6.0, 0.3, half=0.4)  # 0.8 m robot driving down aisle y = 6
        for x in np.arange(0.5, 20.0, 0.5):
            robot.set_pose(Pose.from_xyz(float(x), 6.0, 0.3))
            assert pairs_with(sim, robot) == [], x
        robot.set_pose(Pose.from_xyz(10.0, 7.8, 0.3))  # into shelf_B2
        shelf_b2 = next(o for o in objs if o.name == "shelf_B2")
        assert pairs_with(sim, robot) == [(shelf_b2.object_id, robot.object_id)]


# ----- config errors ----------------------------------------------------------------------


def test_unknown_key_names_the_key_and_the_nearest_valid_key(sim):
    with pytest.raises(ValueError, match=r"'world_fiel'.*nearest valid key: 'world_file'"):
        sim.load_world({"world_fiel": str(WORLD)})
    with pytest.raises(ValueError, match=r"'skip_model'.*nearest valid key: 'skip_models'"):
        sim.load_world({"world_file": str(WORLD), "skip_model": ["x"]})


def test_no_source_key_says_which_keys_are_accepted(sim):
    with pytest.raises(ValueError, match=r"one of 'world_file'.*'sdf'.*'mesh_dir'"):
        sim.load_world({"skip_models": ["x"]})
    with pytest.raises(TypeError, match="world_config must be a mapping"):
        sim.load_world("office.world")  # type: ignore[arg-type]


def test_missing_source_raises_file_not_found_with_the_absolute_path(sim, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for key, value in (("world_file", "nope.world"), ("sdf", "nope.sdf"), ("mesh_dir", "nope")):
        with pytest.raises(
            FileNotFoundError, match=rf"'{key}'.*{re.escape(str(tmp_path / value))}"
        ):
            sim.load_world({key: value})
    with pytest.raises(FileNotFoundError, match=r"model_paths directory not found: .*/gone"):
        sim.load_world({"world_file": str(WORLD), "model_paths": ["gone"]})


def test_bad_option_values_are_named(sim):
    with pytest.raises(ValueError, match="on_error must be 'raise' or 'warn', got 'ignore'"):
        sim.load_world({"world_file": str(WORLD), "on_error": "ignore"})
    with pytest.raises(ValueError, match="skip_models must be a list of model names, got 'abc'"):
        sim.load_world({"world_file": str(WORLD), "skip_models": "abc"})
    with pytest.raises(ValueError, match="model_paths must be a list of directories"):
        sim.load_world({"world_file": str(WORLD), "model_paths": str(DATA)})


# ----- load failures ----------------------------------------------------------------------


def broken_world(tmp_path: Path) -> Path:
    """A world with one good include and five that fail in different ways."""
    models = tmp_path / "models"
    write_model(models, "good", BOX_MODEL.format(name="good", size=1))
    write_model(models, "garbled", '<sdf version="1.6">\n<model name="garbled">\n<link>\n</sdf>\n')
    # An inertial mass without an inertia block: PyBullet's SDF parser rejects the file.
    write_model(
        models,
        "rejected",
        '<sdf version="1.6"><model name="rejected"><link name="l"><inertial><mass>2</mass>'
        '</inertial><collision name="c"><geometry><box><size>1 1 1</size></box></geometry>'
        "</collision></link></model></sdf>",
    )
    flat = write_model(
        models,
        "flat",
        '<sdf version="1.6"><model name="flat"><link name="l"><collision name="c"><geometry>'
        "<mesh><uri>model://flat/flat.obj</uri></mesh></geometry></collision></link></model></sdf>",
    )
    (flat / "flat.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\n")  # no faces
    (models / "noconfig").mkdir()
    (models / "noconfig" / "model.config").write_text(
        '<model><name>noconfig</name><sdf version="1.6">missing.sdf</sdf></model>'
    )
    world = tmp_path / "broken.world"
    world.write_text(
        world_xml(
            include("model://good", "good_one", "1 0 0 0 0 0"),
            include("model://no_such_model", "ghost"),
            include("model://garbled"),
            include("model://rejected"),
            include("model://flat"),
            include("model://noconfig"),
        )
    )
    return world


def test_every_failure_is_reported_by_name_and_nothing_stays_loaded(sim, tmp_path):
    world = broken_world(tmp_path)
    spawned = []
    sim.events.on(SimEvents.OBJECT_SPAWNED, lambda **kw: spawned.append(kw["obj"]))
    bodies_before = body_count(sim)
    with pytest.raises(WorldLoadError) as info:
        sim.load_world({"world_file": str(world)})
    err = info.value
    assert isinstance(err, RuntimeError) and err.source == str(world)
    assert [f.name for f in err.failures] == ["ghost", "garbled", "rejected", "flat", "noconfig"]
    ghost, garbled, rejected, flat, noconfig = err.failures
    assert "model 'no_such_model' not found" in ghost.reason
    assert str(tmp_path / "models" / "no_such_model") in ghost.paths
    assert f"malformed XML in {tmp_path / 'models' / 'garbled' / 'model.sdf'} at line 4" in (
        garbled.reason
    )
    assert "PyBullet could not load the SDF" in rejected.reason
    assert "is not a usable OBJ mesh: it has no faces" in flat.reason
    assert "names SDF file 'missing.sdf' (version 1.6), which does not exist" in noconfig.reason
    assert "'ghost': model 'no_such_model' not found" in str(err)
    assert sim.sim_objects == [] and spawned == [] and body_count(sim) == bodies_before


def test_on_error_warn_logs_each_failure_and_returns_what_loaded(sim, tmp_path, caplog):
    world = broken_world(tmp_path)
    with caplog.at_level(logging.WARNING, logger="fleet_async.core.scenario.world_loader"):
        objs = sim.load_world({"world_file": str(world), "on_error": "warn"})
    assert [o.name for o in objs] == ["good_one"]
    assert np.allclose(objs[0].get_pose().position, [1.0, 0.0, 0.0])
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warnings) == 5
    assert all("not loaded" in w for w in warnings)
    assert [w.split("not loaded: ")[1].split(":")[0] for w in warnings] == [
        "'ghost'",
        "'garbled'",
        "'rejected'",
        "'flat'",
        "'noconfig'",
    ]


def test_malformed_world_file_reports_file_and_line(sim, tmp_path):
    world = tmp_path / "bad.world"
    world.write_text('<sdf version="1.6">\n<world name="w">\n<include>\n</world></sdf>\n')
    with pytest.raises(
        WorldLoadError, match=rf"malformed XML in {re.escape(str(world))} at line 4, column 2"
    ):
        sim.load_world({"world_file": str(world)})
    world.write_text('<sdf version="1.6"><model name="m"/></sdf>')
    with pytest.raises(WorldLoadError, match=r"no <world> element.*use the 'sdf' key"):
        sim.load_world({"world_file": str(world)})


def test_include_errors_in_the_world_itself_are_named(sim, tmp_path, caplog):
    world = tmp_path / "w.world"
    world.write_text(
        world_xml(
            "<include><name>nouri</name></include>",
            include("model://x", "badpose", "1 2 3"),
            include("https://fuel.example/models/x", "remote"),
            "<model><link name='l'/></model>",
            "<actor name='walker'/>",
        )
    )
    with (
        pytest.raises(WorldLoadError) as info,
        caplog.at_level(logging.WARNING, logger="fleet_async.core.scenario.world_loader"),
    ):
        sim.load_world({"world_file": str(world)})
    assert "<actor name='walker'> is not loaded (not supported)" in caplog.text
    reasons = {f.name: f.reason for f in info.value.failures}
    assert reasons["nouri"] == "<include> #1 of the world has no <uri>"
    assert "needs 6 numbers 'x y z roll pitch yaw', got '1 2 3'" in reasons["badpose"]
    assert "only model://, file:// and file paths are supported" in reasons["remote"]
    assert reasons["<model> #4"] == "inline <model> #4 has no name attribute"


def test_include_by_file_path_relative_to_the_world(sim, tmp_path):
    write_model(tmp_path / "assets", "crate", BOX_MODEL.format(name="crate", size=1))
    world = tmp_path / "w.world"
    world.write_text(
        world_xml(
            include("assets/crate", "by_dir", "0 0 0.5 0 0 0"),
            include(f"file://{tmp_path}/assets/crate/model.sdf", pose="3 0 0.5 0 0 90"),
        )
    )
    objs = sim.load_world({"world_file": str(world)})
    assert [o.name for o in objs] == ["by_dir", "crate"]
    assert np.allclose(objs[1].get_pose().position, [3.0, 0.0, 0.5])


def test_sdf_files_pybullet_cannot_handle_are_reported(sim, tmp_path):
    sdf = tmp_path / "scene.sdf"
    sdf.write_text(
        '<sdf version="1.6"><world name="w"><include><uri>model://x</uri></include>'
        '<model name="outer"><link name="a"/><model name="inner"><link name="b"/></model></model>'
        "</world></sdf>"
    )
    with pytest.raises(WorldLoadError) as info:
        sim.load_world({"sdf": str(sdf)})
    reasons = [f.reason for f in info.value.failures]
    assert "<include> of 'model://x' inside an SDF file" in reasons[0]
    assert "model 'outer': nested <model> ['inner'] is not supported" in reasons[1]


def test_mesh_dir_failures_and_an_empty_directory(sim, tmp_path):
    (tmp_path / "ok.obj").write_text((DATA / "meshes" / "tetra.obj").read_text())
    (tmp_path / "noise.stl").write_bytes(b"\x01" * 10)
    (tmp_path / "short.stl").write_bytes(b"\0" * 80 + struct.pack("<I", 3) + b"\0" * 50)
    (tmp_path / "empty.obj").write_text("# nothing\n")
    bodies_before = body_count(sim)
    with pytest.raises(WorldLoadError) as info:
        sim.load_world({"mesh_dir": str(tmp_path)})
    reasons = {f.name: f.reason for f in info.value.failures}
    not_stl = "is not a valid STL mesh (neither binary nor ASCII)"
    assert reasons == {
        "empty": f"file {tmp_path / 'empty.obj'} is not a usable OBJ mesh: it has no vertices",
        "noise": f"file {tmp_path / 'noise.stl'} {not_stl}",
        "short": f"file {tmp_path / 'short.stl'} {not_stl}",
    }
    assert body_count(sim) == bodies_before and sim.sim_objects == []
    (empty := tmp_path / "none").mkdir()
    with pytest.raises(ValueError, match=re.escape(f"mesh_dir {empty} holds no .obj or .stl file")):
        sim.load_world({"mesh_dir": str(empty)})


def test_a_failure_while_registering_removes_everything(sim, monkeypatch):
    made = []

    class Flaky(SimObject):
        def __init__(self, *args, **kwargs):
            if len(made) == 2:
                raise RuntimeError("registration failed")
            super().__init__(*args, **kwargs)
            made.append(self)

    monkeypatch.setattr(world_loader, "SimObject", Flaky)
    bodies_before = body_count(sim)
    with pytest.raises(RuntimeError, match="registration failed"):
        sim.load_world({"world_file": str(WORLD)})
    assert len(made) == 2 and sim.sim_objects == [] and body_count(sim) == bodies_before


def test_loaded_geometry_stays_put_and_holds_up_a_dynamic_box_under_physics():
    with MultiRobotSimulationCore(headless_params(physics=True, timestep=0.01)) as sim:
        objs = sim.load_world({"world_file": str(WAREHOUSE)})
        shape = ShapeParams("box", half_extents=[0.1, 0.1, 0.1])
        crate = SimObject.from_mesh(
            visual_shape=shape,
            collision_shape=shape,
            pose=Pose.from_xyz(5.0, 17.0, 1.5),
            mass=1.0,
            sim_core=sim,
        )
        for _ in range(300):
            sim.step_once()
        assert {o.name: tuple(o.get_pose().position) for o in objs} == {
            name: (x, y, 0.0) for name, (x, y) in {**SHELVES, **STATIONS}.items()
        }
        # came to rest on station_1's top (0.75 m) instead of falling through
        assert np.allclose(crate.get_pose().position, [5.0, 17.0, 0.85], atol=0.01)


def test_an_empty_world_config_loads_nothing(sim):
    assert sim.load_world({}) == [] and sim.sim_objects == []
