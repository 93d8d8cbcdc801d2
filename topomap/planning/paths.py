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
from .._fast import lookup, ranges
from ..core.geometry import line_pixels

__all__ = ["PlanningError", "NotInRoomError", "NoPathError", "room_at", "neighbors", "doors_between",
           "room_distances", "travel_graph", "door_graph", "plan_path"]


# --------------------------------------------------------------------------
# Context: labels and frame of a segmentation or a room graph
# --------------------------------------------------------------------------

#: Offset (px) of the point at which a cell is tested against room polygons.
#: Room outlines (:func:`topomap.core.roomgraph.room_polygons`) run along cell
#: edges on the top/left side of a room and may run through the cell centres
#: on its bottom/right side; a point a quarter cell up and left of the centre
#: is inside every cell of the room under either convention and outside the
#: cells of its neighbours, so rasterising the polygons gives back the label
#: image exactly (checked by the tests for every segmentation method).
_PROBE = -0.25


class _Ctx:
    """Room cells, doors and the pixel <-> metre frame of ``seg_or_G``."""

    def __init__(self, seg_or_G):
        from ..io.maps import OccupancyGrid

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
                                    "topomap.io.export.load_graph") from None
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
        self._points = {}  # door -> the cell a route crosses it at (door_point)

    # -- rooms ------------------------------------------------------------
    def room_bbox(self, r):
        """(r0, r1, c0, c1) half-open pixel box of room ``r``'s cells."""
        if self.seg is not None:
            if self._bbox is None:
                from ..core.roomgraph import _BOXES

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

    def window_room(self, r, rooms, win):
        """The cells of room ``r`` in the window ``(r0, r1, c0, c1)`` (a new bool array) and a test
        ``(rows, cols) -> bool array``: window cells on one of ``rooms``."""
        if self.seg is None:
            L = self.window_labels(rooms, win)
            return L == r, lambda rr, cc: L[rr, cc] > 0
        r0, r1, c0, c1 = win
        L = self.seg.labels[r0:r1, c0:c1]  # a view: one pass for the room's cells, none for the others
        ids = np.array(sorted(rooms), np.intp)
        if ids.size and ids[0] >= 1:  # a table over the labels (np.isin costs more on a door's few cells)
            on = np.zeros(int(ids[-1]) + 2, bool)
            on[ids] = True
            top = len(on) - 1  # labels 0, below 0 (clipped to 0) and above the rooms (clipped to top): False
            return L == r, lambda rr, cc: on[np.clip(L[rr, cc], 0, top)]
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

    def in_room(self, row, col, r) -> bool:
        """Whether cell ``(row, col)`` is a cell of room ``r`` (for a graph: a test against that
        room's polygon only, not every room's)."""
        H, W = self.shape
        if not (0 <= row < H and 0 <= col < W):
            return False
        if self.seg is not None:
            return int(self.seg.labels[row, col]) == r
        import shapely

        poly = self.G.nodes[r].get("polygon") if r in self.G else None
        if poly is None or poly.is_empty:
            return False
        x, y = self.grid.pixel_to_world(row + _PROBE, col + _PROBE)
        return bool(shapely.contains_xy(poly, float(x), float(y)))

    def doors_of(self, r):
        return list(self._of.get(r, ()))

    def door_cells(self, did):
        """The cells of door ``did``'s segment (:func:`topomap.core.geometry.line_pixels`; drawn once)."""
        cells = self._cells.get(did)
        if cells is None:
            _, _, p1, p2, _, _ = self.doors[did]
            cells = self._cells[did] = line_pixels(p1, p2, self.shape)
        return cells

    def door_point(self, did):
        """The cell ``(row, col)`` of door ``did``'s segment a route crosses it at, or None (no cell of it
        on its rooms): of its cells on its two rooms, those beside both rooms (a cell of one room with
        a cell of the other among its 8 neighbours), the one closest to the door's midpoint (the first
        along the segment of equals). Only when no cell is beside both, the one closest of all.

        A segment may run on past the place where its rooms meet, through a wall into a part of one
        of them that the other does not reach: its cell closest to the midpoint can lie there, and
        a route to it from the other room does not exist."""
        if did in self._points:
            return self._points[did]
        a, b, p1, p2 = self.doors[did][:4]
        rr, cc = self.door_cells(did)
        pt = None
        if len(rr):
            H, W = self.shape
            r0, c0 = max(int(rr.min()) - 1, 0), max(int(cc.min()) - 1, 0)
            r1, c1 = min(int(rr.max()) + 2, H), min(int(cc.max()) + 2, W)
            L = np.pad(self.window_labels({a, b}, (r0, r1, c0, c1)), 1)
            lr, lc = rr - r0 + 1, cc - c0 + 1
            on = L[lr, lc] > 0
            if on.any():
                near_a = np.zeros(len(rr), bool)
                near_b = np.zeros(len(rr), bool)
                for dr in (-1, 0, 1):
                    for dc in (-1, 0, 1):
                        v = L[lr + dr, lc + dc]
                        near_a |= v == a
                        near_b |= v == b
                both = on & near_a & near_b
                cand = both if both.any() else on
                mr, mc = (p1[0] + p2[0]) / 2, (p1[1] + p2[1]) / 2
                d2 = np.where(cand, (rr - mr) ** 2 + (cc - mc) ** 2, np.inf)
                i = int(np.argmin(d2))
                pt = (int(rr[i]), int(cc[i]))
        self._points[did] = pt
        return pt


def _pixel(ctx, x, y):
    r, c = ctx.grid.world_to_pixel(x, y)
    return int(np.rint(r)), int(np.rint(c))


class _RoomSpace:
    """Traversable cells of one room (its cells plus its doors' cells) and its door cells."""

    def __init__(self, ctx: _Ctx, r: int, doors=None):
        self.ctx, self.r = ctx, r
        doors = ctx.doors_of(r) if doors is None else doors
        H, W = ctx.shape
        box = ctx.room_bbox(r)
        lines = [ctx.door_cells(d) for d in doors]
        if not box and not lines:
            self.win, self.mask, self.door_px = (0, 0, 0, 0), np.zeros((0, 0), bool), {}
            return
        # all the doors' cells at once (one test against the rooms instead of one per door)
        RR = np.concatenate([rr for rr, _ in lines]) if lines else np.zeros(0, np.intp)
        CC = np.concatenate([cc for _, cc in lines]) if lines else np.zeros(0, np.intp)
        rows = ([box[0], box[1] - 1] if box else []) + ([int(RR.min()), int(RR.max())] if RR.size else [])
        cols = ([box[2], box[3] - 1] if box else []) + ([int(CC.min()), int(CC.max())] if CC.size else [])
        r0, r1 = max(min(rows) - 1, 0), min(max(rows) + 2, H)
        c0, c1 = max(min(cols) - 1, 0), min(max(cols) + 2, W)
        self.win = (r0, r1, c0, c1)
        rooms = {r} | {x for d in doors for x in ctx.doors[d][:2]}
        mask, on_rooms = ctx.window_room(r, rooms, self.win)
        RR, CC = RR - r0, CC - c0
        ok = on_rooms(RR, CC)
        mask[RR[ok], CC[ok]] = True
        # each door at the cell a route crosses it (its cells on the rooms are on the mask)
        self.door_px = {}
        for d in doors:
            pt = ctx.door_point(d)
            if pt is not None:
                self.door_px[d] = (pt[0] - r0, pt[1] - c0)
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
                    out[(di, ids[j])] = float(_octile(*(pts[i] - pts[j]))) * self.ctx.res
                for dj, L in zip(rest, self.distances(self.door_px[di], [self.door_px[d] for d in rest])):
                    if np.isfinite(L):
                        out[(di, dj)] = L
            return out
        f = _coarse_factor(self.ctx.res)
        pts = np.array([self.door_px[d] for d in ids], float)
        seen = _in_sight(self.mask, pts) if f > 1 else np.zeros((len(ids), len(ids)), bool)
        need = ~seen  # the coarse search only for the pairs out of sight (none: no search)
        np.fill_diagonal(need, False)
        D = _coarse_door_distances(self.mask, pts, f, need)
        D[seen] = _octile(*(pts[:, None, :] - pts[None, :, :]).transpose(2, 0, 1))[seen]
        short = REFINE_CELLS * f if f > 1 else 0
        for i in range(len(ids)):
            near = [j for j in range(i + 1, len(ids)) if D[i, j] < short and not seen[i, j]]
            if near:
                D[i, near] = _windowed_distances(self.mask, pts, i, near, D[i, near], f)
        res = self.ctx.res
        return {(ids[i], ids[j]): float(D[i, j]) * res
                for i in range(len(ids)) for j in range(i + 1, len(ids)) if np.isfinite(D[i, j])}


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
    R, C = np.nonzero(_block_any(m, f))
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
    full[1:-1, 1:-1] = ~_block_any(~np.ascontiguousarray(mask[:H * f, :W * f]), f)
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
    used, node = np.unique(node, return_inverse=True)
    return node, cen[used]


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
    """Label pairs of 8-adjacent cells, ``a`` the row above ``b`` (0 = no cell)."""
    out = []
    w = a.shape[1]
    on_a, on_b = a > 0, b > 0
    for dc in (-1, 0, 1):
        sa, sb = slice(max(0, -dc), w - max(0, dc)), slice(max(0, dc), w - max(0, -dc))
        x, y = a[:, sa], b[:, sb]
        ok = on_a[:, sa] & on_b[:, sb] & (x != y)
        x, y = x[ok], y[ok]
        keep = np.ones(len(x), bool)  # runs of the same pair along a block edge: keep one
        keep[1:] = (x[1:] != x[:-1]) | (y[1:] != y[:-1])
        out.append(np.stack([x[keep], y[keep]], 1))
    return out


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
    pairs = _touching(lab[f - 1::f][:nb], lab[f::f])
    right = np.ascontiguousarray(lab[:, f::f].T)  # the columns at the blocks' edges, as rows
    left = np.ascontiguousarray(lab[:, f - 1::f][:, :len(right)].T)
    pairs += [p[:, ::-1] for p in _touching(left, right)]
    if many and f > 1:  # open floor merged: pieces -> their nodes
        node, cen = _merged_nodes(mask, lab, n, cen, f)
        E = node[np.concatenate(pairs)]
        E = E[E[:, 0] != E[:, 1]]
        pairs = [E]
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
    E = np.concatenate(pairs + [np.stack([np.concatenate(su), np.concatenate(sv)], 1)]).astype(np.int32)
    pr = np.concatenate([cen[:, 0], pts[:, 0]])
    pc = np.concatenate([cen[:, 1], pts[:, 1]])
    A = _travel_matrix(E, n + 1 + k, lambda u, v: _octile(pr[u] - pr[v], pc[u] - pc[v]) + 1e-9, both_ways=many)
    rows = np.nonzero(np.triu(need, 1).any(axis=1))[0]  # one search from each door with a pair i < j
    out[rows] = dijkstra(A, directed=many, indices=n + 1 + rows)[:, n + 1:]
    return out


def _travel_matrix(E, m, length, *, both_ways):
    """The (m, m) CSR matrix joining each pair of rows of ``E`` ((e, 2) ints, repeats allowed) by
    ``length(u, v)`` (arrays of node indices -> lengths), one entry per pair.

    With ``both_ways`` every pair is entered in both directions, to be searched as a directed
    graph (:func:`scipy.sparse.csgraph.dijkstra` with ``directed=True``: faster than an undirected
    search, which scans every node's row and its column, when there are several searches);
    otherwise once, to be searched with ``directed=False``.
    """
    from scipy.sparse import coo_matrix

    rows, cols = (np.concatenate([E[:, 0], E[:, 1]]), np.concatenate([E[:, 1], E[:, 0]])) if both_ways else E.T
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
    return _RoomSpace(ctx, room).door_distances(exact=exact)


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
    for r in G.nodes:
        dist = _room_distances(ctx, r, exact=exact)
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
        nd = G.nodes[r]
        # the room's interior point (a cell of the room, roomgraph.interior_points); a graph without
        # it (written by an older version): the centroid, when it is in the room
        key = ("interior_x", "interior_y") if "interior_x" in nd and "interior_y" in nd else ("x", "y")
        x, y = float(nd[key[0]]), float(nd[key[1]])
        row, col = _pixel(ctx, x, y) if np.isfinite(x) and np.isfinite(y) else (-1, -1)
        if ctx.in_room(row, col, r):
            return r, (x, y), (row, col)
        x, y = float(nd["x"]), float(nd["y"])
        row, col = _pixel(ctx, x, y)
        if ctx.in_room(row, col, r):
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
from .tour import plan_tour  # noqa: E402,F401  (re-exported: room tours, topomap.planning.tour)
