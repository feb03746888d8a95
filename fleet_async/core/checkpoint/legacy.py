"""Format-1 checkpoints (pickles), read only when the caller says the file is trusted.

A pickle runs code while it is read: any function its ``__reduce__`` names. Format 1 is read
only by ``restore_state(path, unsafe=True)`` (``fleet-async sweep --checkpoint F --unsafe``);
the default path refuses it before a byte is unpickled. New checkpoints are never pickles.
"""

from __future__ import annotations

import io
import pickle
from typing import TYPE_CHECKING, Any

from fleet_async.core.checkpoint.format import FORMAT, PICKLE_VERSION, CheckpointError

if TYPE_CHECKING:
    import os

    from fleet_async.core.sim.kernel import SimulationKernel

__all__ = ["read_pickle"]


class _StateUnpickler(pickle.Unpickler):
    """Reads format 1, resolving ``("sim",)`` and ``("object", id)`` against ``sim``."""

    def __init__(self, file: io.BytesIO, sim: SimulationKernel) -> None:
        super().__init__(file)
        self._sim = sim

    def persistent_load(self, pid: Any) -> Any:
        if pid == ("sim",):
            return self._sim
        obj = self._sim.get_object_by_id(pid[1])
        if obj is None:
            raise CheckpointError(f"restore_state: the checkpoint refers to object {pid[1]}")
        return obj


def read_pickle(
    sim: SimulationKernel, path: str | os.PathLike[str], data: bytes
) -> tuple[dict[str, Any], dict[str, Any]]:
    """The header and state of a trusted format-1 checkpoint (this RUNS the file's code).

    Raises:
        CheckpointError: for a file that is no format-1 checkpoint.
    """
    unpickler = _StateUnpickler(io.BytesIO(data), sim)
    try:
        header = unpickler.load()
        if not isinstance(header, dict) or header.get("format") != FORMAT:
            raise CheckpointError(f"restore_state: {path} is not a fleet_async checkpoint")
        if header.get("version") != PICKLE_VERSION:
            raise CheckpointError(f"restore_state: {path}: unknown pickled checkpoint format")
        state = unpickler.load()
    except CheckpointError:
        raise
    except Exception as exc:
        raise CheckpointError(
            f"restore_state: {path} is not a readable checkpoint ({exc})"
        ) from exc
    if not isinstance(state, dict):
        raise CheckpointError(f"restore_state: {path} is not a fleet_async checkpoint")
    return header, state
