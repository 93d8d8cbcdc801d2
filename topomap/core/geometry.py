"""Small geometry helpers on pixel grids, shared by every module.

One copy of each: distances from points to segments, the cells of a door
line, disk-shaped kernels, the bounding box of the true cells of a mask, the
conversion of metres to whole pixels and the outlines of a mask's cells. Coordinates are pixel
``(row, col)`` unless said otherwise; nothing here validates user input
(options are checked in :mod:`topomap.options`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["point_segment_distances", "points_near_segments", "line_pixels", "disk", "true_bbox", "metres_to_px", "mask_rings", "label_rings",
           "LabelRings"]


def point_segment_distances(p, a, b) -> np.ndarray:
    """Euclidean distance from points to closed segments, broadcast.

    Parameters
    ----------
    p : (..., 2) array_like of float
        Points.
    a, b : (..., 2) array_like of float
        Segment end points (same units as ``p``; ``a == b`` allowed, the
        distance is then to the point ``a``). ``p``, ``a`` and ``b``
        broadcast against each other: one point against many segments, many
        points against one segment, or pairwise.

    Returns
    -------
    ndarray of float
        The broadcast shape without the last axis.
    """
    p = np.asarray(p, float)
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    ab = b - a
    den = (ab * ab).sum(-1)
    nz = den > 0
    t = np.where(nz, ((p - a) * ab).sum(-1) / np.where(nz, den, 1), 0.0)
    t = np.clip(t, 0, 1)
    proj = a + t[..., None] * ab
    d = p - proj
    return np.hypot(d[..., 0], d[..., 1])


def points_near_segments(points, reach, a, b) -> tuple:
    """The pairs ``(i, j)`` of a point ``points[i]`` lying within ``reach[i]`` (strictly) of the
    segment ``a[j]``–``b[j]``: two ``(K,)`` int arrays, in the order of the points.

    The segments each point may lie that near are found with a k-d tree of the segments'
    midpoints (a segment is no nearer than its midpoint less half its length): time and memory
    linear in the points and segments, not in their product.
    """
    from itertools import chain

    from scipy.spatial import cKDTree

    points = np.asarray(points, float).reshape(-1, 2)
    a, b = np.asarray(a, float).reshape(-1, 2), np.asarray(b, float).reshape(-1, 2)
    reach = np.broadcast_to(np.asarray(reach, float), (len(points),))
    if len(points) == 0 or len(a) == 0:
        return np.zeros(0, np.intp), np.zeros(0, np.intp)
    half = np.hypot(*(b - a).T) / 2
    near_of = cKDTree((a + b) / 2).query_ball_point(points, reach + float(half.max()) + 1e-6)
    i = np.repeat(np.arange(len(points)), [len(js) for js in near_of])
    j = np.fromiter(chain.from_iterable(near_of), np.intp, count=i.size)
    close = point_segment_distances(points[i], a[j], b[j]) < reach[i]
    return i[close], j[close]


def line_pixels(p, q, shape):
    """Cells of the digital line from ``p`` to ``q`` (pixel ``(row, col)``).

    The end points are rounded to the nearest cell and clipped to an image
    of ``shape``; the line is :func:`skimage.draw.line` (8-connected).

    Returns
    -------
    rows, cols : ndarray of int
    """
    from skimage.draw import line

    H, W = shape[:2]
    # on Python numbers (round() rounds half to even, as np.rint): the same cells, without four
    # small-array operations a line (several hundred lines a map: cutting rooms, the travel spaces)
    (a, b), (c, d) = p, q
    r0, c0 = min(max(round(float(a)), 0), H - 1), min(max(round(float(b)), 0), W - 1)
    r1, c1 = min(max(round(float(c)), 0), H - 1), min(max(round(float(d)), 0), W - 1)
    return line(r0, c0, r1, c1)


def disk(r: int, dtype=np.uint8) -> np.ndarray:
    """``(2r+1, 2r+1)`` kernel, 1 on the cells within ``r`` of the centre."""
    y, x = np.ogrid[-r:r + 1, -r:r + 1]
    return (x * x + y * y <= r * r).astype(dtype)


def true_bbox(mask: np.ndarray, pad: int = 0):
    """Bounding box ``(r0, r1, c0, c1)`` (end exclusive) of the true cells.

    Grown by ``pad`` cells on every side and clipped to the array; None when
    no cell is true.
    """
    mask = np.asarray(mask)
    rows = np.flatnonzero(mask.any(axis=1))
    if rows.size == 0:
        return None
    cols = np.flatnonzero(mask.any(axis=0))
    H, W = mask.shape
    return (max(int(rows[0]) - pad, 0), min(int(rows[-1]) + pad + 1, H),
            max(int(cols[0]) - pad, 0), min(int(cols[-1]) + pad + 1, W))


def metres_to_px(metres: float, resolution: float, minimum: int = 0) -> int:
    """A length in metres as a whole number of cells, at least ``minimum``."""
    return max(int(round(float(metres) / resolution)), minimum)


def mask_rings(mask: np.ndarray):
    """Rings along the cell edges of the 4-connected pieces of a mask.

    Every ring is simple (no ring passes a corner twice: where two cells of
    a piece touch at a corner only, its shell and a hole, or two holes,
    touch there instead), so the shell and holes of each piece make a valid
    polygon without any repair, holding exactly the piece's cells. Time and
    memory are linear in the mask's cells.

    Parameters
    ----------
    mask : (M, N) array_like of bool

    Returns
    -------
    xy : (K, 2) ndarray of float
        The rings' corners as ``(row, col)``; cell ``(r, c)`` spans
        ``r - 0.5 .. r + 0.5`` and ``c - 0.5 .. c + 0.5``. Points on straight
        runs are left out and a ring's first corner is not repeated at its
        end. Shells run clockwise on the image (rows down), holes
        counterclockwise.
    ring : (K,) ndarray of int
        Ring (0, 1, ...) of each corner; a ring's corners are consecutive.
    piece : (R,) ndarray of int
        For each ring, its 4-connected piece (0, 1, ... in the order of the
        pieces' first cells in a row-major scan).
    hole : (R,) ndarray of bool
        Whether the ring is a hole of its piece. Rings are ordered by piece,
        each piece's shell first, then its holes.
    """
    return label_rings(np.asarray(mask, bool).view(np.uint8))[:4]


class LabelRings(NamedTuple):
    """The rings of every label of a label image (:func:`label_rings`)."""

    #: (K, 2) float: the rings' corners as ``(row, col)`` (see :func:`mask_rings`).
    xy: np.ndarray
    #: (K,) int: ring of each corner; a ring's corners are consecutive.
    ring: np.ndarray
    #: (R,) int: piece of each ring; pieces ordered by label, then by their first cell (row-major).
    piece: np.ndarray
    #: (R,) bool: whether the ring is a hole of its piece (each piece's shell first, then its holes).
    hole: np.ndarray
    #: (P,) int: label of each piece.
    piece_label: np.ndarray
    #: (P,) int: number of cell edges on the rings of each piece.
    piece_edges: np.ndarray
    #: The runs of equal non-zero labels along the rows, row-major: (U,) int arrays ``row``,
    #: ``col`` (first cell), ``length`` (cells) and ``label``.
    runs: tuple


def label_rings(labels: np.ndarray) -> LabelRings:
    """The rings of :func:`mask_rings` of every label of a label image, in one pass over the image.

    The rings of label ``i`` are those of :func:`mask_rings` of ``labels ==
    i`` (the same corners in the same order): pieces are 4-connected cells
    of one label, every ring is simple. Time and memory are linear in the
    image's cells.

    Parameters
    ----------
    labels : (M, N) array_like of int
        Labels ``>= 0``; 0 is no label (it gets no rings).

    Returns
    -------
    LabelRings
    """
    f, W, it = _padded_labels(labels)
    h = np.flatnonzero(f[:-1] != f[1:]).astype(it)  # cell h and the one right of it differ
    v = np.flatnonzero(f[:-W] != f[W:]).astype(it)  # cell v and the one below it differ
    # runs of equal non-zero labels along the rows (none crosses a row's end: the padding is 0)
    run0 = h[f[h + 1] != 0] + 1
    run1 = h[f[h] != 0] + 1
    run_label = f[run0].astype(np.int64)
    z = np.zeros(0, np.int64)
    if run0.size == 0:
        return LabelRings(np.zeros((0, 2)), z, z, np.zeros(0, bool), z, z, (z, z, z, z))
    run_piece, piece_label = _run_pieces(f, W, run0, run_label)
    start, d, blocks = _ring_edges(f, W, h, v)
    del h, v
    own_cell, nxt = _next_edges(f, W, start, d, blocks, run0, run_piece, it)
    corner, cyc, first = _ring_corners(nxt, d, it)
    rcyc = cyc[corner]
    ring_edges = np.bincount(cyc)
    del cyc
    r, c = np.divmod(start[corner], W)
    del corner
    bounds, ring_cyc, hole = _ring_orientations(r, c, rcyc, it)
    del rcyc
    piece = run_piece[_run_of(run0, own_cell[first[ring_cyc]])]
    del own_cell, start
    piece_edges = np.bincount(piece, weights=ring_edges[ring_cyc], minlength=piece_label.size).astype(np.int64)
    xy, ring, rank = _rings_by_piece(r, c, bounds, first[ring_cyc], hole, piece)
    rows, cols = np.divmod(run0.astype(np.int64), W)
    runs = (rows - 1, cols - 1, (run1 - run0).astype(np.int64), run_label)
    return LabelRings(xy, ring, piece[rank], hole[rank], piece_label, piece_edges, runs)


def _padded_labels(labels: np.ndarray):
    """``(f, W, it)``: the labels padded and flattened, the padded rows' length and the index dtype.

    Padded by one cell above and left, two below and right: vertex ``(i, j)``, the top-left corner
    of cell ``(i, j)``, has the cell's flat index, and every ring closes inside. ``f`` is of the
    smallest unsigned dtype that holds the labels; ``it`` (int32 or int64) holds every edge index.
    """
    L = np.asarray(labels)
    top = int(L.max(initial=0))
    dt = np.uint8 if top < 2 ** 8 else np.uint16 if top < 2 ** 16 else np.int64
    W = L.shape[1] + 3
    P = np.zeros((L.shape[0] + 3, W), dt)
    P[1:-2, 1:-2] = L
    it = np.int32 if 4 * P.size < 2 ** 31 else np.int64
    return P.ravel(), W, it


def _run_of(run0: np.ndarray, k):
    """The run (index into the runs' first cells ``run0``) holding each non-zero cell ``k``."""
    return np.searchsorted(run0, k, side="right") - 1


def _run_pieces(f: np.ndarray, W: int, run0: np.ndarray, run_label: np.ndarray):
    """``(run_piece, piece_label)``: the piece of each row run and the label of each piece.

    Pieces are runs of one label in adjacent rows that overlap, joined (each overlap starts at a
    run's start); they are numbered by label, then by their first cell (row-major).
    """
    from scipy import sparse
    from scipy.sparse import csgraph

    up = run0[f[run0 - W] == f[run0]]
    down = run0[f[run0 + W] == f[run0]]
    a = np.concatenate([_run_of(run0, up - W), _run_of(run0, down)])
    b = np.concatenate([_run_of(run0, up), _run_of(run0, down + W)])
    nr = run0.size
    _, comp = csgraph.connected_components(sparse.csr_matrix((np.ones(a.size, np.int8), (a, b)), shape=(nr, nr)),
                                           directed=False)
    _, first_run = np.unique(comp, return_index=True)  # runs are row-major: a piece's first run holds its first cell
    order = np.lexsort((first_run, run_label[first_run]))  # pieces by label, then by their first cell
    rank = np.empty(order.size, np.int64)
    rank[order] = np.arange(order.size)
    return rank[comp], run_label[first_run[order]]


def _ring_edges(f: np.ndarray, W: int, h: np.ndarray, v: np.ndarray):
    """``(start, d, blocks)``: the directed cell edges with a label's cell on their right (rows down).

    ``start``: each edge's start vertex; ``d``: its direction (0 east, 1 south, 2 west, 3 north);
    the edges are by direction, ``blocks[k]:blocks[k + 1]`` those of direction ``k``, each block
    by start vertex. ``h``, ``v``: the cells that differ from the one right of / below them.
    """
    east = v[f[v + W] != 0] + W                 # below cell (i, j)
    south = h[f[h] != 0] + 1                    # left of cell (i, j)
    west = v[f[v] != 0] + (W + 1)               # cell (i - 1, j) above
    north = h[f[h + 1] != 0] + (W + 1)          # cell (i, j) right
    blocks = np.cumsum([0, east.size, south.size, west.size, north.size])
    start = np.concatenate([east, south, west, north])
    d = np.repeat(np.arange(4, dtype=np.int8), np.diff(blocks))
    return start, d, blocks


def _next_edges(f: np.ndarray, W: int, start: np.ndarray, d: np.ndarray, blocks: np.ndarray, run0: np.ndarray,
                run_piece: np.ndarray, it):
    """``(own_cell, nxt)``: each edge's cell (on its right) and the edge that follows it on its ring.

    The next edge at the end vertex: a right turn if the cell straight ahead (right of the straight
    edge) is not the label's, else straight on if the cell ahead-left is not, else a left turn. Two
    cells that touch at the corner only (the cell ahead-left and this edge's own): a right turn
    keeps them apart, unless they are the same piece: then the left turn, so that no ring passes a
    corner twice (the piece's shell and a hole, or two holes, touch there instead).
    """
    n = start.size
    step = np.array([1, W, -1, -W], it)            # vertex steps east, south, west, north
    right = np.array([0, -1, -W - 1, -W], it)      # the cell on an edge's right, from its start
    own_cell = start + right[d]
    own = f[own_cell]                              # every edge's label
    end = start + step[d]
    dl = (d + 3) % 4
    ahead = f[end + right[d]] == own
    left_cell = end + right[dl]
    left = f[left_cell] == own
    apart = ~ahead & left                          # corner contacts: the same piece?
    sel = np.flatnonzero(apart)
    apart[sel] = run_piece[_run_of(run0, left_cell[sel])] != run_piece[_run_of(run0, own_cell[sel])]
    nd = np.where(~ahead & (~left | apart), (d + 1) % 4, np.where(~left, d, dl))
    del ahead, left, apart, left_cell, dl, own, sel
    nxt = np.empty(n, it)  # the next edge: the one of direction nd from the end vertex
    for k in range(4):
        sel = np.flatnonzero(nd == k)
        nxt[sel] = np.searchsorted(start[blocks[k]:blocks[k + 1]], end[sel]) + blocks[k]
    return own_cell, nxt


def _ring_corners(nxt: np.ndarray, d: np.ndarray, it):
    """``(corner, cyc, first)``: the edges that start with a turn, ring by ring in walk order; the
    cycle (ring) of each edge; the lowest edge of each cycle.

    The edges form disjoint cycles, the rings: each is cut before its lowest edge, the rings are
    chained (the last edge of one to the first of the next) and all read in one walk along the chain.
    """
    from scipy import sparse
    from scipy.sparse import csgraph

    n = nxt.size
    idx = np.arange(n, dtype=it)
    _, cyc = csgraph.connected_components(sparse.csr_matrix((np.ones(n, np.int8), nxt, np.arange(n + 1)),
                                                            shape=(n, n)), directed=True, connection="strong")
    first = np.full(int(cyc.max()) + 1, n, it)
    np.minimum.at(first, cyc, idx)
    chain = nxt.copy()
    last = np.flatnonzero(nxt == first[cyc])  # each ring's last edge, in the order of these edges
    chain[last] = np.r_[first[cyc[last]][1:], n]
    walk = csgraph.depth_first_order(
        sparse.csr_matrix((np.ones(n, np.int8), chain, np.r_[np.arange(n + 1), n]), shape=(n + 1, n + 1)),
        int(first[cyc[last[0]]]), directed=True, return_predecessors=False)[:-1]
    del chain, last
    prev = np.empty(n, it)
    prev[nxt] = idx
    return walk[d[walk] != d[prev[walk]]], cyc, first


def _ring_orientations(r: np.ndarray, c: np.ndarray, rcyc: np.ndarray, it):
    """``(bounds, ring_cyc, hole)``: each ring's first corner (into ``r``, ``c``), its cycle and
    whether it is a hole, for the corners ``r``, ``c`` of the rings in walk order (``rcyc``: the
    cycle of each). The orientation is the shoelace's sign (x = col, y = row: shells positive)."""
    bounds = np.flatnonzero(np.r_[True, rcyc[1:] != rcyc[:-1]])
    ring_cyc = rcyc[bounds]  # the cycle of each ring in walk order
    after = np.arange(1, r.size + 1, dtype=it)
    after[np.r_[bounds[1:], r.size] - 1] = bounds
    twice_area = np.add.reduceat(c.astype(np.int64) * r[after] - c[after].astype(np.int64) * r, bounds)
    return bounds, ring_cyc, twice_area < 0


def _rings_by_piece(r: np.ndarray, c: np.ndarray, bounds: np.ndarray, lowest: np.ndarray, hole: np.ndarray,
                    piece: np.ndarray):
    """``(xy, ring, rank)``: the corners and their rings with the rings ordered by piece, its shell
    first, then by their lowest edge (``lowest``); ``rank``: the rings in that order.

    Each ring's corners (``r``, ``c`` in the padded image, from ``bounds`` on) are moved as a block.
    """
    rank = np.lexsort((lowest, hole, piece))
    size = np.diff(np.r_[bounds, r.size])
    new_start = np.empty(rank.size, np.int64)
    new_start[rank] = np.r_[0, np.cumsum(size[rank])[:-1]]
    walk_ring = np.repeat(np.arange(rank.size), size)
    dest = np.arange(r.size) - bounds[walk_ring] + new_start[walk_ring]
    xy = np.empty((r.size, 2))
    xy[dest, 0] = r
    xy[dest, 1] = c
    xy -= 1.5
    ring = np.empty(r.size, np.int64)
    pos = np.empty(rank.size, np.int64)
    pos[rank] = np.arange(rank.size)
    ring[dest] = pos[walk_ring]
    return xy, ring, rank
