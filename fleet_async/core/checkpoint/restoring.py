"""Restoring: check that the simulation was built like the saved one, then set every part.

The header is read and checked first (format, version, timestep, the same objects with the
same ids and types, no step run yet), so nothing is changed in a simulation that cannot take
the checkpoint. Then plugins and schedules, objects (attachments, names, collision modes, the
store's rows), agents (engine, queues, controllers, plugins, joints), the collision system, the
safety fields and the random generator get their saved state back through ``set_state()``.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from fleet_async.core.checkpoint.codec import CodecError, decode
from fleet_async.core.checkpoint.format import (
    ROW_COLUMNS,
    CheckpointError,
    CheckpointParts,
    is_pickle,
    read_file,
    type_name,
)
from fleet_async.core.checkpoint.legacy import read_pickle
from fleet_async.core.checkpoint.references import resolver_for
from fleet_async.core.checkpoint.saving import collect
from fleet_async.core.checkpoint.validation import validate

if TYPE_CHECKING:
    from fleet_async.core.agents.agent import Agent
    from fleet_async.core.sim.kernel import SimulationKernel

__all__ = ["restore"]


def _load(
    sim: SimulationKernel, path: str | os.PathLike[str], step_count: int, unsafe: bool
) -> dict[str, Any]:
    """The checkpoint's state, once its header shows that ``sim`` can take it."""
    data = Path(path).read_bytes()
    if is_pickle(data):
        if not unsafe:
            raise CheckpointError(
                f"restore_state: {path} is a format-1 checkpoint, a pickle: reading it would run "
                "any code it names, so it is refused. Only if you trust whoever made it, restore "
                "it with restore_state(path, unsafe=True) (fleet-async sweep --unsafe) and save "
                "it again: new checkpoints hold plain data only"
            )
        header, legacy_state = read_pickle(sim, path, data)
        _check_target(sim, header, step_count)
        return legacy_state
    file = read_file(path, data)
    _check_target(sim, file.header, step_count)
    try:
        state = decode(file.document, file.arrays, resolver_for(sim))
    except (CodecError, RecursionError) as exc:
        raise CheckpointError(f"restore_state: {path} is damaged ({exc})") from exc
    if not isinstance(state, dict):
        raise CheckpointError(f"restore_state: {path} is damaged (the state is not a dict)")
    return state


def _check_target(sim: SimulationKernel, header: dict[str, Any], step_count: int) -> None:
    where = "restore_state"
    if sim.params.physics:
        raise CheckpointError(f"{where}: physics=True: checkpoints cover kinematic simulations")
    runtime = sim.mission_runtime
    if runtime is not None and (runtime.driving or sim.suspended_missions()):
        raise CheckpointError(
            f"{where}: missions are running or suspended ({sim.suspended_missions()}); restore "
            "before fleet_async.run, or end them with sim.end_missions() first"
        )
    if step_count != 0:
        raise CheckpointError(
            f"{where}: this simulation has run {step_count} steps; restore into one freshly "
            "built from the scenario the checkpoint was saved from"
        )
    if header.get("timestep") != sim.params.timestep:
        raise CheckpointError(
            f"{where}: the checkpoint's timestep is {header['timestep']} s, this simulation's "
            f"{sim.params.timestep} s"
        )
    here = [(obj.object_id, type_name(obj)) for obj in sim.sim_objects]
    objects = header.get("objects")
    objects = objects if isinstance(objects, (list, tuple)) else []
    there = [tuple(e) for e in objects if isinstance(e, (list, tuple))]
    if here != there:
        diff = next(
            (
                f"{a} here, {b} in the checkpoint"
                for a, b in zip(here, there, strict=False)
                if a != b
            ),
            f"{len(here)} objects here, {len(there)} in the checkpoint",
        )
        raise CheckpointError(
            f"{where}: this simulation has other objects than the checkpoint ({diff}); build it "
            "from the same scenario"
        )


def _restore_typed(owner: str, items: list[Any], saved: list[tuple[str, dict[str, Any]]]) -> None:
    names = [type_name(item) for item in items]
    if names != [name for name, _ in saved]:
        raise CheckpointError(
            f"restore_state: {owner} has {names}, the checkpoint {[n for n, _ in saved]}"
        )
    for item, (_, item_state) in zip(items, saved, strict=True):
        item.set_state(item_state)


def _restore_objects(sim: SimulationKernel, state: dict[str, Any]) -> None:
    objects = sim.sim_objects
    for obj in objects:  # the scenario's own attachments make way for the saved ones
        held = sim.attachments.of_child(obj)
        if held is not None:
            sim.world.detach(held.parent, obj, None, None)
    for parent_id, child_id, link, relative in state["attachments"]:
        parent, child = sim.get_object_by_id(parent_id), sim.get_object_by_id(child_id)
        assert parent is not None  # the object lists matched
        assert child is not None
        if not sim.world.attach(parent, child, link, relative, False):
            raise CheckpointError(f"restore_state: {child!r} cannot be attached to {parent!r}")
    for obj, name, mode in zip(objects, state["names"], state["collision_modes"], strict=True):
        obj.set_name(name)
        if obj.collision_mode.value != mode:
            obj.set_collision_mode(mode)
    store = sim.state
    rows = np.array([obj.state_row for obj in objects], dtype=np.int64)
    for name in ROW_COLUMNS:
        getattr(store, name)[rows] = state["rows"][name]
    store.dirty[rows] = True
    store.written[rows] = True  # carried objects follow the restored poses
    sim.sync_pybullet()


def _restore_agents(sim: SimulationKernel, state: dict[str, Any], parts: CheckpointParts) -> None:
    def agent_of(object_id: int) -> Agent:
        return cast("Agent", sim.get_object_by_id(object_id))

    try:
        parts.engine.set_state(state["engine"])
    except ValueError as exc:
        raise CheckpointError(f"restore_state: {exc}") from exc
    parts.actions.set_state(state["actions"], agent_of)
    for agent in (cast("Agent", a) for a in sim.agents):
        saved = state["agents"][agent.object_id]
        agent.motion_result = saved["motion_result"]
        _restore_typed(repr(agent), agent.controllers, saved["controllers"])
        _restore_typed(repr(agent), agent.plugins, saved["plugins"])
        if saved["joints"] is not None:
            agent.joints.set_state(saved["joints"])
    for object_id in state["joint_motion"]:
        agent = agent_of(object_id)
        parts.joint_motion.activate(agent, agent.joints)


def _apply(sim: SimulationKernel, state: dict[str, Any], parts: CheckpointParts) -> None:
    _restore_typed("the simulation's plugins", sim.plugins, state["plugins"])
    try:
        parts.callbacks.set_state(state["callbacks"])
        parts.plugin_schedule.set_state(state["plugin_schedule"])
    except ValueError as exc:
        raise CheckpointError(f"restore_state: {exc}") from exc
    _restore_objects(sim, state)
    _restore_agents(sim, state, parts)
    parts.collision.set_state(state["collision"])
    sim.rng.bit_generator.state = state["rng"]
    if "streams" in state:  # format 1 had none
        sim.random_streams.set_state(state["streams"])
    if "safety" in state:  # checkpoints before safety fields had none
        sim.safety.set_state(state["safety"])


def restore(
    sim: SimulationKernel, path: str | os.PathLike[str], parts: CheckpointParts, unsafe: bool
) -> tuple[int, int, bool]:
    """Bring ``sim`` (freshly built from the same scenario) to the state saved in ``path``.

    Everything is checked before anything changes (``validation.py``); should a part still
    refuse while the state is applied, the simulation is set back to a snapshot taken first.

    Returns:
        (step count, collision count, paused) for the simulation's clock.

    Raises:
        CheckpointError: for a file that is no checkpoint (or a format-1 pickle without
            ``unsafe``), or a simulation that differs from the saved one or has stepped
            already, naming the difference.
    """
    state = _load(sim, path, parts.step_count, unsafe)
    validate(sim, state, parts)
    snapshot = collect(sim, parts)
    try:
        _apply(sim, state, parts)
    except Exception as exc:
        _apply(sim, snapshot, parts)
        if isinstance(exc, CheckpointError):
            raise
        raise CheckpointError(
            f"restore_state: {path} does not fit this simulation ({type(exc).__name__}: {exc}); "
            "the simulation is unchanged"
        ) from exc
    step_count, collision_count, paused = state["clock"]
    return step_count, collision_count, paused
