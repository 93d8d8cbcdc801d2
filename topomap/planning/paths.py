"""Queries and topological path planning on the room–door graph.

Stateless functions in the style of networkx: the graph (or segmentation)
comes first. Every function that takes ``seg_or_G`` accepts either a
:class:`~topomap.core.segmentation.Segmentation` or a room–door graph as built by
:func:`topomap.core.roomgraph.room_graph` (also one loaded back with
:func:`topomap.io.export.load_graphml` / :func:`~topomap.io.export.load_json` /
:func:`~topomap.io.export.load_geojson`). A graph carries everything planning
needs: room polygons that follow cell edges exactly (so the room cells are
recovered by rasterising them at the graph's ``resolution``, ``origin`` and
``shape``), doors with their end points, and, once :func:`travel_graph` has
annotated it, the in-room door-to-door travel distances.

Room IDs
--------
Room IDs are the labels ``1..N`` of the label image and are deterministic:
:func:`topomap.core.rooms.relabel_sequential` numbers rooms in order of their
first cell in a row-major scan of the map image (top row first, left to
right), so room 1 holds the top-most, then left-most free cell of the image
(rows count down from the top of the image, which is the largest map-frame
``y`` when the origin has no yaw). The same map and method give the same IDs.
Door IDs are ``0..K-1`` in the order the segmentation method found them.

Travel distances
----------------
Distances are geodesic, through free space, never straight lines through
walls: inside a room ``r`` the traversable cells are the cells labelled ``r``
plus the cells of the door segments of ``r`` (a door's cells belong to one of
the two rooms it joins). Each door is represented by the free door-segment
cell closest to its midpoint. The reference metric is the 8-connected
geodesic on the map's grid (steps of 1 and √2 cells, as
:class:`skimage.graph.MCP_Geometric`), converted to metres.

Door-to-door distances (:func:`room_distances`, :func:`travel_graph`) are
computed per room, in a window (the room's bounding box with its doors,
one cell around):

* a window of at most :data:`EXACT_CELLS` cells gets the map-grid geodesic
  itself: the octile distance for two doors in sight of each other (see
  below), one search per door for the others;
* a larger one is cut into blocks of ``f`` x ``f`` cells, ``f`` =
  :data:`TRAVEL_CELL` / resolution (4 at 0.05 m/px); a node is one
  connected piece of the room's cells inside one block (so a wall or a
  piece of furniture inside a block is never crossed), placed at the
  piece's centroid. In a room with at least :data:`MANY_DOORS` doors, open
  floor is coarser: each 2 x 2 group of blocks (on even block rows and
  columns) whose four blocks and the ring of blocks around them are all
  wholly on the room's cells is one node, at the group's centre
  (:func:`_merged_nodes`), so walls, furniture and doors keep their 0.2 m
  blocks;
* two nodes are joined when any of their cells are 8-neighbours, by the
  octile distance between their centroids; each door cell is joined to the
  nodes of its 3 x 3 neighbourhood the same way;
* two doors in sight of each other (a digital straight line between their
  cells runs on the room's cells only, :func:`_in_sight`) get their octile
  distance, which is then exactly the map-grid geodesic;
* the other pairs come from Dijkstra (:func:`scipy.sparse.csgraph.dijkstra`)
  on the coarse graph, one search from every door that has such a pair with
  a later door; a room whose doors all see each other needs no search;
* pairs closer than :data:`REFINE_CELLS` blocks on the coarse graph (3.2 m
  at 0.05 m/px) are measured again exactly on the map's grid, in a window
  around the two doors large enough to hold every path not much longer than
  the coarse one.

On the 28 images of the ipa benchmark (7,277 door pairs) this stays within
5.5 % (and 0.99 m) of the map-grid geodesic for every pair (mean +0.54 %,
95 % of the pairs within 1.7 %, 0.07 % of the pairs beyond 5 %;
``benchmarks/travel_accuracy.py`` measures it) at a small fraction of its
cost. ``exact=True`` gives the map-grid geodesic for every pair (one
search per door over the whole room). The legs from a start or goal point
to the doors of its room (:func:`plan_path`) are always measured on the
map's grid.

A route is a sequence of legs: start → first door (in the start room),
door → door (in the room between them), last door → goal (in the goal
room), so its length is the length of a real path through free space.
Waypoints are the start, the door midpoints and the goal.

All coordinates are map-frame metres ``(x, y)``, the frame of the map YAML's
``origin``; all lengths and widths are metres.
"""

from __future__ import annotations

import numbers

import numpy as np
import networkx as nx

from ..errors import NoPathError, NotInRoomError, PlanningError  # noqa: F401  (re-exported)
from .._fast import ranges
from ..core.roommap import RoomMap

__all__ = ["PlanningError", "NotInRoomError", "NoPathError", "room_at", "neighbors", "doors_between",
           "room_distances", "travel_graph", "door_graph", "plan_path"]



class RoomSpace:
    """The traversable cells of one room and the cells its doors are crossed at.

    The traversable cells are the room's cells plus the cells of its doors'
    segments that lie on the room or on the room across the door, in a window
    (the room's bounding box with its doors, one cell around).

    Parameters
    ----------
    room_map : RoomMap
        The rooms and doors (:class:`topomap.core.roommap.RoomMap`).
    room : int
        Room ID.
    doors : list of int, optional
        The doors to include (default: all of the room's doors).

    Attributes
    ----------
    win : (int, int, int, int)
        The window ``(r0, r1, c0, c1)`` (half-open pixel box of the map).
    mask : (r1 - r0, c1 - c0) ndarray of bool
        The traversable cells in the window.
    door_px : dict
        ``door id -> (row, col)`` in the window: the cell a route crosses the
        door at (:meth:`RoomMap.door_point <topomap.core.roommap.RoomMap.door_point>`),
        for the doors that have one.
    """

    def __init__(self, room_map: RoomMap, room: int, doors=None):
        self.room_map, self.room = room_map, room
        doors = room_map.doors_of(room) if doors is None else doors
        H, W = room_map.shape
        box = room_map.room_bbox(room)
        lines = [room_map.door_cells(d) for d in doors]
        if not box and not lines:
            self.win, self.mask, self.door_px = (0, 0, 0, 0), np.zeros((0, 0), bool), {}
            return
        # all the doors' cells at once (one test against the rooms instead of one per door)
        door_rows = np.concatenate([rr for rr, _ in lines]) if lines else np.zeros(0, np.intp)
        door_cols = np.concatenate([cc for _, cc in lines]) if lines else np.zeros(0, np.intp)
        rows = ([box[0], box[1] - 1] if box else []) + ([int(door_rows.min()), int(door_rows.max())]
                                                         if door_rows.size else [])
        cols = ([box[2], box[3] - 1] if box else []) + ([int(door_cols.min()), int(door_cols.max())]
                                                         if door_cols.size else [])
        r0, r1 = max(min(rows) - 1, 0), min(max(rows) + 2, H)
        c0, c1 = max(min(cols) - 1, 0), min(max(cols) + 2, W)
        self.win = (r0, r1, c0, c1)
        rooms = {room} | {x for d in doors for x in room_map.doors[d][:2]}
        mask, on_rooms = room_map.window_room(room, rooms, self.win)
        door_rows, door_cols = door_rows - r0, door_cols - c0
        ok = on_rooms(door_rows, door_cols)
        mask[door_rows[ok], door_cols[ok]] = True
        # each door at the cell a route crosses it (its cells on the rooms are on the mask)
        self.door_px = {}
        for d in doors:
            pt = room_map.door_point(d)
            if pt is not None:
                self.door_px[d] = (pt[0] - r0, pt[1] - c0)
        self.mask = mask

    def local(self, row: int, col: int):
        """Map cell ``(row, col)`` as a cell of the window, or None when it is not traversable."""
        r0, r1, c0, c1 = self.win
        if r0 <= row < r1 and c0 <= col < c1 and self.mask[row - r0, col - c0]:
            return row - r0, col - c0
        return None

    def distances(self, src, targets) -> list:
        """Geodesic distances (m) from window cell ``src`` to window cells ``targets`` (inf where
        unreachable), on the map's grid (steps of 1 and √2 cells)."""
        if not targets:
            return []
        cum = _mcp_costs(self.mask, [src], targets)
        return [float(cum[t]) * self.room_map.resolution for t in targets]

    def door_distances(self, *, exact=False):
        """``{(door_i, door_j): metres}`` between this room's doors (``i < j``, reachable pairs only).

        Exact 8-connected geodesics on the map's grid for small rooms (doors
        in sight of each other: their octile distance, the same number) or
        with ``exact=True`` (one search per door); on a coarse grid with
        short pairs refined on the map's grid otherwise (see the module
        notes).
        """
        ids = sorted(self.door_px)
        if len(ids) < 2:
            return {}
        if exact or self.mask.size <= EXACT_CELLS:  # the reference: one search per door on the map's grid
            out = {}
            if exact:
                seen = np.zeros((len(ids), len(ids)), bool)
            else:  # a small room: doors in sight of each other get their octile distance, the geodesic itself
                pts = np.array([self.door_px[d] for d in ids], float)
                seen = _in_sight(self.mask, pts)
            for i, di in enumerate(ids[:-1]):
                rest = [ids[j] for j in range(i + 1, len(ids)) if not seen[i, j]]
                for j in np.flatnonzero(seen[i, i + 1:]) + i + 1:
                    out[(di, ids[j])] = float(_octile(*(pts[i] - pts[j]))) * self.room_map.resolution
                for dj, L in zip(rest, self.distances(self.door_px[di], [self.door_px[d] for d in rest])):
                    if np.isfinite(L):
                        out[(di, dj)] = L
            return out
        f = _coarse_factor(self.room_map.resolution)
        pts = np.array([self.door_px[d] for d in ids], float)
        seen = _in_sight(self.mask, pts) if f > 1 else np.zeros((len(ids), len(ids)), bool)
        need = ~seen  # the coarse search only for the pairs out of sight (none: no search)
        np.fill_diagonal(need, False)
        cells = _coarse_door_distances(self.mask, pts, f, need)  # (k, k) distances in cells
        cells[seen] = _octile(*(pts[:, None, :] - pts[None, :, :]).transpose(2, 0, 1))[seen]
        short = REFINE_CELLS * f if f > 1 else 0
        close = np.triu((cells < short) & ~seen, 1)  # (a row's refinement changes only that row)
        for i in np.flatnonzero(close.any(axis=1)):
            near = np.flatnonzero(close[i])
            cells[i, near] = _windowed_distances(self.mask, pts, i, list(near), cells[i, near], f)
        res = self.room_map.resolution
        I, J = np.triu_indices(len(ids), 1)
        ok = np.isfinite(cells[I, J])
        return {(ids[i], ids[j]): L * res for i, j, L in zip(I[ok].tolist(), J[ok].tolist(), cells[I, J][ok].tolist())}


#: Rooms with at least this many doors: open floor merged into larger travel nodes
#: (:func:`_merged_nodes`), searched on a matrix of both directions (:func:`_travel_matrix`),
#: in-sight tested for all pairs together (:func:`_in_sight`); fewer doors: the 0.2 m blocks.
MANY_DOORS = 6
#: Side (m) of the coarse cells on which door-to-door distances are computed in large rooms.
TRAVEL_CELL = 0.2
#: Rooms (their window: bounding box of the room and its doors) of at most this many cells get
#: exact distances on the map's own grid.
EXACT_CELLS = 5_000
#: Door pairs closer than this many coarse cells (on the coarse grid) are measured again on the map's grid.
REFINE_CELLS = 16


def _coarse_factor(res):
    """Map cells per coarse cell side: :data:`TRAVEL_CELL` / resolution, at least 1."""
    return max(1, int(round(TRAVEL_CELL / res)))


def _mcp_costs(mask, starts, ends):
    """Cumulative 8-connected travel cost (cells; steps 1 and sqrt 2) from ``starts`` over ``mask``."""
    from skimage.graph import MCP_Geometric

    mcp = MCP_Geometric(np.where(mask, 1.0, np.inf), fully_connected=True)
    cum, _ = mcp.find_costs(list(starts), list(ends), find_all_ends=True)
    return cum


def _octile(dr, dc):
    a, b = np.abs(dr), np.abs(dc)
    return np.maximum(a, b) + (np.sqrt(2) - 1) * np.minimum(a, b)


def _block_components(mask, f):
    """Connected pieces of ``mask`` inside each ``f`` x ``f`` block.

    Returns labels ``1..n`` (0 off the mask), ``n`` and the (n + 1, 2)
    ``(row, col)`` centroids of the pieces (row 0 unused). The blocks are
    labelled one empty cell apart, so pieces never join across blocks;
    when most blocks hold no mask cell (a long room's window is mostly
    other rooms), only those that do, side by side in one strip. A piece's
    centroid is the mean of its cells either way.
    """
    import cv2

    h, w = mask.shape
    H, W = -(-h // f), -(-w // f)
    m = np.zeros((H * f, W * f), bool)
    m[:h, :w] = mask
    blocks = m.reshape(H, f, W, f)
    R, C = np.nonzero(block_any(m, f))
    if 3 * R.size > H * W:  # mostly full: all blocks at once, one empty cell apart both ways
        g = np.zeros((H, f + 1, W, f + 1), np.uint8)
        g[:, :f, :, :f] = blocks
        n, lab, _, cen = cv2.connectedComponentsWithStats(g.reshape(H * (f + 1), W * (f + 1)), connectivity=8,
                                                          ltype=cv2.CV_32S)
        lab = lab.reshape(H, f + 1, W, f + 1)[:, :f, :, :f].reshape(H * f, W * f)[:h, :w]
        cen = cen[:, ::-1]  # (row, col) in the spaced image: take out one gap cell per block before it
        return lab, n - 1, cen - np.floor(cen / (f + 1))
    lab = np.zeros((H * f, W * f), np.int32)
    if R.size == 0:
        return lab[:h, :w], 0, np.zeros((1, 2))
    K = R.size
    strip = np.zeros((f, K, f + 1), np.uint8)
    strip[:, :, :f] = blocks.transpose(1, 0, 2, 3)[:, R, C]
    n, slab, stats, scen = cv2.connectedComponentsWithStats(strip.reshape(f, K * (f + 1)), connectivity=8,
                                                            ltype=cv2.CV_32S)
    blab = slab.reshape(f, K, f + 1)[:, :, :f]  # (f, K, f): row in block, block, column in block
    lab.reshape(H, f, W, f).transpose(1, 0, 2, 3)[:, R, C] = blab
    # the centroids OpenCV gives on the image of all blocks one empty cell apart (each coordinate's
    # sum over the piece / its area there), then moved back onto the window's cells. The sums are
    # integers: those on the strip, exact from its centroids, moved to the spaced image's blocks
    area = stats[:, cv2.CC_STAT_AREA].astype(float)
    area[0] = 1
    k = stats[:, cv2.CC_STAT_LEFT] // (f + 1)  # each piece's block on the strip
    sr = np.rint(scen[:, 1] * area) + area * (R[k] * (f + 1))
    sc = np.rint(scen[:, 0] * area) + area * ((C[k] - k) * (f + 1))
    cen = np.stack([sr / area, sc / area], 1)
    cen[0] = 0
    cen = cen - np.floor(cen / (f + 1))
    return lab[:h, :w], n - 1, cen


def _merged_nodes(mask, lab, n, cen, f):
    """Merge each aligned 2 x 2 group of blocks inside the fully free part of ``mask`` into one node.

    A block is fully free when all its ``f`` x ``f`` cells are on the mask; a group of 2 x 2
    blocks (aligned on even block rows and columns) is merged when its blocks and the ring of
    blocks around them are all fully free, so paths along walls, around furniture and into
    doors keep the blocks' own nodes, and only open floor is crossed on the coarser grid.

    Parameters
    ----------
    mask : (h, w) bool ndarray
        The room's cells.
    lab, n, cen
        The block pieces of ``mask`` (:func:`_block_components`).
    f : int
        Block side (cells).

    Returns
    -------
    node : (n + 1,) int ndarray
        The node (``1..m``; 0 for label 0) of every piece.
    cen : (m + 1, 2) float ndarray
        The ``(row, col)`` centroids of the nodes (the mean of their cells; row 0 unused).
    """
    node = np.arange(n + 1)
    h, w = mask.shape
    H, W = h // f, w // f  # the whole blocks (a window's last, partial blocks are never fully free)
    if H < 4 or W < 4:
        return node, cen
    full = np.zeros((H + 2, W + 2), bool)  # blocks wholly on the mask, in a ring of blocks that are not
    full[1:-1, 1:-1] = ~block_any(~np.ascontiguousarray(mask[:H * f, :W * f]), f)
    inner = full[1:-1, 1:-1].copy()  # full, with its 8 neighbours full
    for dr in (0, 1, 2):
        for dc in (0, 1, 2):
            inner &= full[dr:dr + H, dc:dc + W]
    H2, W2 = H // 2, W // 2
    GR, GC = np.nonzero(inner[:2 * H2, :2 * W2].reshape(H2, 2, W2, 2).all(axis=(1, 3)))
    if GR.size == 0:
        return node, cen
    # a full block holds one piece; the group's pieces become the first one's node, at the group's centre
    members = lab[:2 * H2 * f:f, :2 * W2 * f:f].reshape(H2, 2, W2, 2)[GR, :, GC, :].reshape(GR.size, 4)
    node[members] = members[:, :1]
    cen = cen.copy()
    cen[members[:, 0]] = np.stack([(GR + 0.5) * 2 * f - 0.5, (GC + 0.5) * 2 * f - 0.5], 1)
    used = np.zeros(n + 1, bool)  # the nodes left, numbered in order (np.unique without its sort)
    used[node] = True
    return (np.cumsum(used) - 1)[node], cen[used]


def block_any(m: np.ndarray, f: int) -> np.ndarray:
    """Which ``f`` x ``f`` blocks of a bool image hold a True cell.

    Parameters
    ----------
    m : (H f, W f) ndarray of bool
        C-contiguous, a whole number of blocks each way.
    f : int
        Block side (cells).

    Returns
    -------
    (H, W) ndarray of bool

    Notes
    -----
    The rows of each block are OR-ed together, then each block's ``f`` bytes
    read as one integer when ``f`` is 1, 2, 4 or 8 (much faster than numpy's
    ``any`` over two axes of a 4-D view).
    """
    Hf, Wf = m.shape
    H, W = Hf // f, Wf // f
    rows = np.bitwise_or.reduce(m.view(np.uint8).reshape(H, f, Wf), axis=1)  # (H, W f)
    if f in (1, 2, 4, 8):
        return rows.view(np.dtype(f"u{f}")).reshape(H, W) > 0
    return rows.reshape(H, W, f).any(axis=2)


def _touching(a, b):
    """Label pairs of 8-adjacent cells, ``a`` the row above ``b`` (0 = no cell): the labels above and
    the labels below (lists of arrays, one each way of touching)."""
    above, below = [], []
    w = a.shape[1]
    on_a, on_b = a > 0, b > 0
    for dc in (-1, 0, 1):
        sa, sb = slice(max(0, -dc), w - max(0, dc)), slice(max(0, dc), w - max(0, -dc))
        x, y = a[:, sa], b[:, sb]
        ok = on_a[:, sa] & on_b[:, sb] & (x != y)
        x, y = x[ok], y[ok]
        keep = np.ones(len(x), bool)  # runs of the same pair along a block edge: keep one
        keep[1:] = (x[1:] != x[:-1]) | (y[1:] != y[:-1])
        above.append(x[keep])
        below.append(y[keep])
    return above, below


def _coarse_door_distances(mask, pts, f, need=None):
    """(k, k) travel distances (map cells) between the points ``pts`` (local ``(row, col)``
    cells of ``mask``) on the coarse grid of ``f`` x ``f`` blocks of ``mask``; only the pairs
    ``need`` ((k, k) bool, symmetric; default all) are searched, the others are inf.

    A node is a connected piece of the mask inside one block (so walls and
    furniture within a block are never crossed), placed at the piece's
    centroid; with at least :data:`MANY_DOORS` points, open floor is merged
    into larger nodes (:func:`_merged_nodes`). Two nodes are joined when any
    of their cells are 8-neighbours, with the octile distance (steps of 1
    and sqrt 2 cells, the metric of the map-grid geodesic) between their
    centroids; each point is joined to the nodes of its 3 x 3 neighbourhood
    by the octile distance to their centroids. Shortest paths: Dijkstra
    (:func:`scipy.sparse.csgraph.dijkstra`) from every point with a pair
    ``i < j`` in ``need`` (the rows of those points are filled); with
    :data:`MANY_DOORS` points or more on a matrix holding both directions of
    every edge, searched as directed (see :func:`_travel_matrix`).
    """
    from scipy.sparse.csgraph import dijkstra

    k = len(pts)
    if need is None:
        need = ~np.eye(k, dtype=bool)
    out = np.full((k, k), np.inf)
    if not need.any():
        return out
    many = k >= MANY_DOORS
    lab, n, cen = _block_components(mask, f)
    nb = len(lab[f::f])
    us, vs = _touching(lab[f - 1::f][:nb], lab[f::f])  # the pairs of touching pieces, each way
    right = np.ascontiguousarray(lab[:, f::f].T)  # the columns at the blocks' edges, as rows
    left = np.ascontiguousarray(lab[:, f - 1::f][:, :len(right)].T)
    ls, rs = _touching(left, right)
    us, vs = us + rs, vs + ls
    if many and f > 1:  # open floor merged: pieces -> their nodes
        node, cen = _merged_nodes(mask, lab, n, cen, f)
        u, v = node[np.concatenate(us)], node[np.concatenate(vs)]
        apart = u != v
        us, vs = [u[apart]], [v[apart]]
        n = len(cen) - 1
        lab_node = lambda v: node[v]  # noqa: E731
    else:
        lab_node = lambda v: v  # noqa: E731
    su, sv = [], []
    for i, (pr, pc) in enumerate(pts):
        r, c = int(pr), int(pc)
        near = lab[max(r - 1, 0):r + 2, max(c - 1, 0):c + 2].ravel()
        near = lab_node(near[near > 0])
        su.append(np.full(len(near), n + 1 + i))
        sv.append(near)
    u, v = np.concatenate(us + su).astype(np.int32), np.concatenate(vs + sv).astype(np.int32)
    pr = np.concatenate([cen[:, 0], pts[:, 0]])
    pc = np.concatenate([cen[:, 1], pts[:, 1]])
    A = _travel_matrix(u, v, n + 1 + k, lambda u, v: _octile(pr[u] - pr[v], pc[u] - pc[v]) + 1e-9, both_ways=many)
    rows = np.nonzero(np.triu(need, 1).any(axis=1))[0]  # one search from each door with a pair i < j
    out[rows] = dijkstra(A, directed=many, indices=n + 1 + rows)[:, n + 1:]
    return out


def _travel_matrix(a, b, m, length, *, both_ways):
    """The (m, m) CSR matrix joining each pair ``a[i], b[i]`` of nodes ((e,) ints, repeats allowed) by
    ``length(u, v)`` (arrays of node indices -> lengths), one entry per pair.

    With ``both_ways`` every pair is entered in both directions, to be searched as a directed
    graph (:func:`scipy.sparse.csgraph.dijkstra` with ``directed=True``: faster than an undirected
    search, which scans every node's row and its column, when there are several searches);
    otherwise once, to be searched with ``directed=False``.
    """
    from scipy.sparse import coo_matrix

    rows, cols = (np.concatenate([a, b]), np.concatenate([b, a])) if both_ways else (a, b)
    # one entry per pair (the sparse matrix merges repeats), then its length
    A = coo_matrix((np.ones(len(rows), np.float32), (rows, cols)), shape=(m, m)).tocsr()
    u = np.repeat(np.arange(m), np.diff(A.indptr))
    A.data = length(u, A.indices).astype(float)
    return A


#: Slack of the refinement windows: a path up to this factor (plus two coarse cells) longer
#: than the coarse distance still fits in the window.
_WINDOW_SLACK = 1.1


def _in_sight(mask, pts):
    """(k, k) bool: the digital straight line between two points runs on ``mask`` cells only.

    A digital straight line from ``p`` to ``q`` takes ``n = max(|dr|, |dc|)``
    steps, one cell along the longer axis and 0 or 1 along the other each
    step, so it is a shortest 8-connected path and the map-grid geodesic
    between two points in sight is exactly their octile distance. Fewer than
    :data:`MANY_DOORS` points: Bresenham's line
    (:func:`skimage.draw.line`), pair by pair. More: step ``t`` at ``p +
    round(t (q - p) / n)``, all pairs together, first
    :data:`_SIGHT_PROBES` cells of each line, then every cell of the lines
    that passed, in batches of at most :data:`_SIGHT_BATCH` cells.
    """
    k = len(pts)
    out = np.zeros((k, k), bool)
    if k < 2:
        return out
    p = np.asarray(pts).astype(np.int64)
    flat = np.ascontiguousarray(mask).ravel()
    w = mask.shape[1]
    if k < MANY_DOORS:  # a few pairs: Bresenham's line (skimage.draw.line) pair by pair
        from skimage.draw import line

        for i in range(k - 1):
            for j in range(i + 1, k):
                rr, cc = line(p[i, 0], p[i, 1], p[j, 0], p[j, 1])
                out[i, j] = out[j, i] = bool(mask[rr, cc].all())
        return out
    I, J = np.triu_indices(k, 1)
    steps = np.abs(p[J] - p[I]).max(axis=1)
    probe = np.floor(np.linspace(0, 1, _SIGHT_PROBES)[None, :] * steps[:, None] + 0.5).astype(np.int64)
    keep = np.nonzero(_line_cells(flat, w, p[I], p[J], steps, probe).all(axis=1))[0]
    ends = np.cumsum(steps[keep] + 1)
    lo = 0
    while lo < len(keep):  # the whole lines of the pairs that passed
        hi = max(int(np.searchsorted(ends, ends[lo] - steps[keep[lo]] - 1 + _SIGHT_BATCH, side="right")), lo + 1)
        b = keep[lo:hi]
        n = steps[b] + 1
        start = np.concatenate([[0], np.cumsum(n)[:-1]])
        pair = np.repeat(np.arange(len(b)), n)
        t = ranges(np.zeros_like(n), n)[:, None]
        on = _line_cells(flat, w, p[I[b]][pair], p[J[b]][pair], steps[b][pair], t)[:, 0]
        ok = np.logical_and.reduceat(on, start)
        out[I[b[ok]], J[b[ok]]] = True
        lo = hi
    return out | out.T


def _line_cells(flat, w, a, b, steps, t):
    """``flat[...]`` (the raveled mask, ``w`` columns) at step ``t`` (m, s) of the lines ``a`` -> ``b``
    ((m, 2) ``(row, col)``, ``steps`` (m,) = their longer axis' length), as in :func:`_in_sight`."""
    frac = t / np.maximum(steps, 1)[:, None]
    rr = a[:, :1] + np.floor(frac * (b[:, :1] - a[:, :1]) + 0.5).astype(np.int64)
    cc = a[:, 1:] + np.floor(frac * (b[:, 1:] - a[:, 1:]) + 0.5).astype(np.int64)
    return flat[rr * w + cc]


#: Cells of each line (evenly spread, both ends included) :func:`_in_sight` tests before the whole line.
_SIGHT_PROBES = 9
#: Line cells tested at once by :func:`_in_sight`.
_SIGHT_BATCH = 1 << 20


def _windowed_distances(mask, pts, i, near, bound, f):
    """Exact distances (cells) from point ``i`` to points ``near`` on ``mask``, searched in a window.

    A path of length at most ``L`` between two points stays inside the
    ellipse with the two points as foci and ``L`` as the sum of the
    distances to them, so inside their bounding box padded by ``(L - |pq|) /
    2``; the window is the union of these boxes for ``L`` =
    :data:`_WINDOW_SLACK` x the coarse distance ``bound`` + 2 ``f``. Where the
    window holds no path, the coarse distance is kept.
    """
    p = pts[[i] + list(near)]
    h, w = mask.shape
    L = np.where(np.isfinite(bound), bound, max(h, w) * 2.0) * _WINDOW_SLACK + 2 * f
    pad = np.ceil(np.maximum(L - np.hypot(*(p[1:] - p[0]).T), 0) / 2) + 1
    r0 = max(int(np.min(np.minimum(p[0, 0], p[1:, 0]) - pad)), 0)
    c0 = max(int(np.min(np.minimum(p[0, 1], p[1:, 1]) - pad)), 0)
    r1 = min(int(np.max(np.maximum(p[0, 0], p[1:, 0]) + pad)) + 1, h)
    c1 = min(int(np.max(np.maximum(p[0, 1], p[1:, 1]) + pad)) + 1, w)
    loc = [(int(r) - r0, int(c) - c0) for r, c in p]
    cum = _mcp_costs(mask[r0:r1, c0:c1], loc[:1], loc[1:])
    got = np.array([cum[t] for t in loc[1:]], float)
    return np.where(np.isfinite(got), got, bound)


# --------------------------------------------------------------------------
# Queries
# --------------------------------------------------------------------------

def _graph(seg_or_G):
    """The room graph of a segmentation, or the graph itself."""
    return seg_or_G if isinstance(seg_or_G, nx.Graph) else seg_or_G.room_graph


def room_at(seg_or_G, x: float, y: float) -> int:
    """The room at map-frame point ``(x, y)``.

    Parameters
    ----------
    seg_or_G : Segmentation or networkx.MultiGraph
        A segmentation or a room–door graph (rooms are found from their
        polygons, which follow cell edges, so both give the same answer).
    x, y : float
        Map-frame coordinates in metres.

    Returns
    -------
    int
        Room ID (``1..N``) of the cell that holds the point; ``0`` when the
        point is outside the map or not on a room's cell (wall, unknown).
    """
    room_map = RoomMap(seg_or_G)
    return room_map.label_at_pixel(*room_map.cell_at(x, y))


def neighbors(G, room: int) -> list:
    """Rooms that share at least one door with ``room``.

    Parameters
    ----------
    G : networkx.MultiGraph or Segmentation
        The room–door graph (or a segmentation, whose ``room_graph`` is used).
    room : int
        Room ID.

    Returns
    -------
    list of int
        Neighbouring room IDs, ascending.
    """
    G = _graph(G)
    if room not in G:
        raise NotInRoomError(f"no room {room!r} in the graph (rooms 1..{G.number_of_nodes()})")
    return sorted(int(n) for n in G.neighbors(room) if n != room)


def doors_between(G, a: int, b: int) -> list:
    """Doors joining rooms ``a`` and ``b``.

    Parameters
    ----------
    G : networkx.MultiGraph or Segmentation
    a, b : int
        Room IDs.

    Returns
    -------
    list of int
        Door IDs, ascending (empty when the rooms are not adjacent). Each
        door's attributes (``width`` m, midpoint ``x``, ``y`` m, ...) are
        ``G.edges[a, b, door_id]``.
    """
    G = _graph(G)
    for r in (a, b):
        if r not in G:
            raise NotInRoomError(f"no room {r!r} in the graph (rooms 1..{G.number_of_nodes()})")
    if not G.has_edge(a, b):
        return []
    return sorted(int(d.get("door", k)) for k, d in G[a][b].items())


# --------------------------------------------------------------------------
# Travel distances
# --------------------------------------------------------------------------

def room_distances(seg_or_G, room: int, *, exact: bool = False) -> dict:
    """In-room travel distances between every pair of the room's doors.

    Parameters
    ----------
    seg_or_G : Segmentation or networkx.MultiGraph
    room : int
        Room ID.
    exact : bool
        Measure every pair on the map's own grid (one search per door over
        the whole room) instead of the coarse grid large rooms use by
        default (see the module notes); slower, for checking.

    Returns
    -------
    dict
        ``{(door_i, door_j): metres}`` for ``door_i < door_j``, geodesic
        distance through the room's free cells between the two doors'
        midpoint cells; pairs not connected inside the room are left out.
    """
    room_map = RoomMap(seg_or_G)
    if room not in room_map.graph:
        raise NotInRoomError(f"no room {room!r} in the graph")
    return _room_distances(room_map, room, exact=exact)


def _room_distances(room_map, room, exact=False):
    """:func:`room_distances` of a room of ``room_map`` (a :class:`RoomMap`)."""
    if len(room_map.doors_of(room)) < 2:
        return {}
    return RoomSpace(room_map, room).door_distances(exact=exact)


def travel_graph(seg_or_G, *, exact: bool = False) -> nx.MultiGraph:
    """A copy of the room–door graph with in-room door-to-door distances.

    Every room node gets ``door_distances``: a tuple of
    ``(door_i, door_j, metres)`` triples (``door_i < door_j``), the geodesic
    travel distance inside that room between the two doors' midpoints (see
    the module notes). :func:`topomap.cli.write_segmentation` saves this graph,
    so ``topomap plan`` works from the saved graph file alone, and
    :func:`door_graph` / :func:`plan_path` reuse the stored distances instead
    of recomputing them.

    Parameters
    ----------
    seg_or_G : Segmentation or networkx.MultiGraph
    exact : bool
        Every pair measured on the map's own grid (see
        :func:`room_distances`); slower.

    Returns
    -------
    networkx.MultiGraph
        The annotated copy (the input is not modified); the graph attribute
        ``travel_distances`` is ``"geodesic"``.
    """
    room_map = RoomMap(seg_or_G)
    G = room_map.graph.copy()
    for r in G.nodes:
        dist = _room_distances(room_map, r, exact=exact)
        G.nodes[r]["door_distances"] = tuple((int(i), int(j), float(L)) for (i, j), L in sorted(dist.items()))
    G.graph["travel_distances"] = "geodesic"
    return G


def annotated_graph(seg_or_G) -> nx.MultiGraph:
    """The room graph with in-room door-to-door distances: ``seg_or_G``'s own graph when every room
    carries ``door_distances`` already (a graph :func:`travel_graph` made or a saved one), else
    :func:`travel_graph` of it.

    Parameters
    ----------
    seg_or_G : Segmentation or networkx.MultiGraph

    Returns
    -------
    networkx.MultiGraph
        Not a copy when the graph was annotated already: do not modify it.
    """
    G = _graph(seg_or_G)
    if G.number_of_nodes() and all("door_distances" in d for _, d in G.nodes(data=True)):
        return G
    return travel_graph(seg_or_G)


def door_graph(seg_or_G, *, min_width: float = 0.0) -> nx.Graph:
    """The door-level graph: doors as nodes, in-room travel between them as edges.

    Parameters
    ----------
    seg_or_G : Segmentation or networkx.MultiGraph
        A segmentation or a room–door graph (stored ``door_distances`` from
        :func:`travel_graph` are used when present, else computed).
    min_width : float
        Doors narrower than this (m) are left out.

    Returns
    -------
    networkx.Graph
        Nodes: door IDs with ``x``, ``y`` (midpoint, m), ``width`` (m) and
        ``rooms`` (the two room IDs). Edges join two doors of the same room,
        with ``length`` (m, in-room geodesic travel distance between the
        midpoints) and ``room`` (the room crossed); when two doors share two
        rooms the shorter crossing is kept.
    """
    G = annotated_graph(seg_or_G)
    doors = nx.Graph(min_width=float(min_width))
    for a, b, k, d in G.edges(keys=True, data=True):
        if float(d["width"]) < min_width:
            continue
        doors.add_node(int(d.get("door", k)), x=float(d["x"]), y=float(d["y"]), width=float(d["width"]),
                       rooms=(int(a), int(b)))
    for r, nd in G.nodes(data=True):
        for i, j, L in nd.get("door_distances", ()):
            i, j, L = int(i), int(j), float(L)
            if i in doors and j in doors and (not doors.has_edge(i, j) or doors.edges[i, j]["length"] > L):
                doors.add_edge(i, j, length=L, room=int(r))
    return doors


# --------------------------------------------------------------------------
# Planning
# --------------------------------------------------------------------------

def _is_room_id(v):
    """Whether ``v`` is a room ID (an integer, not a bool)."""
    return isinstance(v, numbers.Integral) and not isinstance(v, bool)


def _coordinate(nd, key) -> float:
    """The room attribute ``key`` of ``nd`` as a float; NaN when the room (of a hand-made graph) lacks it."""
    try:
        return float(nd[key])
    except (KeyError, TypeError, ValueError):
        return float("nan")


def _room_endpoint(room_map, G, r, what):
    """``(room, (x, y), (row, col))`` of room ``r`` as a start or goal: its interior point."""
    if r not in G:
        raise NotInRoomError(f"{what} room {r} does not exist (rooms: "
                             f"{', '.join(str(n) for n in sorted(G.nodes))})")
    nd = G.nodes[r]
    # the room's interior point (a cell of the room, roomgraph.interior_points); a graph without
    # it (written by an older version): the centroid, when it is in the room
    for key in (("interior_x", "interior_y"), ("x", "y")):
        x, y = _coordinate(nd, key[0]), _coordinate(nd, key[1])
        row, col = room_map.cell_at(x, y) if np.isfinite(x) and np.isfinite(y) else (-1, -1)
        if room_map.in_room(row, col, r):
            return r, (x, y), (row, col)
    # centroid outside the room (L shape, ring): nearest cell of the room
    space = RoomSpace(room_map, r, doors=[])
    r0, _, c0, _ = space.win
    rr, cc = np.nonzero(space.mask)
    if rr.size == 0:
        raise NotInRoomError(f"{what} room {r} has no cells")
    i = int(np.argmin((rr + r0 - row) ** 2 + (cc + c0 - col) ** 2))
    row, col = int(rr[i] + r0), int(cc[i] + c0)
    x, y = room_map.grid.pixel_to_world(row, col)
    return r, (float(x), float(y)), (row, col)


def locate_endpoint(room_map: RoomMap, G, v, what: str) -> tuple:
    """The room, point and cell of a route's start or goal.

    Parameters
    ----------
    room_map : RoomMap
        The rooms of ``G`` (:class:`topomap.core.roommap.RoomMap`).
    G : networkx.MultiGraph
        The room graph.
    v : (float, float) or int
        A map-frame point ``(x, y)`` in metres, or a room ID (its interior
        point, see :func:`plan_path`).
    what : str
        What ``v`` is (``"start"``, ``"goal"``, ...), for the error messages.

    Returns
    -------
    tuple
        ``(room, (x, y), (row, col))``.

    Raises
    ------
    NotInRoomError
        An unknown room ID, a room without cells, or a point off the map or
        on no room.
    PlanningError
        ``v`` is neither a point nor a room ID, or not finite.
    """
    if _is_room_id(v):
        return _room_endpoint(room_map, G, int(v), what)
    try:
        x, y = (float(t) for t in v)
    except (TypeError, ValueError):
        raise PlanningError(f"{what} must be (x, y) in metres or a room ID, got {v!r}") from None
    if not (np.isfinite(x) and np.isfinite(y)):
        raise PlanningError(f"{what} must be finite, got ({x}, {y})")
    row, col = room_map.cell_at(x, y)
    H, W = room_map.shape
    if not (0 <= row < H and 0 <= col < W):
        raise NotInRoomError(f"{what} ({x:g}, {y:g}) m is outside the map")
    r = room_map.label_at_pixel(row, col)
    if r == 0:
        raise NotInRoomError(f"{what} ({x:g}, {y:g}) m is not in the free space of any room")
    return r, (x, y), (row, col)


def attach_to_doors(room_map: RoomMap, graph: nx.Graph, node, room: int, cell):
    """Join ``node`` of a door graph to the doors of its room by in-room legs.

    Parameters
    ----------
    room_map : RoomMap
        The rooms and doors (:class:`topomap.core.roommap.RoomMap`).
    graph : networkx.Graph
        A door graph (:func:`door_graph`) holding ``node``; the edges from
        ``node`` to the doors of ``room`` that are in it are added, with
        ``length`` (m, the geodesic through the room) and ``room``.
    node : hashable
        The node to join.
    room : int
        The room the node is in.
    cell : (int, int)
        The node's cell ``(row, col)``.

    Returns
    -------
    RoomSpace or None
        The room's traversable cells (to measure more legs in the same
        room), or None when ``cell`` is not one of them (no edge added).
    """
    doors = [d for d in room_map.doors_of(room) if d in graph]
    space = RoomSpace(room_map, room, doors=doors)
    src = space.local(*cell)
    if src is None:
        return None
    reach = [d for d in doors if d in space.door_px]
    for d, L in zip(reach, space.distances(src, [space.door_px[d] for d in reach])):
        if np.isfinite(L):
            graph.add_edge(node, d, length=L, room=room)
    return space


def plan_path(seg_or_G, start, goal, *, robot_width: float = 0.0) -> dict:
    """Plan a route from ``start`` to ``goal`` through rooms and doors.

    Edge costs are real travel distances through free space (see the module
    notes); the route minimises the total length with Dijkstra on the door
    graph plus the start and the goal.

    Parameters
    ----------
    seg_or_G : Segmentation or networkx.MultiGraph
        A segmentation, or a room–door graph (best one annotated by
        :func:`travel_graph`, such as ``rooms.graphml``/``rooms.json`` written
        by ``topomap segment``, so door-to-door distances are not recomputed).
    start, goal : (float, float) or int
        A map-frame point ``(x, y)`` in metres, or a room ID; a room stands
        for its interior point (node attributes ``interior_x``,
        ``interior_y``: a cell of the room as far from its edge as any; for
        a graph without them, the centroid, or the room's cell nearest to it
        when the centroid lies outside the room).
    robot_width : float
        Doors narrower than this (m) are not used.

    Returns
    -------
    dict
        ``rooms`` (list of int): the rooms passed, from the start room to
        the goal room; ``doors`` (list of int): the doors passed, in order;
        ``waypoints`` ((K, 2) ndarray, m): the start, the door midpoints and
        the goal; ``length`` (float, m): travel distance through free space;
        ``legs`` (list of float, m): the length of each piece between two
        waypoints; ``start_room``, ``goal_room`` (int).

    Raises
    ------
    NotInRoomError
        The start or goal is outside the map, not on a room's free cell, or
        an unknown room ID.
    NoPathError
        The goal cannot be reached (separated by walls, or every connecting
        door is narrower than ``robot_width``).
    """
    try:
        robot_width = float(robot_width)
    except (TypeError, ValueError):
        raise PlanningError(f"robot_width must be a width in metres, got {robot_width!r}") from None
    if not np.isfinite(robot_width) or robot_width < 0:
        raise PlanningError(f"robot_width must be >= 0 m, got {robot_width!r}")
    room_map = RoomMap(seg_or_G)
    G = annotated_graph(seg_or_G)
    rs, ps, pxs = locate_endpoint(room_map, G, start, "start")
    rg, pg, pxg = locate_endpoint(room_map, G, goal, "goal")
    travel = door_graph(G, min_width=robot_width)
    start_node, goal_node = ("start",), ("goal",)
    travel.add_node(start_node)
    travel.add_node(goal_node)
    same = rs == rg
    for r, p, node in ((rs, pxs, start_node), (rg, pxg, goal_node)):
        space = attach_to_doors(room_map, travel, node, r, p)
        if same and node is start_node and space is not None:
            q = space.local(*pxg)
            if q is not None:
                (L,) = space.distances(space.local(*p), [q])
                if np.isfinite(L):
                    travel.add_edge(start_node, goal_node, length=L, room=r)
    try:
        length, path = nx.single_source_dijkstra(travel, start_node, goal_node, weight="length")
    except nx.NetworkXNoPath:
        why = f" with doors at least {robot_width:g} m wide" if robot_width > 0 else ""
        raise NoPathError(f"no path from room {rs} ({ps[0]:g}, {ps[1]:g}) to room {rg} "
                          f"({pg[0]:g}, {pg[1]:g}){why}") from None
    doors = [int(n) for n in path[1:-1]]
    rooms = [int(travel.edges[u, v]["room"]) for u, v in zip(path[:-1], path[1:])]
    legs = [float(travel.edges[u, v]["length"]) for u, v in zip(path[:-1], path[1:])]
    pts = [ps] + [room_map.doors[d][5] for d in doors] + [pg]
    return {"rooms": rooms, "doors": doors, "waypoints": np.asarray(pts, float).reshape(-1, 2),
            "length": float(length), "legs": legs, "start_room": rs, "goal_room": rg}
