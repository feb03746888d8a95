"""Checkpoints: save a kinematic simulation and restore it into one built the same way.

``sim.save_state(path)`` writes the state of a simulation between two steps; in a fresh
process, ``sim.restore_state(path)`` on a simulation freshly built from the same scenario
brings it to that state, and from there the two continue step for step identically (same
poses, same events, same random numbers). A sweep can so branch many runs from one warmed-up
state (``fleet-async sweep --checkpoint``).

Saved: the clock (step count, collisions so far, paused); the random generator; every
object's pose, velocity, angular velocity, collision mode, name and "moved since the last
collision check" flag; attachments; the kinematic engine (paths in progress, segment
progress, velocity commands); every action queue (queued and running actions with their
progress, timers); each agent's controllers, agent plugins (battery) and joints; the
simulation plugins; the schedules of callbacks and plugins; the collision system's active pairs
and check schedule. Objects that actions, controllers or plugins refer to are saved by id.

Not saved, and refused where it matters:

- **missions**: a coroutine waiting mid-await cannot be saved, so ``save_state`` refuses while
  ``fleet_async.run`` is in progress. Save before it starts or after it returns, and start new
  missions after a restore (the actions they had queued are saved with the queues).
- **physics**: PyBullet's dynamic state (contacts, solver) is not captured: ``physics=True`` is
  refused on both sides.
- **per-object callbacks** (``obj.register_callback``): refused.
- **callbacks** (``sim.register_callback``) are code: the restoring scenario registers the same
  ones, in the same order; only their schedules are restored. The same holds for plugins,
  controllers and agent plugins, whose state goes through their ``get_state`` / ``set_state``.
- the KPI collector, recordings, the GUI and the monitor.

Restoring checks that the target was built the same way (the same objects, of the same types,
with the same ids, controllers and plugins, the same timestep) and has not stepped yet; it
refuses otherwise, naming the difference. The file is a pickle: load only checkpoints you
trust.
"""

from __future__ import annotations

import dataclasses
import io
import os
import pickle
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any, cast

import numpy as np
import pybullet as p

from fleet_async.core.sim_object import SimObject

if TYPE_CHECKING:
    from fleet_async.core.action_queue import ActionQueue
    from fleet_async.core.agent import Agent
    from fleet_async.core.collision import CollisionSystem
    from fleet_async.core.joints import JointMotion
    from fleet_async.core.kinematics import KinematicEngine
    from fleet_async.core.scheduling import PeriodicSchedule
    from fleet_async.core.simulation import MultiRobotSimulationCore

__all__ = ["CheckpointError", "CheckpointParts", "restore", "save"]

FORMAT = "fleet_async checkpoint"
VERSION = 1
_ROW_COLUMNS = ("position", "orientation", "velocity", "angular_velocity", "moved")


class CheckpointError(ValueError):
    """A simulation that cannot be saved, or a checkpoint that cannot be restored into it."""


@dataclasses.dataclass(frozen=True)
class CheckpointParts:
    """What the simulation hands the checkpoint: its clock and its collaborators."""

    step_count: int
    collision_count: int
    paused: bool
    engine: KinematicEngine
    actions: ActionQueue
    callbacks: PeriodicSchedule
    plugin_schedule: PeriodicSchedule
    collision: CollisionSystem
    joint_motion: JointMotion


class _Pickler(pickle.Pickler):
    """Saves the simulation and its objects by reference (``("object", id)``)."""

    def __init__(self, file: IO[bytes], sim: MultiRobotSimulationCore) -> None:
        super().__init__(file, protocol=pickle.HIGHEST_PROTOCOL)
        self._sim = sim

    def persistent_id(self, obj: Any) -> Any:
        if obj is self._sim:
            return ("sim",)
        if isinstance(obj, SimObject):
            if obj.sim_core is not self._sim:
                raise CheckpointError(f"save_state: the state refers to {obj!r}, not in it")
            return ("object", obj.object_id)
        return None


class _Unpickler(pickle.Unpickler):
    def __init__(self, file: IO[bytes], sim: MultiRobotSimulationCore) -> None:
        super().__init__(file)
        self._sim = sim

    def persistent_load(self, pid: Any) -> Any:
        if pid == ("sim",):
            return self._sim
        obj = self._sim.get_object_by_id(pid[1])
        if obj is None:
            raise CheckpointError(f"restore_state: the checkpoint refers to object {pid[1]}")
        return obj


def _type_name(obj: object) -> str:
    return f"{type(obj).__module__}.{type(obj).__qualname__}"


def _typed_states(items: list[Any]) -> list[tuple[str, dict[str, Any]]]:
    return [(_type_name(item), item.get_state()) for item in items]


# ----- saving --------------------------------------------------------------------------------


def _refuse_unsaveable(sim: MultiRobotSimulationCore) -> None:
    if sim.params.physics:
        raise CheckpointError(
            "save_state: physics=True: PyBullet's dynamic state is not captured; checkpoints "
            "cover kinematic simulations (physics=False)"
        )
    if sim.mission_runtime is not None:
        raise CheckpointError(
            "save_state: missions are running (fleet_async.run in progress), and a mission "
            "waiting mid-await cannot be saved; save before fleet_async.run or after it returns"
        )
    if sim.in_step:
        raise CheckpointError("save_state: not inside step_once; save between steps")
    with_callbacks = sim.world.objects_with_callbacks()
    if with_callbacks:
        raise CheckpointError(
            f"save_state: per-object callbacks are not captured ({with_callbacks[0]!r} has some)"
        )


def _agent_state(agent: Agent) -> dict[str, Any]:
    return {
        "motion_result": agent.motion_result,
        "controllers": _typed_states(agent.controllers),
        "plugins": _typed_states(agent.plugins),
        "joints": agent.joints.get_state() if agent.is_urdf_robot() else None,
    }


def _header(sim: MultiRobotSimulationCore) -> dict[str, Any]:
    """What a restore checks before it reads anything that refers to objects."""
    return {
        "format": FORMAT,
        "version": VERSION,
        "timestep": sim.params.timestep,
        "objects": [(obj.object_id, _type_name(obj)) for obj in sim.sim_objects],
    }


def _collect(sim: MultiRobotSimulationCore, parts: CheckpointParts) -> dict[str, Any]:
    store = sim.state
    objects = sim.sim_objects
    rows = np.array([obj.state_row for obj in objects], dtype=np.int64)
    attachments = [sim.attachments.of_child(obj) for obj in objects]
    return {
        "names": [obj.name for obj in objects],
        "collision_modes": [obj.collision_mode.value for obj in objects],
        "rows": {name: getattr(store, name)[rows].copy() for name in _ROW_COLUMNS},
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
        "plugins": _typed_states(sim.plugins),
        "collision": parts.collision.get_state(),
    }


def save(
    sim: MultiRobotSimulationCore, path: str | os.PathLike[str], parts: CheckpointParts
) -> None:
    """Write ``sim``'s state to ``path`` (see the module doc for what is and is not saved).

    Raises:
        CheckpointError: for a simulation that cannot be saved (physics, running missions,
            per-object callbacks, state that cannot be pickled), naming why.
    """
    _refuse_unsaveable(sim)
    buffer = io.BytesIO()
    try:
        pickler = _Pickler(buffer, sim)
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


# ----- restoring -----------------------------------------------------------------------------


def _load(
    sim: MultiRobotSimulationCore, path: str | os.PathLike[str], step_count: int
) -> dict[str, Any]:
    """The checkpoint's state, once its header shows that ``sim`` can take it."""
    unpickler = _Unpickler(io.BytesIO(Path(path).read_bytes()), sim)
    try:
        header = unpickler.load()
    except Exception as exc:
        raise CheckpointError(
            f"restore_state: {path} is not a readable checkpoint ({exc})"
        ) from exc
    if not isinstance(header, dict) or header.get("format") != FORMAT:
        raise CheckpointError(f"restore_state: {path} is not a fleet_async checkpoint")
    if header["version"] != VERSION:
        raise CheckpointError(
            f"restore_state: {path} has checkpoint format {header['version']}; this "
            f"fleet_async reads format {VERSION}"
        )
    _check_target(sim, header, step_count)
    try:
        state: dict[str, Any] = unpickler.load()
    except CheckpointError:
        raise
    except Exception as exc:
        raise CheckpointError(f"restore_state: {path} is cut short or damaged ({exc})") from exc
    return state


def _check_target(sim: MultiRobotSimulationCore, header: dict[str, Any], step_count: int) -> None:
    where = "restore_state"
    if sim.params.physics:
        raise CheckpointError(f"{where}: physics=True: checkpoints cover kinematic simulations")
    if sim.mission_runtime is not None:
        raise CheckpointError(f"{where}: missions are running; restore before fleet_async.run")
    if step_count != 0:
        raise CheckpointError(
            f"{where}: this simulation has run {step_count} steps; restore into one freshly "
            "built from the scenario the checkpoint was saved from"
        )
    if header["timestep"] != sim.params.timestep:
        raise CheckpointError(
            f"{where}: the checkpoint's timestep is {header['timestep']} s, this simulation's "
            f"{sim.params.timestep} s"
        )
    here = [(obj.object_id, _type_name(obj)) for obj in sim.sim_objects]
    there = [tuple(entry) for entry in header["objects"]]
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
    names = [_type_name(item) for item in items]
    if names != [name for name, _ in saved]:
        raise CheckpointError(
            f"restore_state: {owner} has {names}, the checkpoint {[n for n, _ in saved]}"
        )
    for item, (_, item_state) in zip(items, saved, strict=True):
        item.set_state(item_state)


def _restore_objects(sim: MultiRobotSimulationCore, state: dict[str, Any]) -> None:
    objects = sim.sim_objects
    for obj in objects:  # the scenario's own attachments make way for the saved ones
        held = sim.attachments.of_child(obj)
        if held is not None:
            sim.world.detach(held.parent, obj, None, None)
    for parent_id, child_id, link, relative in state["attachments"]:
        parent, child = sim.get_object_by_id(parent_id), sim.get_object_by_id(child_id)
        assert parent is not None  # the object lists matched
        assert child is not None
        sim.world.attach(parent, child, link, relative, p.JOINT_FIXED, False)
    for obj, name, mode in zip(objects, state["names"], state["collision_modes"], strict=True):
        obj.set_name(name)
        if obj.collision_mode.value != mode:
            obj.set_collision_mode(mode)
    store = sim.state
    rows = np.array([obj.state_row for obj in objects], dtype=np.int64)
    for name in _ROW_COLUMNS:
        getattr(store, name)[rows] = state["rows"][name]
    store.dirty[rows] = True
    sim.sync_pybullet()


def _restore_agents(
    sim: MultiRobotSimulationCore, state: dict[str, Any], parts: CheckpointParts
) -> None:
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


def restore(
    sim: MultiRobotSimulationCore, path: str | os.PathLike[str], parts: CheckpointParts
) -> tuple[int, int, bool]:
    """Bring ``sim`` (freshly built from the same scenario) to the state saved in ``path``.

    Returns:
        (step count, collision count, paused) for the simulation's clock.

    Raises:
        CheckpointError: for a file that is no checkpoint, or a simulation that differs from
            the saved one or has stepped already, naming the difference.
    """
    state = _load(sim, path, parts.step_count)
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
    step_count, collision_count, paused = state["clock"]
    return step_count, collision_count, paused
