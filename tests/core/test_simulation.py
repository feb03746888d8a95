from __future__ import annotations

import logging

import numpy as np
import pybullet as p
import pytest

from fleet_async import (
    MultiRobotSimulationCore,
    Pose,
    ShapeParams,
    SimEvents,
    SimObject,
    SimPlugin,
)
from tests.conftest import headless_params


def box(sim, x=0.0, y=0.0, z=0.5, **kw):
    return SimObject.from_mesh(
        visual_shape=ShapeParams("box", half_extents=[0.1, 0.1, 0.1]),
        collision_shape=ShapeParams("box", half_extents=[0.1, 0.1, 0.1]),
        pose=Pose.from_xyz(x, y, z),
        sim_core=sim,
        **kw,
    )


def test_sim_time_is_step_count_times_timestep(sim):
    for _ in range(1000):
        sim.step_once()
    assert sim.step_count == 1000
    assert sim.sim_time == 1000 * 0.1  # exact: computed, never accumulated


def test_step_phases_run_in_design_order(sim):
    order = []
    sim.events.on(
        SimEvents.PRE_STEP, lambda **kw: order.append(("pre_step", kw["step"], kw["sim_time"]))
    )
    sim.register_callback(lambda s, dt: order.append(("callback", s.step_count, dt)))
    sim.events.on(SimEvents.PRE_UPDATE, lambda **kw: order.append(("pre_update", kw["dt"])))
    sim.events.on(SimEvents.POST_UPDATE, lambda **kw: order.append(("post_update", kw["dt"])))
    sim.events.on(
        SimEvents.POST_STEP, lambda **kw: order.append(("post_step", kw["step"], kw["sim_time"]))
    )
    sim.step_once()
    assert order == [
        ("pre_step", 0, 0.0),
        ("callback", 0, 0.1),
        ("pre_update", 0.1),
        ("post_update", 0.1),
        ("post_step", 1, 0.1),
    ]


def test_return_profiling_has_the_reference_keys_and_custom_fields(sim):
    # The reference API's step_once(return_profiling=True) keys, plus attachments and
    # safety_fields (ours) and custom fields; collision_breakdown is "present only when
    # collision ran".
    sim.register_callback(lambda s, dt: s.record_profiling("custom_logic", 1.5))
    sim.register_callback(lambda s, dt: s.record_profiling("custom_logic", 0.5))
    timings = sim.step_once(return_profiling=True)
    assert set(timings) == {
        "phase1_update",
        "phase2_pose_flush",
        "phase3_aabb_grid_flush",
        "agent_update",
        "attachments",
        "safety_fields",
        "callbacks",
        "step_simulation",
        "collision_check",
        "collision_breakdown",
        "events_pre_step",
        "events_post_step",
        "events_collision",
        "monitor_update",
        "total",
        "custom_logic",
    }
    assert set(timings["collision_breakdown"]) == {
        "get_aabbs",
        "spatial_hashing",
        "aabb_filtering",
        "contact_points",
        "total",
    }
    assert timings["custom_logic"] == 2.0
    assert timings["total"] >= timings["phase1_update"] >= timings["callbacks"] >= 0
    assert timings["step_simulation"] == 0.0 and timings["phase2_pose_flush"] == 0.0
    assert dict(sim.last_profiling) == timings
    with pytest.raises(TypeError):
        sim.last_profiling["total"] = 0.0  # read-only
    sim.set_collision_check_frequency(0)
    assert "collision_breakdown" not in sim.step_once(return_profiling=True)
    assert sim.step_once() is None
    assert sim.last_profiling is None


def test_physics_phase_only_with_physics():
    with MultiRobotSimulationCore(headless_params(physics=True)) as psim:
        assert "step_simulation" in psim.step_once(return_profiling=True)


def test_callback_frequency_in_sim_time(sim):
    calls = []
    sim.register_callback(lambda s, dt: calls.append((s.step_count, round(dt, 9))), frequency=2.0)
    for _ in range(21):
        sim.step_once()
    assert calls == [(5, 0.5), (10, 0.5), (15, 0.5), (20, 0.5)]
    assert sim.unregister_callback(calls.append) is False


def test_unregister_callback(sim):
    calls = []

    def cb(s, dt):
        calls.append(s.step_count)

    sim.register_callback(cb)
    sim.step_once()
    assert sim.unregister_callback(cb) is True
    sim.step_once()
    assert calls == [0]


class CountingPlugin(SimPlugin):
    frequency = 5.0

    def on_init(self):
        self.log = ["init", self.config.get("tag")]

    def on_step(self, dt):
        self.log.append(("step", self.sim_core.step_count, round(dt, 9)))

    def on_reset(self):
        self.log.append("reset")


def test_plugin_lifecycle_and_frequency(sim):
    plugin = sim.register_plugin(CountingPlugin, config={"tag": "x"})
    assert sim.plugins == [plugin]
    for _ in range(5):
        sim.step_once()
    sim.reset()
    assert plugin.log == ["init", "x", ("step", 2, 0.2), ("step", 4, 0.2), "reset"]


def test_plugin_frequency_override_and_bad_plugins(sim):
    plugin = CountingPlugin(sim)
    sim.register_plugin(plugin, frequency=10.0)  # overrides the class's 5 Hz
    sim.step_once()
    sim.step_once()
    assert plugin.log[-1] == ("step", 1, 0.1)
    with pytest.raises(TypeError, match="SimPlugin"):
        sim.register_plugin(object())  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="config applies to a plugin class"):
        sim.register_plugin(CountingPlugin(sim), config={"a": 1})


def test_pause_and_resume_skip_steps_and_emit(sim):
    seen = []
    sim.events.on(SimEvents.PAUSED, lambda **kw: seen.append("paused"))
    sim.events.on(SimEvents.RESUMED, lambda **kw: seen.append("resumed"))
    sim.pause()
    assert sim.is_paused
    assert sim.step_once() is None
    assert sim.step_count == 0
    sim.resume()
    sim.step_once()
    assert sim.step_count == 1 and seen == ["paused", "resumed"]


def test_run_simulation_runs_exact_step_count(sim):
    sim.run_simulation(duration=2.0)
    assert sim.step_count == 20
    sim.run_simulation(duration=0.35)  # runs until sim time has covered the duration
    assert sim.step_count == 24


def test_initialize_simulation_zeroes_counters(sim):
    for _ in range(3):
        sim.step_once()
    sim.initialize_simulation()
    assert sim.step_count == 0 and sim.sim_time == 0.0 and sim.collision_count == 0


def test_add_and_remove_objects_emit_events_and_free_bodies(sim):
    events = []
    sim.events.on(
        SimEvents.OBJECT_SPAWNED, lambda **kw: events.append(("spawned", kw["obj"].object_id))
    )
    sim.events.on(
        SimEvents.OBJECT_REMOVED, lambda **kw: events.append(("removed", kw["obj"].object_id))
    )
    a, b = box(sim), box(sim, x=1)
    assert [o.object_id for o in sim.sim_objects] == [0, 1]
    assert sim.get_object_by_id(1) is b
    body = a.body_id
    sim.remove_object(a)
    assert sim.sim_objects == [b] and a.sim_core is None and a.object_id == -1
    assert events == [("spawned", 0), ("spawned", 1), ("removed", 0)]
    with pytest.raises(p.error):
        p.getBasePositionAndOrientation(body, physicsClientId=sim.client)
    sim.remove_object(a)  # a second removal does nothing, as the reference implementation
    assert sim.sim_objects == [b] and events[-1] == ("removed", 0)


def test_add_object_twice_does_nothing_the_second_time(sim):
    obj = box(sim)
    sim.add_object(obj)
    assert sim.sim_objects == [obj]


def test_objects_of_another_simulation_are_refused(sim):
    other = MultiRobotSimulationCore(headless_params())
    try:
        obj = box(other)
        with pytest.raises(ValueError, match="already belongs to another simulation"):
            sim.add_object(obj)
        with pytest.raises(ValueError, match="not part of this simulation"):
            sim.remove_object(obj)
    finally:
        other.close()


def test_manual_add_of_standalone_object(sim):
    body = p.createMultiBody(0, -1, -1, [1, 2, 3], physicsClientId=sim.client)
    obj = SimObject(body_id=body, sim_core=None, mass=0.0)
    assert obj.object_id == -1 and obj.sim_core is None
    sim.add_object(obj)
    assert obj.object_id == 0 and obj.sim_core is sim
    assert obj.get_pose().position.tolist() == [1, 2, 3]


def test_set_poses_and_get_poses_batch(sim):
    objs = [box(sim, x=i) for i in range(3)]
    ids = [o.object_id for o in objs]
    pos = np.array([[0, 0, 1.0], [1, 1, 1.0], [2, 2, 1.0]])
    orn = np.array([[0, 0, 0, 2.0], [0, 0, 0, 1.0], [0, 0, 1, 0.0]])
    sim.set_poses(ids, pos, orn)
    got_pos, got_orn = sim.get_poses(ids)
    assert got_pos.tolist() == pos.tolist()
    assert got_orn[0].tolist() == [0, 0, 0, 1.0]  # normalised
    # outside a step the write reaches PyBullet at once
    assert p.getBasePositionAndOrientation(objs[1].body_id, physicsClientId=sim.client)[0] == (
        1.0,
        1.0,
        1.0,
    )


def test_set_poses_rejects_bad_input_without_writing(sim):
    obj = box(sim, x=5)
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        sim.set_poses([obj.object_id], np.zeros((1, 2)), np.array([[0, 0, 0, 1.0]]))
    with pytest.raises(ValueError, match="zero quaternion"):
        sim.set_poses([obj.object_id], np.zeros((1, 3)), np.zeros((1, 4)))
    with pytest.raises(KeyError, match="99"):
        sim.get_poses([99])
    assert obj.get_pose().x == 5


def test_pybullet_sync_is_lazy_inside_steps(sim):
    obj = box(sim)
    sim.step_once()  # the collision system registers the new body (and syncs it) once
    sim.register_callback(lambda s, dt: obj.set_pose(Pose.from_xyz(3, 0, 0.5)))
    sim.step_once()
    assert obj.get_pose().x == 3
    assert p.getBasePositionAndOrientation(obj.body_id, physicsClientId=sim.client)[0][0] == 0.0
    assert sim.sync_pybullet() == 1
    assert p.getBasePositionAndOrientation(obj.body_id, physicsClientId=sim.client)[0][0] == 3.0


def test_reset_clears_world_but_keeps_callbacks(sim):
    calls = []
    sim.register_callback(lambda s, dt: calls.append(s.step_count))
    box(sim)
    sim.step_once()
    first_rng = sim.rng.random()
    sim.reset()
    assert sim.sim_objects == [] and sim.step_count == 0
    assert sim.rng.random() == first_rng  # reseeded with params.seed
    obj = box(sim)
    assert obj.object_id == 1  # ids stay unique across resets
    sim.step_once()
    assert calls == [0, 0]


def test_managers_register_sync_and_lookup(sim):
    class Manager:
        def __init__(self, name):
            self.name, self.objects, self.sim_core = name, [], None

        def remove_object(self, obj):
            if obj in self.objects:
                self.objects.remove(obj)
                return True
            return False

        def clear(self):
            self.objects.clear()

    fleet = Manager("fleet")
    sim.register_manager(fleet)
    sim.register_manager(fleet)
    assert (
        fleet.sim_core is sim and sim.get_manager("fleet") is fleet and sim.get_manager("x") is None
    )
    a, b = box(sim), box(sim)
    fleet.objects += [a, b]
    sim.remove_object(a)
    assert fleet.objects == [b]
    sim.reset()
    assert fleet.objects == []
    assert sim.unregister_manager(fleet) is True and sim.unregister_manager(fleet) is False


def test_gui_without_display_falls_back_with_one_warning(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    with pytest.warns(RuntimeWarning, match="no display") as record:
        core = MultiRobotSimulationCore(headless_params(gui=True))
    try:
        assert len(record) == 1
        assert core.is_gui is False
        core.step_once()
    finally:
        core.close()


def test_log_level_applies_to_package_logger():
    with MultiRobotSimulationCore(headless_params(log_level="debug")):
        assert logging.getLogger("fleet_async").level == logging.DEBUG
    with MultiRobotSimulationCore(headless_params(log_level="warn")):
        assert logging.getLogger("fleet_async").level == logging.WARNING


def test_memory_usage_only_when_enabled(sim):
    assert sim.get_memory_usage() is None
    with MultiRobotSimulationCore(headless_params(enable_memory_profiling=True)) as msim:
        usage = msim.get_memory_usage()
        assert usage is not None and usage["peak_mb"] >= usage["current_mb"] > 0


def test_monitor_figures_go_to_the_log_headless(caplog, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    with MultiRobotSimulationCore(headless_params(monitor=True, log_level="info")) as msim:
        box(msim)
        with caplog.at_level(logging.INFO, logger="fleet_async.core.view.monitor"):
            msim.run_simulation(duration=1.0)
    text = caplog.text
    assert (
        "sim_time=" in text
        and "real_time_factor=" in text
        and "objects=1" in text
        and "collisions=0" in text
    )


def test_batch_spawn_and_scene_bounds(sim):
    with sim.batch_spawn():
        for i in range(4):
            box(sim, x=i, y=2 * i, z=0.5)
    center, extent = sim.compute_scene_bounds()
    assert center == [1.5, 3.0, 0.5] and extent == [3.0, 6.0, 0.0]
    distance, _yaw, pitch, target = sim.setup_camera({"camera_view_type": "top_down"})
    assert target == pytest.approx(center) and pitch == -89.9 and distance > 0
    with pytest.raises(ValueError, match="camera_zoom"):
        sim.setup_camera({"camera_zoom": 2})


def test_from_dict_and_from_yaml(tmp_path):
    core = MultiRobotSimulationCore.from_dict(
        {"simulation": {"gui": False, "monitor": False, "timestep": 0.02}}
    )
    try:
        assert core.params.timestep == 0.02
    finally:
        core.close()
    path = tmp_path / "sim.yaml"
    path.write_text("gui: false\nmonitor: false\ntimestep: 0.5\n")
    core = MultiRobotSimulationCore.from_yaml(str(path))
    try:
        assert core.params.timestep == 0.5
    finally:
        core.close()
    with pytest.raises(ValueError, match="unknown key 'entites'"):
        MultiRobotSimulationCore.from_dict({"simulation": {"gui": False}, "entites": []})


def test_time_profiling_logs_a_summary_every_interval(caplog):
    params = headless_params(enable_time_profiling=True, profiling_interval=5, log_level="info")
    with (
        MultiRobotSimulationCore(params) as psim,
        caplog.at_level(logging.INFO, logger="fleet_async.core.sim.profiling"),
    ):
        for _ in range(10):
            psim.step_once()
    summaries = [r for r in caplog.records if "step profile" in r.getMessage()]
    assert len(summaries) == 2
    assert (
        "over 10 steps" in summaries[-1].getMessage()
        and "agent_update=" in summaries[-1].getMessage()
    )


def test_set_poses_moves_carried_objects_and_reaches_pybullet(sim):
    carrier, crate = box(sim), box(sim, x=5)
    carrier.attach_object(crate, relative_pose=Pose.from_xyz(0, 0, 0.3))
    sim.set_poses([carrier.object_id], np.array([[2.0, 1.0, 0.5]]), np.array([[0, 0, 0, 1.0]]))
    assert crate.get_pose().position.tolist() == pytest.approx([2.0, 1.0, 0.8])
    pos, _ = p.getBasePositionAndOrientation(crate.body_id, physicsClientId=sim.client)
    assert pos == pytest.approx((2.0, 1.0, 0.8))
