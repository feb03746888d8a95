"""Saving: refuse what cannot be restored exactly, then write the header and the state.

The owners of state hand it over through ``get_state()``: the kinematic engine, the action
queue, the schedules, the collision system, joints, controllers and plugins; the store's rows of
every object are copied here. What is saved and what is refused is listed in
``fleet_async.core.checkpoint``.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from fleet_async.core.checkpoint.codec import CodecError, encode
from fleet_async.core.checkpoint.format import (
    FORMAT,
    ROW_COLUMNS,
    VERSION,
    CheckpointError,
    CheckpointParts,
    type_name,
    typed_states,
    write_file,
)
from fleet_async.core.checkpoint.references import resolver_for

if TYPE_CHECKING:
    from fleet_async.core.agents.agent import Agent
    from fleet_async.core.sim.kernel import SimulationKernel

__all__ = ["collect", "save"]


def _refuse_unsaveable(sim: SimulationKernel, parts: CheckpointParts) -> None:
    if sim.params.physics:
        raise CheckpointError(
            "save_state: physics=True: PyBullet's dynamic state is not captured; checkpoints "
            "cover kinematic simulations (physics=False)"
        )
    runtime = sim.mission_runtime
    if runtime is not None and runtime.driving:
        raise CheckpointError(
            "save_state: missions are running (fleet_async.run in progress), and a mission "
            "waiting mid-await cannot be saved; save before fleet_async.run or after it returns"
        )
    waiting = sim.suspended_missions()
    if waiting:
        raise CheckpointError(
            f"save_state: missions {waiting} wait mid-await (a run stopped at until= left "
            "them suspended), and a mission's place in its code cannot be saved; continue them "
            "with fleet_async.run(sim, until=...) or end them with sim.end_missions() first"
        )
    if sim.in_step:
        raise CheckpointError("save_state: not inside step_once; save between steps")
    if parts.other_motion:
        raise CheckpointError(
            f"save_state: {type(parts.other_motion[0]).__name__} (added with "
            "sim.add_motion_system; doors, lifts and workcells move by one) is not captured"
        )
    with_callbacks = sim.world.objects_with_callbacks()
    if with_callbacks:
        raise CheckpointError(
            f"save_state: per-object callbacks are not captured ({with_callbacks[0]!r} has some)"
        )


def _agent_state(agent: Agent) -> dict[str, Any]:
    return {
        "motion_result": agent.motion_result,
        "controllers": typed_states(agent.controllers),
        "plugins": typed_states(agent.plugins),
        "joints": agent.joints.get_state() if agent.is_urdf_robot() else None,
    }


def _header(sim: SimulationKernel) -> dict[str, Any]:
    """What a restore checks before it reads anything that refers to objects."""
    return {
        "format": FORMAT,
        "version": VERSION,
        "timestep": sim.params.timestep,
        "objects": [(obj.object_id, type_name(obj)) for obj in sim.sim_objects],
    }


def collect(sim: SimulationKernel, parts: CheckpointParts) -> dict[str, Any]:
    """The state tree of ``sim`` (what a checkpoint holds, before encoding)."""
    store = sim.state
    objects = sim.sim_objects
    rows = np.array([obj.state_row for obj in objects], dtype=np.int64)
    attachments = [sim.attachments.of_child(obj) for obj in objects]
    return {
        "names": [obj.name for obj in objects],
        "collision_modes": [obj.collision_mode.value for obj in objects],
        "rows": {name: getattr(store, name)[rows].copy() for name in ROW_COLUMNS},
        "attachments": [
            (a.parent.object_id, a.child.object_id, a.link_index, a.relative)
            for a in attachments
            if a is not None
        ],
        "clock": (parts.step_count, parts.collision_count, parts.paused),
        "rng": sim.rng.bit_generator.state,
        "engine": parts.engine.get_state(),
        "actions": parts.actions.get_state(),
        "agents": {a.object_id: _agent_state(cast("Agent", a)) for a in sim.agents},
        "joint_motion": parts.joint_motion.active_ids(),
        "callbacks": parts.callbacks.get_state(),
        "plugin_schedule": parts.plugin_schedule.get_state(),
        "plugins": typed_states(sim.plugins),
        "collision": parts.collision.get_state(),
        "streams": sim.random_streams.get_state(),
        "safety": sim.safety.get_state(),
    }


def _holders(sim: SimulationKernel) -> list[tuple[str, object]]:
    """Every user-extensible piece of state, with the name an error gives it."""
    holders: list[tuple[str, object]] = [
        (f"simulation plugin {type_name(p)}", p) for p in sim.plugins
    ]
    for agent in cast("list[Agent]", list(sim.agents)):
        holders += [(f"{agent!r}: controller {type_name(c)}", c) for c in agent.controllers]
        holders += [(f"{agent!r}: plugin {type_name(p)}", p) for p in agent.plugins]
    return holders


def _refuse_non_plain(sim: SimulationKernel) -> None:
    """Name the first controller or plugin whose ``get_state()`` is not plain data."""
    resolver = resolver_for(sim)
    for label, holder in _holders(sim):
        try:
            encode(holder.get_state(), resolver, label)  # type: ignore[attr-defined]
        except (CodecError, ValueError) as exc:
            raise CheckpointError(
                f"save_state: {exc}; a checkpoint holds numbers, strings, arrays, lists and "
                "dicts only: give it get_state / set_state methods that return and take such data"
            ) from exc


def save(sim: SimulationKernel, path: str | os.PathLike[str], parts: CheckpointParts) -> None:
    """Write ``sim``'s state to ``path`` (see ``fleet_async.core.checkpoint`` for what is and is not
    saved).

    Raises:
        CheckpointError: for a simulation that cannot be saved (physics, running missions,
            added motion systems such as the devices', per-object callbacks, controller or
            plugin state that is not plain data), naming why.
    """
    _refuse_unsaveable(sim, parts)
    _refuse_non_plain(sim)
    try:
        document, arrays = encode(collect(sim, parts), resolver_for(sim))
    except (CodecError, ValueError) as exc:
        raise CheckpointError(f"save_state: some state is not plain data ({exc})") from exc
    write_file(path, _header(sim), document, arrays)
