"""The shapes of safety fields, for a whole fleet at once (numpy, no loop over robots).

A robot's fields are rectangles in its *travel frame*: axis ``u`` along its direction of
travel, axis ``w`` to its left. The footprint (a ``length`` x ``width`` rectangle turned by the
robot's heading) reaches ``ext_u`` ahead of the robot's centre along ``u`` and ``ext_w`` to each
side; a field of depth ``d`` covers ``ext_u <= s <= ext_u + d`` along ``u`` and
``|t| <= ext_w + side_margin`` across. Obstacles are axis-aligned boxes (AABBs); a field and a
box overlap when no separating axis among x, y, u and w separates them.
"""

from __future__ import annotations

import numpy as np

__all__ = ["FieldShapes", "heading_of", "rect_hits_box"]


def heading_of(quats: np.ndarray) -> np.ndarray:
    """(N, 2) unit x axes (in the ground plane) of (N, 4) quaternions (x, y, z, w)."""
    x, y, z, w = quats[:, 0], quats[:, 1], quats[:, 2], quats[:, 3]
    hx = 1.0 - 2.0 * (y * y + z * z)
    hy = 2.0 * (w * z + x * y)
    norm = np.hypot(hx, hy)
    norm[norm < 1e-12] = 1.0
    return np.stack((hx / norm, hy / norm), axis=1)


class FieldShapes:
    """The fields of M robots in one step: travel frames, footprint extents, depths.

    Args:
        centre: (M, 2) robot centres (m, world frame).
        heading: (M, 2) unit headings.
        travel: (M, 2) unit directions of travel.
        half_length: (M,) footprint half lengths along the robot's x (m).
        half_width: (M,) footprint half widths (m).
        side: (M,) side margins (m).
    """

    def __init__(
        self,
        centre: np.ndarray,
        heading: np.ndarray,
        travel: np.ndarray,
        half_length: np.ndarray,
        half_width: np.ndarray,
        side: np.ndarray,
    ) -> None:
        self.centre = centre
        self.u = travel
        self.w = np.stack((-travel[:, 1], travel[:, 0]), axis=1)
        cos = np.abs(np.einsum("ij,ij->i", travel, heading))
        sin = np.abs(travel[:, 0] * heading[:, 1] - travel[:, 1] * heading[:, 0])
        self.ext_u = half_length * cos + half_width * sin
        self.half_w = half_length * sin + half_width * cos + side

    def rect(
        self, depth: np.ndarray, which: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """(centres (K, 2), half depths (K,)) of the fields of ``depth`` (M,) metres, of the
        robots ``which`` (indices, repeats allowed; default all M)."""
        if which is None:
            half = 0.5 * depth
            return self.centre + self.u * (self.ext_u + half)[:, None], half
        half = 0.5 * depth[which]
        return self.centre[which] + self.u[which] * (self.ext_u[which] + half)[:, None], half

    def bounds(self, depth: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(min (M, 2), max (M, 2)) world-frame bounds of the fields of ``depth`` metres."""
        centre, half = self.rect(depth)
        au, aw = np.abs(self.u), np.abs(self.w)
        reach = au * half[:, None] + aw * self.half_w[:, None]
        return centre - reach, centre + reach

    def corners(self, index: int, depth: float) -> list[tuple[float, float]]:
        """The four world-frame corners (m) of robot ``index``'s field of ``depth`` metres,
        counter-clockwise from the footprint's front right."""
        u, w = self.u[index], self.w[index]
        base = self.centre[index] + u * self.ext_u[index]
        hw = self.half_w[index]
        pts = (base - w * hw, base + u * depth - w * hw, base + u * depth + w * hw, base + w * hw)
        return [(float(p[0]), float(p[1])) for p in pts]


def rect_hits_box(
    centre: np.ndarray,
    u: np.ndarray,
    w: np.ndarray,
    half_u: np.ndarray,
    half_w: np.ndarray,
    box_lo: np.ndarray,
    box_hi: np.ndarray,
) -> np.ndarray:
    """Row-wise overlap (touching counts) of K oriented rectangles and K boxes (2D, SAT).

    Args:
        centre: (K, 2) rectangle centres.
        u, w: (K, 2) the rectangles' unit axes.
        half_u, half_w: (K,) half extents along ``u`` and ``w``.
        box_lo, box_hi: (K, 2) the boxes' corners.
    """
    hx, hy = 0.5 * (box_hi[:, 0] - box_lo[:, 0]), 0.5 * (box_hi[:, 1] - box_lo[:, 1])
    dx = centre[:, 0] - 0.5 * (box_hi[:, 0] + box_lo[:, 0])
    dy = centre[:, 1] - 0.5 * (box_hi[:, 1] + box_lo[:, 1])
    ux, uy, wx, wy = u[:, 0], u[:, 1], w[:, 0], w[:, 1]
    aux, auy, awx, awy = np.abs(ux), np.abs(uy), np.abs(wx), np.abs(wy)
    ok = np.abs(dx) <= aux * half_u + awx * half_w + hx
    ok &= np.abs(dy) <= auy * half_u + awy * half_w + hy
    ok &= np.abs(dx * ux + dy * uy) <= half_u + hx * aux + hy * auy
    ok &= np.abs(dx * wx + dy * wy) <= half_w + hx * awx + hy * awy
    return ok
