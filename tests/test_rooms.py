"""cut_rooms' fill of the cells between pieces, cell for cell the general route.

``rooms._fill_pieces`` grows only the cells without a seed and renumbers with
one lookup table; it must give exactly what ``_rooms_first(fill_unlabeled(
seed[pieces], free), min_cells)`` gives (labels, dtype and room count),
including the cases where fill_unlabeled's watershed decides (a gap between
two labels wider than 8 steps), where one label floods a wide gap, and free
regions no seed reaches. Also: the lookup helper equals numpy indexing.
"""

import cv2
import numpy as np
import pytest
from scipy import ndimage as ndi

from topomap.core import rooms
from topomap._fast import lookup
from topomap.core.rooms import _fill_pieces, _rooms_first, _runs, fill_unlabeled


def _case(rng, shape, small_share):
    """A random free mask, its 4-connected pieces with a band of free cells cut out, and seeds
    (some pieces unseeded, as cut_rooms does with pieces smaller than a room)."""
    free = ndi.binary_opening(rng.random(shape) < 0.72, iterations=1)
    cut = np.zeros(shape, bool)
    for _ in range(rng.integers(1, 6)):  # wide bands: gaps of more than 8 cells between pieces
        if rng.random() < 0.5:
            r = rng.integers(0, shape[0])
            cut[r:r + rng.integers(1, 25), :] = True
        else:
            c = rng.integers(0, shape[1])
            cut[:, c:c + rng.integers(1, 25)] = True
    whole = free & ~cut
    n, pieces = cv2.connectedComponents(whole.view(np.uint8), connectivity=4, ltype=cv2.CV_16U)
    seed = rng.permutation(n).astype(np.int32)  # any numbering, 0 kept on the background
    seed[seed == 0] = seed[0]
    seed[0] = 0
    seed[1:][rng.random(n - 1) < small_share] = 0
    return free, pieces, seed, _runs(whole, pieces), free > whole


# the components by OpenCV, the neighbours by a table; by scipy, by a binary search
@pytest.mark.parametrize("box", [(rooms._BOX_CELLS, rooms._DENSE_CELLS), (0, 0)])
@pytest.mark.parametrize("small_share", [0.0, 0.3, 0.8])
@pytest.mark.parametrize("min_cells", [0, 1, 40])
def test_fill_pieces_is_the_general_route(small_share, min_cells, box, monkeypatch):
    monkeypatch.setattr(rooms, "_BOX_CELLS", box[0])
    monkeypatch.setattr(rooms, "_DENSE_CELLS", box[1])
    rng = np.random.default_rng(int(small_share * 10) * 100 + min_cells)
    kinds = set()
    for _ in range(12):
        shape = tuple(int(v) for v in rng.integers(40, 140, size=2))
        free, pieces, seed, runs, between = _case(rng, shape, small_share)
        want, want_rooms = _rooms_first(fill_unlabeled(seed[pieces], free), min_cells)
        got, got_rooms = _fill_pieces(pieces, seed, runs, free, between, min_cells)
        assert got.dtype == want.dtype
        np.testing.assert_array_equal(got, want)
        assert got_rooms == want_rooms
        kinds.add(bool((want == 0)[free].any()))
    assert kinds == {False}  # every free cell labelled, as fill_unlabeled guarantees


def test_fill_pieces_wide_gap_between_two_labels():
    # two rooms with a 30-cell band of unseeded free cells between them: the watershed decides
    free = np.ones((30, 90), bool)
    pieces = np.zeros(free.shape, np.uint16)
    pieces[:, :30] = 1
    pieces[:, 60:] = 2
    whole = (pieces == 1) | (pieces == 2)
    n, pieces = cv2.connectedComponents(whole.view(np.uint8), connectivity=4, ltype=cv2.CV_16U)
    seed = np.arange(n, dtype=np.int32)
    between = free & (pieces == 0)
    want, want_rooms = _rooms_first(fill_unlabeled(seed[pieces], free), 0)
    got, got_rooms = _fill_pieces(pieces, seed, _runs(whole, pieces), free, between, 0)
    np.testing.assert_array_equal(got, want)
    assert got_rooms == want_rooms == 2
    assert set(np.unique(got[:, 30:60])) == {1, 2}


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.int32, np.int64])
def test_lookup_is_indexing(dtype):
    rng = np.random.default_rng(3)
    labels = rng.integers(0, 256 if dtype == np.uint8 else 300, size=(120, 130)).astype(dtype)
    for table in (rng.permutation(300).astype(np.int32), rng.random(300).astype(np.float32),
                  rng.integers(0, 255, 300).astype(np.uint8)):
        got = lookup(table, labels)
        assert got.dtype == table.dtype
        np.testing.assert_array_equal(got, table[labels])


@pytest.mark.parametrize("short", [0, 2])
def test_a_cut_reaches_the_walls_it_was_rounded_short_of(short):
    # two 2 m x 2 m rooms joined by a 1 m doorway in a 0.2 m wall (cols 40..43);
    # the door segment across the doorway ends `short` cells before its lower
    # post (2: on the free cell above the doorway's last row, which a cut
    # rounded onto the cell beside a wall leaves): still two rooms, no
    # 4-connected way round its end
    from topomap.io import from_array
    from topomap.core.rooms import cut_rooms

    free = np.zeros((44, 84), bool)
    free[2:42, 2:40] = True
    free[2:42, 44:82] = True
    free[12:32, 40:44] = True                       # doorway rows 12..31
    grid = from_array(free, resolution=0.05)
    seg = ((11.0, 41.5), (32.0 - short, 41.5))      # posts at rows 11 and 32 (wall cells)
    labels, doors, n = cut_rooms(grid, [seg])
    assert n == 2 and len(doors) == 1
    assert (labels > 0)[free].all()


@pytest.mark.parametrize("edge", [False, True])
def test_runs(edge, monkeypatch):
    # row runs of the pieces against the pieces' cells; in bands of rows as on a large map
    # (with `edge`: free cells along every side, so runs start and end on the map's edges)
    rng = np.random.default_rng(7 + edge)
    for _ in range(20):
        shape = tuple(int(v) for v in rng.integers(1, 60, size=2))
        whole = rng.random(shape) < 0.6
        if edge:
            whole[[0, -1], :] = whole[:, [0, -1]] = True
        n, pieces = cv2.connectedComponents(whole.view(np.uint8), connectivity=4, ltype=cv2.CV_16U)
        start, end, piece = runs = _runs(whole, pieces)
        cells = np.concatenate([np.arange(s, e) for s, e in zip(start, end)]) if start.size else np.zeros(0, int)
        np.testing.assert_array_equal(cells, np.flatnonzero(whole))
        assert (pieces.ravel()[cells] == np.repeat(piece, end - start)).all()
        for band in (1, 5, 64):  # a band of rows at a time: the same runs
            monkeypatch.setattr(rooms, "_RUN_BAND", band)
            for a, b in zip(runs, _runs(whole, pieces)):
                np.testing.assert_array_equal(a, b)
            monkeypatch.undo()
