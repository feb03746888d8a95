"""Grid maps: map_server YAML + PGM / PNG, MovingAI .map / .scen, merged static bodies, and
safety fields that see a map's walls."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from fleet_async import (
    Agent,
    AgentSpawnParams,
    MultiRobotSimulationCore,
    OccupancyGrid,
    Pose,
    ShapeParams,
    read_movingai_scen,
)
from fleet_async.core.maps import read_map_server, read_movingai_map
from fleet_async.core.maps.readers import read_pgm
from tests.conftest import headless_params

DATA = Path(__file__).resolve().parents[2] / "data" / "traffic"


def test_a_pgm_map_reads_with_origin_thresholds_and_the_image_flipped():
    grid = read_map_server(DATA / "room.yaml")
    assert grid.shape == (10, 20)
    assert grid.resolution == 0.1
    assert grid.origin == (-1.0, -0.5)
    # the image's top row is the map's top: row 9 here; the block sits at image rows 6-7
    assert grid.occupied[9].all()
    assert grid.occupied[2:4, 3:7].all() and grid.occupied.sum() == 20 + 8
    assert not grid.occupied[6, 15]  # unknown (grey) counts as free
    assert grid.cell_center(0, 0) == pytest.approx((-0.95, -0.45))
    assert grid.cell_of(-0.95, -0.45) == (0, 0)


def test_a_png_map_reads_as_the_pgm_does():
    assert np.array_equal(
        read_map_server(DATA / "room_png.yaml").occupied,
        read_map_server(DATA / "room.yaml").occupied,
    )


def test_negate_and_raw_modes(tmp_path):
    (tmp_path / "m.pgm").write_bytes(b"P2\n2 1\n255\n0 255\n")
    (tmp_path / "m.yaml").write_text("image: m.pgm\nresolution: 1\norigin: [0, 0, 0]\nnegate: 1\n")
    assert read_map_server(tmp_path / "m.yaml").occupied.tolist() == [[False, True]]
    (tmp_path / "r.yaml").write_text("image: m.pgm\nresolution: 1\norigin: [0, 0]\nmode: raw\n")
    assert read_map_server(tmp_path / "r.yaml").occupied.tolist() == [[False, True]]
    assert read_pgm(tmp_path / "m.pgm").tolist() == [[0, 255]]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            "image: room.pgm\nresolution: 0.1\norigin: [0, 0, 0]\ncolour: 1\n",
            "unknown key 'colour'",
        ),
        ("image: room.pgm\nresolution: -1\norigin: [0, 0, 0]\n", "resolution"),
        ("image: room.pgm\nresolution: 0.1\norigin: [0, 0, 0.5]\n", "rotated"),
        ("image: room.pgm\nresolution: 0.1\n", "missing key 'origin'"),
        ("image: room.pgm\nresolution: 0.1\norigin: [0, 0]\nmode: fancy\n", "mode"),
    ],
)
def test_bad_map_server_files_are_named(tmp_path, text, message):
    (tmp_path / "room.pgm").write_bytes((DATA / "room.pgm").read_bytes())
    (tmp_path / "bad.yaml").write_text(text)
    with pytest.raises(ValueError, match=message):
        read_map_server(tmp_path / "bad.yaml")


def test_a_movingai_map_and_its_scenario():
    grid = read_movingai_map(DATA / "warehouse-small.map", resolution=0.5)
    assert grid.shape == (17, 33)
    assert grid.occupied[2, 2] and not grid.occupied[4, 2]
    assert len(grid.rectangles()) == 10  # each shelf block is one rectangle
    tasks = read_movingai_scen(DATA / "warehouse-small.scen")
    assert [(t.start, t.goal) for t in tasks] == [
        ((0, 0), (32, 16)),
        ((16, 1), (16, 15)),
        ((1, 4), (31, 13)),
    ]
    assert grid.is_free(tasks[2].start[1], tasks[2].start[0])


def test_a_bad_movingai_row_is_named(tmp_path):
    path = tmp_path / "bad.map"
    path.write_text("type octile\nheight 2\nwidth 3\nmap\n...\n.x.\n")
    with pytest.raises(ValueError, match=r"bad.map:6: unknown terrain 'x'"):
        read_movingai_map(path)


def test_rectangles_cover_every_occupied_cell_once():
    rng = np.random.default_rng(3)
    grid = OccupancyGrid(rng.random((23, 31)) < 0.3)
    cover = np.zeros(grid.shape, dtype=np.int64)
    for r0, c0, r1, c1 in grid.rectangles().tolist():
        cover[r0:r1, c0:c1] += 1
    assert np.array_equal(cover, grid.occupied.astype(np.int64))


def test_a_map_is_few_static_bodies_that_robots_collide_with():
    params = headless_params(enable_floor=False, ignore_static_collision=False)
    with MultiRobotSimulationCore(params) as sim:
        loaded = sim.load_map(DATA / "warehouse-small.map", resolution=0.5, tile=8.0)
        assert sim.maps == [loaded]
        assert 1 < len(loaded.bodies) < 10
        assert len(loaded.lo) == 10
        box = ShapeParams("box", half_extents=[0.2, 0.2, 0.2])
        robot = Agent.from_mesh(
            box,
            box,
            Pose.from_xyz(*loaded.cell_position(4, 4, 0.2)),
            sim_core=sim,
            controller="omni",
        )
        robot.set_path([Pose.from_xyz(*loaded.cell_position(1, 4, 0.2))])  # through a shelf
        hits = []
        sim.events.on("collision_started", lambda obj_a, obj_b, **_: hits.append({obj_a, obj_b}))
        for _ in range(30):
            sim.step_once()
        assert any(robot in pair for pair in hits)


def test_ignoring_static_collisions_leaves_the_map_out_but_not_the_robots():
    # The default leaves every pair with a static body out, so the check does not hash the
    # map's tile bodies at all; robots still meet each other among them.
    with MultiRobotSimulationCore(headless_params(enable_floor=False)) as sim:
        loaded = sim.load_map(DATA / "warehouse-small.map", resolution=0.5, tile=8.0)
        box = ShapeParams("box", half_extents=[0.2, 0.2, 0.2])
        a, b = (
            Agent.from_mesh(
                box,
                box,
                Pose.from_xyz(*loaded.cell_position(row, 4, 0.2)),
                sim_core=sim,
                controller="omni",
            )
            for row in (4, 0)
        )
        a.set_path([Pose.from_xyz(*loaded.cell_position(0, 4, 0.2))])  # through a shelf to b
        hits = []
        sim.events.on("collision_started", lambda obj_a, obj_b, **_: hits.append({obj_a, obj_b}))
        for _ in range(40):
            sim.step_once()
        assert hits == [{a, b}]


def test_the_movingai_warehouse_map_loads_with_its_shelves_and_aisles():
    path = DATA / "warehouse-10-20-10-2-1.map"
    assert path.read_text().splitlines()[:3] == ["type octile", "height 63", "width 161"]
    grid = read_movingai_map(path, 1.0)
    assert grid.occupied.shape == (63, 161)
    assert int(grid.occupied.sum()) == 4444  # the border and 200 shelf blocks of 10 x 2
    with MultiRobotSimulationCore(headless_params(enable_floor=False)) as sim:
        loaded = sim.load_map(path)
        assert len(loaded.lo) == 204  # one box per shelf block, four for the border
        sizes = np.round(loaded.hi[:, :2] - loaded.lo[:, :2], 6)
        assert int(np.count_nonzero((sizes == [10.0, 2.0]).all(axis=1))) == 200
        assert len(loaded.free_cells()) == 63 * 161 - 4444


def test_safety_fields_stop_a_robot_before_a_maps_shelf():
    with MultiRobotSimulationCore(headless_params(enable_floor=False)) as sim:
        loaded = sim.load_map(DATA / "warehouse-small.map", resolution=0.5)
        box = ShapeParams("box", half_extents=[0.2, 0.2, 0.2])
        params = AgentSpawnParams(
            visual_shape=box,
            collision_shape=box,
            initial_pose=Pose.from_xyz(*loaded.cell_position(4, 4, 0.2)),
            motion_mode="omnidirectional",
            safety_field={"warning_margin": 0.0},
        )
        robot = Agent.from_params(params, sim)
        robot.set_path([Pose.from_xyz(*loaded.cell_position(1, 4, 0.2))])
        for _ in range(40):
            sim.step_once()
        assert sim.safety.is_stopped(robot)
        # stopped before the shelf's edge (row 4's lower edge: y = 2.0 m) within its margin
        front = robot.get_pose().y - 0.2
        assert front > 2.0 and front - 2.0 <= 0.1 + 1e-9


def test_an_unknown_map_kind_is_refused(tmp_path):
    path = tmp_path / "m.txt"
    path.write_text("x")
    with (
        MultiRobotSimulationCore(headless_params()) as sim,
        pytest.raises(ValueError, match=r"m\.txt"),
    ):
        sim.load_map(path)
