"""A served robot's VDA 5050 factsheet: what it is and what it can do, from the simulation.

Kinematics from its controller (differential -> ``DIFF``, else ``OMNI``), speeds and
accelerations from its limits, length / width / height from its visual shapes in its own frame
(the footprint the viewer draws: the same whichever way the robot faces), the actions the
fleet interface runs, and the payload limit the decoder enforces.
"""

from __future__ import annotations

from typing import Any

from fleet_async.core.base.types import MotionMode
from fleet_async.core.view.trace.footprints import describe_body
from fleet_async.interfaces.vda5050.config import Vda5050Config
from fleet_async.interfaces.vda5050.decode import MAX_PAYLOAD_BYTES

__all__ = ["describe"]

_LOAD_KEYS = ("loadId", "loadType", "stationType", "stationName", "lhd", "height", "depth")


def _action(
    action_type: str,
    scopes: list[str],
    description: str,
    params: list[dict[str, Any]] | None = None,
    blocking: list[str] | None = None,
    version: str = "2.1.0",
) -> dict[str, Any]:
    entry: dict[str, Any] = {
        "actionType": action_type,
        "actionScopes": scopes,
        "actionDescription": description,
    }
    if params:
        entry["actionParameters"] = params
    if blocking and not version.startswith("2.0"):
        entry["blockingTypes"] = blocking
    return entry


def _actions(version: str) -> list[dict[str, Any]]:
    load: list[dict[str, Any]] = [
        {"key": k, "valueDataType": "STRING" if k != "height" else "FLOAT", "isOptional": True}
        for k in _LOAD_KEYS
    ]
    number: list[dict[str, Any]] = [
        {"key": k, "valueDataType": "FLOAT", "isOptional": False} for k in ("x", "y", "theta")
    ]
    init = [*number, {"key": "lastNodeId", "valueDataType": "STRING", "isOptional": True}]
    node_edge = ["NODE", "EDGE"]
    return [
        _action(
            "pick",
            node_edge,
            "attach the nearest pickable object (loadId: by name) within 1 m",
            load,
            ["SOFT", "HARD"],
            version,
        ),
        _action(
            "drop",
            node_edge,
            "release what the vehicle carries where it stands",
            load,
            ["SOFT", "HARD"],
            version,
        ),
        _action(
            "startCharging",
            ["INSTANT", *node_edge],
            "charge the battery",
            blocking=["NONE", "SOFT", "HARD"],
            version=version,
        ),
        _action(
            "stopCharging",
            ["INSTANT", *node_edge],
            "stop charging",
            blocking=["NONE", "SOFT", "HARD"],
            version=version,
        ),
        _action("cancelOrder", ["INSTANT"], "stop now and drop the order"),
        _action("startPause", ["INSTANT"], "stop driving until stopPause"),
        _action("stopPause", ["INSTANT"], "drive on after startPause"),
        _action("stateRequest", ["INSTANT"], "publish a state now"),
        _action("factsheetRequest", ["INSTANT"], "publish the factsheet now"),
        _action("initPosition", ["INSTANT"], "set the pose (no order running)", init),
    ]


def _size(robot: Any) -> tuple[float, float, float]:
    """Length, width and height (m) of the robot in its own frame (its visual shapes)."""
    footprint, _ = describe_body(robot, robot.sim_core.world, {})
    low, high = footprint["z"]
    if footprint["type"] == "circle":
        side = 2.0 * float(footprint["radius"])
        return side, side, float(high - low)
    half = footprint["half"]
    return 2.0 * float(half[0]), 2.0 * float(half[1]), float(high - low)


def _limit(value: Any) -> float:
    return float(max(value)) if isinstance(value, (tuple, list)) else float(value)


def _geometry(robot: Any, length: float, width: float, vmax: float) -> dict[str, Any]:
    """``agvGeometry``: the safety fields as ``envelopes2d`` (vehicle frame, x ahead), at
    standstill and at full speed; ``{}`` for a robot without fields."""
    fields = robot.sim_core.safety.params_of(robot)
    if fields is None:
        return {}
    if fields.footprint is not None:
        length, width = fields.footprint
    front, side = 0.5 * length, 0.5 * width + fields.side_margin
    envelopes = []
    for name, depth_at in (
        ("protectiveField", fields.protective_depth),
        ("warningField", fields.warning_depth),
    ):
        for speed_name, speed in (("standstill", 0.0), ("maxSpeed", vmax)):
            depth = depth_at(speed)
            points = [(front, -side), (front + depth, -side), (front + depth, side), (front, side)]
            envelopes.append(
                {
                    "set": f"{name}_{speed_name}",
                    "polygonPoints": [{"x": round(x, 6), "y": round(y, 6)} for x, y in points],
                    "description": f"{name} at {speed:g} m/s, ahead in the direction of travel",
                }
            )
    return {"envelopes2d": envelopes}


def describe(robot: Any, config: Vda5050Config) -> dict[str, Any]:
    """The factsheet body (without the header) of ``robot``."""
    params = robot.controller_params
    length, width, height = _size(robot)
    accel = _limit(params.max_linear_accel)
    kinematic = "DIFF" if robot.motion_mode is MotionMode.DIFFERENTIAL else "OMNI"
    return {
        "typeSpecification": {
            "seriesName": config.series_name or robot.name,
            "seriesDescription": "fleet_async simulated vehicle",
            "agvKinematic": kinematic,
            "agvClass": "CARRIER",
            "maxLoadMass": 0.0,
            "localizationTypes": ["NATURAL"],
            "navigationTypes": ["AUTONOMOUS"],
        },
        "physicalParameters": {
            "speedMin": 0.0,
            "speedMax": _limit(params.max_linear_vel),
            "accelerationMax": accel,
            "decelerationMax": accel,
            "heightMin": 0.0,
            "heightMax": height,
            "width": width,
            "length": length,
        },
        "protocolLimits": {
            "maxStringLens": {"msgLen": MAX_PAYLOAD_BYTES},
            "maxArrayLens": {},
            "timing": {
                "minOrderInterval": 0.0,
                "minStateInterval": 0.0,
                "defaultStateInterval": config.state_period,
                **(
                    {"visualizationInterval": config.visualization_period}
                    if config.visualization_period
                    else {}
                ),
            },
        },
        "protocolFeatures": {
            "optionalParameters": [],
            "agvActions": _actions(config.version),
        },
        "agvGeometry": _geometry(robot, length, width, _limit(params.max_linear_vel)),
        "loadSpecification": {},
    }
