from __future__ import annotations

import numpy as np
import pytest

from fleet_async.core.world.state import KinematicState


def test_allocate_fills_row_and_flags():
    store = KinematicState(capacity=2)
    row = store.allocate(7, 3, [1, 2, 3], [0, 0, 0, 1], kinematic=False, collision_code=2)
    assert row == 0
    assert store.position[row].tolist() == [1, 2, 3]
    assert store.object_id[row] == 7 and store.body_id[row] == 3
    assert not store.kinematic[row] and store.collision_mode[row] == 2
    assert store.active[row] and store.moved[row] and not store.dirty[row]
    assert store.count == 1


def test_growth_keeps_rows_and_identity_orientations():
    store = KinematicState(capacity=1)
    rows = [store.allocate(i, i, [i, 0, 0], [0, 0, 0, 1]) for i in range(5)]
    assert rows == [0, 1, 2, 3, 4]
    assert store.capacity >= 5
    assert store.position[:5, 0].tolist() == [0, 1, 2, 3, 4]
    assert (store.orientation[5:, 3] == 1.0).all()
    assert (store.body_id[5:] == -1).all()


def test_released_rows_are_reused_smallest_first():
    store = KinematicState()
    for i in range(4):
        store.allocate(i, i, [0, 0, 0], [0, 0, 0, 1])
    store.release(2)
    store.release(0)
    assert store.count == 2
    assert store.live_rows().tolist() == [1, 3]
    assert store.allocate(10, 10, [0, 0, 0], [0, 0, 0, 1]) == 0
    assert store.allocate(11, 11, [0, 0, 0], [0, 0, 0, 1]) == 2
    assert store.allocate(12, 12, [0, 0, 0], [0, 0, 0, 1]) == 4


def test_release_twice_is_an_error():
    store = KinematicState()
    row = store.allocate(0, 0, [0, 0, 0], [0, 0, 0, 1])
    store.release(row)
    with pytest.raises(ValueError, match="row 0 is not in use"):
        store.release(row)


def test_allocate_many_and_dirty_rows():
    store = KinematicState()
    rows = store.allocate_many(
        np.arange(3), np.arange(3), np.zeros((3, 3)), np.tile([0, 0, 0, 1.0], (3, 1))
    )
    assert rows.tolist() == [0, 1, 2]
    store.moved[:] = False
    store.mark_moved(np.array([2, 0]))
    assert store.dirty_rows().tolist() == [0, 2]
    assert store.moved[:3].tolist() == [True, False, True]
    store.clear()
    assert store.count == 0 and store.live_rows().size == 0
    assert store.nbytes() > 0


def test_fresh_rows_hold_defaults_after_growth_and_clear():
    store = KinematicState(2)
    for i in range(5):  # grows twice
        row = store.allocate(i, -1, [i, 0, 0], [0, 0, 0, 1], kinematic=i != 1, collision_code=i % 3)
        store.velocity[row] = 1.0
    assert store.kinematic[:5].tolist() == [True, False, True, True, True]
    assert store.collision_mode[:5].tolist() == [0, 1, 2, 0, 1]
    store.clear()
    row = store.allocate(9, -1, [0, 0, 0], [0, 0, 0, 1])
    assert row == 0 and store.kinematic[0] and store.collision_mode[0] == 0
    assert not store.velocity[:5].any() and store.kinematic[:5].all()
