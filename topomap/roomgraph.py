"""The room–door graph: rooms as nodes, doors as edges.

:func:`room_graph` turns a :class:`~topomap.segmentation.Segmentation` into a
:class:`networkx.MultiGraph` (two rooms can share several doors, each its own
edge, keyed by the door id). Every attribute, with its unit, is listed on the
"Graph attributes" page of the documentation.
"""

from __future__ import annotations

import weakref

import numpy as np
import networkx as nx
from scipy import ndimage as ndi

__all__ = ["room_graph", "room_polygons"]

#: graph -> (weak reference to the labels, their rooms' boxes) of the graphs room_graph built, for
#: topomap.planning's room windows (beside the graph, not in it: never saved, copied or pickled)
_BOXES = weakref.WeakKeyDictionary()


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
        ``label -> shapely geometry``. The outline follows the outer edges of
        the room's cells (a cell is a unit square centred on its pixel).
    """
    return _room_polygons(labels, ndi.find_objects(labels), to_world)


def _room_polygons(labels, objs, to_world):
    """:func:`room_polygons` with the rooms' bounding boxes (``ndi.find_objects(labels)``) given."""
    import cv2
    import shapely
    from shapely.geometry import MultiPolygon, Polygon

    out = {}
    q = 0.25 * (abs(to_world(0, 1)[0] - to_world(0, 0)[0]) + abs(to_world(0, 1)[1] - to_world(0, 0)[1])
                if to_world is not None else 1.0)
    for i, sl in enumerate(objs, start=1):
        if sl is None:
            continue
        r0, c0 = sl[0].start, sl[1].start
        m = (labels[sl] == i).astype(np.uint8)
        # upsample x2 so contours run along cell edges rather than centres (nearest: each cell 2 x 2)
        m2 = np.zeros((2 * m.shape[0] + 2, 2 * m.shape[1] + 2), np.uint8)  # padded by one sub-cell
        m2[1:-1, 1:-1] = cv2.resize(m, (2 * m.shape[1], 2 * m.shape[0]), interpolation=cv2.INTER_NEAREST)
        contours, hier = cv2.findContours(m2, cv2.RETR_CCOMP, cv2.CHAIN_APPROX_SIMPLE)
        polys = []
        if hier is not None:
            hier = hier[0]
            xy = _to_coords(np.concatenate(contours), r0, c0, to_world)  # every contour's points at once
            ends = np.cumsum([len(c) for c in contours])
            rings = np.split(xy, ends[:-1])
            for k in range(len(contours)):
                if hier[k][3] != -1:
                    continue  # a hole, handled with its parent
                holes = []
                child = hier[k][2]
                while child != -1:
                    if len(rings[child]) >= 3:
                        holes.append(shapely.linearrings(rings[child]))
                    child = hier[child][0]
                if len(rings[k]) >= 3:
                    polys.append(shapely.polygons(rings[k], holes=holes or None))
        if polys:
            geom = shapely.union_all(shapely.buffer(polys, 0)) if len(polys) > 1 else \
                shapely.union_all([polys[0].buffer(0)])
        else:
            geom = Polygon()
        if not geom.is_empty:
            # the outline ran through sub-cell centres a quarter cell inside
            # the cells' edges: offset it out by that quarter cell
            geom = geom.buffer(q, join_style="mitre", mitre_limit=2.0)
        if geom.geom_type == "GeometryCollection":
            geom = MultiPolygon([g for g in geom.geoms if g.geom_type == "Polygon"])
        out[i] = geom
    return out


def _to_coords(cnt, r0, c0, to_world):
    # contour points are centres of sub-cells of the x2, padded grid: sub-cell
    # k (after the pad) has its centre at k / 2 - 0.25 in cell units, a
    # quarter cell inside the cells' outer edges (pushed back out by the caller)
    pts = cnt[:, 0, :].astype(float) - 1.0
    cols = pts[:, 0] / 2.0 - 0.25 + c0
    rows = pts[:, 1] / 2.0 - 0.25 + r0
    if to_world is not None:
        x, y = to_world(rows, cols)
        return np.stack([np.asarray(x, float), np.asarray(y, float)], 1)
    return np.stack([cols, rows], 1)


def room_graph(seg) -> nx.MultiGraph:
    """Build the room–door graph of a segmentation.

    Nodes are room labels (``int``, 1..N) with ``area`` (m²), ``x``, ``y``
    (centroid, m), ``row``, ``col`` (centroid, pixels), ``cells`` (count) and
    ``polygon`` (shapely geometry in map-frame metres). Edges are doors,
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
                      n_fragments=int(seg.n_fragments), fragment_area=float(seg.fragment_area))
    if n == 0:
        return G
    # cell counts and row / column sums per room, from each room's bounding box (exact integer sums)
    cnt, sr, sc = np.zeros(n + 1), np.zeros(n + 1), np.zeros(n + 1)
    objs = ndi.find_objects(labels, max_label=n)  # once: the sums below and the outlines
    for i, sl in enumerate(objs, start=1):
        if sl is not None:
            m = labels[sl] == i
            cnt[i] = np.count_nonzero(m)
            sr[i] = float(m.sum(1) @ np.arange(sl[0].start, sl[0].stop))
            sc[i] = float(m.sum(0) @ np.arange(sl[1].start, sl[1].stop))
    polys = _room_polygons(labels, objs, grid.pixel_to_world)
    _BOXES[G] = (weakref.ref(seg.labels), objs)
    area_cell = grid.resolution ** 2
    for i in range(1, n + 1):
        if cnt[i] == 0:
            continue
        r, c = sr[i] / cnt[i], sc[i] / cnt[i]
        x, y = grid.pixel_to_world(r, c)
        G.add_node(i, area=float(cnt[i] * area_cell), cells=int(cnt[i]), x=float(x), y=float(y),
                   row=float(r), col=float(c), polygon=polys.get(i))
    for d in seg.doors:
        a, b = d.rooms
        mx, my = d.midpoint
        G.add_edge(a, b, key=d.id, door=d.id, width=float(d.width), x=float(mx), y=float(my),
                   x1=float(d.xy1[0]), y1=float(d.xy1[1]), x2=float(d.xy2[0]), y2=float(d.xy2[1]),
                   p1=tuple(d.p1), p2=tuple(d.p2))
    return G
