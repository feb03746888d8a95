"""One colour per link, so PyBullet's GUI and the recordings show a body alike.

PyBullet's GUI (OpenGL) draws each link in one colour, the colour of the link's last visual;
its tiny renderer, which recordings use, draws every visual in its own colour. A URDF link with
visuals of several colours (a blue chassis with a grey caster) is therefore grey in the GUI and
blue in a GIF. When a URDF is loaded, each such link is painted the colour of its largest
visual, in both renderers, with one warning per file that says how to keep the colours apart
(each coloured part in a link of its own, on a fixed joint).
"""

from __future__ import annotations

import logging
import math
from typing import Any

import pybullet as p

__all__ = ["one_colour_per_link"]

logger = logging.getLogger(__name__)

_PLANS: dict[str, dict[int, list[float]]] = {}  # URDF path -> {link: colour to paint it}


def _volume(geometry: int, dims: Any) -> float:
    """Rough volume (m^3) of one visual primitive, to find a link's largest."""
    if geometry == p.GEOM_BOX:
        return float(dims[0] * dims[1] * dims[2])
    if geometry == p.GEOM_SPHERE:
        return 4.0 / 3.0 * math.pi * float(dims[0]) ** 3
    if geometry in (p.GEOM_CYLINDER, p.GEOM_CAPSULE):
        return math.pi * float(dims[1]) ** 2 * float(dims[0])
    return float(abs(dims[0] * dims[1] * dims[2])) if len(dims) >= 3 else 0.0  # mesh scale


def _plan(client: int, body: int) -> tuple[dict[int, list[float]], list[int]]:
    """{link: colour of its largest visual} for links with visuals of several colours."""
    by_link: dict[int, list[tuple[float, list[float]]]] = {}
    for visual in p.getVisualShapeData(body, physicsClientId=client):
        link, geometry, dims, rgba = visual[1], visual[2], visual[3], list(visual[7])
        by_link.setdefault(link, []).append((_volume(geometry, dims), rgba))
    plan = {}
    for link, parts in by_link.items():
        if len({tuple(rgba) for _, rgba in parts}) > 1:
            plan[link] = max(parts, key=lambda part: part[0])[1]
    return plan, sorted(plan)


def _link_name(client: int, body: int, link: int) -> str:
    if link < 0:
        return p.getBodyInfo(body, physicsClientId=client)[0].decode()
    return p.getJointInfo(body, link, physicsClientId=client)[12].decode()


def one_colour_per_link(client: int, body: int, source: str) -> None:
    """Paint each link of ``body`` (loaded from ``source``) whose visuals differ in colour.

    Args:
        client: PyBullet client.
        body: The body just loaded.
        source: The URDF file (the plan is worked out once per file).
    """
    plan = _PLANS.get(source)
    if plan is None:
        plan, links = _plan(client, body)
        _PLANS[source] = plan
        if links:
            names = ", ".join(repr(_link_name(client, body, link)) for link in links)
            logger.warning(
                "%s: link(s) %s have visuals of several colours; PyBullet's GUI draws a link in "
                "one colour, so fleet_async paints each the colour of its largest visual (GUI and "
                "recordings alike). To keep the colours, put each coloured part in a link of its "
                "own (a fixed joint).",
                source,
                names,
            )
    for link, rgba in plan.items():
        p.changeVisualShape(body, link, rgbaColor=rgba, physicsClientId=client)
