"""Missions with safety fields: a move held by the protective field stays active and ends
when the robot arrives after the field cleared (both backends, exact sim times)."""

from __future__ import annotations

from fleet_async import Agent, AgentSpawnParams, Pose, ShapeParams, SimEvents, SimObject

BOX = ShapeParams("box", half_extents=[0.3, 0.2, 0.2])


def robot(sim, x, name):
    params = AgentSpawnParams(
        visual_shape=BOX,
        collision_shape=BOX,
        initial_pose=Pose.from_xyz(x, 0.0, 0.2),
        name=name,
        motion_mode="omnidirectional",
        safety_field=True,
    )
    return Agent.from_params(params, sim)


async def test_a_held_move_waits_for_the_field_to_clear(fleet_sim):
    a = robot(fleet_sim, 0.0, "a")
    crate = SimObject.from_mesh(BOX, BOX, Pose.from_xyz(3.0, 0.0, 0.2), sim_core=fleet_sim)
    log = []
    fleet_sim.events.on(
        SimEvents.SAFETY_STOP_STARTED, lambda agent, **_: log.append(("stop", fleet_sim.sim_time))
    )

    async def clear_later():
        await fleet_sim.sleep(4.0)
        fleet_sim.remove_object(crate)

    async with fleet_sim.task_group() as tg:
        tg.start_soon(clear_later)
        await a.move(Pose.from_xyz(5.0, 0.0, 0.2))
    assert fleet_sim.safety.stats()[a.object_id][0] == len(log) >= 1
    # Unhindered the move takes 29 steps (5 m at 2 m/s and 5 m/s^2); here the robot waits at
    # the crate until it goes at 4.0 s, then ramps up at its field's deceleration (1 m/s^2).
    assert fleet_sim.step_count == 65
    assert all(t < 4.0 for _, t in log)
    assert a.get_pose().position[0] == 5.0
