"""How a checkpoint refers to the simulation, its objects and its random streams.

The codec (``codec.py``) writes them as tags (``{"sim": 0}``, ``{"obj": id}``,
``{"stream": [key]}``) and this module makes and resolves the tags against one simulation:
saving refuses an object of another simulation; restoring refuses an id it does not have.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from fleet_async.core.bodies.sim_object import SimObject
from fleet_async.core.checkpoint.codec import Resolver

if TYPE_CHECKING:
    from fleet_async.core.sim.kernel import SimulationKernel

__all__ = ["resolver_for"]


def resolver_for(sim: SimulationKernel) -> Resolver:
    """The references of ``sim`` (see the module's docstring)."""

    def ref_of(value: Any) -> dict[str, Any] | None:
        if value is sim:
            return {"sim": 0}
        if isinstance(value, SimObject):
            if value.sim_core is not sim:
                raise ValueError(f"save_state: the state refers to {value!r}, not in it")
            return {"obj": value.object_id}
        if value is sim.rng:
            return {"stream": []}
        key = sim.random_streams.key_of(value)
        return None if key is None else {"stream": list(key)}

    def resolve(tag: dict[str, Any]) -> Any:
        ((name, body),) = tag.items()
        if name == "sim" and body == 0:
            return sim
        if name == "obj" and isinstance(body, int) and not isinstance(body, bool):
            obj = sim.get_object_by_id(body)
            if obj is None:
                raise ValueError(f"the checkpoint refers to object {body}, not in this simulation")
            return obj
        if name == "stream" and isinstance(body, list):
            if not body:
                return sim.rng
            return sim.rng_for(*body)
        raise ValueError(f"unknown entry {tag!r}")

    return Resolver(ref_of, resolve)
