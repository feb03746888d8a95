"""The PyBullet adapter: connection, world setup, and lazy pose sync.

PyBullet is the geometry and physics backend, not the source of truth for kinematic bodies: the
state store is. Rows whose pose changed are flagged ``dirty`` and pushed here only when
something needs PyBullet's view (a narrow-phase query, a frame, the GUI, a physics step, or a
user asking for raw access). Dynamic bodies (physics on, mass > 0) are the other way round:
PyBullet owns them and their poses are read back after each physics step.
"""

from __future__ import annotations

import logging
import os
import sys
import tempfile
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING

import numpy as np
import pybullet as p
import pybullet_data

from fleet_async.core.world.shapes import clear_shape_cache, forget_body_shape
from fleet_async.core.world.state import KinematicState

if TYPE_CHECKING:
    from fleet_async.core.base.params import SimulationParams

__all__ = ["PyBulletBackend", "display_available", "native_output_logged"]

logger = logging.getLogger(__name__)

GRAVITY = (0.0, 0.0, -9.81)


def display_available() -> bool:
    """Return whether a GUI window can be opened here.

    On X11/Wayland systems that means ``DISPLAY`` or ``WAYLAND_DISPLAY`` is set; macOS and
    Windows always have a display server.
    """
    if sys.platform.startswith(("linux", "freebsd", "openbsd", "netbsd")):
        return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    return True


@contextmanager
def native_output_logged(log: logging.Logger) -> Iterator[None]:
    """Route what PyBullet's C++ code prints (b3Warning lines from its importers) to ``log`` at
    DEBUG instead of the terminal, for the duration of the block.

    Python's own output is flushed first and keeps its place; nothing is lost, only moved.
    """
    try:
        sys.stdout.flush()
        sys.stderr.flush()
        saved = (os.dup(1), os.dup(2))
    except (OSError, ValueError):  # no real stdout / stderr file descriptors: leave them be
        yield
        return
    with tempfile.TemporaryFile() as sink:
        try:
            os.dup2(sink.fileno(), 1)
            os.dup2(sink.fileno(), 2)
            yield
        finally:
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            os.close(saved[0])
            os.close(saved[1])
            sink.seek(0)
            text = sink.read().decode("utf-8", errors="replace").strip()
            if text:
                log.debug("PyBullet printed: %s", text)


class PyBulletBackend:
    """One PyBullet physics client and the operations the simulator needs from it."""

    def __init__(self, params: SimulationParams) -> None:
        self._params = params
        self._client = -1
        self._gui = False
        self._floor_body: int | None = None

    @property
    def client(self) -> int:
        """The PyBullet physics client id (``physicsClientId`` for raw calls)."""
        return self._client

    @property
    def is_gui(self) -> bool:
        """Whether this client drives a GUI window."""
        return self._gui

    @property
    def is_connected(self) -> bool:
        """Whether the client is connected."""
        return self._client >= 0 and p.isConnected(physicsClientId=self._client)

    @property
    def floor_body(self) -> int | None:
        """Body id of the floor plane, or None when ``enable_floor`` is off."""
        return self._floor_body

    def connect(self) -> int:
        """Connect (GUI if asked and possible, else DIRECT) and set the world up."""
        want_gui = self._params.gui
        if want_gui and not display_available():
            warnings.warn(
                "SimulationParams.gui=True but no display is available (DISPLAY is not set); "
                "running headless (pybullet.DIRECT) instead",
                RuntimeWarning,
                stacklevel=3,
            )
            want_gui = False
        if want_gui:
            options = f"--width={self._params.window_width} --height={self._params.window_height}"
            self._client = p.connect(p.GUI, options=options)
        else:
            self._client = p.connect(p.DIRECT)
        if self._client < 0:
            raise RuntimeError("pybullet.connect failed (is another GUI client already open?)")
        self._gui = want_gui
        # Client ids are reused after a disconnect: shape ids cached for an earlier world with
        # this id are meaningless here.
        clear_shape_cache(self._client)
        self.configure_world()
        return self._client

    def disconnect(self) -> None:
        """Disconnect the client; safe to call twice."""
        if self._client >= 0 and p.isConnected(physicsClientId=self._client):
            p.disconnect(physicsClientId=self._client)
        clear_shape_cache(self._client)
        self._client = -1
        self._floor_body = None

    def configure_world(self) -> None:
        """Apply gravity, timestep, search path and the floor to a fresh world."""
        cid = self._client
        p.setAdditionalSearchPath(pybullet_data.getDataPath(), physicsClientId=cid)
        p.setGravity(*GRAVITY, physicsClientId=cid)
        p.setTimeStep(self._params.timestep, physicsClientId=cid)
        if self._gui:
            p.configureDebugVisualizer(
                p.COV_ENABLE_GUI, int(self._params.enable_gui_panel), physicsClientId=cid
            )
        self._floor_body = None
        if self._params.enable_floor:
            self._floor_body = p.loadURDF("plane.urdf", useFixedBase=True, physicsClientId=cid)

    def reset_world(self) -> None:
        """Remove every body and set the world up again."""
        p.resetSimulation(physicsClientId=self._client)
        clear_shape_cache(self._client)
        self.configure_world()

    @contextmanager
    def rendering_disabled(self) -> Iterator[None]:
        """Suspend GUI rendering (no-op headless), restoring the previous state after."""
        if not self._gui:
            yield
            return
        p.configureDebugVisualizer(p.COV_ENABLE_RENDERING, 0, physicsClientId=self._client)
        try:
            yield
        finally:
            p.configureDebugVisualizer(p.COV_ENABLE_RENDERING, 1, physicsClientId=self._client)

    def set_rendering(self, enabled: bool) -> None:
        """Turn GUI rendering on or off (no-op headless)."""
        if self._gui:
            p.configureDebugVisualizer(
                p.COV_ENABLE_RENDERING, int(enabled), physicsClientId=self._client
            )

    def push_rows(self, store: KinematicState, rows: np.ndarray) -> None:
        """Write the given rows' poses into PyBullet and clear their ``dirty`` flag."""
        cid = self._client
        reset = p.resetBasePositionAndOrientation
        positions = store.position[rows].tolist()
        orientations = store.orientation[rows].tolist()
        for body, pos, orn in zip(
            store.body_id[rows].tolist(), positions, orientations, strict=True
        ):
            if body >= 0:
                reset(body, pos, orn, physicsClientId=cid)
        store.dirty[rows] = False

    def sync(self, store: KinematicState) -> int:
        """Push every dirty row to PyBullet; return how many were pushed."""
        rows = store.dirty_rows()
        if len(rows):
            self.push_rows(store, rows)
        return len(rows)

    def read_back(self, store: KinematicState, rows: np.ndarray) -> None:
        """Copy poses and velocities of PyBullet-owned (dynamic) bodies into the store."""
        cid = self._client
        for row in rows.tolist():
            body = int(store.body_id[row])
            pos, orn = p.getBasePositionAndOrientation(body, physicsClientId=cid)
            lin, ang = p.getBaseVelocity(body, physicsClientId=cid)
            if pos != tuple(store.position[row]) or orn != tuple(store.orientation[row]):
                store.moved[row] = True
                store.written[row] = True
            store.position[row] = pos
            store.orientation[row] = orn
            store.velocity[row] = lin
            store.angular_velocity[row] = ang

    def read_pose(self, body_id: int) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """PyBullet's current (position, orientation) of a body."""
        pos, orn = p.getBasePositionAndOrientation(body_id, physicsClientId=self._client)
        return pos, orn

    def step_physics(self) -> None:
        """Advance PyBullet's dynamics by one timestep."""
        p.stepSimulation(physicsClientId=self._client)

    def remove_body(self, body_id: int) -> None:
        """Remove a body from the PyBullet world."""
        if body_id >= 0:
            p.removeBody(body_id, physicsClientId=self._client)
            forget_body_shape(self._client, body_id)

    def body_mass(self, body_id: int, link: int = -1) -> float:
        """Mass of one link of a body as PyBullet holds it (kg; link -1 is the base)."""
        return float(p.getDynamicsInfo(body_id, link, physicsClientId=self._client)[0])

    def body_total_mass(self, body_id: int) -> float:
        """Mass of every link of a body summed (kg)."""
        links = range(-1, p.getNumJoints(body_id, physicsClientId=self._client))
        return float(sum(self.body_mass(body_id, link) for link in links))

    def set_body_mass(self, body_id: int, mass: float) -> None:
        """Change a body's base mass (0 makes it immovable by dynamics)."""
        p.changeDynamics(body_id, -1, mass=mass, physicsClientId=self._client)
