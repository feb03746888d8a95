"""SimObject's constructors: from spawn parameters, shapes, a mapping, an SDF file, or many at
once (mixed into SimObject; ``Agent`` overrides them with its own parameters).

``from_params`` on a headless simulation leaves a kinematic body pending and the world makes
the pending bodies in batches (``bodies/spawning.py``, ``world/pending.py``), so a loop of
``from_mesh`` calls costs little more per object than one ``spawn_batch``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, ClassVar, cast

from fleet_async.core.base.types import CollisionMode
from fleet_async.core.bodies.spawn_params import SimObjectSpawnParams
from fleet_async.core.bodies.spawning import (
    construct,
    load_sdf_objects,
    reserve_bodies,
    reserve_body,
    wrap_all,
)
from fleet_async.core.geometry.pose import Pose
from fleet_async.core.world.shapes import ShapeParams, get_or_create_shapes

if TYPE_CHECKING:
    from fleet_async.core.bodies.host import BodyHost
    from fleet_async.core.bodies.sim_object import SimObject

__all__ = ["SimObjectConstructors"]


class SimObjectConstructors:
    """The class methods that create objects (mixed into SimObject)."""

    _spawn_params_cls: ClassVar[type[SimObjectSpawnParams]] = SimObjectSpawnParams

    @classmethod
    def create_shared_shapes(
        cls,
        visual_shape: ShapeParams | None = None,
        collision_shape: ShapeParams | None = None,
        physics_client_id: int = 0,
    ) -> tuple[int, int]:
        """Return (visual_id, collision_id), reusing shapes with identical parameters."""
        return get_or_create_shapes(visual_shape, collision_shape, physics_client_id)

    @classmethod
    def from_params(
        cls, spawn_params: SimObjectSpawnParams, sim_core: BodyHost | None = None
    ) -> SimObject:
        """Create the body described by ``spawn_params`` and wrap it.

        Raises:
            FileNotFoundError: for a mesh file that does not exist.
            ValueError: for shapes PyBullet rejects.
        """
        body_id, deferred = reserve_body(spawn_params, sim_core)
        return construct(
            lambda body: cast("type[SimObject]", cls)(
                body,
                sim_core=sim_core,
                pickable=spawn_params.pickable,
                mass=spawn_params.mass,
                collision_mode=spawn_params.collision_mode,
                name=spawn_params.name,
                user_data=dict(spawn_params.user_data),
            ),
            body_id,
            deferred,
            sim_core,
        )

    @classmethod
    def spawn_batch(
        cls, params_list: Sequence[SimObjectSpawnParams], sim_core: BodyHost
    ) -> list[SimObject]:
        """Spawn many shape-based objects fast (bodies pending or created in batches, as
        ``from_params`` would); input order kept.

        If anything fails, nothing this call created is left behind.
        """
        params_list = list(params_list)
        make = cast("type[SimObject]", cls)
        with sim_core.batch_spawn():
            reserved = reserve_bodies(params_list, sim_core)

            def build(i: int, body: int) -> SimObject:
                prm = params_list[i]
                return construct(
                    lambda b: make(
                        b,
                        sim_core=sim_core,
                        pickable=prm.pickable,
                        mass=prm.mass,
                        collision_mode=prm.collision_mode,
                        name=prm.name,
                        user_data=dict(prm.user_data),
                    ),
                    body,
                    reserved[i][1],
                    sim_core,
                )

            return wrap_all([body for body, _ in reserved], build, sim_core)

    @classmethod
    def from_mesh(
        cls,
        visual_shape: ShapeParams | None = None,
        collision_shape: ShapeParams | None = None,
        pose: Pose | None = None,
        mass: float = 0.0,
        pickable: bool = True,
        sim_core: BodyHost | None = None,
        collision_mode: CollisionMode | str = CollisionMode.NORMAL_3D,
        name: str | None = None,
        user_data: dict[str, Any] | None = None,
    ) -> SimObject:
        """Create an object from visual and collision shapes (box, sphere, cylinder or mesh)."""
        params = SimObjectSpawnParams(
            visual_shape=visual_shape,
            collision_shape=collision_shape,
            initial_pose=pose if pose is not None else Pose([0.0, 0.0, 0.0]),
            mass=mass,
            pickable=pickable,
            name=name,
            collision_mode=collision_mode,  # type: ignore[arg-type]  # coerced in __post_init__
            user_data=user_data or {},
        )
        return cls.from_params(params, sim_core)

    @classmethod
    def from_dict(cls, config: dict[str, Any], sim_core: BodyHost | None = None) -> SimObject:
        """``from_params(_spawn_params_cls.from_dict(config))`` in one call."""
        return cls.from_params(cls._spawn_params_cls.from_dict(config), sim_core)

    @classmethod
    def from_sdf(
        cls,
        sdf_path: str,
        sim_core: BodyHost | None = None,
        collision_mode: CollisionMode | str = CollisionMode.NORMAL_3D,
        global_scaling: float = 1.0,
        name_prefix: str | None = None,
        pickable: bool = False,
        use_fixed_base: bool = True,
    ) -> list[SimObject]:
        """Load every body of an SDF file (``pybullet.loadSDF``) and wrap each one.

        Raises:
            FileNotFoundError: naming the paths tried when the file does not exist.
            ValueError: if PyBullet cannot parse the file.
        """
        return load_sdf_objects(
            cast("type[SimObject]", cls),
            sdf_path,
            sim_core,
            collision_mode,
            global_scaling,
            name_prefix,
            pickable,
            use_fixed_base,
        )
