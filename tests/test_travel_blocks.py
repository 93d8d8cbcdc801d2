"""The coarse travel grid: its pieces, merged open floor and in-sight tests.

``planning._block_components`` labels sparse windows block by block in a
strip and dense ones all at once; both must give each block's pieces with
their centroids (the mean of their cells, as OpenCV computes it on the image
of blocks one empty cell apart: sum / area there, moved back).
``_merged_nodes`` merges 2 x 2 groups of fully free blocks inside open floor,
``_in_sight`` tests digital straight lines (all pairs at once for many
points).
"""

import numpy as np
import pytest
from scipy import ndimage as ndi

from topomap.planning import paths as P
from topomap.planning.paths import _block_components, block_any


def _reference(mask, f):
    """{frozenset of (row, col) cells: centroid} of every piece."""
    out = {}
    h, w = mask.shape
    for r0 in range(0, h, f):
        for c0 in range(0, w, f):
            lab, n = ndi.label(mask[r0:r0 + f, c0:c0 + f], structure=np.ones((3, 3)))
            for i in range(1, n + 1):
                rr, cc = np.nonzero(lab == i)
                R, C = r0 // f, c0 // f
                # the spaced image's coordinates, their mean, one gap cell per block taken out
                cen = np.array([(R * (f + 1) + rr).sum() / rr.size, (C * (f + 1) + cc).sum() / cc.size])
                out[frozenset(zip((rr + r0).tolist(), (cc + c0).tolist()))] = cen - np.floor(cen / (f + 1))
    return out


@pytest.mark.parametrize("density", [0.03, 0.3, 0.9])
@pytest.mark.parametrize("f", [1, 3, 4])
def test_block_components(density, f):
    rng = np.random.default_rng(int(density * 100) + f)
    for _ in range(5):
        h, w = (int(v) for v in rng.integers(5, 60, 2))
        mask = rng.random((h, w)) < density
        lab, n, cen = _block_components(mask, f)
        got = {}
        for i in range(1, n + 1):
            rr, cc = np.nonzero(lab == i)
            got[frozenset(zip(rr.tolist(), cc.tolist()))] = cen[i]
        want = _reference(mask, f)
        assert got.keys() == want.keys()
        for k in want:
            np.testing.assert_array_equal(got[k], want[k])


@pytest.mark.parametrize("f", [1, 2, 3, 4, 5, 8])
def test_block_any(f):
    rng = np.random.default_rng(f)
    m = rng.random((7 * f, 11 * f)) < 0.02
    np.testing.assert_array_equal(block_any(m, f), m.reshape(7, f, 11, f).any(axis=(1, 3)))


def test_merged_nodes_only_inside_open_floor():
    """A 24 x 24-cell room (6 x 6 blocks of 4) with a wall stub along its left edge: a 2 x 2 group of
    blocks (on even block rows and columns) is merged only where the group and its ring of blocks
    are wholly free, here only the group of blocks (2..3, 2..3)."""
    f = 4
    mask = np.ones((24, 24), bool)
    mask[0:9, 0] = False  # blocks (0, 0), (1, 0), (2, 0) are not wholly free
    lab, n, cen = _block_components(mask, f)
    assert n == 36
    node, mcen = P._merged_nodes(mask, lab, n, cen, f)
    assert node.shape == (n + 1,) and node[0] == 0 and len(mcen) == n + 1 - 3
    piece = lab[f - 1::f, f - 1::f]  # each block's piece (its last cell is free in every block)
    groups = {}
    for R in range(6):
        for C in range(6):
            groups.setdefault(int(node[piece[R, C]]), []).append((R, C))
    merged = [sorted(v) for v in groups.values() if len(v) > 1]
    assert merged == [[(2, 2), (2, 3), (3, 2), (3, 3)]]
    # the merged node at the mean of its 8 x 8 cells; the other nodes at their pieces' centroids
    np.testing.assert_allclose(mcen[node[piece[2, 2]]], [11.5, 11.5])
    for R, C in [(0, 0), (1, 1), (4, 4), (5, 5)]:
        np.testing.assert_array_equal(mcen[node[piece[R, C]]], cen[piece[R, C]])


def test_merged_nodes_nothing_to_merge():
    mask = np.zeros((16, 16), bool)
    mask[::2] = True  # no block wholly free
    lab, n, cen = _block_components(mask, 4)
    node, mcen = P._merged_nodes(mask, lab, n, cen, 4)
    np.testing.assert_array_equal(node, np.arange(n + 1))
    np.testing.assert_array_equal(mcen, cen)


def _line(p, q):
    """The digital straight line _in_sight tests for many points: step t at p + round(t (q - p) / n)."""
    n = int(np.abs(np.subtract(q, p)).max())
    t = np.arange(n + 1) / max(n, 1)
    return (p[0] + np.floor(t * (q[0] - p[0]) + 0.5).astype(int), p[1] + np.floor(t * (q[1] - p[1]) + 0.5).astype(int))


@pytest.mark.parametrize("seed", range(4))
def test_in_sight_many_points_against_each_line(seed, monkeypatch):
    rng = np.random.default_rng(seed)
    mask = rng.random((40, 50)) < 0.93
    cells = np.argwhere(mask)
    pts = cells[rng.choice(len(cells), 9, replace=False)].astype(float)
    if seed == 3:
        monkeypatch.setattr(P, "_SIGHT_BATCH", 7)  # the whole lines in many batches
    got = P._in_sight(mask, pts)
    assert got.shape == (9, 9) and (got == got.T).all()
    for i in range(9):
        for j in range(i + 1, 9):
            rr, cc = _line(pts[i].astype(int), pts[j].astype(int))
            assert got[i, j] == bool(mask[rr, cc].all())
            # a line of n steps moves one cell along the longer axis each step: a shortest 8-connected path
            assert (np.abs(np.diff(rr)) <= 1).all() and (np.abs(np.diff(cc)) <= 1).all()
            assert len(rr) == int(np.abs(pts[j] - pts[i]).max()) + 1


def test_in_sight_octile_is_the_grid_geodesic():
    rng = np.random.default_rng(7)
    mask = np.ones((30, 30), bool)
    mask[10:20, 14] = False
    pts = np.argwhere(mask)[rng.choice(int(mask.sum()), 8, replace=False)].astype(float)
    seen = P._in_sight(mask, pts)
    assert seen.any() and not seen.all()
    for i, j in zip(*np.nonzero(np.triu(seen, 1))):
        cum = P._mcp_costs(mask, [tuple(pts[i].astype(int))], [tuple(pts[j].astype(int))])
        d = np.abs(pts[i] - pts[j])
        assert cum[tuple(pts[j].astype(int))] == pytest.approx(d.max() + (np.sqrt(2) - 1) * d.min())


def test_coarse_distances_of_many_doors_close_to_the_grid_geodesic(monkeypatch):
    """An L-shaped corridor (2 m wide at 0.05 m/px) with doors along its walls: the coarse distances
    (merged open floor, searched both ways) within the stated tolerance of the exact geodesic, and
    close to those of the 0.2 m blocks alone."""
    mask = np.zeros((200, 200), bool)
    mask[10:50, 10:190] = True   # the long leg
    mask[10:190, 150:190] = True  # the short leg
    mask[10:50, 100] = False      # a pillar row across part of the corridor
    mask[25:35, 100] = True
    doors = [(10, 20), (49, 40), (10, 70), (49, 90), (10, 120), (49, 140), (100, 150), (150, 189), (189, 170)]
    pts = np.array(doors, float)
    k = len(pts)
    assert k >= P.MANY_DOORS
    need = ~np.eye(k, dtype=bool)
    D = P._coarse_door_distances(mask, pts, 4, need)
    up = np.triu(need, 1)  # the pairs i < j are filled
    assert np.isfinite(D[up]).all()
    monkeypatch.setattr(P, "MANY_DOORS", k + 1)  # the same doors on the 0.2 m blocks alone
    D_blocks = P._coarse_door_distances(mask, pts, 4, need)
    assert not np.allclose(D[up], D_blocks[up])  # the merged floor is another graph ...
    np.testing.assert_allclose(D[up], D_blocks[up], rtol=0.03)  # ... with much the same distances
    for i in range(k - 1):
        cum = P._mcp_costs(mask, [doors[i]], doors[i + 1:])
        for j in range(i + 1, k):
            assert D[i, j] == pytest.approx(cum[doors[j]], rel=0.06)
