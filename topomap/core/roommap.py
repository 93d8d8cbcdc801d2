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
        a route to it from the other room does not exist."""
        if did in self._door_points:
            return self._door_points[did]
        a, b, p1, p2 = self.doors[did][:4]
        rr, cc = self.door_cells(did)
        point = None
        if len(rr):
            H, W = self.shape
            r0, c0 = max(int(rr.min()) - 1, 0), max(int(cc.min()) - 1, 0)
            r1, c1 = min(int(rr.max()) + 2, H), min(int(cc.max()) + 2, W)
            labels = np.pad(self.window_labels({a, b}, (r0, r1, c0, c1)), 1)
            lr, lc = rr - r0 + 1, cc - c0 + 1
            on = labels[lr, lc] > 0
            if on.any():
                near_a = np.zeros(len(rr), bool)
                near_b = np.zeros(len(rr), bool)
                for dr in (-1, 0, 1):
                    for dc in (-1, 0, 1):
                        v = labels[lr + dr, lc + dc]
                        near_a |= v == a
                        near_b |= v == b
                both = on & near_a & near_b
                cand = both if both.any() else on
                mr, mc = (p1[0] + p2[0]) / 2, (p1[1] + p2[1]) / 2
                d2 = np.where(cand, (rr - mr) ** 2 + (cc - mc) ** 2, np.inf)
                i = int(np.argmin(d2))
                point = (int(rr[i]), int(cc[i]))
        self._door_points[did] = point
        return point
