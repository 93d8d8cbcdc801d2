"""The turning of benchmarks/orientation.py: maps turned by any angle keep their values and all their cells."""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import orientation  # noqa: E402


def _room_map():
    cells = np.full((40, 60), -1, np.int8)
    cells[5:35, 5:55] = 100
    cells[6:34, 6:54] = 0
    cells[6:34, 30] = 100  # a wall, with a door
    cells[18:22, 30] = 0
    return cells


def test_a_quarter_turn_multiple_is_the_grid_turned_exactly():
    cells = _room_map()
    assert np.array_equal(orientation.turn_by(cells, 0, -1), cells)
    assert np.array_equal(orientation.turn_by(cells, 90, -1), np.rot90(cells))


def test_other_angles_keep_the_values_and_grow_the_grid():
    cells = _room_map()
    for deg in (10, 30, 45):
        t = orientation.turn_by(cells, deg, -1)
        assert set(np.unique(t).tolist()) == {-1, 0, 100}  # no value made up between free and occupied
        a = np.radians(deg)
        assert t.shape[0] >= int(40 * np.cos(a) + 60 * np.sin(a))  # the whole map still on the grid
        assert abs(int((t == 0).sum()) - int((cells == 0).sum())) < 0.05 * (cells == 0).sum()  # about the same area


def test_labels_turn_with_the_map():
    cells = _room_map()
    labels = np.zeros(cells.shape, np.int32)
    labels[6:34, 6:30] = 1
    labels[6:34, 31:54] = 2
    tc, tl = orientation.turn_by(cells, 30, -1), orientation.turn_by(labels, 30, 0)
    assert tc.shape == tl.shape
    assert set(np.unique(tl).tolist()) == {0, 1, 2}
    assert (tc[tl > 0] == 0).mean() > 0.95  # the turned rooms lie on the turned free cells


def test_a_turned_map_marks_every_wall_cell():
    rng = np.random.default_rng(3)
    cells = np.where(rng.random((50, 70)) < 0.1, 100, 0).astype(np.int8)  # scattered laser hits
    for deg in (10, 20, 30, 45):
        t = orientation.turn_map(cells, deg)
        a = np.radians(deg)
        r, c = np.nonzero(cells == 100)
        dr, dc = r - 24.5, c - 34.5
        rr = np.rint(np.cos(a) * dr - np.sin(a) * dc + (t.shape[0] - 1) / 2).astype(int)
        cc = np.rint(np.sin(a) * dr + np.cos(a) * dc + (t.shape[1] - 1) / 2).astype(int)
        assert (t[rr, cc] == 100).all()  # each hit lands on an occupied cell of the turned map
        assert (t == 100).sum() >= (cells == 100).sum()  # none lost where two nearest cells coincide
