"""One colour per link, so PyBullet's GUI and the recordings show a body alike.

PyBullet's GUI (OpenGL) draws each link in one colour, the colour of the link's last visual;
its tiny renderer, which recordings use, draws every visual in its own colour. A link with
visuals of several colours (a blue chassis with a grey caster, a shelf rack's blue frame and
brown boards) therefore looked different in the GUI and in a GIF. When a URDF or SDF body is
loaded, each such link is painted the colour that covers most of its surface, in both
renderers. For a URDF, one warning per file says how to keep the colours apart (each coloured
part in a link of its own, on a fixed joint).
"""

from __future__ import annotations

import logging
import math
from typing import Any

import pybullet as p

__all__ = ["one_colour_per_link"]

logger = logging.getLogger(__name__)

_PLANS: dict[str, dict[int, list[float]]] = {}  # URDF path -> {link: colour to paint it}


def _area(client: int, body: int, link: int, geometry: int, dims: Any) -> float:
    """Surface area (m^2) of one visual primitive (a mesh: its link's bounding box)."""
    if geometry == p.GEOM_BOX:
        a, b, c = (float(v) for v in dims[:3])
        return 2.0 * (a * b + b * c + c * a)
    if geometry == p.GEOM_SPHERE:
        return 4.0 * math.pi * float(dims[0]) ** 2
    if geometry in (p.GEOM_CYLINDER, p.GEOM_CAPSULE):
        length, radius = float(dims[0]), float(dims[1])
        return 2.0 * math.pi * radius * (length + radius)
    lo, hi = p.getAABB(body, link, physicsClientId=client)
    a, b, c = (h - low for low, h in zip(lo, hi, strict=True))
    return 2.0 * (a * b + b * c + c * a)


def _plan(client: int, body: int) -> dict[int, list[float]]:
    """{link: its dominant colour} for the links whose visuals differ in colour."""
    by_link: dict[int, dict[tuple[float, ...], float]] = {}
    for visual in p.getVisualShapeData(body, physicsClientId=client):
        link, geometry, dims = visual[1], visual[2], visual[3]
        rgba = tuple(float(c) for c in visual[7])
        areas = by_link.setdefault(link, {})
        areas[rgba] = areas.get(rgba, 0.0) + _area(client, body, link, geometry, dims)
    plan: dict[int, list[float]] = {}
    for link, areas in by_link.items():
        if len(areas) > 1:
            dominant: tuple[float, ...] = max(areas, key=areas.__getitem__)
            plan[link] = list(dominant)
    return plan


def _link_name(client: int, body: int, link: int) -> str:
    if link < 0:
        return str(p.getBodyInfo(body, physicsClientId=client)[0].decode())
    return str(p.getJointInfo(body, link, physicsClientId=client)[12].decode())


def one_colour_per_link(client: int, body: int, urdf: str | None = None) -> None:
    """Paint each link of ``body`` whose visuals differ in colour its dominant colour.

    Args:
        client: PyBullet client.
        body: The body just loaded.
        urdf: The URDF file it came from: the plan is worked out once per file and the user is
            warned once. None (SDF scenery): worked out per body, logged at INFO level.
    """
    plan = _PLANS.get(urdf) if urdf is not None else None
    if plan is None:
        plan = _plan(client, body)
        if plan:
            names = ", ".join(repr(_link_name(client, body, link)) for link in sorted(plan))
            logger.log(
                logging.WARNING if urdf is not None else logging.INFO,
                "%s: link(s) %s have visuals of several colours; PyBullet's GUI draws a link in "
                "one colour, so fleet_async paints each its dominant colour (GUI and recordings "
                "alike). To keep the colours, put each coloured part in a link of its own (a "
                "fixed joint).",
                urdf if urdf is not None else f"body {body}",
                names,
            )
        if urdf is not None:
            _PLANS[urdf] = plan
    for link, rgba in plan.items():
        p.changeVisualShape(body, link, rgbaColor=rgba, physicsClientId=client)
