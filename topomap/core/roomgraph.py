"""The room–door graph: rooms as nodes, doors as edges.

:func:`room_graph` turns a :class:`~topomap.core.segmentation.Segmentation` into a
:class:`networkx.MultiGraph` (two rooms can share several doors, each its own
edge, keyed by the door id). Every attribute, with its unit, is listed on the
"Graph attributes" page of the documentation.
"""

from __future__ import annotations

import logging
import weakref

import numpy as np
import networkx as nx
from scipy import ndimage as ndi

from .._fast import edt, lookup, ranges
from .geometry import label_rings, mask_rings, true_bbox
from .kinds import annotate_kinds

__all__ = ["room_graph", "room_polygons", "interior_points", "cached_room_boxes", "OUTLINE_MIN_RINGS",
           "OUTLINE_CELLS_PER_RING"]

log = logging.getLogger("topomap")

#: Detail limit of a room's outline: at most ``OUTLINE_MIN_RINGS + cells // OUTLINE_CELLS_PER_RING``
#: rings (pieces and holes) for a room of ``cells`` cells. Beyond it (a room of scan specks or of
#: thousands of pieces that touch at corners only) the smallest pieces are left out of the outline
#: and the smallest holes holding no other room are filled; the labels keep every cell.
OUTLINE_MIN_RINGS = 4000
#: See :data:`OUTLINE_MIN_RINGS`.
OUTLINE_CELLS_PER_RING = 64

#: graph -> (weak reference to the labels, their rooms' boxes) of the graphs room_graph built, read by
#: :func:`cached_room_boxes` (beside the graph, not in it: never saved, copied or pickled)
_BOXES = weakref.WeakKeyDictionary()


def cached_room_boxes(G: nx.Graph, labels: np.ndarray):
    """The rooms' bounding boxes :func:`room_graph` found when it built ``G`` from ``labels``, if it did.

    Parameters
    ----------
    G : networkx.MultiGraph
        A room graph.
    labels : (M, N) ndarray of int
        The label image of its segmentation (``Segmentation.labels``, the very array).

    Returns
    -------
    list or None
        As ``scipy.ndimage.find_objects(labels)`` for the rooms ``1..N`` (``None`` for a label
        without cells); None when ``G`` was not built by :func:`room_graph` from this array (a
        copy, a graph loaded from a file, or labels that have been replaced).
    """
    ref, boxes = _BOXES.get(G, (lambda: None, None))
    return boxes if ref() is labels else None


def room_polygons(labels: np.ndarray, to_world=None) -> dict:
    """Outline of every room as a shapely (Multi)Polygon.

    Parameters
    ----------
    labels : (M, N) ndarray of int
        Room labels, 0 = no room.
    to_world : callable, optional
        ``(rows, cols) -> (x, y)``; without it the polygons are in pixel
        ``(col, row)`` coordinates.

    Returns
    -------
    dict
        ``label -> shapely geometry``. The outline runs exactly along the
        outer edges of the room's cells (a cell is a unit square centred on
        its pixel): a Polygon for a room whose cells are 4-connected, else a
        MultiPolygon of its 4-connected pieces (cells that touch at a corner
        only are different pieces), each with a hole for every enclosed
        patch of other cells. The geometry is valid as built (no repair) and
        holds exactly the room's cells; exteriors run counterclockwise,
        holes clockwise (in the map frame, as RFC 7946 asks). Time and
        memory are linear in the cells of the label image (all rooms are
        outlined in one pass over it).

        A room of more pieces and holes than :data:`OUTLINE_MIN_RINGS` +
        cells / :data:`OUTLINE_CELLS_PER_RING` (never seen in a building
        map: scan specks at more than one cell in 64, or a checkerboard)
        gets a simplified outline, with a warning: its smallest pieces are
        left out and its smallest holes that hold no other room are filled,
        down to that limit (its largest piece is always kept). Its cells
        stay in the labels and in the room's ``cells`` and ``area``.
    """
    labels = np.asarray(labels)
    if labels.size and labels.min() < 0:  # negative labels are no room, as 0
        labels = np.maximum(labels, 0)
    return _room_polygons(labels, to_world)


def _detailed(labels: np.ndarray, n: int) -> np.ndarray:
    """The labels ``1..n`` beyond the outline detail limit, from the cell edges on their boundaries
    (every ring has at least 4, and the pieces and holes the limit counts are at most the edges / 4):
    found before any ring is traced, so that such a room's rings are never all traced.

    The edges are counted on the labels padded by one cell of 0 and read flat (two neighbours
    differ: an edge of each), in the smallest integer type that holds them; the cells are counted
    only when some label has more edges than any room within the limit can have."""
    if n == 0 or labels.size == 0:
        return np.zeros(0, np.int64)
    dt = np.uint8 if n < 2 ** 8 else np.uint16 if n < 2 ** 16 else labels.dtype
    H, W = labels.shape
    P = np.zeros((H + 2, W + 2), dt)
    P[1:-1, 1:-1] = labels
    f = P.ravel()
    edges = np.zeros(n + 1, np.int64)
    for step in (1, W + 2):  # the cell right of, then below each cell (row ends meet padding only)
        k = np.flatnonzero(f[:-step] != f[step:])
        edges += np.bincount(f[k], minlength=n + 1)[:n + 1]
        edges += np.bincount(f[k + step], minlength=n + 1)[:n + 1]
    del P, f
    edges[0] = 0
    out = np.flatnonzero(edges > 4 * OUTLINE_MIN_RINGS)  # the limit of a room of no cells
    if not out.size:
        return out
    cells = np.bincount(labels.ravel(), minlength=n + 1)[:n + 1]
    return out[edges[out] > 4 * (OUTLINE_MIN_RINGS + cells[out] // OUTLINE_CELLS_PER_RING)]


def _without(labels: np.ndarray, drop: np.ndarray) -> np.ndarray:
    """``labels`` with the labels in ``drop`` set to 0 (the same array when there are none)."""
    if not len(drop):
        return labels
    lut = np.arange(int(labels.max(initial=0)) + 1, dtype=labels.dtype)
    lut[drop] = 0
    return lookup(lut, labels)


def _room_polygons(labels, to_world, rings=None, objs=None, detailed=None):
    """:func:`room_polygons`, from the labels' rings (:func:`topomap.core.geometry.label_rings`) and their rooms'
    bounding boxes (as ``ndi.find_objects(labels)``) when given.

    All rooms' outlines come from one pass over the labels; a room beyond the detail limit
    (``detailed``, :func:`_detailed`; its rings are not traced in that pass) is outlined from its own
    cells (:func:`_outline_cells`).
    """
    import shapely

    if detailed is None:
        detailed = _detailed(labels, int(labels.max(initial=0)))
    R = label_rings(_without(labels, detailed)) if rings is None else rings
    cell, mirror = 1.0, False  # m² per cell (for the warning); whether to_world turns rings around
    if to_world is not None:
        x, y = to_world(np.array([0.0, 0.0, 1.0]), np.array([0.0, 1.0, 0.0]))
        cell = float(np.hypot(x[1] - x[0], y[1] - y[0])) ** 2
        mirror = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]) < 0  # (col, row) to (x, y)
    n = int(R.piece_label.max(initial=0))
    polys = _polygons(R.xy, R.ring, R.piece, (0, 0), to_world, mirror)
    npieces = np.bincount(R.piece_label, minlength=n + 1)
    first = np.r_[0, np.cumsum(npieces)]
    out = {}
    multi = np.flatnonzero(npieces > 1)
    if multi.size:
        sel = np.concatenate([np.arange(first[i], first[i + 1]) for i in multi])
        for i, g in zip(multi, shapely.multipolygons(polys[sel], indices=np.repeat(np.arange(multi.size),
                                                                                    npieces[multi]))):
            out[int(i)] = g
    for i in np.flatnonzero(npieces == 1):
        out[int(i)] = polys[first[i]]
    if detailed.size:
        if objs is None:
            objs = ndi.find_objects(labels)
        for i in detailed:
            sl = objs[i - 1]
            m = _outline_cells(labels[sl], int(i), cell if to_world is not None else None)
            xy, ring, piece, _ = mask_rings(m)
            del m
            p = _polygons(xy, ring, piece, (sl[0].start, sl[1].start), to_world, mirror)
            out[int(i)] = p[0] if len(p) == 1 else shapely.multipolygons(p)
    return {i: out[i] for i in sorted(out)}


def _polygons(xy, ring, piece, offset, to_world, mirror):
    """shapely Polygons of the rings ``xy, ring, piece`` of :func:`topomap.core.geometry.mask_rings` (``(row, col)``
    + ``offset``), through ``to_world`` (turned around when ``mirror``), one per piece."""
    import shapely

    if mirror:  # every ring backwards: exteriors counterclockwise in (x, y)
        bounds = np.flatnonzero(np.r_[True, ring[1:] != ring[:-1], True])
        size = np.diff(bounds)
        xy = xy[np.repeat(bounds[:-1] + bounds[1:] - 1, size) - np.arange(ring.size)]
    rows, cols = xy[:, 0] + offset[0], xy[:, 1] + offset[1]
    del xy
    if to_world is not None:
        x, y = to_world(rows, cols)
        x, y = np.asarray(x, float), np.asarray(y, float)
    else:
        x, y = cols, rows
    return shapely.polygons(shapely.linearrings(np.stack([x, y], 1), indices=ring), indices=piece)


def _room_stats(runs, n):
    """Cell counts, row sums and column sums (exact integers, as floats) and bounding boxes (as
    ``ndi.find_objects``) of labels ``1..n``, from the labels' runs (:attr:`topomap.core.geometry.LabelRings.runs`)."""
    row, col, length, lab = runs
    cnt = np.bincount(lab, weights=length, minlength=n + 1)
    sr = np.bincount(lab, weights=row * length, minlength=n + 1)
    sc = np.bincount(lab, weights=length * col + length * (length - 1) // 2, minlength=n + 1)
    objs = [None] * n
    if lab.size:
        order = np.argsort(lab, kind="stable")  # runs by label, each label's row-major
        ls = lab[order]
        g = np.flatnonzero(np.r_[True, ls[1:] != ls[:-1]])
        r0 = row[order][g]
        r1 = row[order][np.r_[g[1:], ls.size] - 1] + 1
        c0 = np.minimum.reduceat(col[order], g)
        c1 = np.maximum.reduceat((col + length)[order], g)
        for i, a, b, c, e in zip(ls[g].tolist(), r0.tolist(), r1.tolist(), c0.tolist(), c1.tolist()):
            if i <= n:
                objs[i - 1] = (slice(a, b, None), slice(c, e, None))
    return cnt, sr, sc, objs


def _components(mask, connectivity):
    """``(labels, count)`` of the ``connectivity``-connected components of ``mask`` (labels 1..count, 0 = not in it)."""
    import cv2

    n, lab = cv2.connectedComponents(mask.view(np.uint8), connectivity=connectivity, ltype=cv2.CV_32S)
    return lab, n - 1


def _first(values, k, largest):
    """Indices of the ``k`` largest (or smallest) ``values``, ties by index: the same choice everywhere."""
    if k <= 0:
        return np.zeros(0, np.int64)
    if k >= values.size:
        return np.arange(values.size)
    v = -values if largest else values
    t = np.partition(v, k - 1)[k - 1]  # the k-th value
    below = np.flatnonzero(v < t)
    return np.r_[below, np.flatnonzero(v == t)[:k - below.size]]


def _outline_cells(L, i, cell):
    """The cells the outline of room ``i`` (in its box of labels ``L``) encloses: the room's cells, or
    beyond the detail limit (:data:`OUTLINE_MIN_RINGS`) its largest pieces (up to half the limit) and
    the holes among them, the smallest filled where they hold no other room, with a warning."""
    m = L == i
    cells = int(np.count_nonzero(m))
    limit = OUTLINE_MIN_RINGS + cells // OUTLINE_CELLS_PER_RING
    # every ring has at least 4 edges: rooms of few edges need no count of their pieces and holes
    edges = (np.count_nonzero(m[1:] != m[:-1]) + np.count_nonzero(m[:, 1:] != m[:, :-1])
             + 2 * (m.shape[0] + m.shape[1]))
    if edges <= 4 * limit:
        return m
    pieces, n_pieces = _components(m, 4)
    n_holes = _components(np.pad(~m, 1, constant_values=True), 4)[1] - 1  # all but the patch around the box
    if n_pieces + n_holes <= limit:
        return m
    size = np.bincount(pieces.ravel())
    size[0] = 0
    keep = np.zeros(size.size, bool)
    keep[_first(size[1:], min(n_pieces, max(limit // 2, 1)), True) + 1] = True
    dropped = size[~keep][1:]
    del size
    m2 = keep[pieces]
    del pieces
    # the holes among the pieces kept: 4-connected patches of other cells that do not reach the box's
    # border; the smallest of those that hold no other room's cell are filled, until within the limit
    holes, n = _components(np.pad(~m2, 1, constant_values=True), 4)
    hsize = np.bincount(holes.ravel())
    may = np.ones(hsize.size, bool)
    may[[0, holes[0, 0]]] = False
    may[holes[1:-1, 1:-1][(L != 0) & ~m]] = False
    cand = np.flatnonzero(may)
    fill = cand[_first(hsize[cand], int(keep.sum()) + n - 1 - limit, False)]
    lut = np.zeros(hsize.size, bool)
    lut[fill] = True
    m2 |= lut[holes[1:-1, 1:-1]]
    del holes, lut
    unit = "m²" if cell is not None else "cells"
    cell = 1.0 if cell is None else cell
    log.warning("room %d: %d pieces and %d enclosed patches of other cells, more detail than its outline holds "
                "(%d rings for its %d cells): the outline leaves out %d of its pieces (%.4g %s, the largest %.4g "
                "%s) and fills %d patches among the others (%.4g %s, the largest %.4g %s); the labels keep every "
                "cell", i, n_pieces, n_holes, limit, cells, dropped.size, dropped.sum() * cell, unit,
                (dropped.max() if dropped.size else 0) * cell, unit, fill.size, hsize[fill].sum() * cell, unit,
                (hsize[fill].max() if fill.size else 0) * cell, unit)
    return m2


def interior_points(labels: np.ndarray, n: int, centroids=None):
    """A cell inside each room, as far from the room's edge as any: its pole of inaccessibility on
    the grid, where its label is drawn and a route to the room goes.

    Parameters
    ----------
    labels : (M, N) ndarray of int
        Room labels ``1..n``; 0 (and labels above ``n``: fragments) are no room.
    n : int
        The largest room label.
    centroids : (n + 1, 2) ndarray of float, optional
        ``(row, col)`` of each room's centroid (row ``i`` for room ``i``): of the cells within half a
        cell of the room's largest clearance, the one nearest it is taken (the middle of a ridge of
        equal clearance, as in a rectangular room); default: the first in a row-major scan.

    Returns
    -------
    rows, cols : (n + 1,) ndarray of int
        The cell of room ``i`` at index ``i`` (-1 for a label without cells); always a cell of the
        room, unlike the centroid of a ring corridor or an L-shaped room. Its clearance is the
        Euclidean distance (cells) to the nearest cell of the room's edge (a cell with a
        4-neighbour of another label, of no room or off the map). Time and memory linear in the
        cells of the labels' bounding box.
    """
    rows = np.full(n + 1, -1, np.int64)
    cols = np.full(n + 1, -1, np.int64)
    L = np.asarray(labels)
    box = true_bbox((L > 0) & (L <= n)) if n > 0 and L.size else None
    if box is None:
        return rows, cols
    r0, r1, c0, c1 = box
    L = L[r0:r1, c0:c1]
    if L.max() > n or L.min() < 0:
        L = np.where((L > 0) & (L <= n), L, 0)
    return _interior_points(L, n, centroids, r0, c0)


def _interior_points(L, n, centroids, r0, c0):
    """:func:`interior_points` of the labels ``L`` (``0..n``), the box of the map's labels whose first
    cell is ``(r0, c0)``: rows and columns in the map."""
    rows = np.full(n + 1, -1, np.int64)
    cols = np.full(n + 1, -1, np.int64)
    # cells whose 4 neighbours are of their own room (each pair of neighbours compared once); the
    # cells on the map's border are on their room's edge
    inner = L > 0
    same = L[1:] == L[:-1]
    inner[1:] &= same
    inner[:-1] &= same
    same = L[:, 1:] == L[:, :-1]
    inner[:, 1:] &= same
    inner[:, :-1] &= same
    inner[[0, -1], :] = False
    inner[:, [0, -1]] = False
    clear = edt(inner, exact=False)  # 0 on the rooms' edges, else the distance to the nearest edge cell
    del inner
    # runs of one label along the rows: each room's largest clearance is the largest of its runs'
    # largest, and only the runs that reach within half a cell of it hold candidates
    W = L.shape[1]
    brk = np.ones(L.shape, bool)
    brk[:, 1:] = ~same
    del same
    start = np.flatnonzero(brk)
    del brk
    end = np.r_[start[1:], L.size]
    lab = L[start // W, start % W]
    val = clear.ravel()
    vmax = np.maximum.reduceat(val, start)
    top = np.zeros(n + 1, val.dtype)
    np.maximum.at(top, lab, vmax)  # each room's largest clearance (label 0: ignored)
    sel = np.flatnonzero((lab > 0) & (vmax >= top[lab] - 0.5))
    cells = ranges(start[sel], end[sel])
    lab = np.repeat(lab[sel], end[sel] - start[sel])
    keep = val[cells] >= top[lab] - 0.5
    cand, lab = cells[keep], lab[keep]
    del cells
    r, c = np.divmod(cand, W)
    if centroids is not None:
        cen = np.asarray(centroids, float)
        d2 = (r + r0 - cen[lab, 0]) ** 2 + (c + c0 - cen[lab, 1]) ** 2
    else:
        d2 = np.zeros(cand.size)
    order = np.lexsort((cand, d2, lab))  # per room: nearest the centroid, then first in the scan
    lab, r, c = lab[order], r[order], c[order]
    first = np.r_[True, lab[1:] != lab[:-1]]
    rows[lab[first]] = r[first] + r0
    cols[lab[first]] = c[first] + c0
    return rows, cols


def room_graph(seg) -> nx.MultiGraph:
    """Build the room–door graph of a segmentation.

    Nodes are room labels (``int``, 1..N) with ``area`` (m²), ``x``, ``y``
    (centroid, m), ``row``, ``col`` (centroid, pixels), ``interior_x``,
    ``interior_y`` (m), ``interior_row``, ``interior_col`` (pixels: the centre
    of a cell of the room as far from its edge as any,
    :func:`interior_points`; the centroid may lie outside the room),
    ``cells`` (count) and ``polygon`` (shapely geometry in map-frame metres). Edges are doors,
    keyed by door id, with ``door`` (id), ``width`` (m), ``x``, ``y``
    (midpoint, m), ``x1``, ``y1``, ``x2``, ``y2`` (end points, m) and ``p1``,
    ``p2`` (end points, pixels). Graph attributes: ``resolution`` (m/px),
    ``origin`` (x, y, yaw), ``method``, ``threshold`` (m or None), ``map``
    (source file), ``shape`` (rows, cols).

    Parameters
    ----------
    seg : Segmentation

    Returns
    -------
    networkx.MultiGraph
    """
    grid = seg.grid
    labels = seg.room_labels
    n = int(labels.max()) if labels.size else 0  # the largest room ID (IDs may have gaps)
    G = nx.MultiGraph(resolution=grid.resolution, origin=tuple(grid.origin), method=seg.method,
                      threshold=seg.threshold, map=grid.name, shape=tuple(labels.shape),
                      n_fragments=int(seg.n_fragments), fragment_area=float(seg.fragment_area),
                      outside_area=float(getattr(seg, "outside_area", 0.0)))
    if n == 0:
        return G
    # cell counts, row / column sums and boxes per room and the outlines: one pass over the labels
    detailed = _detailed(labels, n)  # rooms beyond the outline detail limit: their rings are not traced here
    rings = label_rings(_without(labels, detailed))
    cnt, sr, sc, objs = _room_stats(rings.runs, n)
    if detailed.size:
        boxes = ndi.find_objects(labels, max_label=n)
        for i in detailed.tolist():
            sl = boxes[i - 1]
            rr, cc = np.nonzero(labels[sl] == i)
            cnt[i], sr[i], sc[i] = rr.size, float((rr + sl[0].start).sum()), float((cc + sl[1].start).sum())
            objs[i - 1] = sl
    polys = _room_polygons(labels, grid.pixel_to_world, rings, objs, detailed)
    del rings
    _BOXES[G] = (weakref.ref(seg.labels), objs)
    area_cell = grid.resolution ** 2
    with np.errstate(invalid="ignore", divide="ignore"):
        cen = np.stack([sr[:n + 1] / cnt[:n + 1], sc[:n + 1] / cnt[:n + 1]], 1)
    # the box of all rooms (the union of theirs: labels are 0..n here)
    boxes = np.array([(sl[0].start, sl[0].stop, sl[1].start, sl[1].stop) for sl in objs if sl is not None])
    r0, c0 = boxes[:, [0, 2]].min(axis=0)
    r1, c1 = boxes[:, [1, 3]].max(axis=0)
    ir, ic = _interior_points(labels[r0:r1, c0:c1], n, cen, int(r0), int(c0))
    ix, iy = grid.pixel_to_world(ir.astype(float), ic.astype(float))
    cx, cy = grid.pixel_to_world(cen[:, 0], cen[:, 1])
    for i in range(1, n + 1):
        if cnt[i] == 0:
            continue
        r, c = cen[i]
        x, y = cx[i], cy[i]
        G.add_node(i, area=float(cnt[i] * area_cell), cells=int(cnt[i]), x=float(x), y=float(y),
                   row=float(r), col=float(c), interior_x=float(ix[i]), interior_y=float(iy[i]),
                   interior_row=float(ir[i]), interior_col=float(ic[i]), polygon=polys.get(i))
    for d in seg.doors:
        a, b = d.rooms
        mx, my = d.midpoint
        G.add_edge(a, b, key=d.id, door=d.id, width=float(d.width), x=float(mx), y=float(my),
                   x1=float(d.xy1[0]), y1=float(d.xy1[1]), x2=float(d.xy2[0]), y2=float(d.xy2[1]),
                   p1=tuple(d.p1), p2=tuple(d.p2))
    annotate_kinds(G, labels, grid.resolution, boxes=objs)
    return G
