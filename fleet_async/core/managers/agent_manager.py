"""AgentManager: a SimObjectManager for agents, with goals, actions, callbacks and fleet-wide
controller settings."""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any, ClassVar, cast

from fleet_async.core.agents.agent import Agent
from fleet_async.core.agents.agent_params import AgentSpawnParams
from fleet_async.core.base.config_utils import resolve_class
from fleet_async.core.bodies.sim_object import SimObject
from fleet_async.core.bodies.spawn_params import SimObjectSpawnParams
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.managers.grid_spawn import GridSpawnParams
from fleet_async.core.managers.sim_object_manager import SimObjectManager
from fleet_async.core.motion.controllers import (
    CONTROLLER_REGISTRY,
    Controller,
    ControllerParams,
    DifferentialController,
    KinematicController,
    OmniController,
)

if TYPE_CHECKING:
    from fleet_async.core.actions.action import Action
    from fleet_async.core.managers.host import CameraHost, ManagerHost

__all__ = ["AgentManager"]

logger = logging.getLogger(__name__)


def _selects_base(entry: Any) -> bool | None:
    """Whether a controller entry selects a base controller; None when it cannot be told."""
    if isinstance(entry, Controller):
        return entry.is_base
    cls: Any = None
    if isinstance(entry, str):
        cls = CONTROLLER_REGISTRY.get(entry)
    elif isinstance(entry, dict):
        if "class" in entry:
            try:
                cls = resolve_class(str(entry["class"]))
            except (ValueError, ImportError, AttributeError):
                return None
        elif "type" in entry:
            cls = CONTROLLER_REGISTRY.get(str(entry["type"]))
        else:
            return True  # params only: the agent's default base
    return issubclass(cls, KinematicController) if isinstance(cls, type) else None


def _with_fleet_controller(spec: Any, fleet: dict[str, Any] | None) -> Any:
    """Merge fleet-wide ControllerParams fields under an agent's own ``controller`` spec.

    The fleet values go into the spec's base controller entry, the agent's own values winning;
    a spec without a base entry (only high-level controllers) gets a params-only base entry
    first. A ControllerParams, a base Controller instance, or a spec that names an unknown
    controller is returned unchanged (the chain builder reports the latter).
    """
    if not fleet or isinstance(spec, ControllerParams):
        return spec
    if spec is None:
        return dict(fleet)
    single = not isinstance(spec, list)
    entries = [spec] if single else list(spec)
    kinds = [_selects_base(entry) for entry in entries]
    if None in kinds:
        return spec
    if True in kinds:
        i = kinds.index(True)
        if isinstance(entries[i], Controller):
            return spec
        own = {"type": entries[i]} if isinstance(entries[i], str) else entries[i]
        entries[i] = {**fleet, **own}
    else:
        entries.insert(0, dict(fleet))
    return entries[0] if single and len(entries) == 1 else entries


_BATCH_MODES: dict[str, type[KinematicController]] = {
    "batch_omni": OmniController,
    "batch_differential": DifferentialController,
}


def _batch_controller_class(mode: str) -> type[KinematicController]:
    """The base controller class for a batch mode name or a dotted class path.

    Raises:
        ValueError: naming ``mode`` and the accepted names, when it is neither.
    """
    accepted = f"accepted: {sorted(_BATCH_MODES)} or a dotted path to a KinematicController"
    if isinstance(mode, str) and mode in _BATCH_MODES:
        return _BATCH_MODES[mode]
    if not (isinstance(mode, str) and "." in mode):
        raise ValueError(f"enable_batch: unknown batch controller {mode!r}; {accepted}")
    try:
        cls = resolve_class(mode)
    except (ValueError, ImportError, AttributeError) as exc:
        raise ValueError(f"enable_batch: cannot resolve {mode!r} ({exc}); {accepted}") from exc
    if not (isinstance(cls, type) and issubclass(cls, KinematicController)):
        raise ValueError(f"enable_batch: {mode!r} is not a KinematicController; {accepted}")
    return cls


class AgentManager(SimObjectManager[Agent]):
    """A SimObjectManager for agents: goals, actions, callbacks and fleet-wide controllers.

    Args:
        sim_core: The simulation.
        name: Name under which ``sim_core.get_manager(name)`` finds this manager.
        update_frequency: Default frequency (Hz of sim time) of :meth:`register_callback`.
        object_class: Agent class the spawn methods instantiate.
        enable_profiling: Log each spawn call's elapsed time at INFO.
        batch_controller: Same as calling :meth:`enable_batch` with it.
        fleet_controller: ControllerParams fields (e.g. ``{"max_linear_vel": 2.0}``) applied to
            agents spawned through this manager; an agent's own ``controller`` values win.

    Attributes:
        name: The manager's name, or None.
        update_frequency: Default callback frequency in Hz.
        fleet_controller: The fleet-wide ControllerParams fields, or None.
    """

    _managed_type: ClassVar[type[SimObject]] = Agent

    def __init__(
        self,
        sim_core: ManagerHost | None = None,
        name: str | None = None,
        update_frequency: float = 10.0,
        object_class: type[Agent] = Agent,
        enable_profiling: bool = False,
        batch_controller: str | None = None,
        fleet_controller: dict[str, Any] | None = None,
    ) -> None:
        if name is not None and not isinstance(name, str):
            raise ValueError(f"AgentManager.name: expected a string or None, got {name!r}")
        self.name = name
        self.update_frequency = _frequency(update_frequency, "AgentManager.update_frequency")
        self.fleet_controller = _fleet_controller(fleet_controller)
        self._batch_mode: str | None = None
        self._batch_class: type[KinematicController] | None = None
        self._pending_callbacks: list[tuple[Callable[[Any, float], Any], float]] = []
        super().__init__(sim_core, object_class, enable_profiling)
        if batch_controller is not None:
            self.enable_batch(batch_controller)

    def __repr__(self) -> str:
        return f"AgentManager(name={self.name!r}, objects={len(self.objects)})"

    def _attach(self, sim: ManagerHost) -> None:
        other = None if self.name is None else sim.get_manager(self.name)
        if other is not None and other is not self:
            raise ValueError(
                f"AgentManager.name: a manager named {self.name!r} is already registered"
            )
        super()._attach(sim)
        for wrapper, frequency in self._pending_callbacks:
            sim.register_callback(wrapper, frequency)
        self._pending_callbacks.clear()

    def add_object(self, obj: Agent) -> None:
        """Track ``obj`` (see :meth:`SimObjectManager.add_object`) and apply the batch mode."""
        super().add_object(obj)
        if self._batch_class is not None and self._by_object_id.get(obj.object_id) is obj:
            self._apply_batch(obj)

    # ----- spawning -----------------------------------------------------------------------

    def spawn_agents_grid(
        self,
        num_agents: int,
        grid_params: GridSpawnParams,
        spawn_params: AgentSpawnParams,
        *,
        name_prefix: str | None = None,
    ) -> list[Agent]:
        """Alias of :meth:`spawn_objects_grid`."""
        return self.spawn_objects_grid(
            num_agents, grid_params, spawn_params, name_prefix=name_prefix
        )

    def spawn_agents_grid_mixed(
        self,
        num_agents: int,
        grid_params: GridSpawnParams,
        spawn_params_list: Sequence[tuple[SimObjectSpawnParams, float]],
        *,
        name_prefix: str | None = None,
    ) -> list[Agent]:
        """Alias of :meth:`spawn_grid_mixed`."""
        return self.spawn_grid_mixed(
            num_agents, grid_params, spawn_params_list, name_prefix=name_prefix
        )

    def spawn_agent_grid_counts(
        self,
        grid_params: GridSpawnParams,
        spawn_params_count_list: Sequence[tuple[SimObjectSpawnParams, int]],
        *,
        name_prefix: str | None = None,
    ) -> list[Agent]:
        """Alias of :meth:`spawn_grid_counts`."""
        return self.spawn_grid_counts(grid_params, spawn_params_count_list, name_prefix=name_prefix)

    def _prepare_params(self, params: SimObjectSpawnParams) -> SimObjectSpawnParams:
        if not self.fleet_controller or not isinstance(params, AgentSpawnParams):
            return params
        merged = _with_fleet_controller(params.controller, self.fleet_controller)
        return (
            params
            if merged is params.controller
            else dataclasses.replace(params, controller=merged)
        )

    def _prepare_config(self, cls: type[SimObject], config: dict[str, Any]) -> dict[str, Any]:
        if not self.fleet_controller or not issubclass(cls, Agent):
            return config
        return {
            **config,
            "controller": _with_fleet_controller(config.get("controller"), self.fleet_controller),
        }

    # ----- goals and motion ---------------------------------------------------------------

    def set_goal_pose(self, agent_index: int, goal: Pose) -> None:
        """Send ``objects[agent_index]`` to ``goal``.

        Raises:
            IndexError: for an index out of range.
        """
        self._at(agent_index, "set_goal_pose").set_goal_pose(goal)

    def set_goal_pose_by_body_id(self, body_id: int, goal: Pose) -> None:
        """Send the agent with PyBullet ``body_id`` to ``goal``.

        Raises:
            KeyError: if no managed agent has that body id.
        """
        if body_id not in self.body_ids:
            raise KeyError(f"set_goal_pose_by_body_id: no managed agent has body_id {body_id!r}")
        self.objects[self.body_ids.index(body_id)].set_goal_pose(goal)

    def set_goal_pose_by_object_id(self, object_id: int, goal: Pose) -> None:
        """Send the agent with simulation ``object_id`` to ``goal``.

        Raises:
            KeyError: if no managed agent has that object id.
        """
        agent = self._by_object_id.get(object_id)
        if agent is None:
            raise KeyError(
                f"set_goal_pose_by_object_id: no managed agent has object_id {object_id!r}"
            )
        agent.set_goal_pose(goal)

    def set_goal_pose_all(self, goal_factory: Callable[[Agent], Pose]) -> None:
        """``agent.set_goal_pose(goal_factory(agent))`` for every agent, in order."""
        for agent in list(self.objects):
            agent.set_goal_pose(goal_factory(agent))

    def stop_all(self) -> None:
        """Stop every agent and forget its goal."""
        for agent in self.objects:
            agent.stop()

    def get_moving_count(self) -> int:
        """Number of agents currently moving."""
        return sum(1 for agent in self.objects if agent.is_moving)

    def set_joints_targets_all(
        self,
        targets_factory: Callable[[Agent], Sequence[float] | Mapping[str, float]],
        max_force: float = 500.0,
    ) -> None:
        """``agent.set_joints_targets(targets_factory(agent), max_force)`` for every arm.

        Agents without joints (mobile robots, mesh robots) are skipped, and the factory is not
        called for them.
        """
        for agent in list(self.objects):
            if agent.get_num_joints() > 0:
                agent.set_joints_targets(targets_factory(agent), max_force=max_force)

    # ----- actions ------------------------------------------------------------------------

    def add_action_sequence_all(self, action_factory: Callable[[Agent], Sequence[Action]]) -> None:
        """``agent.add_action_sequence(action_factory(agent))`` for every agent, in order."""
        for agent in list(self.objects):
            agent.add_action_sequence(action_factory(agent))

    def add_action_all(self, action_factory: Callable[[Agent], Action]) -> None:
        """``agent.add_action(action_factory(agent))`` for every agent, in order."""
        for agent in list(self.objects):
            agent.add_action(action_factory(agent))

    # ----- callbacks and camera -----------------------------------------------------------

    def register_callback(
        self, callback: Callable[[AgentManager, float], Any], frequency: float | None = None
    ) -> None:
        """Call ``callback(manager, dt)`` at ``frequency`` Hz of sim time.

        Args:
            callback: Receives this manager and the sim time (s) since its previous call.
            frequency: Hz; None uses ``update_frequency``. Registered with the simulation now,
                or as soon as the manager joins one.

        Raises:
            ValueError: if ``frequency`` is not a number > 0.
        """
        if not callable(callback):
            raise TypeError(f"register_callback: callback is not callable: {callback!r}")
        freq = self.update_frequency if frequency is None else frequency
        freq = _frequency(freq, "register_callback.frequency")

        def run(_sim: Any, dt: float) -> None:
            callback(self, dt)

        if self.sim_core is not None:
            self.sim_core.register_callback(run, freq)
        else:
            self._pending_callbacks.append((run, freq))

    def setup_camera(
        self, camera_config: dict[str, Any] | None = None
    ) -> tuple[float, float, float, list[float]]:
        """Frame the camera on the managed agents (``sim_core.setup_camera``).

        Returns:
            (distance, yaw, pitch, target) of the view.

        Raises:
            ValueError: without a simulation.
        """
        if self.sim_core is None:
            raise ValueError("setup_camera: the manager has no simulation (sim_core)")
        positions = (
            self.sim_core.get_poses(self.object_ids)[0].tolist() if self.object_ids else None
        )
        # A manager's simulation is the whole one, whose view floor adds the GUI camera.
        camera = cast("CameraHost", self.sim_core)
        return camera.setup_camera(camera_config, entity_positions=positions)

    # ----- batch mode ---------------------------------------------------------------------

    @property
    def batch_controller(self) -> str | None:
        """The batch mode set by :meth:`enable_batch`, or None."""
        return self._batch_mode

    def enable_batch(self, mode: str) -> type[KinematicController]:
        """Put every managed agent (and every agent spawned later) on one base controller.

        Built-in omni / differential controllers are always vectorised by the simulation's
        kinematic engine, so ``"batch_omni"`` / ``"batch_differential"`` install
        OmniController / DifferentialController with each agent's current controller params. A
        dotted path names a KinematicController subclass to install the same way. Agents
        already on that class, fixed-base agents and agents whose movement was disabled
        (``set_controller(None)``) are left alone; switched agents stop.

        Returns:
            The controller class installed.

        Raises:
            ValueError: naming ``mode`` and the accepted names, for anything else.
        """
        cls = _batch_controller_class(mode)
        self._batch_mode, self._batch_class = mode, cls
        for agent in list(self.objects):
            self._apply_batch(agent)
        return cls

    def disable_batch(self) -> None:
        """Forget the batch mode; agents keep the controller they have."""
        self._batch_mode = self._batch_class = None

    def _apply_batch(self, agent: Agent) -> None:
        cls = self._batch_class
        if cls is None or agent.use_fixed_base or agent.controller is None:
            return
        if type(agent.controller) is not cls:
            agent.set_controller(cls(params=agent.controller_params))


def _frequency(value: Any, what: str) -> float:
    real = isinstance(value, (int, float)) and not isinstance(value, bool)
    if not (real and math.isfinite(value) and value > 0):
        raise ValueError(f"{what}: expected a number > 0 (Hz), got {value!r}")
    return float(value)


def _fleet_controller(value: Any) -> dict[str, Any] | None:
    if value is None:
        return None
    if not isinstance(value, dict):
        raise ValueError(f"AgentManager.fleet_controller: expected a mapping, got {value!r}")
    unknown = sorted(set(value) - set(ControllerParams.field_names()))
    if unknown:
        raise ValueError(
            f"AgentManager.fleet_controller: unknown key(s) {unknown}; "
            f"valid: {list(ControllerParams.field_names())}"
        )
    ControllerParams(**value)  # validates the values, naming the field
    return dict(value)
