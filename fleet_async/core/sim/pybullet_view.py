"""PyBullet's view of a simulation: the client, lazy pose sync, ray tests, rendering.

The state store is the truth for kinematic bodies; PyBullet sees their poses when something
needs it (``world/backend.py``). These methods are the safe path for code that talks to PyBullet
itself: :meth:`PyBulletViewApi.sync_pybullet` pushes what PyBullet has not seen, the ray tests
sync first, and ``SimulationParams.sync_pybullet_every_step`` keeps PyBullet current after every
step for scripts that call ``pybullet`` directly.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

import numpy as np
import pybullet as p

if TYPE_CHECKING:
    from fleet_async.core.world.backend import PyBulletBackend
    from fleet_async.core.world.world import World

__all__ = ["PyBulletViewApi"]


class PyBulletViewApi:
    """The PyBullet client of a simulation (mixed into the simulation kernel)."""

    # Provided by the simulation kernel.
    _world: World
    _backend: PyBulletBackend

    @property
    def client(self) -> int:
        """PyBullet physics client id, for raw ``pybullet`` calls (``physicsClientId=``).

        Bodies of objects spawned with a pending body (``world/pending.py``) are created
        first, so raw calls see every object."""
        if self._world.has_pending_bodies:
            self._world.create_pending_bodies()
        return self._backend.client

    @property
    def is_gui(self) -> bool:
        """Whether a GUI window is open (False after a headless fallback)."""
        return self._backend.is_gui

    def sync_pybullet(self) -> int:
        """Push every pose PyBullet has not seen yet; return how many bodies were pushed.

        Call it before raw ``pybullet`` queries made inside a step (a callback, an event
        handler, a controller): poses written there reach PyBullet lazily. Between steps
        PyBullet is already current. Pending bodies are created first.
        """
        self._world.create_pending_bodies()
        return self._backend.sync(self._world.store)

    def ray_test(self, ray_from: Sequence[float], ray_to: Sequence[float]) -> list[tuple[Any, ...]]:
        """``pybullet.rayTest`` on this simulation's client, after :meth:`sync_pybullet`.

        Returns:
            PyBullet's hits: ``(body_id, link_index, hit_fraction, hit_position,
            hit_normal)`` per ray (``body_id`` -1 when nothing was hit).
        """
        self.sync_pybullet()
        return list(p.rayTest(list(ray_from), list(ray_to), physicsClientId=self.client))

    def ray_test_batch(
        self,
        rays_from: Sequence[Sequence[float]] | np.ndarray,
        rays_to: Sequence[Sequence[float]] | np.ndarray,
        **kwargs: Any,
    ) -> list[tuple[Any, ...]]:
        """``pybullet.rayTestBatch`` on this simulation's client, after :meth:`sync_pybullet`.

        Extra keyword arguments (``numThreads``, ``collisionFilterMask``, ...) go to PyBullet.

        Raises:
            ValueError: if the two lists differ in length.
        """
        froms = np.asarray(rays_from, dtype=float).reshape(-1, 3)
        tos = np.asarray(rays_to, dtype=float).reshape(-1, 3)
        if len(froms) != len(tos):
            raise ValueError(
                f"ray_test_batch: {len(froms)} rays_from but {len(tos)} rays_to; give one each"
            )
        self.sync_pybullet()
        return list(
            p.rayTestBatch(froms.tolist(), tos.tolist(), physicsClientId=self.client, **kwargs)
        )

    def _push_dirty(self, rows: np.ndarray) -> None:
        store = self._world.store
        dirty = rows[store.dirty[rows]]
        if len(dirty):
            self._backend.push_rows(store, dirty)

    def disable_rendering(self) -> None:
        """Stop GUI rendering (for fast spawning)."""
        self._backend.set_rendering(False)

    def enable_rendering(self) -> None:
        """Resume GUI rendering."""
        self._backend.set_rendering(True)

    @contextmanager
    def batch_spawn(self) -> Iterator[None]:
        """Spawn many objects with rendering suspended; rendering is restored afterwards."""
        with self._backend.rendering_disabled():
            yield
