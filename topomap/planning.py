"""Queries and topological path planning on the room–door graph.

Stateless functions in the style of networkx: the graph (or segmentation)
comes first. Every function that takes ``seg_or_G`` accepts either a
:class:`~topomap.segmentation.Segmentation` or a room–door graph as built by
:func:`topomap.roomgraph.room_graph` (also one loaded back with
:func:`topomap.export.load_graphml` / :func:`~topomap.export.load_json` /
:func:`~topomap.export.load_geojson`). A graph carries everything planning
needs: room polygons that follow cell edges exactly (so the room cells are
recovered by rasterising them at the graph's ``resolution``, ``origin`` and
``shape``), doors with their end points, and, once :func:`travel_graph` has
annotated it, the in-room door-to-door travel distances.

Room IDs
--------
Room IDs are the labels ``1..N`` of the label image and are deterministic:
:func:`topomap.rooms.relabel_sequential` numbers rooms in order of their
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
computed on a coarse grid, so that a room with many doors costs little:

* the room's window (its bounding box with its doors) is cut into blocks of
  ``f`` x ``f`` cells, ``f`` = :data:`TRAVEL_CELL` / resolution (4 at
  0.05 m/px; 1, i.e. the map's grid, for windows of at most
  :data:`EXACT_CELLS` cells);
* a node is one connected piece of the room's cells inside one block (so a
  wall or a piece of furniture inside a block is never crossed), placed at
  the piece's centroid; two pieces are joined when any of their cells are
  8-neighbours, with the octile distance between their centroids; each door
  cell is joined to the pieces around it;
* Dijkstra (:func:`scipy.sparse.csgraph.dijkstra`) from every door that
  has a pair out of sight (below) gives those pairs at once; a room whose
  doors all see each other needs no search;
* two doors in sight of each other (the digital straight line between
  their cells runs on the room's cells only) get their octile distance,
  which is then exactly the map-grid geodesic;
* other pairs closer than :data:`REFINE_CELLS` coarse cells (3.2 m at 0.05 m/px)
  are measured again exactly on the map's grid, in a window around the two
  doors large enough to hold every path not much longer than the coarse
  one.

On the 28 images of the ipa benchmark this stays within 5.5 % of the
map-grid geodesic for every door pair (mean +0.5 %, 95 % of the pairs within
1.5 %; ``benchmarks/travel_accuracy.py`` measures it) at a small fraction of
its cost. ``exact=True`` gives the map-grid geodesic for every pair (one
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

from .errors import NoPathError, NotInRoomError, PlanningError  # noqa: F401  (re-exported)
from ._fast import lookup
from .geometry import line_pixels

__all__ = ["PlanningError", "NotInRoomError", "NoPathError", "room_at", "neighbors", "doors_between",
           "room_distances", "travel_graph", "door_graph", "plan_path"]


# --------------------------------------------------------------------------
# Context: labels and frame of a segmentation or a room graph
# --------------------------------------------------------------------------

#: Offset (px) of the point at which a cell is tested against room polygons.
#: Room outlines (:func:`topomap.roomgraph.room_polygons`) run along cell
#: edges on the top/left side of a room and may run through the cell centres
#: on its bottom/right side; a point a quarter cell up and left of the centre
#: is inside every cell of the room under either convention and outside the
#: cells of its neighbours, so rasterising the polygons gives back the label
#: image exactly (checked by the tests for every segmentation method).
_PROBE = -0.25


class _Ctx:
    """Room cells, doors and the pixel <-> metre frame of ``seg_or_G``."""

    def __init__(self, seg_or_G):
        from .io import OccupancyGrid

        if isinstance(seg_or_G, nx.Graph):
            G = seg_or_G
            self.seg = None
            try:
                shape = tuple(int(v) for v in G.graph["shape"])
                res = float(G.graph["resolution"])
                origin = tuple(float(v) for v in G.graph["origin"])
            except (KeyError, TypeError, ValueError):
                raise PlanningError("room graph lacks the map frame (graph attributes 'shape', 'resolution', "
                                    "'origin'); build it with topomap.room_graph or load it with "
                                    "topomap.export.load_graph") from None
            # frame only: a read-only all-zero view of the map's shape (no memory)
            self.grid = OccupancyGrid(np.broadcast_to(np.int8(0), shape), res, origin)
        elif hasattr(seg_or_G, "labels") and hasattr(seg_or_G, "grid"):
            self.seg = seg_or_G
            G = seg_or_G.room_graph
            self.grid = seg_or_G.grid
        else:
            raise PlanningError(f"expected a Segmentation or a room graph, got {type(seg_or_G).__name__}")
        self.G = G
        self.shape = tuple(self.grid.shape)
        self.res = self.grid.resolution
        self.doors = {}  # id -> (a, b, p1, p2, width, (x, y))
        for a, b, k, d in G.edges(keys=True, data=True):
            try:
                did = int(d.get("door", k))
                p1 = tuple(float(v) for v in d["p1"])
                p2 = tuple(float(v) for v in d["p2"])
                self.doors[did] = (int(a), int(b), p1, p2, float(d["width"]), (float(d["x"]), float(d["y"])))
                if len(p1) != 2 or len(p2) != 2:
                    raise ValueError("p1 and p2 must be (row, col)")
            except KeyError as exc:
                raise PlanningError(f"room graph: door {a}-{b} lacks the attribute {exc.args[0]!r} (doors need "
                                    "p1, p2, width, x, y)") from None
            except (TypeError, ValueError) as exc:
                raise PlanningError(f"room graph: door {a}-{b} has a bad attribute: {exc}") from None
        self._of = {}  # room -> its door IDs, ascending
        for did in sorted(self.doors):
            a, b = self.doors[did][:2]
            for r in {a, b}:
                self._of.setdefault(r, []).append(did)
        self._bbox = None
        self._cells = {}  # door -> its cells (door_cells)

    # -- rooms ------------------------------------------------------------
    def room_bbox(self, r):
        """(r0, r1, c0, c1) half-open pixel box of room ``r``'s cells."""
        if self.seg is not None:
            if self._bbox is None:
                from .roomgraph import _BOXES

                # the boxes room_graph found for these labels (rooms 1..N: the same as the labels' own)
                ref, boxes = _BOXES.get(self.G, (lambda: None, None))
                if ref() is self.seg.labels:
                    self._bbox = boxes
                else:
                    from scipy import ndimage as ndi

                    self._bbox = ndi.find_objects(self.seg.labels)
            sl = self._bbox[r - 1] if 0 < r <= len(self._bbox) else None
            if sl is None:
                return None
            return sl[0].start, sl[0].stop, sl[1].start, sl[1].stop
        poly = self.G.nodes[r].get("polygon")
        if poly is None or poly.is_empty:
            return None
        x0, y0, x1, y1 = poly.bounds
        rows, cols = self.grid.world_to_pixel(np.array([x0, x0, x1, x1]), np.array([y0, y1, y0, y1]))
        H, W = self.shape
        r0 = max(int(np.floor(rows.min())), 0)
        c0 = max(int(np.floor(cols.min())), 0)
        r1 = min(int(np.ceil(rows.max())) + 1, H)
        c1 = min(int(np.ceil(cols.max())) + 1, W)
        return r0, r1, c0, c1

    def window_labels(self, rooms, win):
        """Labels of ``rooms`` (others 0) in the window ``(r0, r1, c0, c1)``."""
        r0, r1, c0, c1 = win
        if self.seg is not None:
            L = self.seg.labels[r0:r1, c0:c1]
            if L.size == 0 or L.min() < 0:
                return np.where(np.isin(L, list(rooms)), L, 0).astype(np.int32)
            keep = np.zeros(int(L.max()) + 1, np.int32)  # label -> itself for the rooms kept, else 0
            idx = np.array([r for r in rooms if 0 <= r < len(keep)], np.intp)
            keep[idx] = idx
            return lookup(keep, L)
        import shapely

        out = np.zeros((r1 - r0, c1 - c0), np.int32)
        rr, cc = np.mgrid[r0:r1, c0:c1]
        xs, ys = self.grid.pixel_to_world(rr + _PROBE, cc + _PROBE)
        for r in rooms:
            poly = self.G.nodes[r].get("polygon")
            if poly is None or poly.is_empty:
                continue
            inside = shapely.contains_xy(poly, xs, ys)
            out[inside & (out == 0)] = r
        return out

    def labels_in(self, win):
        """The label image (every room) in the window ``(r0, r1, c0, c1)`` (a view for a segmentation)."""
        r0, r1, c0, c1 = win
        if self.seg is not None:
            return self.seg.labels[r0:r1, c0:c1]
        rooms = []
        for r in self.G.nodes:
            b = self.room_bbox(r)
            if b is not None and b[0] < r1 and b[1] > r0 and b[2] < c1 and b[3] > c0:
                rooms.append(r)
        return self.window_labels(rooms, win)

    def window_room(self, r, rooms, win):
        """The cells of room ``r`` in the window ``(r0, r1, c0, c1)`` (a new bool array) and a test
        ``(rows, cols) -> bool array``: window cells on one of ``rooms``."""
        if self.seg is None:
            L = self.window_labels(rooms, win)
            return L == r, lambda rr, cc: L[rr, cc] > 0
        r0, r1, c0, c1 = win
        L = self.seg.labels[r0:r1, c0:c1]  # a view: one pass for the room's cells, none for the others
        ids = np.array(sorted(rooms))
        return L == r, lambda rr, cc: np.isin(L[rr, cc], ids)

    def label_at_pixel(self, row, col):
        H, W = self.shape
        if not (0 <= row < H and 0 <= col < W):
            return 0
        if self.seg is not None:
            return int(self.seg.labels[row, col])
        import shapely

        x, y = self.grid.pixel_to_world(row + _PROBE, col + _PROBE)
        for r, d in self.G.nodes(data=True):
            poly = d.get("polygon")
            if poly is not None and not poly.is_empty and shapely.contains_xy(poly, float(x), float(y)):
                return int(r)
        return 0

    def doors_of(self, r):
        return list(self._of.get(r, ()))

    def door_cells(self, did):
        """The cells of door ``did``'s segment (:func:`topomap.geometry.line_pixels`; drawn once)."""
        cells = self._cells.get(did)
        if cells is None:
            _, _, p1, p2, _, _ = self.doors[did]
            cells = self._cells[did] = line_pixels(p1, p2, self.shape)
        return cells


def _pixel(ctx, x, y):
    r, c = ctx.grid.world_to_pixel(x, y)
    return int(np.rint(r)), int(np.rint(c))


class _RoomSpace:
    """Traversable cells of one room (its cells plus its doors' cells) and its door cells."""

    def __init__(self, ctx: _Ctx, r: int, doors=None):
        self.ctx, self.r = ctx, r
        doors = ctx.doors_of(r) if doors is None else doors
        self.win = _room_window(ctx, r, doors)
        if self.win is None:
            self.win, self.mask, self.door_px = (0, 0, 0, 0), np.zeros((0, 0), bool), {}
            return
        r0, r1, c0, c1 = self.win
        rooms = {r} | {x for d in doors for x in ctx.doors[d][:2]}
        mask, on_rooms = ctx.window_room(r, rooms, self.win)
        self.door_px = {}
        for d, (rr, cc, (pr, pc)) in _door_cells_on(ctx, doors, lambda rr, cc: on_rooms(rr - r0, cc - c0)).items():
            mask[rr - r0, cc - c0] = True
            self.door_px[d] = (pr - r0, pc - c0)
        self.mask = mask

    def local(self, row, col):
        r0, r1, c0, c1 = self.win
        if r0 <= row < r1 and c0 <= col < c1 and self.mask[row - r0, col - c0]:
            return row - r0, col - c0
        return None

    def distances(self, src, targets):
        """Geodesic distances (m) from local pixel ``src`` to local pixels ``targets`` (inf if unreachable)."""
        if not targets:
            return []
        cum = _mcp_costs(self.mask, [src], targets)
        return [float(cum[t]) * self.ctx.res for t in targets]

    def door_distances(self):
        """``{(door_i, door_j): metres}`` between this room's doors (``i < j``, reachable pairs only):
        the 8-connected geodesic on the map's grid, one search per door."""
        ids = sorted(self.door_px)
        out = {}
        for i, di in enumerate(ids[:-1]):
            rest = ids[i + 1:]
            for dj, L in zip(rest, self.distances(self.door_px[di], [self.door_px[d] for d in rest])):
                if np.isfinite(L):
                    out[(di, dj)] = L
        return out


def _room_window(ctx, r, doors):
    """The half-open box ``(r0, r1, c0, c1)`` of room ``r``'s cells and the cells of ``doors``, one
    cell around, clipped to the map (None: no cells)."""
    H, W = ctx.shape
    box = ctx.room_bbox(r)
    rows = [box[0], box[1] - 1] if box else []
    cols = [box[2], box[3] - 1] if box else []
    for d in doors:
        rr, cc = ctx.door_cells(d)
        rows += [rr.min(), rr.max()]
        cols += [cc.min(), cc.max()]
    if not rows:
        return None
    return (max(int(min(rows)) - 1, 0), min(int(max(rows)) + 2, H),
            max(int(min(cols)) - 1, 0), min(int(max(cols)) + 2, W))


def _door_cells_on(ctx, doors, on):
    """``{door: (rows, cols, (row, col))}``: the cells of each door's segment where ``on(rows, cols)``
    (map pixels) and, of these, the one closest to the door's midpoint (doors with none left out)."""
    out = {}
    for d in doors:
        rr, cc = ctx.door_cells(d)
        ok = on(rr, cc)
        if not ok.any():
            continue
        rr, cc = rr[ok], cc[ok]
        _, _, p1, p2, _, _ = ctx.doors[d]
        mr, mc = (p1[0] + p2[0]) / 2, (p1[1] + p2[1]) / 2
        i = int(np.argmin((rr - mr) ** 2 + (cc - mc) ** 2))
        out[d] = (rr, cc, (int(rr[i]), int(cc[i])))
    return out


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


def _block_components(mask, f, *, with_full=False):
    """Connected pieces of ``mask`` inside each ``f`` x ``f`` block.

    Returns labels ``1..n`` (0 off the mask), ``n`` and the (n + 1, 2)
    ``(row, col)`` centroids of the pieces (row 0 unused); with
    ``with_full``, also the (H, W) bool grid of the blocks wholly on the
    mask. A block wholly on the mask is one piece, centred in the block;
    the blocks partly on it are labelled side by side in one strip, one
    empty cell apart, so pieces never join across blocks. A piece's
    centroid is the mean of its cells either way.
    """
    import cv2

    h, w = mask.shape
    H, W = -(-h // f), -(-w // f)
    if (h, w) == (H * f, W * f) and mask.dtype == bool and mask.flags.c_contiguous:
        m = mask
    else:
        m = np.zeros((H * f, W * f), bool)
        m[:h, :w] = mask
    blocks = m.reshape(H, f, W, f)
    full = ~_block_any(~m, f)
    R, C = np.nonzero(_block_any(m, f) & ~full)
    FR, FC = np.nonzero(full)
    lab = np.zeros((H * f, W * f), np.int32)
    K = R.size
    n, cen = 0, np.zeros((1, 2))
    if K:
        strip = np.zeros((f, K, f + 1), np.uint8)
        strip[:, :, :f] = blocks.transpose(1, 0, 2, 3)[:, R, C]
        n, slab, stats, scen = cv2.connectedComponentsWithStats(strip.reshape(f, K * (f + 1)), connectivity=8,
                                                                ltype=cv2.CV_32S)
        n -= 1
        blab = slab.reshape(f, K, f + 1)[:, :, :f]  # (f, K, f): row in block, block, column in block
        lab.reshape(H, f, W, f).transpose(1, 0, 2, 3)[:, R, C] = blab
        # the centroids OpenCV gives on the strip (each coordinate's sum over the piece / its area),
        # moved onto the window's cells: the sums are integers, exact from the centroids
        area = stats[:, cv2.CC_STAT_AREA].astype(float)
        area[0] = 1
        k = stats[:, cv2.CC_STAT_LEFT] // (f + 1)  # each piece's block on the strip
        sr = np.rint(scen[:, 1] * area) + area * (R[k] * (f + 1))
        sc = np.rint(scen[:, 0] * area) + area * ((C[k] - k) * (f + 1))
        cen = np.stack([sr / area, sc / area], 1)
        cen[0] = 0
        cen = cen - np.floor(cen / (f + 1))
    if FR.size:  # a block wholly on the mask: one piece, at the block's centre
        ids = np.arange(n + 1, n + 1 + FR.size, dtype=np.int32)
        lab.reshape(H, f, W, f)[FR, :, FC, :] = ids[:, None, None]
        cen = np.concatenate([cen, np.stack([FR * f + (f - 1) / 2, FC * f + (f - 1) / 2], 1)])
        n += FR.size
    out = (lab[:h, :w], n, cen)
    return out + (full,) if with_full else out


def _merged_nodes(full, lab, n, cen, f):
    """Merge each aligned 2 x 2 group of blocks inside open floor into one node.

    A group of 2 x 2 blocks (aligned on even block rows and columns) is
    merged when its blocks and the ring of blocks around them are all fully
    free cells of one room, so paths along walls, around furniture and into
    doors keep the blocks' own pieces, and only open floor is crossed on the
    coarser grid.

    Parameters
    ----------
    full : (H, W) int ndarray
        The room of each block whose cells are all one piece of that room; 0 for the others.
    lab, n, cen
        The block pieces (:func:`_block_components`; ``lab`` covers the ``H`` x ``W`` blocks).
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
    H, W = full.shape
    if H < 4 or W < 4:
        return node, cen
    pad = np.zeros((H + 2, W + 2), full.dtype)  # blocks out of the window are not free
    pad[1:-1, 1:-1] = full
    inner = full > 0  # full, with its 8 neighbours full of the same room
    for dr in (0, 1, 2):
        for dc in (0, 1, 2):
            inner &= pad[dr:dr + H, dc:dc + W] == full
    H2, W2 = H // 2, W // 2
    GR, GC = np.nonzero(inner[:2 * H2, :2 * W2].reshape(H2, 2, W2, 2).all(axis=(1, 3)))
    if GR.size == 0:
        return node, cen
    # a full block holds one piece; the group's pieces become the first one's node, at the group's centre
    members = lab[:2 * H2 * f:f, :2 * W2 * f:f].reshape(H2, 2, W2, 2)[GR, :, GC, :].reshape(GR.size, 4)
    node[members] = members[:, :1]
    cen = cen.copy()
    cen[members[:, 0]] = np.stack([(GR + 0.5) * 2 * f - 0.5, (GC + 0.5) * 2 * f - 0.5], 1)
    used = node == np.arange(n + 1)  # the nodes kept: renumbered in order
    return (np.cumsum(used) - 1)[node], cen[used]


def _block_reduce(a, f, op):
    """(H, W): ``op`` (a ufunc, e.g. :data:`numpy.maximum`) over each ``f`` x ``f`` block of ``a``
    ((H f, W f), C-contiguous): over the rows of each block first, then along them."""
    Hf, Wf = a.shape
    H, W = Hf // f, Wf // f
    rows = op.reduce(a.reshape(H, f, Wf), axis=1)
    return op.reduce(rows.reshape(H, W, f), axis=2)


def _block_any(m, f):
    """(H, W) bool: the ``f`` x ``f`` blocks of ``m`` ((H f, W f) bool, C-contiguous) holding a True cell.

    The rows of each block OR-ed together, then each block's ``f`` bytes read as one integer
    when ``f`` is 1, 2, 4 or 8 (numpy's ``any`` over two axes of a 4-D view is 50 times slower).
    """
    Hf, Wf = m.shape
    H, W = Hf // f, Wf // f
    rows = np.bitwise_or.reduce(m.view(np.uint8).reshape(H, f, Wf), axis=1)  # (H, W f)
    if f in (1, 2, 4, 8):
        return rows.view(np.dtype(f"u{f}")).reshape(H, W) > 0
    return rows.reshape(H, W, f).any(axis=2)


def _touching(a, b):
    """Label pairs of 8-adjacent cells, ``a`` the row above ``b`` (0 = no cell).

    Returns two arrays ``(x, y)``: ``x`` the label in ``a``, ``y`` the one in
    ``b`` (different, both nonzero), in order along the rows, the three cells
    of ``a`` next to each cell of ``b`` together, with runs of the same pair
    (a block edge between two pieces) kept once.
    """
    rows, w = a.shape
    A3 = np.zeros((rows, w, 3), a.dtype)  # the cells up-left, up and up-right of each cell of b
    A3[:, 1:, 0] = a[:, :-1]
    A3[:, :, 1] = a
    A3[:, :-1, 2] = a[:, 1:]
    B3 = np.broadcast_to(b[:, :, None], A3.shape)
    ok = (A3 != B3) & (A3 > 0) & (B3 > 0)
    x, y = A3[ok], B3[ok]
    keep = np.ones(len(x), bool)
    keep[1:] = (x[1:] != x[:-1]) | (y[1:] != y[:-1])
    return x[keep], y[keep]


class _MapTravel:
    """The coarse travel graph of several rooms at once, built in one pass over their window.

    Parameters
    ----------
    ctx : _Ctx
    rooms : iterable of int
        The rooms to measure (each with at least two doors).
    f : int
        Block side (cells), :func:`_coarse_factor`.

    Notes
    -----
    The window (the rooms' boxes with their doors, one cell around) is
    aligned on the map's grid of ``f`` x ``f`` blocks, so a room's graph does
    not depend on which other rooms are measured with it. In every block:

    * a block holding cells of two rooms is *mixed*; its cells with an
      8-neighbour of another room inside the block are nodes on their own;
    * the other cells of a block form its pieces (8-connected, of one room
      each, :func:`_block_components`), nodes at their centroids; aligned 2 x 2
      groups of open floor are merged (:func:`_merged_nodes`);
    * a door's cells that belong to the other room it joins (or to a room
      another door of the room joins) are nodes of the room on their own.

    Two nodes of the same room are joined when any of their cells are
    8-neighbours, by the octile distance between their positions; each door
    cell by the octile distance to the nodes of the room in its 3 x 3
    neighbourhood. Nodes are numbered room by room, so each room's graph is
    a slice of one sparse matrix.
    """

    def __init__(self, ctx, rooms, f):
        self.ctx, self.f = ctx, f
        rooms = sorted(set(int(r) for r in rooms))
        H, W = ctx.shape
        boxes = []
        for r in rooms:
            box = ctx.room_bbox(r)
            rows, cols = ([box[0], box[1] - 1], [box[2], box[3] - 1]) if box else ([], [])
            for d in ctx.doors_of(r):
                rr, cc = ctx.door_cells(d)
                rows += [rr.min(), rr.max()]
                cols += [cc.min(), cc.max()]
            if rows:
                boxes.append((min(rows) - 1, max(rows) + 2, min(cols) - 1, max(cols) + 2))
        self.rooms, self.px, self.extra = rooms, {}, {}
        if not boxes:
            self.win, self.L = (0, 0, 0, 0), np.zeros((0, 0), np.int32)
            return
        b = np.array(boxes)
        r0, c0 = max(int(b[:, 0].min()) // f * f, 0), max(int(b[:, 2].min()) // f * f, 0)
        r1, c1 = min(-(-int(b[:, 1].max()) // f) * f, H), min(-(-int(b[:, 3].max()) // f) * f, W)
        self.win = (r0, r1, c0, c1)
        L = np.asarray(ctx.labels_in(self.win))
        if L.size and L.min() < 0:
            L = np.where(L > 0, L, 0)
        self.L = L = L.astype(np.int32, copy=False)
        h, w = L.shape
        # the doors of each room: their cells on the room or on a room one of its doors joins
        singles = []  # (room, row, col): cells that are nodes on their own
        side_r, side_d, allowed = [], [], []
        for r in rooms:
            doors = ctx.doors_of(r)
            side_r += [r] * len(doors)
            side_d += doors
            allowed += [(r, x) for x in {r} | {x for d in doors for x in ctx.doors[d][:2]}]
        lines = [ctx.door_cells(d) for d in side_d]
        n_at = np.array([len(rr) for rr, _ in lines])
        side = np.repeat(np.arange(len(side_d)), n_at)
        rr = np.concatenate([rr for rr, _ in lines]) - r0
        cc = np.concatenate([cc for _, cc in lines]) - c0
        sr = np.array(side_r, np.int64)[side]
        lab_at = L[rr, cc].astype(np.int64)
        K = int(max(L.max(), max(rooms))) + 1
        ok = np.isin(sr * K + lab_at, np.array([a * K + b for a, b in allowed], np.int64))
        side, sr, rr, cc, lab_at = side[ok], sr[ok], rr[ok], cc[ok], lab_at[ok]
        mid = np.array([[(ctx.doors[d][2][0] + ctx.doors[d][3][0]) / 2 - r0,
                         (ctx.doors[d][2][1] + ctx.doors[d][3][1]) / 2 - c0] for d in side_d]).reshape(-1, 2)
        dist = (rr - mid[side, 0]) ** 2 + (cc - mid[side, 1]) ** 2
        # each side's cell closest to the door's midpoint (the first of equals along the segment)
        order = np.lexsort((np.arange(len(side)), dist, side))
        first = order[np.concatenate([[True], side[order][1:] != side[order][:-1]])] if len(order) else order
        for t in first:
            self.px.setdefault(side_r[side[t]], {})[side_d[side[t]]] = (int(rr[t]), int(cc[t]))
        other = lab_at != sr  # door cells of another room: nodes of this room on their own
        xkey = np.unique(sr[other] * (h * w) + rr[other] * w + cc[other])
        xr_, xflat = xkey // (h * w), xkey % (h * w)
        for r in rooms:
            self.px.setdefault(r, {})
            lo, hi = np.searchsorted(xr_, [r, r + 1])
            self.extra[r] = xflat[lo:hi]
        singles.append(np.stack([xr_, xflat // w, xflat % w], 1))
        # blocks: the labels padded to whole blocks; mixed blocks and their cells next to another room
        Hb, Wb = -(-h // f), -(-w // f)
        Lp = np.zeros((Hb * f, Wb * f), np.int32)
        Lp[:h, :w] = L
        bmax = _block_reduce(Lp, f, np.maximum)
        bmin = _block_reduce(Lp.view(np.uint32) - np.uint32(1), f, np.minimum).astype(np.int64) + 1
        mixed = (bmax > 0) & (bmin < bmax)  # (bmin of a block without free cells wraps to 0)
        pick = np.zeros(K, np.uint8)  # the rooms measured
        pick[rooms] = 1
        m = lookup(pick, Lp).view(bool) if Lp.size else np.zeros(Lp.shape, bool)
        MR, MC = np.nonzero(mixed)
        if MR.size:
            S = Lp.reshape(Hb, f, Wb, f)[MR, :, MC, :]  # (K, f, f)
            P = np.zeros((len(MR), f + 2, f + 2), np.int32)
            P[:, 1:-1, 1:-1] = S
            edge = np.zeros(S.shape, bool)
            for dr in (0, 1, 2):
                for dc in (0, 1, 2):
                    nb = P[:, dr:dr + f, dc:dc + f]
                    edge |= (nb > 0) & (nb != S)
            edge &= pick[S].view(bool)
            k, i, j = np.nonzero(edge)
            er, ec = MR[k] * f + i, MC[k] * f + j
            m[er, ec] = False
            singles.append(np.stack([Lp[er, ec], er, ec], 1))
        lab, n, cen, whole = _block_components(m, f, with_full=True)
        proom = np.zeros(n + 1, np.int64)  # the room of every piece
        br = np.clip(np.floor(cen[1:, 0] / f).astype(np.int64), 0, Hb - 1)
        bc = np.clip(np.floor(cen[1:, 1] / f).astype(np.int64), 0, Wb - 1)
        proom[1:] = bmax[br, bc]
        if MR.size:
            ml = lab.reshape(Hb, f, Wb, f)[MR, :, MC, :]
            on = ml > 0
            proom[ml[on]] = S[on]
        # pieces touching across block edges (of one room), then open floor merged
        nb_ = len(lab[f::f])
        x1, y1 = _touching(lab[f - 1::f][:nb_], lab[f::f])
        right = np.ascontiguousarray(lab[:, f::f].T)  # the columns at the blocks' edges, as rows
        left = np.ascontiguousarray(lab[:, f - 1::f][:, :len(right)].T)
        x2, y2 = _touching(left, right)
        eu, ev = np.concatenate([x1, x2]), np.concatenate([y1, y2])
        same = proom[eu] == proom[ev]
        full = np.where(whole, bmax, 0) if f > 1 else np.zeros((Hb, Wb), np.int32)
        node, cen = _merged_nodes(full, lab, n, cen, f)
        nroom = np.zeros(len(cen), np.int64)
        nroom[node] = proom
        us, vs = [node[eu[same]]], [node[ev[same]]]
        npc = len(cen)  # merged pieces 0..npc-1 (0 unused)
        # single cells, then the door cells
        Sg = np.concatenate(singles).astype(np.int64)
        skey = Sg[:, 0] * (h * w) + Sg[:, 1] * w + Sg[:, 2]
        o = np.argsort(skey)
        skey = skey[o]
        firsts = np.concatenate([[True], skey[1:] != skey[:-1]]) if len(skey) else np.zeros(0, bool)
        skey, Sg = skey[firsts], Sg[o][firsts]
        ids = [(r, d) for r in rooms for d in sorted(self.px[r])]
        Pt = np.array([(r,) + self.px[r][d] for r, d in ids], np.int64).reshape(-1, 3)
        ns, nq = len(Sg), len(Pt)
        pos = np.concatenate([cen, Sg[:, 1:].astype(float), Pt[:, 1:].astype(float)])
        room_of = np.concatenate([nroom, Sg[:, 0], Pt[:, 0]])

        def around(src, R, rr, cc, offsets):
            """Join nodes ``src`` (of rooms ``R``, at cells ``rr, cc``) to the nodes of their rooms at
            the cells ``offsets`` away: the pieces there, and the single cells."""
            for dr, dc in offsets:
                qr, qc = rr + dr, cc + dc
                ok = (qr >= 0) & (qr < h) & (qc >= 0) & (qc < w)
                s_, R_, qr, qc = src[ok], R[ok], qr[ok], qc[ok]
                t = lab[qr, qc]
                hit = (t > 0) & (proom[t] == R_)
                us.append(s_[hit])
                vs.append(node[t[hit]])
                if len(skey):
                    key = R_ * (h * w) + qr * w + qc
                    at = np.minimum(np.searchsorted(skey, key), len(skey) - 1)
                    hit = skey[at] == key
                    us.append(s_[hit])
                    vs.append(npc + at[hit])

        ring = [(dr, dc) for dr in (-1, 0, 1) for dc in (-1, 0, 1) if dr or dc]
        around(npc + np.arange(ns), Sg[:, 0], Sg[:, 1], Sg[:, 2], ring)
        around(npc + ns + np.arange(nq), Pt[:, 0], Pt[:, 1], Pt[:, 2], ring + [(0, 0)])
        # number the nodes room by room, then one sparse matrix
        order = np.argsort(room_of[1:] * len(room_of) + np.arange(1, len(room_of))) + 1
        new = np.empty(len(room_of), np.int64)
        new[order] = np.arange(len(order))
        new[0] = -1
        eu, ev = new[np.concatenate(us)], new[np.concatenate(vs)]
        loop = eu != ev
        px, pc = pos[order, 0], pos[order, 1]
        self.A = _symmetric_graph(eu[loop], ev[loop], len(order),
                                  lambda u, v: _octile(px[u] - px[v], pc[u] - pc[v]) + 1e-9)
        rs = room_of[order]
        self.span = {r: (int(np.searchsorted(rs, r)), int(np.searchsorted(rs, r, side="right"))) for r in rooms}
        self.node = {rd: int(new[npc + ns + i]) for i, rd in enumerate(ids)}

    def door_distances(self, r):
        """``{(door_i, door_j): metres}`` between room ``r``'s doors (``i < j``, reachable pairs only)."""
        from scipy.sparse import csr_matrix
        from scipy.sparse.csgraph import dijkstra

        px = self.px.get(r, {})
        ids = sorted(px)
        if len(ids) < 2:
            return {}
        L, f, extra = self.L, self.f, self.extra[r]
        w = L.shape[1]
        pts = np.array([px[d] for d in ids], float)

        def on(rr, cc):
            ok = L[rr, cc] == r
            return ok | np.isin(rr * w + cc, extra) if len(extra) else ok

        def window(r0, r1, c0, c1):
            out = L[r0:r1, c0:c1] == r
            er, ec = extra // w, extra % w
            sel = (er >= r0) & (er < r1) & (ec >= c0) & (ec < c1)
            out[er[sel] - r0, ec[sel] - c0] = True
            return out

        lo, hi = self.span[r]
        A = self.A
        a, b = A.indptr[lo], A.indptr[hi]
        sub = csr_matrix((A.data[a:b], A.indices[a:b] - lo, A.indptr[lo:hi + 1] - a), shape=(hi - lo, hi - lo))
        at = np.array([self.node[(r, d)] - lo for d in ids])

        def search(need):
            out = np.full(need.shape, np.inf)
            for i, targets, limit in _search_plan(need, pts, f):
                got = dijkstra(sub, directed=True, indices=at[i], limit=limit)[at[targets]]
                if np.isinf(got).any():  # beyond the limit (or unreachable): search the whole room
                    got = dijkstra(sub, directed=True, indices=at[i])[at[targets]]
                out[i, targets] = out[targets, i] = got
            return out

        D = _door_pairs(pts, f, on, window, L.shape, search)
        res = self.ctx.res
        return {(ids[i], ids[j]): float(D[i, j]) * res
                for i in range(len(ids)) for j in range(i + 1, len(ids)) if np.isfinite(D[i, j])}


def _symmetric_graph(u, v, m, length):
    """The (m, m) CSR matrix joining both ways each pair ``(u[i], v[i])`` (node indices, repeats
    allowed, no loops) by ``length(u, v)`` (arrays of node indices -> lengths), one entry per pair.

    Searched as a directed graph (:func:`scipy.sparse.csgraph.dijkstra` with ``directed=True``;
    an undirected search scans every node's row and its column).
    """
    from scipy.sparse import csr_matrix

    u, v = np.asarray(u, np.int64), np.asarray(v, np.int64)
    keys = np.concatenate([u * m + v, v * m + u])
    keys.sort()
    if len(keys):
        keys = keys[np.concatenate([[True], keys[1:] != keys[:-1]])]
    u, v = np.divmod(keys, m)
    indptr = np.concatenate([[0], np.cumsum(np.bincount(u, minlength=m))])
    return csr_matrix((length(u, v).astype(float), v.astype(np.int32), indptr.astype(np.int32)), shape=(m, m))


#: A search from a door is stopped beyond this factor times the octile distance to its farthest
#: pair (plus :data:`_LIMIT_CELLS` coarse cells); a pair found beyond it is searched again in the whole room.
_LIMIT_FACTOR = 1.6
_LIMIT_CELLS = 4


def _search_plan(need, pts, f):
    """The searches that give the pairs ``need`` ((k, k) bool, symmetric) of the points ``pts``.

    Each pair is measured from one of its two points: the pairs longest (in octile distance)
    first, each from the end whose search already reaches farther (so a search from a door
    near the middle of a corridor does not run to both ends). Returns ``(i, targets,
    limit)`` triples: a search from point ``i`` up to ``limit`` (cells; :data:`_LIMIT_FACTOR`
    x the octile distance to its farthest target + :data:`_LIMIT_CELLS` ``f``) gives
    ``targets``.
    """
    I, J = np.nonzero(np.triu(need, 1))
    est = _octile(*(pts[I] - pts[J]).T)
    reach = np.full(len(pts), -1.0)
    ecc = np.zeros(len(pts))  # the longest pair of each point: a tie goes to the point with the shorter
    np.maximum.at(ecc, I, est)
    np.maximum.at(ecc, J, est)
    src = np.empty(len(I), np.intp)
    for t in np.argsort(-est, kind="stable"):
        i, j = I[t], J[t]
        s = i if (reach[i], -ecc[i]) >= (reach[j], -ecc[j]) else j
        src[t] = s
        reach[s] = max(reach[s], est[t])
    plan = []
    for s in np.unique(src):
        sel = src == s
        targets = np.where(I[sel] == s, J[sel], I[sel])
        plan.append((int(s), targets, float(_LIMIT_FACTOR * est[sel].max() + _LIMIT_CELLS * f)))
    return plan


#: Slack of the refinement windows: a path up to this factor (plus two coarse cells) longer
#: than the coarse distance still fits in the window.
_WINDOW_SLACK = 1.1


def _in_sight(on, pts):
    """(k, k) bool: the digital straight line between two points runs on traversable cells only.

    ``on(rows, cols)`` tells which cells are traversable (a bool array). The
    line from ``p`` to ``q`` takes ``n = max(|dr|, |dc|)`` steps, step ``t``
    at ``p + round(t (q - p) / n)``: one cell along the longer axis and 0 or
    1 along the other each step, so it is a shortest 8-connected path and the
    map-grid geodesic between two points in sight is exactly their octile
    distance. All pairs are tested together: first :data:`_SIGHT_PROBES`
    cells of each line, then every cell of the lines that passed, in batches
    of at most :data:`_SIGHT_BATCH` cells.
    """
    k = len(pts)
    out = np.zeros((k, k), bool)
    if k < 2:
        return out
    p = np.asarray(pts).astype(np.int64)
    if k <= 3:  # a few pairs: each whole line at once
        for i in range(k - 1):
            for j in range(i + 1, k):
                n = int(np.abs(p[j] - p[i]).max())
                t = np.arange(n + 1)[None, :]
                out[i, j] = out[j, i] = bool(on(*_line_cells(p[i:i + 1], p[j:j + 1], np.array([n]), t)).all())
        return out
    I, J = np.triu_indices(k, 1)
    steps = np.abs(p[J] - p[I]).max(axis=1)
    probe = np.floor(np.linspace(0, 1, _SIGHT_PROBES)[None, :] * steps[:, None] + 0.5).astype(np.int64)
    keep = np.nonzero(on(*_line_cells(p[I], p[J], steps, probe)).all(axis=1))[0]
    ends = np.cumsum(steps[keep] + 1)
    lo = 0
    while lo < len(keep):  # the whole lines of the pairs that passed
        hi = max(int(np.searchsorted(ends, ends[lo] - steps[keep[lo]] - 1 + _SIGHT_BATCH, side="right")), lo + 1)
        b = keep[lo:hi]
        n = steps[b] + 1
        start = np.concatenate([[0], np.cumsum(n)[:-1]])
        pair = np.repeat(np.arange(len(b)), n)
        t = (np.arange(int(n.sum())) - start[pair])[:, None]
        ok = np.logical_and.reduceat(on(*_line_cells(p[I[b]][pair], p[J[b]][pair], steps[b][pair], t))[:, 0], start)
        out[I[b[ok]], J[b[ok]]] = True
        lo = hi
    return out | out.T


def _line_cells(a, b, steps, t):
    """``(rows, cols)``, each (m, s): step ``t`` (m, s) of the lines ``a`` -> ``b`` ((m, 2) ``(row, col)``,
    ``steps`` (m,) = their longer axis' length), as in :func:`_in_sight`."""
    frac = t / np.maximum(steps, 1)[:, None]
    rr = a[:, :1] + np.floor(frac * (b[:, :1] - a[:, :1]) + 0.5).astype(np.int64)
    cc = a[:, 1:] + np.floor(frac * (b[:, 1:] - a[:, 1:]) + 0.5).astype(np.int64)
    return rr, cc


#: Cells of each line (evenly spread, both ends included) :func:`_in_sight` tests before the whole line.
_SIGHT_PROBES = 9
#: Line cells tested at once by :func:`_in_sight`.
_SIGHT_BATCH = 1 << 20


def _windowed_distances(window, shape, pts, i, near, bound, f):
    """Exact distances (cells) from point ``i`` to points ``near``, searched in a window.

    ``window(r0, r1, c0, c1)`` gives the traversable cells (bool) of a window
    of the frame ``shape`` the points ``pts`` are given in. A path of length
    at most ``L`` between two points stays inside the ellipse with the two
    points as foci and ``L`` as the sum of the distances to them, so inside
    their bounding box padded by ``(L - |pq|) / 2``; the window is the union
    of these boxes for ``L`` = :data:`_WINDOW_SLACK` x the coarse distance
    ``bound`` + 2 ``f``. Where the window holds no path, the coarse distance
    is kept.
    """
    p = pts[[i] + list(near)]
    h, w = shape
    L = np.where(np.isfinite(bound), bound, max(h, w) * 2.0) * _WINDOW_SLACK + 2 * f
    pad = np.ceil(np.maximum(L - np.hypot(*(p[1:] - p[0]).T), 0) / 2) + 1
    r0 = max(int(np.min(np.minimum(p[0, 0], p[1:, 0]) - pad)), 0)
    c0 = max(int(np.min(np.minimum(p[0, 1], p[1:, 1]) - pad)), 0)
    r1 = min(int(np.max(np.maximum(p[0, 0], p[1:, 0]) + pad)) + 1, h)
    c1 = min(int(np.max(np.maximum(p[0, 1], p[1:, 1]) + pad)) + 1, w)
    loc = [(int(r) - r0, int(c) - c0) for r, c in p]
    cum = _mcp_costs(window(r0, r1, c0, c1), loc[:1], loc[1:])
    got = np.array([cum[t] for t in loc[1:]], float)
    return np.where(np.isfinite(got), got, bound)


def _door_pairs(pts, f, on, window, shape, search):
    """(k, k) distances (cells) between the door cells ``pts`` ((k, 2) ``(row, col)``) of one room.

    Doors in sight of each other (:func:`_in_sight` with ``on``) get their
    octile distance; ``search(need)`` ((k, k) bool: the pairs out of sight)
    gives the coarse distances of the others; pairs closer than
    :data:`REFINE_CELLS` ``f`` are measured again exactly
    (:func:`_windowed_distances` with ``window``, ``shape``).
    """
    seen = _in_sight(on, pts)
    need = ~seen
    np.fill_diagonal(need, False)
    D = search(need) if need.any() else np.full(seen.shape, np.inf)
    D[seen] = _octile(*(pts[:, None, :] - pts[None, :, :]).transpose(2, 0, 1))[seen]
    short = REFINE_CELLS * f
    for i in range(len(pts)):
        near = [j for j in range(i + 1, len(pts)) if D[i, j] < short and not seen[i, j]]
        if near:
            D[i, near] = _windowed_distances(window, shape, pts, i, near, D[i, near], f)
    return D


# --------------------------------------------------------------------------
# Queries
# --------------------------------------------------------------------------

def _graph(seg_or_G):
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
    ctx = _Ctx(seg_or_G)
    return ctx.label_at_pixel(*_pixel(ctx, x, y))


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
    ctx = _Ctx(seg_or_G)
    if room not in ctx.G:
        raise NotInRoomError(f"no room {room!r} in the graph")
    return _room_distances(ctx, room, exact=exact)


def _room_distances(ctx, room, exact=False):
    if len(ctx.doors_of(room)) < 2:
        return {}
    return _distances(ctx, [room], exact=exact)[room]


def _distances(ctx, rooms, *, exact=False):
    """``{room: {(door_i, door_j): metres}}`` for ``rooms`` (each with at least two doors): the exact
    search for small rooms (or all with ``exact``), one coarse graph (:class:`_MapTravel`) for the others."""
    out, coarse = {}, []
    for r in rooms:
        win = _room_window(ctx, r, ctx.doors_of(r))
        if exact or win is None or (win[1] - win[0]) * (win[3] - win[2]) <= EXACT_CELLS:
            out[r] = _RoomSpace(ctx, r).door_distances()
        else:
            coarse.append(r)
    if coarse:
        travel = _MapTravel(ctx, coarse, _coarse_factor(ctx.res))
        for r in coarse:
            out[r] = travel.door_distances(r)
    return out


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
    ctx = _Ctx(seg_or_G)
    G = ctx.G.copy()
    found = _distances(ctx, [r for r in G.nodes if len(ctx.doors_of(r)) >= 2], exact=exact)
    for r in G.nodes:
        dist = found.get(r, {})
        G.nodes[r]["door_distances"] = tuple((int(i), int(j), float(L)) for (i, j), L in sorted(dist.items()))
    G.graph["travel_distances"] = "geodesic"
    return G


def _annotated(seg_or_G):
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
    G = _annotated(seg_or_G)
    D = nx.Graph(min_width=float(min_width))
    for a, b, k, d in G.edges(keys=True, data=True):
        if float(d["width"]) < min_width:
            continue
        D.add_node(int(d.get("door", k)), x=float(d["x"]), y=float(d["y"]), width=float(d["width"]),
                   rooms=(int(a), int(b)))
    for r, nd in G.nodes(data=True):
        for i, j, L in nd.get("door_distances", ()):
            i, j, L = int(i), int(j), float(L)
            if i in D and j in D and (not D.has_edge(i, j) or D.edges[i, j]["length"] > L):
                D.add_edge(i, j, length=L, room=int(r))
    return D


# --------------------------------------------------------------------------
# Planning
# --------------------------------------------------------------------------

def _is_room_id(v):
    return isinstance(v, numbers.Integral) and not isinstance(v, bool)


def _endpoint(ctx, G, v, what):
    """(room, (x, y), (row, col)) of a start/goal given as a room ID or a point."""
    if _is_room_id(v):
        r = int(v)
        if r not in G:
            raise NotInRoomError(f"{what} room {r} does not exist (rooms: "
                                 f"{', '.join(str(n) for n in sorted(G.nodes))})")
        x, y = float(G.nodes[r]["x"]), float(G.nodes[r]["y"])
        row, col = _pixel(ctx, x, y)
        if ctx.label_at_pixel(row, col) == r:
            return r, (x, y), (row, col)
        # centroid outside the room (L shape, ring): nearest cell of the room
        space = _RoomSpace(ctx, r, doors=[])
        r0, _, c0, _ = space.win
        rr, cc = np.nonzero(space.mask)
        if rr.size == 0:
            raise NotInRoomError(f"{what} room {r} has no cells")
        i = int(np.argmin((rr + r0 - row) ** 2 + (cc + c0 - col) ** 2))
        row, col = int(rr[i] + r0), int(cc[i] + c0)
        x, y = ctx.grid.pixel_to_world(row, col)
        return r, (float(x), float(y)), (row, col)
    try:
        x, y = (float(t) for t in v)
    except (TypeError, ValueError):
        raise PlanningError(f"{what} must be (x, y) in metres or a room ID, got {v!r}") from None
    if not (np.isfinite(x) and np.isfinite(y)):
        raise PlanningError(f"{what} must be finite, got ({x}, {y})")
    row, col = _pixel(ctx, x, y)
    H, W = ctx.shape
    if not (0 <= row < H and 0 <= col < W):
        raise NotInRoomError(f"{what} ({x:g}, {y:g}) m is outside the map")
    r = ctx.label_at_pixel(row, col)
    if r == 0:
        raise NotInRoomError(f"{what} ({x:g}, {y:g}) m is not in the free space of any room")
    return r, (x, y), (row, col)


def _attach_to_doors(ctx, H, node, room, px):
    """Join ``node`` (at pixel ``px`` of ``room``) to the room's doors of ``H`` by in-room legs.

    Returns the room space (to measure more legs in the same room), or None
    when the pixel is not on the room's traversable cells."""
    doors = [d for d in ctx.doors_of(room) if d in H]
    space = _RoomSpace(ctx, room, doors=doors)
    src = space.local(*px)
    if src is None:
        return None
    reach = [d for d in doors if d in space.door_px]
    for d, L in zip(reach, space.distances(src, [space.door_px[d] for d in reach])):
        if np.isfinite(L):
            H.add_edge(node, d, length=L, room=room)
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
        for its centroid (or, when the centroid lies outside the room, the
        room's cell nearest to it).
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
    ctx = _Ctx(seg_or_G)
    G = _annotated(seg_or_G)
    rs, ps, pxs = _endpoint(ctx, G, start, "start")
    rg, pg, pxg = _endpoint(ctx, G, goal, "goal")
    H = door_graph(G, min_width=robot_width)
    S, T = ("start",), ("goal",)
    H.add_node(S)
    H.add_node(T)
    same = rs == rg
    for r, p, node in ((rs, pxs, S), (rg, pxg, T)):
        space = _attach_to_doors(ctx, H, node, r, p)
        if same and node is S and space is not None:
            q = space.local(*pxg)
            if q is not None:
                (L,) = space.distances(space.local(*p), [q])
                if np.isfinite(L):
                    H.add_edge(S, T, length=L, room=r)
    try:
        length, path = nx.single_source_dijkstra(H, S, T, weight="length")
    except nx.NetworkXNoPath:
        why = f" with doors at least {robot_width:g} m wide" if robot_width > 0 else ""
        raise NoPathError(f"no path from room {rs} ({ps[0]:g}, {ps[1]:g}) to room {rg} "
                          f"({pg[0]:g}, {pg[1]:g}){why}") from None
    doors = [int(n) for n in path[1:-1]]
    rooms = [int(H.edges[u, v]["room"]) for u, v in zip(path[:-1], path[1:])]
    legs = [float(H.edges[u, v]["length"]) for u, v in zip(path[:-1], path[1:])]
    pts = [ps] + [ctx.doors[d][5] for d in doors] + [pg]
    return {"rooms": rooms, "doors": doors, "waypoints": np.asarray(pts, float).reshape(-1, 2),
            "length": float(length), "legs": legs, "start_room": rs, "goal_room": rg}
from .tour import plan_tour  # noqa: E402,F401  (re-exported: room tours, topomap.tour)
