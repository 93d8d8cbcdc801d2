"""The rooms of a segmentation or of a room graph, rasterised, with their doors and the map frame.

A room graph carries no label image, but its room polygons follow cell edges
exactly, so the cells of a room are recovered by rasterising its polygon at
the graph's ``resolution``, ``origin`` and ``shape``. :class:`RoomMap` gives
both sources one interface: the cells of rooms in a window, the room at a
cell, the cells of a door's segment and the cell a route crosses a door at.
"""

from __future__ import annotations

import numpy as np
import networkx as nx
from scipy import ndimage as ndi

from .._fast import lookup
from ..errors import PlanningError
from ..grid import OccupancyGrid
from .geometry import line_pixels
from .roomgraph import cached_room_boxes

__all__ = ["RoomMap", "PROBE"]

#: Offset (px) of the point at which a cell is tested against room polygons.
#: Room outlines (:func:`topomap.core.roomgraph.room_polygons`) run along cell
#: edges on the top/left side of a room and may run through the cell centres
#: on its bottom/right side; a point a quarter cell up and left of the centre
#: is inside every cell of the room under either convention and outside the
#: cells of its neighbours, so rasterising the polygons gives back the label
#: image exactly (checked by the tests for every segmentation method).
PROBE = -0.25


def _graph_frame(G) -> OccupancyGrid:
    """The map frame of room graph ``G``: a grid of its shape, resolution and origin whose cells are a
    read-only all-zero view (no memory); PlanningError when the graph lacks them."""
    try:
        shape = tuple(int(v) for v in G.graph["shape"])
        resolution = float(G.graph["resolution"])
        origin = tuple(float(v) for v in G.graph["origin"])
    except (KeyError, TypeError, ValueError):
        raise PlanningError("room graph lacks the map frame (graph attributes 'shape', 'resolution', "
                            "'origin'); build it with topomap.room_graph or load it with "
                            "topomap.io.export.load_graph") from None
    return OccupancyGrid(np.broadcast_to(np.int8(0), shape), resolution, origin)


def _graph_doors(G) -> dict:
    """``door id -> (room a, room b, p1, p2, width, (x, y))`` of the edges of room graph ``G``;
    PlanningError naming the door and the attribute when one is missing or bad."""
    doors = {}
    for a, b, k, d in G.edges(keys=True, data=True):
        try:
            did = int(d.get("door", k))
            p1 = tuple(float(v) for v in d["p1"])
            p2 = tuple(float(v) for v in d["p2"])
            doors[did] = (int(a), int(b), p1, p2, float(d["width"]), (float(d["x"]), float(d["y"])))
            if len(p1) != 2 or len(p2) != 2:
                raise ValueError("p1 and p2 must be (row, col)")
        except KeyError as exc:
            raise PlanningError(f"room graph: door {a}-{b} lacks the attribute {exc.args[0]!r} (doors need "
                                "p1, p2, width, x, y)") from None
        except (TypeError, ValueError) as exc:
            raise PlanningError(f"room graph: door {a}-{b} has a bad attribute: {exc}") from None
    return doors


class RoomMap:
    """The rooms of a segmentation or of a room graph, rasterised, with their doors and map frame.

    From a :class:`~topomap.core.segmentation.Segmentation` the cells of the
    rooms are its labels; from a room–door graph (as built by
    :func:`topomap.core.roomgraph.room_graph` or loaded back by
    :func:`topomap.io.export.load_graph`) they are found by rasterising the
    room polygons, tested at a point :data:`PROBE` cells up and left of each
    cell's centre, which gives back the label image exactly. Door cells are
    drawn once and kept.

    Parameters
    ----------
    seg_or_G : Segmentation or networkx.MultiGraph
        The segmentation or the room graph.

    Attributes
    ----------
    seg : Segmentation or None
        The segmentation (None for a graph).
    graph : networkx.MultiGraph
        The room graph (the segmentation's ``room_graph``).
    grid : OccupancyGrid
        The map frame (for a graph: a grid of its shape whose cells are all 0).
    shape : (int, int)
        Rows and columns of the map.
    resolution : float
        Metres per cell.
    doors : dict
        ``door id -> (room a, room b, p1, p2, width, (x, y))``: the rooms it
        joins, its end points (pixels ``(row, col)``), width (m) and midpoint
        (m).

    Raises
    ------
    PlanningError
        ``seg_or_G`` is neither, or the graph lacks its map frame or a door
        attribute.
    """

    def __init__(self, seg_or_G):
        if isinstance(seg_or_G, nx.Graph):
            self.seg = None
            self.graph = seg_or_G
            self.grid = _graph_frame(seg_or_G)
        elif hasattr(seg_or_G, "labels") and hasattr(seg_or_G, "grid"):
            self.seg = seg_or_G
            self.graph = seg_or_G.room_graph
            self.grid = seg_or_G.grid
        else:
            raise PlanningError(f"expected a Segmentation or a room graph, got {type(seg_or_G).__name__}")
        self.shape = tuple(self.grid.shape)
        self.resolution = self.grid.resolution
        self.doors = _graph_doors(self.graph)
        self._room_doors = {}  # room -> its door IDs, ascending
        for did in sorted(self.doors):
            a, b = self.doors[did][:2]
            for r in {a, b}:
                self._room_doors.setdefault(r, []).append(did)
        self._boxes = None  # the rooms' boxes (as ndi.find_objects) of a segmentation's labels
        self._door_cells = {}  # door -> its cells (door_cells)
        self._door_points = {}  # door -> the cell a route crosses it at (door_point)

    # -- the frame ---------------------------------------------------------
    def cell_at(self, x: float, y: float) -> tuple:
        """The cell ``(row, col)`` (ints, maybe off the map) that holds map-frame point ``(x, y)`` (m)."""
        r, c = self.grid.world_to_pixel(x, y)
        return int(np.rint(r)), int(np.rint(c))

    # -- rooms ------------------------------------------------------------
    def room_bbox(self, r: int):
        """The half-open pixel box ``(r0, r1, c0, c1)`` of room ``r``'s cells, or None (no cells).

        For a graph, the box of the room polygon's bounds (a cell larger on
        the bottom and right, clipped to the map)."""
        if self.seg is not None:
            if self._boxes is None:
                self._boxes = cached_room_boxes(self.graph, self.seg.labels)
                if self._boxes is None:
                    self._boxes = ndi.find_objects(self.seg.labels)
            sl = self._boxes[r - 1] if 0 < r <= len(self._boxes) else None
            if sl is None:
                return None
            return sl[0].start, sl[0].stop, sl[1].start, sl[1].stop
        poly = self.graph.nodes[r].get("polygon")
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

    def window_labels(self, rooms, win) -> np.ndarray:
        """The labels of ``rooms`` (other cells 0) in the window ``win`` = ``(r0, r1, c0, c1)``, as a new
        int32 array."""
        r0, r1, c0, c1 = win
        if self.seg is not None:
            labels = self.seg.labels[r0:r1, c0:c1]
            if labels.size == 0 or labels.min() < 0:
                return np.where(np.isin(labels, list(rooms)), labels, 0).astype(np.int32)
            keep = np.zeros(int(labels.max()) + 1, np.int32)  # label -> itself for the rooms kept, else 0
            idx = np.array([r for r in rooms if 0 <= r < len(keep)], np.intp)
            keep[idx] = idx
            return lookup(keep, labels)
        import shapely

        out = np.zeros((r1 - r0, c1 - c0), np.int32)
        rr, cc = np.mgrid[r0:r1, c0:c1]
        xs, ys = self.grid.pixel_to_world(rr + PROBE, cc + PROBE)
        for r in rooms:
            poly = self.graph.nodes[r].get("polygon")
            if poly is None or poly.is_empty:
                continue
            inside = shapely.contains_xy(poly, xs, ys)
            out[inside & (out == 0)] = r
        return out

    def window_room(self, r: int, rooms, win):
        """The cells of room ``r`` in the window ``win`` = ``(r0, r1, c0, c1)`` (a new bool array) and a
        test ``(rows, cols) -> bool array``: whether those window cells are on one of ``rooms``."""
        if self.seg is None:
            labels = self.window_labels(rooms, win)
            return labels == r, lambda rr, cc: labels[rr, cc] > 0
        r0, r1, c0, c1 = win
        labels = self.seg.labels[r0:r1, c0:c1]  # a view: one pass for the room's cells, none for the others
        ids = np.array(sorted(rooms), np.intp)
        if ids.size and ids[0] >= 1:  # a table over the labels (np.isin costs more on a door's few cells)
            on = np.zeros(int(ids[-1]) + 2, bool)
            on[ids] = True
            top = len(on) - 1  # labels 0, below 0 (clipped to 0) and above the rooms (clipped to top): False
            return labels == r, lambda rr, cc: on[np.clip(labels[rr, cc], 0, top)]
        return labels == r, lambda rr, cc: np.isin(labels[rr, cc], ids)

    def label_at_pixel(self, row: int, col: int) -> int:
        """The room at cell ``(row, col)``; 0 off the map or on no room."""
        H, W = self.shape
        if not (0 <= row < H and 0 <= col < W):
            return 0
        if self.seg is not None:
            return int(self.seg.labels[row, col])
        import shapely

        x, y = self.grid.pixel_to_world(row + PROBE, col + PROBE)
        for r, d in self.graph.nodes(data=True):
            poly = d.get("polygon")
            if poly is not None and not poly.is_empty and shapely.contains_xy(poly, float(x), float(y)):
                return int(r)
        return 0

    def in_room(self, row: int, col: int, r: int) -> bool:
        """Whether cell ``(row, col)`` is a cell of room ``r`` (for a graph: a test against that
        room's polygon only, not every room's)."""
        H, W = self.shape
        if not (0 <= row < H and 0 <= col < W):
            return False
        if self.seg is not None:
            return int(self.seg.labels[row, col]) == r
        import shapely

        poly = self.graph.nodes[r].get("polygon") if r in self.graph else None
        if poly is None or poly.is_empty:
            return False
        x, y = self.grid.pixel_to_world(row + PROBE, col + PROBE)
        return bool(shapely.contains_xy(poly, float(x), float(y)))

    # -- doors ------------------------------------------------------------
    def doors_of(self, r: int) -> list:
        """The IDs of room ``r``'s doors, ascending."""
        return list(self._room_doors.get(r, ()))

    def door_cells(self, did: int):
        """The cells ``(rows, cols)`` of door ``did``'s segment (:func:`topomap.core.geometry.line_pixels`;
        drawn once)."""
        cells = self._door_cells.get(did)
        if cells is None:
            _, _, p1, p2, _, _ = self.doors[did]
            cells = self._door_cells[did] = line_pixels(p1, p2, self.shape)
        return cells

    def door_point(self, did: int):
        """The cell ``(row, col)`` of door ``did``'s segment a route crosses it at, or None (no cell of it
        on its rooms): of its cells on its two rooms, those beside both rooms (a cell of one room with
        a cell of the other among its 8 neighbours), the one closest to the door's midpoint (the first
        along the segment of equals). Only when no cell is beside both, the one closest of all.

        A segment may run on past the place where its rooms meet, through a wall into a part of one
        of them that the other does not reach: its cell closest to the midpoint can lie there, and
        a route to it from the other room does not exist.

        For a segmentation the cells of every door are found together, at the first call."""
        if did not in self._door_points:
            ids = sorted(self.doors) if self.seg is not None else [did]
            self._door_points.update(zip(ids, self._find_door_points(ids)))
        return self._door_points[did]

    def _find_door_points(self, ids) -> list:
        """:meth:`door_point` of the doors ``ids``, all in one pass over their cells."""
        cells = [self.door_cells(d) for d in ids]
        count = np.array([len(rr) for rr, _ in cells], np.intp)
        door = np.repeat(np.arange(len(ids)), count)
        rr = np.concatenate([rr for rr, _ in cells] + [np.zeros(0, np.intp)])
        cc = np.concatenate([cc for _, cc in cells] + [np.zeros(0, np.intp)])
        a = np.array([self.doors[d][0] for d in ids], np.int64)
        b = np.array([self.doors[d][1] for d in ids], np.int64)
        mid = np.array([((p1[0] + p2[0]) / 2, (p1[1] + p2[1]) / 2) for p1, p2 in
                        (self.doors[d][2:4] for d in ids)], float).reshape(-1, 2)
        around = self._around_doors(ids, cells, rr, cc, a[door], b[door])  # (9, cells): the 3 x 3 neighbours
        on = around[4] > 0
        both = on & (around == a[door]).any(axis=0) & (around == b[door]).any(axis=0)
        has_on = np.bincount(door[on], minlength=len(ids)) > 0
        has_both = np.bincount(door[both], minlength=len(ids)) > 0
        cand = np.where(has_both[door], both, on)
        d2 = np.where(cand, (rr - mid[door, 0]) ** 2 + (cc - mid[door, 1]) ** 2, np.inf)
        order = np.lexsort((np.arange(door.size), d2, door))  # per door: the closest, the first of equals
        first = order[np.r_[True, door[order][1:] != door[order][:-1]]] if door.size else order
        best = dict(zip(door[first].tolist(), first.tolist()))
        return [(int(rr[best[i]]), int(cc[best[i]])) if has_on[i] else None for i in range(len(ids))]

    def _around_doors(self, ids, cells, rr, cc, a, b) -> np.ndarray:
        """``(9, len(rr))``: at the 3 x 3 neighbours of each door cell ``rr, cc`` (row-major, the cell
        itself at index 4; ``cells``: those of the doors ``ids`` in turn), its label when it is one of
        that door's rooms ``a``, ``b``, else 0 (off the map too)."""
        H, W = self.shape
        out = np.zeros((9, rr.size), np.int64)
        if self.seg is not None:
            labels = self.seg.labels
            for k, (dr, dc) in enumerate((dr, dc) for dr in (-1, 0, 1) for dc in (-1, 0, 1)):
                r, c = rr + dr, cc + dc
                ok = (r >= 0) & (r < H) & (c >= 0) & (c < W)
                out[k, ok] = labels[r[ok], c[ok]]
            return np.where((out == a) | (out == b), out, 0)
        at = 0
        for d, (dr_, dc_) in zip(ids, cells):  # a graph: each door's window of its two rooms, rasterised
            if len(dr_):
                r0, c0 = max(int(dr_.min()) - 1, 0), max(int(dc_.min()) - 1, 0)
                r1, c1 = min(int(dr_.max()) + 2, H), min(int(dc_.max()) + 2, W)
                labels = np.pad(self.window_labels(set(self.doors[d][:2]), (r0, r1, c0, c1)), 1)
                lr, lc = dr_ - r0 + 1, dc_ - c0 + 1
                for k, (dr, dc) in enumerate((dr, dc) for dr in (-1, 0, 1) for dc in (-1, 0, 1)):
                    out[k, at:at + len(dr_)] = labels[lr + dr, lc + dc]
            at += len(dr_)
        return out
