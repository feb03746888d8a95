"""A top-down renderer of its own: every body's footprint drawn from the state store with
numpy, for recordings many times faster than PyBullet's software renderer.

Each body is drawn as its top-down footprint (the trace's: the body-frame bounding box of its
visual shapes, or a circle, in its modelled colour; ``trace/footprints.py``), at the pose the
state store holds, lower tops first so a carried tote lies on its robot. Robots get a dark
heading bar. Nothing is skipped: a body without visual shapes is a small grey marker.

Framing (``camera_mode`` ``auto`` / ``top_down`` / ``fleet``): every body, and every place
the robots and the objects they carry have been so far (the view widens, never narrows, so it
does not jitter), with a margin. The view never shrinks the smallest robot below
``min_robot_px`` pixels across: a scene wider than that is shown around the robots' median
position, at that size.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fleet_async.core.view.trace.footprints import describe_body

__all__ = ["BACKGROUND", "RENDERERS", "TopDownRenderer", "topdown_for"]

BACKGROUND = (244, 246, 248)
_GRID = (226, 230, 234)
_MARKER_RGB = (128, 128, 128)
RENDERERS = ("pybullet", "topdown")
"""A recording's renderers: PyBullet's software renderer (any camera), or this one."""
TOPDOWN_CAMERA_MODES = ("auto", "top_down", "fleet")


def topdown_for(sim: Any, renderer: Any, camera_mode: Any, width: int, height: int) -> Any:
    """A recording's top-down renderer for ``renderer="topdown"``; None for ``"pybullet"``.

    Raises:
        ValueError: for an unknown renderer, or a camera mode the top-down view cannot take
            (it frames itself from above), naming the value.
    """
    if renderer not in RENDERERS:
        raise ValueError(f"recording renderer: expected one of {RENDERERS}, got {renderer!r}")
    if renderer == "pybullet":
        return None
    if camera_mode not in TOPDOWN_CAMERA_MODES:
        raise ValueError(
            f"recording renderer 'topdown': camera_mode {camera_mode!r} is not a view from "
            f"above ({', '.join(TOPDOWN_CAMERA_MODES)}); use renderer='pybullet' for it"
        )
    return TopDownRenderer(sim, width, height)


class TopDownRenderer:
    """Draws the simulation seen from straight above into RGB frames.

    Args:
        sim: The simulation (``sim_objects``, ``world``).
        width: Frame width in pixels.
        height: Frame height in pixels.
        min_robot_px: The smallest robot is at least this many pixels across.
        margin: Fraction of the framed extent added around it.
    """

    def __init__(
        self,
        sim: Any,
        width: int,
        height: int,
        min_robot_px: float = 10.0,
        margin: float = 0.08,
    ) -> None:
        self._sim = sim
        self._w, self._h = int(width), int(height)
        self._min_robot_px = float(min_robot_px)
        self._margin = float(margin)
        self._shapes: dict[int, dict[str, Any]] = {}
        self._cache: dict[tuple[Any, ...], dict[str, Any]] = {}
        self._bounds: np.ndarray | None = None  # [xmin, ymin, xmax, ymax] seen so far (m)
        self._robot_size = np.inf  # smallest robot footprint across (m)
        self._robots_at: tuple[float, float] | None = None  # the robots' median position (m)
        self._background: tuple[tuple[float, ...], np.ndarray] | None = None  # grid, statics
        ys, xs = np.mgrid[0 : self._h, 0 : self._w]
        self._px = xs.astype(np.float32) + 0.5
        self._py = ys.astype(np.float32) + 0.5

    # ----- bodies ------------------------------------------------------------------------------

    def _shape(self, obj: Any) -> dict[str, Any]:
        shape = self._shapes.get(obj.object_id)
        if shape is None:
            shape, _ = describe_body(obj, self._sim.world, self._cache)
            rgba = shape.get("rgba") or [0.5, 0.5, 0.5, 1.0]
            shape["rgb"] = np.array([round(255 * c) for c in rgba[:3]], dtype=np.uint8)
            shape["dark"] = (shape["rgb"] * 0.55).astype(np.uint8)
            shape["nose"] = (shape["rgb"] * 0.3).astype(np.uint8)
            self._shapes[obj.object_id] = shape
            if obj.is_agent and "half" in shape:
                self._robot_size = min(self._robot_size, 2.0 * min(shape["half"]))
            elif obj.is_agent and "radius" in shape:
                self._robot_size = min(self._robot_size, 2.0 * shape["radius"])
        return shape

    def _bodies(self) -> list[tuple[Any, dict[str, Any], float, float, float, float]]:
        """(object, shape, x, y, yaw, bottom z) of every body, in drawing order."""
        out = []
        for obj in self._sim.sim_objects:
            shape = self._shape(obj)
            pose = obj.get_pose()
            x, y, z = (float(v) for v in pose.position)
            qx, qy, qz, qw = (float(v) for v in pose.orientation)
            yaw = float(np.arctan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz)))
            bottom = z + float(shape.get("z", [0.0, 0.0])[0])
            out.append((obj, shape, x, y, yaw, bottom))
        # Scenery under everything, then higher bottoms over lower: a carried load lies on
        # its robot even when the robot has a tall mast.
        out.sort(key=lambda b: (not b[0].is_static, b[5]))
        return out

    # ----- framing -----------------------------------------------------------------------------

    def _grow(self, bodies: list[tuple[Any, dict[str, Any], float, float, float, float]]) -> None:
        """Widen the framed bounds by the robots and movable objects where they are now."""
        points = [(x, y, _reach(shape)) for _, shape, x, y, _, _ in bodies]
        if not points:
            return
        robots = [(x, y) for obj, _, x, y, _, _ in bodies if obj.is_agent]
        if robots:
            mx, my = np.median(np.asarray(robots), axis=0)
            self._robots_at = (float(mx), float(my))
        arr = np.asarray(points, dtype=np.float64)
        now = np.array(
            [
                (arr[:, 0] - arr[:, 2]).min(),
                (arr[:, 1] - arr[:, 2]).min(),
                (arr[:, 0] + arr[:, 2]).max(),
                (arr[:, 1] + arr[:, 2]).max(),
            ]
        )
        if self._bounds is None:
            self._bounds = now
        else:
            self._bounds = np.concatenate(
                [np.minimum(self._bounds[:2], now[:2]), np.maximum(self._bounds[2:], now[2:])]
            )

    def view(self) -> tuple[float, float, float]:
        """(centre x m, centre y m, pixels per metre) of the current framing."""
        if self._bounds is None:
            return 0.0, 0.0, 20.0
        x0, y0, x1, y1 = self._bounds
        span_x = max(x1 - x0, 1.0) * (1 + 2 * self._margin)
        span_y = max(y1 - y0, 1.0) * (1 + 2 * self._margin)
        scale = min(self._w / span_x, self._h / span_y)
        least = self._min_robot_px / self._robot_size if np.isfinite(self._robot_size) else 0.0
        if scale < least and self._robots_at is not None:  # too wide: the robots, at size
            return self._robots_at[0], self._robots_at[1], float(least)
        return (x0 + x1) / 2.0, (y0 + y1) / 2.0, float(scale)

    # ----- drawing -----------------------------------------------------------------------------

    def frame(self) -> np.ndarray:
        """The scene now, as an RGB uint8 array of shape (height, width, 3)."""
        bodies = self._bodies()
        self._grow(bodies)
        cx, cy, scale = self.view()
        statics = [b for b in bodies if b[0].is_static]
        image = self._scenery(cx, cy, scale, statics).copy()
        for obj, shape, x, y, yaw, _ in bodies:
            if not obj.is_static:
                self._place(image, obj, shape, x, y, yaw, cx, cy, scale)
        return image

    def _place(
        self,
        image: np.ndarray,
        obj: Any,
        shape: dict[str, Any],
        x: float,
        y: float,
        yaw: float,
        cx: float,
        cy: float,
        scale: float,
    ) -> None:
        """Draw ``obj`` at world (x, y, yaw) in the view centred on (cx, cy) m."""
        px = self._w / 2.0 + (x - cx) * scale
        py = self._h / 2.0 - (y - cy) * scale
        self._draw(image, shape, px, py, yaw, scale, heading=obj.is_agent)

    def _scenery(self, cx: float, cy: float, scale: float, statics: list[Any]) -> np.ndarray:
        """The background: a 1 m grid (10 m when 1 m is under 8 px) and the static bodies,
        which never move, drawn once per view."""
        key = (round(cx, 4), round(cy, 4), round(scale, 4), len(statics))
        if self._background is not None and self._background[0] == key:
            return self._background[1]
        image = np.empty((self._h, self._w, 3), dtype=np.uint8)
        image[:] = BACKGROUND
        step = 1.0 if scale >= 8 else 10.0
        for k in np.arange(
            np.floor((cx - self._w / 2 / scale) / step),
            np.ceil((cx + self._w / 2 / scale) / step) + 1,
        ):
            col = int(self._w / 2.0 + (k * step - cx) * scale)
            if 0 <= col < self._w:
                image[:, col] = _GRID
        for k in np.arange(
            np.floor((cy - self._h / 2 / scale) / step),
            np.ceil((cy + self._h / 2 / scale) / step) + 1,
        ):
            row = int(self._h / 2.0 - (k * step - cy) * scale)
            if 0 <= row < self._h:
                image[row, :] = _GRID
        for obj, shape, x, y, yaw, _ in statics:
            self._place(image, obj, shape, x, y, yaw, cx, cy, scale)
        self._background = (key, image)
        return image

    def _draw(
        self,
        image: np.ndarray,
        shape: dict[str, Any],
        px: float,
        py: float,
        yaw: float,
        scale: float,
        heading: bool,
    ) -> None:
        """Fill one footprint centred (after its offset) at pixel (px, py)."""
        c, s = np.cos(yaw), np.sin(yaw)
        ox, oy = shape.get("center", [0.0, 0.0])
        px += (c * ox - s * oy) * scale
        py -= (s * ox + c * oy) * scale
        round_shape = shape.get("type") == "circle"
        if round_shape:
            hx = hy = max(float(shape["radius"]) * scale, 1.5)
        elif "half" in shape:
            hx, hy = (max(float(h) * scale, 1.5) for h in shape["half"])
        else:  # a body without visual shapes: a small marker
            hx = hy = 2.0
        reach = hx if round_shape else float(np.hypot(hx, hy))
        x0, x1 = max(int(px - reach), 0), min(int(px + reach) + 1, self._w)
        y0, y1 = max(int(py - reach), 0), min(int(py + reach) + 1, self._h)
        if x0 >= x1 or y0 >= y1:
            return
        dx = self._px[y0:y1, x0:x1] - px
        dy = py - self._py[y0:y1, x0:x1]  # y up
        lx, ly = c * dx + s * dy, -s * dx + c * dy
        if round_shape:
            edge = hx - np.sqrt(lx * lx + ly * ly)
        else:
            edge = np.minimum(hx - np.abs(lx), hy - np.abs(ly))
        inside = edge >= 0
        region = image[y0:y1, x0:x1]
        rgb = shape.get("rgb", np.array(_MARKER_RGB, dtype=np.uint8))
        region[inside] = rgb
        if min(hx, hy) > 3:
            region[inside & (edge < 1.0)] = shape["dark"]
        if heading and hx >= 4:
            region[inside & (lx > 0) & (np.abs(ly) < max(1.0, 0.18 * hy))] = shape["nose"]


def _reach(shape: dict[str, Any]) -> float:
    """Half the footprint's diagonal (m), plus its offset from the body origin."""
    if "radius" in shape:
        r = float(shape["radius"])
    elif "half" in shape:
        r = float(np.hypot(*shape["half"]))
    else:
        r = 0.05
    return r + float(np.hypot(*shape.get("center", [0.0, 0.0])))
