"""Doors and lifts named by a Gazebo world the Open-RMF way become devices.

Open-RMF's building map generator (``rmf_building_map_tools``) writes each door and each lift
as an inline ``<model>`` of the ``.world`` file that carries a plugin naming it:

- a door: ``<plugin filename="libregister_component.so"><component name="Door">`` (older
  worlds: ``<plugin filename="libdoor.so">``) holding ``<door name=... type=SlidingDoor |
  DoubleSlidingDoor | SwingDoor | DoubleSwingDoor .../>`` and ``<v_max_door>``;
- a lift: ``<component name="Lift">`` (older: ``liblift.so``) holding ``<floor name=...
  elevation=...>`` elements, ``<initial_floor>`` and ``<v_max_cabin>``.

``sim.load_world({"world_file": ...})`` turns such models into a :class:`Door` / an
:class:`Elevator` instead of static geometry. The door's leaf is the box of its link(s): the
doorway's width is the sum of the leaves' widths, a double door becomes one leaf of that width
(sliding doors slide it by its width; swing doors swing it about its -x edge by the joint's
limit), and ``open_time`` is the travel divided by ``v_max_door`` (accelerations ignored). The
lift's platform is the box of its ``platform`` link's floor, its speed ``v_max_cabin``. Cabin
doors (models nested in the lift) are not modelled; shaft doors are doors of their own.

Open-RMF's workcells are ``<include>`` entries of the models ``TeleportDispenser`` and
``TeleportIngestor``, named after the workcell (``coke_dispenser``); they become
:class:`Workcell` stations of that name at the include's pose, with the default processing
time.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

from fleet_async.core.agents.agent_params import AgentSpawnParams
from fleet_async.core.devices.device import Device
from fleet_async.core.devices.door import Door, DoorParams
from fleet_async.core.devices.elevator import Elevator
from fleet_async.core.devices.elevator_params import ElevatorParams
from fleet_async.core.devices.workcell import Workcell, WorkcellParams
from fleet_async.core.geometry.pose import Pose

__all__ = ["device_class", "rmf_device_params", "rmf_workcell_params"]

RMF_WORKCELL_MODELS = {"TeleportDispenser": "dispenser", "TeleportIngestor": "ingestor"}
"""Open-RMF workcell model names and the kind of station each becomes."""

_DOOR_TYPES = {
    "SlidingDoor": "sliding",
    "DoubleSlidingDoor": "sliding",
    "SwingDoor": "hinged",
    "DoubleSwingDoor": "hinged",
}


def _component(model: ET.Element, kind: str, legacy: str) -> ET.Element | None:
    for plugin in model.findall("plugin"):
        filename = plugin.get("filename", "")
        if filename == legacy:
            return plugin
        for component in plugin.findall("component"):
            if component.get("name") == kind:
                return component
    return None


def _numbers(text: str | None, n: int, where: str) -> list[float]:
    try:
        values = [float(v) for v in (text or "").split()]
    except ValueError:
        raise ValueError(f"{where}: expected {n} numbers, got {text!r}") from None
    if len(values) != n or not all(math.isfinite(v) for v in values):
        raise ValueError(f"{where}: expected {n} finite numbers, got {text!r}")
    return values


def _pose(element: ET.Element, where: str) -> Pose:
    node = element.find("pose")
    if node is None or not (node.text or "").strip():
        return Pose([0.0, 0.0, 0.0])
    x, y, z, roll, pitch, yaw = _numbers(node.text, 6, f"{where} <pose>")
    return Pose.from_euler(x, y, z, roll, pitch, yaw)


def _float(element: ET.Element, tag: str, default: float, where: str) -> float:
    node = element.find(tag)
    return default if node is None else _numbers(node.text, 1, f"{where} <{tag}>")[0]


def _box(link: ET.Element, where: str) -> list[float] | None:
    size = link.find("./visual/geometry/box/size")
    if size is None:
        size = link.find("./collision/geometry/box/size")
    return None if size is None else _numbers(size.text, 3, f"{where} box <size>")


def _door(model: ET.Element, plugin: ET.Element, where: str) -> DoorParams:
    door = plugin.find("door")
    if door is None:
        raise ValueError(f"{where}: its Door plugin has no <door .../> element")
    kind = door.get("type", "")
    if kind not in _DOOR_TYPES:
        raise ValueError(f"{where}: door type {kind!r} is not one of {sorted(_DOOR_TYPES)}")
    leaves = [box for link in model.findall("link") if (box := _box(link, where)) is not None]
    if not leaves:
        raise ValueError(f"{where}: the door has no link with a box to use as its leaf")
    width = sum(b[0] for b in leaves)
    height, thickness = max(b[2] for b in leaves), max(b[1] for b in leaves)
    speed = _float(plugin, "v_max_door", 0.2, where)
    door_type = _DOOR_TYPES[kind]
    travel = width
    angle = math.pi / 2
    if door_type == "hinged":
        limits = model.find("./joint/axis/limit")
        if limits is not None:
            low = _float(limits, "lower", 0.0, where)
            high = _float(limits, "upper", angle, where)
            angle = high if abs(high) >= abs(low) else low
        travel = abs(angle)
    return DoorParams(
        name=door.get("name") or model.get("name"),
        initial_pose=_pose(model, where),
        door_type=door_type,  # type: ignore[arg-type]  # coerced in __post_init__
        width=width,
        height=height,
        thickness=thickness,
        open_time=travel / speed if speed > 0 else 0.0,
        swing_angle=angle,
        user_data={"rmf_door_type": kind},
    )


def _lift(model: ET.Element, plugin: ET.Element, where: str) -> ElevatorParams:
    floors = {
        f.get("name", ""): _numbers(f.get("elevation"), 1, f"{where} <floor> elevation")[0]
        for f in plugin.findall("floor")
    }
    if not floors or "" in floors:
        raise ValueError(f"{where}: the lift needs <floor name=... elevation=...> elements")
    initial = (plugin.findtext("initial_floor") or "").strip() or next(iter(floors))
    name = (plugin.findtext("lift_name") or "").strip() or model.get("name")
    size = [1.6, 1.6, 0.05]
    for link in model.findall("link"):
        if link.get("name") == "platform" and (box := _box(link, where)) is not None:
            size = box
    return ElevatorParams(
        name=name,
        initial_pose=_pose(model, where),
        floors=floors,
        initial_floor=initial,
        speed=_float(plugin, "v_max_cabin", 1.0, where),
        platform_size=size[:2],
        platform_thickness=size[2],
    )


def rmf_device_params(model: ET.Element, where: str) -> AgentSpawnParams | None:
    """The DoorParams / ElevatorParams of an Open-RMF door or lift ``<model>``, else None.

    Raises:
        ValueError: for a door or lift model that cannot be read, naming ``where``.
    """
    door = _component(model, "Door", "libdoor.so")
    if door is not None:
        return _door(model, door, where)
    lift = _component(model, "Lift", "liblift.so")
    if lift is not None:
        return _lift(model, lift, where)
    return None


def rmf_workcell_params(model_name: str, name: str, pose: Pose) -> WorkcellParams | None:
    """The WorkcellParams of an Open-RMF ``TeleportDispenser`` / ``TeleportIngestor``
    include named ``name`` at ``pose``, else None."""
    kind = RMF_WORKCELL_MODELS.get(model_name)
    if kind is None:
        return None
    return WorkcellParams(
        name=name,
        initial_pose=pose,
        kind=kind,  # type: ignore[arg-type]  # coerced in __post_init__
        user_data={"rmf_model": model_name},
    )


def device_class(params: AgentSpawnParams) -> type[Device]:
    """The device class that ``params`` (from this module) build."""
    if isinstance(params, DoorParams):
        return Door
    if isinstance(params, ElevatorParams):
        return Elevator
    return Workcell
