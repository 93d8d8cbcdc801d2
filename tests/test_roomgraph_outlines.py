"""Room outlines of the room–door graph (topomap.core.roomgraph.room_polygons): they follow the cells' edges."""

import numpy as np
import pytest
import shapely

from topomap.io import FREE, OCCUPIED, OccupancyGrid
from topomap.core.roomgraph import room_graph, room_polygons
from topomap.core.segmentation import Segmentation


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
    # the outline runs exactly along the cells' outer edges
    for i in polys:
        assert polys[i].area == pytest.approx((L == i).sum() * cell, rel=1e-12)


def test_room_graph_polygons_are_room_polygons():
    L = _labels()
    grid = OccupancyGrid(np.where(L > 0, FREE, OCCUPIED).astype(np.int8), 0.05, (0.5, -0.25, 0.0))
    seg = Segmentation(grid=grid, labels=L, doors=[], method="manual")
    G = room_graph(seg)
    ref = room_polygons(L, grid.pixel_to_world)
    for i in G.nodes:
        assert G.nodes[i]["polygon"].equals_exact(ref[i], 0)
        assert G.nodes[i]["cells"] == int((L == i).sum())


def _polygons_of(mask):
    from topomap.core.geometry import mask_rings

    xy, ring, piece, hole = mask_rings(mask)
    rings = shapely.linearrings(xy[:, ::-1], indices=ring)  # (row, col) -> (x = col, y = row)
    return shapely.polygons(rings, indices=piece), ring, piece, hole


@pytest.mark.parametrize("seed", range(4))
def test_mask_rings_valid_exact_and_4_connected(seed):
    from scipy import ndimage as ndi

    rng = np.random.default_rng(seed)
    for _ in range(150):
        m = rng.random((rng.integers(1, 20), rng.integers(1, 20))) < rng.random()
        polys, ring, piece, hole = _polygons_of(m)
        assert len(polys) == ndi.label(m)[1]  # one polygon per 4-connected piece
        if not m.any():
            continue
        g = shapely.multipolygons(polys)
        assert g.is_valid, shapely.is_valid_reason(g)
        rr, cc = np.mgrid[0:m.shape[0], 0:m.shape[1]]
        assert np.array_equal(shapely.contains_xy(g, cc, rr), m)
        assert g.area == pytest.approx(m.sum(), abs=1e-9)
        # each piece's shell first, then its holes; shells counterclockwise (x = col, y = row), holes clockwise
        assert np.all(np.diff(piece) >= 0) and not hole[np.r_[True, np.diff(piece) > 0]].any()
        assert all(shapely.is_ccw(p.exterior) and not any(shapely.is_ccw(r) for r in p.interiors) for p in polys)


def test_corner_contacts():
    # two cells of one piece touching at a corner: a hole touching the shell there, one valid polygon
    pinch = np.array([[1, 1, 1, 0],
                      [1, 0, 0, 1],
                      [1, 1, 1, 1]], bool)
    polys, *_ = _polygons_of(pinch)
    assert len(polys) == 1 and polys[0].is_valid and len(polys[0].interiors) == 1
    assert polys[0].exterior.intersection(polys[0].interiors[0]).geom_type == "Point"
    # two pieces touching at a corner: two polygons
    diag = np.eye(2, dtype=bool)
    polys, *_ = _polygons_of(diag)
    assert len(polys) == 2 and shapely.multipolygons(polys).is_valid


def test_area_attribute_is_the_outline_area():
    L = _labels()
    grid = OccupancyGrid(np.where(L > 0, FREE, OCCUPIED).astype(np.int8), 0.05, (0.5, -0.25, 0.3))
    G = room_graph(Segmentation(grid=grid, labels=L, doors=[], method="manual"))
    for i in G.nodes:
        poly = G.nodes[i]["polygon"]
        assert poly.area == pytest.approx(G.nodes[i]["area"], rel=1e-12)
        # exteriors counterclockwise, holes clockwise in the map frame (RFC 7946)
        for p in getattr(poly, "geoms", [poly]):
            assert shapely.is_ccw(p.exterior) and not any(shapely.is_ccw(r) for r in p.interiors)


def test_detail_limit_keeps_the_largest_pieces_and_never_covers_another_room(monkeypatch, caplog):
    import topomap.core.roomgraph as rg

    i = np.arange(60) // 2
    L = ((i[:, None] + i[None, :]) % 2 == 0).astype(np.int32)  # room 1: a checkerboard of 2 x 2 pieces
    L[0:8, 0:8] = 1                # its largest piece
    L[30:40, 30:40] = 1            # a piece with a hole holding room 2 and an empty hole
    L[33:35, 33:35] = 2
    L[37, 37] = 0
    grid = OccupancyGrid(np.where(L > 0, FREE, OCCUPIED).astype(np.int8), 0.05, (0.0, 0.0, 0.0))
    exact = room_polygons(L, grid.pixel_to_world)
    assert len(exact[1].geoms) > 400
    monkeypatch.setattr(rg, "OUTLINE_MIN_RINGS", 20)
    with caplog.at_level("WARNING", logger="topomap"):
        polys = room_polygons(L, grid.pixel_to_world)
    assert "room 1:" in caplog.text and "the labels keep every cell" in caplog.text
    g = polys[1]
    assert g.is_valid
    rr, cc = np.mgrid[0:L.shape[0], 0:L.shape[1]]
    inside = shapely.contains_xy(g, *grid.pixel_to_world(rr - 0.25, cc - 0.25))
    assert not inside[L == 2].any()                       # another room's cells: never covered
    assert inside[0:8, 0:8].all() and inside[30:40, 30:40][L[30:40, 30:40] == 1].all()  # the largest pieces
    assert inside[L == 1].sum() < (L == 1).sum()          # small pieces left out
    limit = 20 + int((L == 1).sum()) // rg.OUTLINE_CELLS_PER_RING
    assert len(g.geoms) + sum(len(p.interiors) for p in g.geoms) <= limit
    assert polys[2].equals_exact(exact[2], 0)             # other rooms as they were
    seg = Segmentation(grid=grid, labels=L, doors=[], method="manual")
    assert room_graph(seg).nodes[1]["cells"] == int((L == 1).sum())  # the labels keep every cell


def test_outline_texts_in_blocks_are_the_plain_texts(monkeypatch):
    import json

    import shapely.wkt

    import topomap.io.export as ex

    i = np.arange(30) // 2
    L = ((i[:, None] + i[None, :]) % 2 == 0).astype(np.int32)
    L[20:30, 0:12] = 1
    L[22, 3] = L[25, 7] = 0  # holes
    grid = OccupancyGrid(np.where(L > 0, FREE, OCCUPIED).astype(np.int8), 0.05, (-3.3, 1.7, 0.0))
    g = room_polygons(L, grid.pixel_to_world)[1]
    for chunk in (1, 7, 1 << 15):  # polygons and rings split across blocks, or all in one
        monkeypatch.setattr(ex, "_CHUNK", chunk)
        text = ex._geom_json_text(g)
        assert json.loads(text) == ex._geom_json(g)
        assert text == json.dumps(ex._geom_json(g))
        assert shapely.wkt.loads(ex.geometry_wkt(g)).equals_exact(g, 0)
        big = max(g.geoms, key=lambda p: len(p.interiors))
        assert shapely.wkt.loads(ex.geometry_wkt(big)).equals_exact(big, 0)


@pytest.mark.parametrize("seed", range(3))
def test_label_rings_are_each_labels_mask_rings(seed):
    # one pass over a label image gives, for every label, the rings of its own mask (same corners, same order)
    from topomap.core.geometry import label_rings, mask_rings

    rng = np.random.default_rng(seed)
    for _ in range(100):
        L = rng.integers(0, rng.integers(1, 7), size=(rng.integers(1, 25), rng.integers(1, 25)))
        R = label_rings(L)
        assert np.all(np.diff(R.piece_label) >= 0)  # pieces grouped by label
        for lab in range(1, int(L.max()) + 1):
            xy, ring, piece, hole = mask_rings(L == lab)
            pieces = np.flatnonzero(R.piece_label == lab)
            rings = np.flatnonzero(np.isin(R.piece, pieces))
            corners = np.isin(R.ring, rings)
            assert np.array_equal(R.xy[corners], xy)
            assert np.array_equal(np.searchsorted(rings, R.ring[corners]), ring)
            assert np.array_equal(np.searchsorted(pieces, R.piece[rings]), piece)
            assert np.array_equal(R.hole[rings], hole)
        # the runs hold every labelled cell once
        row, col, length, lab = R.runs
        back = np.zeros_like(L)
        for r, c, n, v in zip(row, col, length, lab):
            assert (back[r, c:c + n] == 0).all()
            back[r, c:c + n] = v
        assert np.array_equal(back, L)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_detail_limit_found_before_tracing_equals_the_rings_count(seed, monkeypatch):
    # the rooms beyond the detail limit, found from their boundary edges before any ring is traced,
    # are those whose traced rings have more edges than the limit allows
    from topomap.core import roomgraph as RG
    from topomap.core.geometry import label_rings

    monkeypatch.setattr(RG, "OUTLINE_MIN_RINGS", 3)
    rng = np.random.default_rng(seed)
    labels = rng.integers(0, 5, (40, 50))
    labels[rng.random(labels.shape) < 0.5] = 1      # label 1 large and full of holes
    n = int(labels.max())
    R = label_rings(labels)
    edges = np.bincount(R.piece_label, weights=R.piece_edges, minlength=n + 1)
    cells = np.bincount(labels.ravel(), minlength=n + 1)
    want = np.flatnonzero(edges > 4 * (RG.OUTLINE_MIN_RINGS + cells // RG.OUTLINE_CELLS_PER_RING))
    assert list(RG._detailed(labels, n)) == [i for i in want if i > 0]
    assert len(want)  # the case has a room beyond the limit
