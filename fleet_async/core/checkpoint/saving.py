"""Saving: refuse what cannot be restored exactly, then write the header and the state.

The owners of state hand it over through ``get_state()``: the kinematic engine, the action
queue, the schedules, the collision system, joints, controllers and plugins; the store's rows of
every object are copied here. What is saved and what is refused is listed in
``fleet_async.core.checkpoint``.
"""

from __future__ import annotations

import io
import os
import pickle
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from fleet_async.core.checkpoint.format import (
    FORMAT,
    ROW_COLUMNS,
    VERSION,
    CheckpointError,
    CheckpointParts,
    StatePickler,
    type_name,
    typed_states,
)

if TYPE_CHECKING:
    from fleet_async.core.agents.agent import Agent
    from fleet_async.core.sim.kernel import SimulationKernel

__all__ = ["save"]


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


def _collect(sim: SimulationKernel, parts: CheckpointParts) -> dict[str, Any]:
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
    }


def save(sim: SimulationKernel, path: str | os.PathLike[str], parts: CheckpointParts) -> None:
    """Write ``sim``'s state to ``path`` (see ``fleet_async.core.checkpoint`` for what is and is not
    saved).

    Raises:
        CheckpointError: for a simulation that cannot be saved (physics, running missions,
            added motion systems such as the devices', per-object callbacks, state that cannot
            be pickled), naming why.
    """
    _refuse_unsaveable(sim, parts)
    buffer = io.BytesIO()
    try:
        pickler = StatePickler(buffer, sim)
        pickler.dump(_header(sim))
        pickler.dump(_collect(sim, parts))
    except (pickle.PicklingError, TypeError, AttributeError) as exc:
        raise CheckpointError(
            f"save_state: some state cannot be saved ({exc}); give the controller or plugin "
            "that holds it get_state / set_state methods"
        ) from exc
    tmp = Path(f"{os.fspath(path)}.tmp")
    tmp.write_bytes(buffer.getvalue())
    os.replace(tmp, path)
