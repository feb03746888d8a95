"""The active collision pairs, kept as arrays and updated by set operations on sorted codes.

A pair of object ids ``a < b`` is coded as ``a * 2**32 + b``; the active set is the sorted array
of those codes plus the two rows of each pair. A check hands in the pairs found touching among
its candidates; a pair ends when it was re-examined (one side moved, or left the simulation)
and was not found touching, and starts when it was found touching and was not active. Pairs
where neither side moved keep their state. No Python loop runs over pairs.
"""

from __future__ import annotations

import numpy as np

from fleet_async.core.world.state import KinematicState

__all__ = ["ActivePairs", "decode", "id_pairs", "pair_codes"]

_SHIFT = np.int64(32)
_LOW = np.int64((1 << 32) - 1)


def pair_codes(ids: np.ndarray) -> np.ndarray:
    """(K,) codes of (K, 2) object-id pairs (either order)."""
    a = np.minimum(ids[:, 0], ids[:, 1])
    b = np.maximum(ids[:, 0], ids[:, 1])
    return (a << _SHIFT) | b


def decode(codes: np.ndarray) -> list[tuple[int, int]]:
    """``[(a, b), ...]`` object-id pairs of codes, in their order."""
    return list(zip((codes >> _SHIFT).tolist(), (codes & _LOW).tolist(), strict=True))


def id_pairs(codes: np.ndarray) -> np.ndarray:
    """(K, 2) int64 object-id pairs ``(a, b)`` of codes, in their order."""
    out = np.empty((len(codes), 2), dtype=np.int64)
    np.right_shift(codes, _SHIFT, out=out[:, 0])
    np.bitwise_and(codes, _LOW, out=out[:, 1])
    return out


class ActivePairs:
    """Pairs in contact as of the last check."""

    def __init__(self) -> None:
        self.codes = np.empty(0, dtype=np.int64)
        self.rows = np.empty((0, 2), dtype=np.int64)

    def __len__(self) -> int:
        return len(self.codes)

    def clear(self) -> None:
        """Forget every pair."""
        self.codes = np.empty(0, dtype=np.int64)
        self.rows = np.empty((0, 2), dtype=np.int64)

    def get_state(self) -> dict[str, list[int] | list[list[int]]]:
        """The codes and rows (checkpoints)."""
        return {"codes": self.codes.tolist(), "rows": self.rows.tolist()}

    def set_state(self, state: dict[str, list[int] | list[list[int]]]) -> None:
        """Restore :meth:`get_state`."""
        self.codes = np.asarray(state["codes"], dtype=np.int64)
        self.rows = np.asarray(state["rows"], dtype=np.int64).reshape(-1, 2)

    def as_list(self) -> list[tuple[int, int]]:
        """Active pairs (object ids, a < b), sorted."""
        return decode(self.codes)

    def contains(self, codes: np.ndarray) -> np.ndarray:
        """(K,) bool: which of ``codes`` are active."""
        return _member(codes, self.codes)

    def update(
        self, touching_rows: np.ndarray, store: KinematicState
    ) -> tuple[np.ndarray, np.ndarray]:
        """Apply one check's result; return the (ended, started) codes, each ascending.

        Args:
            touching_rows: (K, 2) rows of the candidate pairs found touching (unique pairs).
            store: The state store (``moved`` flags and object ids of this check).
        """
        now_rows = touching_rows
        if len(now_rows):
            now_codes = pair_codes(store.object_id[now_rows])
            order = now_codes.argsort()
            now_codes, now_rows = now_codes[order], now_rows.take(order, axis=0)
        else:
            now_codes = np.empty(0, dtype=np.int64)
        ended = np.empty(0, dtype=np.int64)
        keep = None
        if len(self.codes):
            ra, rb = self.rows[:, 0], self.rows[:, 1]
            ids = store.object_id
            recheck = (
                store.moved[ra]
                | store.moved[rb]
                | (ids[ra] != self.codes >> _SHIFT)
                | (ids[rb] != (self.codes & _LOW))
            )
            if np.count_nonzero(recheck):
                gone = recheck & ~_member(self.codes, now_codes)
                if np.count_nonzero(gone):
                    ended = self.codes[gone]
                    keep = ~gone
        fresh = ~_member(now_codes, self.codes) if len(now_codes) else None
        if fresh is None or not np.count_nonzero(fresh):
            if keep is not None:
                self.codes, self.rows = self.codes[keep], self.rows.compress(keep, axis=0)
            return ended, np.empty(0, dtype=np.int64)
        started = now_codes[fresh]
        codes, rows = self.codes, self.rows
        if keep is not None:
            codes, rows = codes[keep], rows.compress(keep, axis=0)
        codes = np.concatenate((codes, started))
        rows = np.concatenate((rows, now_rows.compress(fresh, axis=0)))
        order = codes.argsort()
        self.codes, self.rows = codes[order], rows.take(order, axis=0)
        return ended, started


def _member(values: np.ndarray, sorted_set: np.ndarray) -> np.ndarray:
    """(len(values),) bool: which values are in the ascending array ``sorted_set``."""
    if not len(sorted_set) or not len(values):
        return np.zeros(len(values), dtype=bool)
    at = sorted_set.searchsorted(values)
    at[at == len(sorted_set)] = 0
    return sorted_set[at] == values
