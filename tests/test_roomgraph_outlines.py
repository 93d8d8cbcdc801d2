"""Room outlines of the room–door graph (topomap.roomgraph.room_polygons): they follow the cells' edges."""

import numpy as np
import pytest
import shapely

from topomap.io import FREE, OCCUPIED, OccupancyGrid
from topomap.roomgraph import room_graph, room_polygons
from topomap.segmentation import Segmentation


def _labels():
    """Rooms with a hole, a room in two pieces, a one-cell room, a room touching the border, a diagonal step."""
    L = np.zeros((40, 50), np.int32)
    L[2:20, 2:30] = 1
    L[8:12, 10:14] = 0          # a hole in room 1
    L[25:30, 3:8] = 2
    L[33:38, 20:26] = 2         # room 2 in two pieces
    L[22, 40] = 3               # one cell
    L[30:40, 40:50] = 4         # at the map's border
    L[5:10, 35:40] = 5
    L[10:15, 40:45] = 5         # two blocks touching at a corner
    return L


@pytest.mark.parametrize("frame", ["pixels", "metres"])
def test_outline_holds_exactly_the_rooms_cell_centres(frame):
    L = _labels()
    grid = OccupancyGrid(np.where(L > 0, FREE, OCCUPIED).astype(np.int8), 0.05, (-1.0, 2.0, 0.0))
    to_world = grid.pixel_to_world if frame == "metres" else None
    polys = room_polygons(L, to_world)
    assert sorted(polys) == [1, 2, 3, 4, 5]
    rr, cc = np.mgrid[0:L.shape[0], 0:L.shape[1]]
    xs, ys = grid.pixel_to_world(rr, cc) if to_world else (cc.astype(float), rr.astype(float))
    for i, g in polys.items():
        assert g.is_valid and not g.is_empty
        inside = shapely.contains_xy(g, xs, ys)
        assert np.array_equal(inside, L == i), i
    assert len(polys[1].interiors) == 1
    assert polys[2].geom_type == "MultiPolygon" and len(polys[2].geoms) == 2
    cell = 0.05 ** 2 if to_world else 1.0
    # the outline runs along the cells' outer edges (corners cut by at most a quarter cell's diagonal)
    for i in (1, 2, 4):
        assert polys[i].area == pytest.approx((L == i).sum() * cell, rel=0.02)


def test_room_graph_polygons_are_room_polygons():
    L = _labels()
    grid = OccupancyGrid(np.where(L > 0, FREE, OCCUPIED).astype(np.int8), 0.05, (0.5, -0.25, 0.0))
    seg = Segmentation(grid=grid, labels=L, doors=[], method="manual")
    G = room_graph(seg)
    ref = room_polygons(L, grid.pixel_to_world)
    for i in G.nodes:
        assert G.nodes[i]["polygon"].equals_exact(ref[i], 0)
        assert G.nodes[i]["cells"] == int((L == i).sum())
