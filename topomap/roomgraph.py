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

from .geometry import mask_rings

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
        ``label -> shapely geometry``. The outline runs exactly along the
        outer edges of the room's cells (a cell is a unit square centred on
        its pixel): a Polygon for a room whose cells are 4-connected, else a
        MultiPolygon of its 4-connected pieces (cells that touch at a corner
        only are different pieces), each with a hole for every enclosed
        patch of other cells. The geometry is valid as built (no repair) and
        holds exactly the room's cells; exteriors run counterclockwise,
        holes clockwise (in the map frame, as RFC 7946 asks). Time and
        memory are linear in the cells of each room's bounding box.
    """
    return _room_polygons(labels, ndi.find_objects(labels), to_world)


def _room_polygons(labels, objs, to_world):
    """:func:`room_polygons` with the rooms' bounding boxes (``ndi.find_objects(labels)``) given."""
    import shapely

    out = {}
    for i, sl in enumerate(objs, start=1):
        if sl is None:
            continue
        xy, ring, piece, _ = mask_rings(labels[sl] == i)
        rows, cols = xy[:, 0] + sl[0].start, xy[:, 1] + sl[1].start
        del xy
        if to_world is not None:
            x, y = to_world(rows, cols)
            x, y = np.asarray(x, float), np.asarray(y, float)
        else:
            x, y = cols, rows
        polys = shapely.polygons(shapely.linearrings(np.stack([x, y], 1), indices=ring), indices=piece)
        out[i] = polys[0] if len(polys) == 1 else shapely.multipolygons(polys)
    return out


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
