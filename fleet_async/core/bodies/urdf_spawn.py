"""URDF bodies for spawning: loaded now, or pending when the simulation holds the model.

The first robot of each URDF model in a simulation is loaded with ``loadURDF`` and the model is
read back from it once (``world/urdf_models.py``). A later robot of the same model whose body
can wait (a headless simulation, the body kinematic: physics off or ``mass=0.0``) gets a
pending body: its row takes the base pose ``loadURDF`` would give it, and the world loads the
body when something needs PyBullet's view (``world/pending.py``). Without a simulation, with a
GUI or with dynamics the body is loaded at once, as always.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from fleet_async.core.geometry.pose import Pose
from fleet_async.core.world.pending import PENDING_BODY, Deferred, UrdfSpawn
from fleet_async.core.world.urdf_models import UrdfKey, load_urdf_body, read_urdf_model

if TYPE_CHECKING:
    from fleet_async.core.bodies.host import BodyHost

__all__ = ["reserve_urdf_body"]


def reserve_urdf_body(
    path: str,
    pose: Pose,
    use_fixed_base: bool,
    mass: float | None,
    sim_core: BodyHost | None,
) -> tuple[int, Deferred | None, float | None]:
    """A body of the URDF at ``path`` (an absolute file) for a robot at ``pose``.

    Args:
        path: The URDF file.
        pose: The URDF base link's pose.
        use_fixed_base: Load it with a fixed base.
        mass: kg as given at spawn: 0.0 makes every link massless, None keeps the URDF's.
        sim_core: The simulation (None: client 0, loaded at once).

    Returns:
        ``(body_id, None, None)`` for a body loaded now, or ``(PENDING_BODY, deferred,
        total_mass)`` for one the world loads later (``total_mass``: the URDF's, kg, what
        PyBullet will hold for it, for robots spawned with ``mass=None``).

    Raises:
        ValueError: when PyBullet cannot load the file.
    """
    key = UrdfKey(path, bool(use_fixed_base), mass == 0.0)
    pos, orn = pose.as_position_orientation()
    if sim_core is None:
        return load_urdf_body(key, pos, orn, 0), None, None
    world = sim_core.world
    can_wait = not sim_core.is_gui and (not sim_core.params.physics or key.zero_mass)
    model = world.urdf_model(key) if can_wait else None
    if model is not None:
        base_pos, base_orn = model.base_pose(pos, orn)
        spawn = UrdfSpawn(key, tuple(pos), tuple(orn), base_pos, base_orn)
        return PENDING_BODY, (spawn, base_pos, base_orn), model.total_mass
    body = load_urdf_body(key, pos, orn, world.client)
    if can_wait:
        world.remember_urdf_model(read_urdf_model(key, body, world.client))
    return body, None, None
