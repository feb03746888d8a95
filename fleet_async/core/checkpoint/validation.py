"""Checking a decoded checkpoint against the simulation before anything of it is changed.

``restore_state`` promises that a refused checkpoint leaves the simulation untouched, so
everything that can differ is checked here first, reading only: the keys of the state, the
store's rows (one per object, columns of the right shape), attachments between objects that
exist, the types of the simulation's plugins and of every agent's controllers and plugins, the
agents, the kinematic engine's slots, the schedules' lengths, the joints, the random generator's
state. ``restoring.py`` then applies it (and rolls back from a snapshot should a part still
refuse).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, cast

import numpy as np

from fleet_async.core.checkpoint.format import ROW_COLUMNS, CheckpointError, type_name
from fleet_async.core.collision.safety_params import SafetyFieldParams

if TYPE_CHECKING:
    from fleet_async.core.agents.agent import Agent
    from fleet_async.core.checkpoint.format import CheckpointParts
    from fleet_async.core.sim.kernel import SimulationKernel

__all__ = ["validate"]

REQUIRED = (
    "names",
    "collision_modes",
    "rows",
    "attachments",
    "clock",
    "rng",
    "engine",
    "actions",
    "agents",
    "joint_motion",
    "callbacks",
    "plugin_schedule",
    "plugins",
    "collision",
)


def _typed(owner: str, items: list[Any], saved: Any) -> None:
    names = [type_name(item) for item in items]
    saved_names = [entry[0] for entry in saved]
    if names != saved_names:
        raise CheckpointError(f"restore_state: {owner} has {names}, the checkpoint {saved_names}")
    for _, item_state in saved:
        if not isinstance(item_state, dict):
            raise CheckpointError(f"restore_state: {owner}: a saved state is not a dict")


def _rows(sim: SimulationKernel, state: dict[str, Any]) -> None:
    count = len(sim.sim_objects)
    if len(state["names"]) != count or len(state["collision_modes"]) != count:
        raise CheckpointError("restore_state: the names or collision modes do not fit")
    for name in ROW_COLUMNS:
        saved = state["rows"][name]
        column = getattr(sim.state, name)
        if not isinstance(saved, np.ndarray) or saved.shape != (count, *column.shape[1:]):
            raise CheckpointError(f"restore_state: the saved {name!r} rows do not fit")
    for parent_id, child_id, _link, _relative in state["attachments"]:
        if sim.get_object_by_id(parent_id) is None or sim.get_object_by_id(child_id) is None:
            raise CheckpointError(f"restore_state: attachment {parent_id}-{child_id}: no object")


def _agents(sim: SimulationKernel, state: dict[str, Any]) -> None:
    agents = [cast("Agent", a) for a in sim.agents]
    if sorted(state["agents"]) != sorted(a.object_id for a in agents):
        raise CheckpointError("restore_state: the checkpoint has other agents")
    for agent in agents:
        saved = state["agents"][agent.object_id]
        _typed(f"{agent!r}'s controllers", agent.controllers, saved["controllers"])
        _typed(f"{agent!r}'s plugins", agent.plugins, saved["plugins"])
        joints = saved["joints"]
        if (joints is None) != (not agent.is_urdf_robot()):
            raise CheckpointError(f"restore_state: {agent!r}: a robot of another kind")
        if joints is not None and len(joints["positions"]) != len(agent.joints.infos):
            raise CheckpointError(
                f"restore_state: {agent!r}: the checkpoint has {len(joints['positions'])} "
                f"joints, this robot {len(agent.joints.infos)} (another URDF)"
            )
    for object_id in state["joint_motion"]:
        if object_id not in state["agents"]:
            raise CheckpointError(f"restore_state: joints of {object_id}, not an agent")


def _safety(sim: SimulationKernel, state: dict[str, Any]) -> None:
    """The safety fields' agents are agents here, with valid field parameters."""
    if "safety" not in state:
        return
    table = state["safety"]["table"]
    for saved in table["agents"]:
        if saved["id"] not in state["agents"]:
            raise CheckpointError(f"restore_state: safety fields of {saved['id']}, not an agent")
        try:
            SafetyFieldParams.coerce(saved["params"], "safety_field")
        except ValueError as exc:
            raise CheckpointError(f"restore_state: {exc}") from exc
        if len(saved["stop"]) != 6:
            raise CheckpointError(f"restore_state: the safety state of {saved['id']} is damaged")


def _check(sim: SimulationKernel, state: dict[str, Any], parts: CheckpointParts) -> None:
    missing = [key for key in REQUIRED if key not in state]
    if missing:
        raise CheckpointError(f"restore_state: the checkpoint has no {missing[0]!r}")
    _rows(sim, state)
    _typed("the simulation's plugins", sim.plugins, state["plugins"])
    _agents(sim, state)
    try:
        parts.engine.check_state(state["engine"])
    except ValueError as exc:
        raise CheckpointError(f"restore_state: {exc}") from exc
    schedules = (("callbacks", parts.callbacks), ("plugin_schedule", parts.plugin_schedule))
    for name, schedule in schedules:
        if len(state[name]) != len(schedule):
            raise CheckpointError(
                f"restore_state: the checkpoint has {len(state[name])} {name}, this "
                f"simulation {len(schedule)}"
            )
    _safety(sim, state)
    np.random.PCG64().state = state["rng"]  # a bad state raises here, on a throwaway
    step_count, collision_count, paused = state["clock"]
    if not all(isinstance(v, int) for v in (step_count, collision_count, paused)):
        raise CheckpointError(f"restore_state: bad clock {state['clock']!r}")


def validate(sim: SimulationKernel, state: dict[str, Any], parts: CheckpointParts) -> None:
    """Check ``state`` against ``sim``, changing nothing.

    Raises:
        CheckpointError: naming the first difference or damage found.
    """
    try:
        _check(sim, state, parts)
    except CheckpointError:
        raise
    except (KeyError, TypeError, ValueError, IndexError, AttributeError) as exc:
        raise CheckpointError(
            f"restore_state: the checkpoint is damaged ({type(exc).__name__}: {exc})"
        ) from exc
