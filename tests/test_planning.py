"""Queries and topological planning on the room–door graph (issue 4)."""

import numpy as np
import networkx as nx
import pytest

from topomap.core.roommap import RoomMap
from topomap.planning import paths as P
from topomap.errors import TopomapError
from topomap.io import FREE, OCCUPIED, OccupancyGrid, load_map
from topomap.core.segmentation import METHODS, Segmentation, cut_rooms, segment

RES = 0.05


# --------------------------------------------------------------------------
# Hand-drawn maps with known rooms and doors
# --------------------------------------------------------------------------

def corridor_of_rooms(widths_px=(16, 20, 12, 20), room=30, wall=3, offsets=None):
    """Rooms in a row (west to east), joined by doors in the walls between them.

    Returns the segmentation built from the known door segments (no
    detection involved), so rooms are 1..n west to east and door i joins
    rooms i+1 and i+2 with width ``widths_px[i] * RES`` metres.
    """
    n = len(widths_px) + 1
    H = room + 2 * wall
    W = n * room + (n + 1) * wall
    cells = np.full((H, W), OCCUPIED, np.int8)
    for i in range(n):
        c0 = wall + i * (room + wall)
        cells[wall:wall + room, c0:c0 + room] = FREE
    segs = []
    for i, w in enumerate(widths_px):
        cw = wall + (i + 1) * room + i * wall  # first column of the wall between rooms i and i+1
        off = 0 if offsets is None else offsets[i]
        g0 = wall + (room - w) // 2 + off
        cells[g0:g0 + w, cw:cw + wall] = FREE
        mid = cw + wall // 2
        segs.append(((g0 - 1.0, float(mid)), (g0 + w - 1.0, float(mid))))
    grid = OccupancyGrid(cells, RES, (1.0, -2.0, 0.0))
    labels, doors, _ = cut_rooms(grid, segs)
    return Segmentation(grid=grid, labels=labels, doors=doors, method="manual")


def room_centre(seg, i, room=30, wall=3):
    c = wall + (i - 1) * (room + wall) + room / 2 - 0.5
    r = wall + room / 2 - 0.5
    x, y = seg.grid.pixel_to_world(r, c)
    return float(x), float(y)


@pytest.fixture(scope="module")
def row():
    return corridor_of_rooms()


@pytest.fixture(scope="module")
def example():
    from topomap.io.example import example_map_path

    return segment(load_map(example_map_path()))


def test_hand_map_is_what_it_claims(row):
    assert row.n_rooms == 5
    assert [d.rooms for d in row.doors] == [(1, 2), (2, 3), (3, 4), (4, 5)]
    np.testing.assert_allclose([d.width for d in row.doors], [0.8, 1.0, 0.6, 1.0])


# --------------------------------------------------------------------------
# Graph invariants
# --------------------------------------------------------------------------

def _check_invariants(seg):
    G = seg.room_graph
    labels = seg.labels
    present = set(np.unique(labels[labels > 0]).tolist())
    # every room node has a label region, and every label region a node
    assert set(G.nodes) == present
    counts = np.bincount(labels.ravel())
    for n, d in G.nodes(data=True):
        assert d["cells"] == counts[n] > 0
    from skimage.draw import line

    H, W = labels.shape
    for d in seg.doors:
        a, b = d.rooms
        assert a != b and G.has_edge(a, b, key=d.id)
        # the two rooms' cells touch (4-neighbours) next to the door segment
        p = np.clip(np.rint(d.p1), 0, [H - 1, W - 1]).astype(int)
        q = np.clip(np.rint(d.p2), 0, [H - 1, W - 1]).astype(int)
        rr, cc = line(p[0], p[1], q[0], q[1])
        near = np.zeros(labels.shape, bool)
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                near[np.clip(rr + dr, 0, H - 1), np.clip(cc + dc, 0, W - 1)] = True
        A = near & (labels == a)
        B = near & (labels == b)
        touch = (A[:, :-1] & B[:, 1:]) | (B[:, :-1] & A[:, 1:])
        touch_v = (A[:-1, :] & B[1:, :]) | (B[:-1, :] & A[1:, :])
        assert touch.any() or touch_v.any(), f"door {d.id}: rooms {a} and {b} do not touch across it"


def test_invariants_hand_map(row):
    _check_invariants(row)


@pytest.mark.parametrize("method", sorted(METHODS))
def test_invariants_example(method):
    from topomap.io.example import example_map_path

    _check_invariants(segment(load_map(example_map_path()), method=method))


@pytest.mark.parametrize("method", sorted(METHODS))
@pytest.mark.parametrize("yaw", [0.0, 0.6])
def test_room_cells_recovered_from_graph_polygons(method, yaw):
    """A graph alone gives back the label image exactly (planning from a saved graph relies on it)."""
    from topomap.io.example import example_map_path

    g = load_map(example_map_path())
    seg = segment(OccupancyGrid(g.cells, g.resolution, (2.0, -1.0, yaw)), method=method)
    room_map = RoomMap(seg.room_graph)
    H, W = seg.labels.shape
    got = room_map.window_labels(list(seg.room_graph.nodes), (0, H, 0, W))
    np.testing.assert_array_equal(got, seg.labels)


# --------------------------------------------------------------------------
# Queries
# --------------------------------------------------------------------------

def test_room_at(row):
    G = row.room_graph
    for i in range(1, 6):
        x, y = room_centre(row, i)
        assert P.room_at(row, x, y) == i
        assert P.room_at(G, x, y) == i
    x, y = row.grid.pixel_to_world(1, 1)  # outer wall
    assert P.room_at(row, x, y) == 0 and P.room_at(G, x, y) == 0
    assert P.room_at(row, -100.0, 0.0) == 0 and P.room_at(G, -100.0, 0.0) == 0


def test_room_at_agrees_with_segmentation_everywhere(example):
    G = example.room_graph
    rng = np.random.default_rng(0)
    H, W = example.labels.shape
    for r, c in rng.uniform([-5, -5], [H + 5, W + 5], size=(300, 2)):
        x, y = example.grid.pixel_to_world(r, c)
        assert P.room_at(G, x, y) == P.room_at(example, x, y) == example.room_at(x, y)


def test_neighbors_and_doors_between(row):
    G = row.room_graph
    assert P.neighbors(G, 1) == [2]
    assert P.neighbors(G, 3) == [2, 4]
    assert P.neighbors(row, 5) == [4]
    assert P.doors_between(G, 2, 3) == [1]
    assert P.doors_between(G, 3, 2) == [1]
    assert P.doors_between(G, 1, 3) == []
    with pytest.raises(P.NotInRoomError):
        P.neighbors(G, 99)
    with pytest.raises(P.NotInRoomError):
        P.doors_between(G, 1, 99)


def test_doors_between_several_doors():
    """Two rooms joined by two doors: both are listed, each its own edge."""
    cells = np.full((40, 70), OCCUPIED, np.int8)
    cells[3:37, 3:33] = FREE
    cells[3:37, 36:67] = FREE
    cells[6:14, 33:36] = FREE
    cells[26:34, 33:36] = FREE
    grid = OccupancyGrid(cells, RES)
    labels, doors, _ = cut_rooms(grid, [((5.0, 34.0), (13.0, 34.0)), ((25.0, 34.0), (33.0, 34.0))])
    seg = Segmentation(grid=grid, labels=labels, doors=doors, method="manual")
    assert P.doors_between(seg.room_graph, 1, 2) == [0, 1]
    D = P.door_graph(seg)
    assert D.edges[0, 1]["length"] == pytest.approx(20 * RES, abs=2 * RES)


# --------------------------------------------------------------------------
# Travel distances and the door graph
# --------------------------------------------------------------------------

def test_room_distances_are_geodesic(row):
    # doors 0 and 1 both lie on the middle row of room 2: straight across it
    d = P.room_distances(row, 2)
    (m0x, _), (m1x, _) = row.doors[0].midpoint, row.doors[1].midpoint
    assert set(d) == {(0, 1)}
    assert d[(0, 1)] == pytest.approx(abs(m1x - m0x), abs=2 * RES)
    assert P.room_distances(row, 1) == {}  # one door only


def test_detour_is_not_a_straight_line():
    """Doors at opposite ends of a wall-split room: the distance goes around, not through."""
    seg = corridor_of_rooms(widths_px=(8, 8), offsets=(-10, 10))
    (d01,) = P.room_distances(seg, 2).values()
    (x0, y0), (x1, y1) = seg.doors[0].midpoint, seg.doors[1].midpoint
    assert d01 >= np.hypot(x1 - x0, y1 - y0) - 1e-9
    assert d01 == pytest.approx(max(abs(x1 - x0), abs(y1 - y0)) + (np.sqrt(2) - 1) * min(abs(x1 - x0), abs(y1 - y0)),
                                abs=2 * RES)  # 8-connected geodesic in an empty room


def test_travel_graph_stores_distances(row):
    G = P.travel_graph(row)
    assert G.graph["travel_distances"] == "geodesic"
    assert "door_distances" not in row.room_graph.nodes[2]  # the input is not modified
    (i, j, L), = G.nodes[2]["door_distances"]
    assert (i, j) == (0, 1) and isinstance(L, float)
    assert G.nodes[1]["door_distances"] == ()
    # the same from the graph alone (room cells rasterised from polygons)
    H = P.travel_graph(row.room_graph)
    for n in G:
        assert H.nodes[n]["door_distances"] == G.nodes[n]["door_distances"]


def test_door_graph(row):
    D = P.door_graph(row)
    assert sorted(D.nodes) == [0, 1, 2, 3]
    assert sorted(tuple(sorted(e)) for e in D.edges) == [(0, 1), (1, 2), (2, 3)]
    assert [D.edges[e]["room"] for e in [(0, 1), (1, 2), (2, 3)]] == [2, 3, 4]
    assert D.nodes[2]["rooms"] == (3, 4)
    assert D.nodes[2]["width"] == pytest.approx(0.6)
    x, y = row.doors[1].midpoint
    assert (D.nodes[1]["x"], D.nodes[1]["y"]) == pytest.approx((x, y))
    narrow = P.door_graph(row, min_width=0.7)
    assert sorted(narrow.nodes) == [0, 1, 3] and sorted(tuple(sorted(e)) for e in narrow.edges) == [(0, 1)]


# --------------------------------------------------------------------------
# Planning
# --------------------------------------------------------------------------

def test_plan_along_the_row(row):
    s, g = room_centre(row, 1), room_centre(row, 5)
    route = P.plan_path(row, s, g)
    assert route["rooms"] == [1, 2, 3, 4, 5]
    assert route["doors"] == [0, 1, 2, 3]
    wp = route["waypoints"]
    assert wp.shape == (6, 2)
    np.testing.assert_allclose(wp[0], s)
    np.testing.assert_allclose(wp[-1], g)
    np.testing.assert_allclose(wp[1:-1], [d.midpoint for d in row.doors])
    # doors centred on the rooms' middle row: the way is (nearly) straight
    assert route["length"] == pytest.approx(g[0] - s[0], abs=3 * RES)
    assert route["length"] == pytest.approx(sum(route["legs"]))
    assert (route["start_room"], route["goal_room"]) == (1, 5)
    back = P.plan_path(row, g, s)
    assert back["rooms"] == [5, 4, 3, 2, 1] and back["doors"] == [3, 2, 1, 0]
    assert back["length"] == pytest.approx(route["length"])


def test_plan_room_ids(row):
    route = P.plan_path(row, 2, 4)
    assert route["rooms"] == [2, 3, 4] and route["doors"] == [1, 2]
    n = row.room_graph.nodes[2]
    np.testing.assert_allclose(route["waypoints"][0], [n["interior_x"], n["interior_y"]])
    same = P.plan_path(row, 3, 3)
    assert same["rooms"] == [3] and same["doors"] == [] and same["length"] == 0


def test_plan_within_one_room(row):
    x, y = room_centre(row, 3)
    route = P.plan_path(row, (x - 0.5, y), (x + 0.5, y))
    assert route["rooms"] == [3] and route["doors"] == []
    assert route["length"] == pytest.approx(1.0, abs=RES)
    assert route["waypoints"].shape == (2, 2)


def test_plan_same_from_segmentation_graph_and_saved_file(row, tmp_path):
    from topomap.io.export import load_graphml, save_graphml

    s, g = room_centre(row, 1), room_centre(row, 4)
    a = P.plan_path(row, s, g)
    b = P.plan_path(P.travel_graph(row), s, g)
    c = P.plan_path(row.room_graph, s, g)  # no stored distances: computed from polygons
    save_graphml(P.travel_graph(row), tmp_path / "g.graphml")
    d = P.plan_path(load_graphml(tmp_path / "g.graphml"), s, g)
    for r in (b, c, d):
        assert r["rooms"] == a["rooms"] and r["doors"] == a["doors"]
        assert r["length"] == pytest.approx(a["length"], abs=1e-9)
        np.testing.assert_allclose(r["waypoints"], a["waypoints"])


def test_robot_width_excludes_narrow_doors(row):
    s, g = room_centre(row, 1), room_centre(row, 5)
    assert P.plan_path(row, s, g, robot_width=0.6)["doors"] == [0, 1, 2, 3]  # exactly as wide: fits
    with pytest.raises(P.NoPathError, match="0.7 m wide"):
        P.plan_path(row, s, g, robot_width=0.7)  # door 2 is 0.6 m
    assert P.plan_path(row, s, room_centre(row, 3), robot_width=0.7)["rooms"] == [1, 2, 3]
    with pytest.raises(P.PlanningError):
        P.plan_path(row, s, g, robot_width=-1)


def test_robot_width_takes_the_wider_detour():
    """Two ways between two rooms: the short one through a narrow door, the long one through a wide door."""
    cells = np.full((60, 70), OCCUPIED, np.int8)
    cells[3:57, 3:33] = FREE
    cells[3:57, 36:67] = FREE
    cells[26:34, 33:36] = FREE   # narrow door (0.4 m) in the middle
    cells[4:24, 33:36] = FREE    # wide door (1.0 m) at the top
    grid = OccupancyGrid(cells, RES)
    labels, doors, _ = cut_rooms(grid, [((25.0, 34.0), (33.0, 34.0)), ((3.0, 34.0), (23.0, 34.0))])
    seg = Segmentation(grid=grid, labels=labels, doors=doors, method="manual")
    s = tuple(float(v) for v in grid.pixel_to_world(45, 10))
    g = tuple(float(v) for v in grid.pixel_to_world(45, 60))
    assert P.plan_path(seg, s, g)["doors"] == [0]
    wide = P.plan_path(seg, s, g, robot_width=0.5)
    assert wide["doors"] == [1]
    assert wide["length"] > P.plan_path(seg, s, g)["length"]


def test_no_path_across_a_wall():
    cells = np.full((40, 70), OCCUPIED, np.int8)
    cells[3:37, 3:33] = FREE
    cells[3:37, 36:67] = FREE  # a solid wall between, no door
    grid = OccupancyGrid(cells, RES)
    labels, doors, _ = cut_rooms(grid, [])
    seg = Segmentation(grid=grid, labels=labels, doors=doors, method="manual")
    assert seg.n_rooms == 2 and doors == []
    s = tuple(float(v) for v in grid.pixel_to_world(20, 10))
    g = tuple(float(v) for v in grid.pixel_to_world(20, 60))
    with pytest.raises(P.NoPathError) as ei:
        P.plan_path(seg, s, g)
    assert isinstance(ei.value, TopomapError) and isinstance(ei.value, ValueError)
    assert "no path" in str(ei.value) and "\n" not in str(ei.value)


def test_bad_endpoints(row):
    s = room_centre(row, 1)
    wall = tuple(float(v) for v in row.grid.pixel_to_world(1, 1))
    with pytest.raises(P.NotInRoomError, match="not in the free space"):
        P.plan_path(row, wall, s)
    with pytest.raises(P.NotInRoomError, match="outside the map"):
        P.plan_path(row, s, (-100.0, 0.0))
    with pytest.raises(P.NotInRoomError, match="room 42"):
        P.plan_path(row, s, 42)
    with pytest.raises(P.PlanningError):
        P.plan_path(row, "kitchen", s)
    with pytest.raises(P.PlanningError):
        P.plan_path(row, (np.nan, 0.0), s)
    for cls in (P.PlanningError, P.NotInRoomError, P.NoPathError):
        assert issubclass(cls, TopomapError) and issubclass(cls, ValueError)


def test_room_id_with_centroid_outside_the_room():
    """An L-shaped room's centroid lies outside it: the nearest cell of the room stands in."""
    cells = np.full((50, 50), OCCUPIED, np.int8)
    cells[3:47, 3:13] = FREE
    cells[37:47, 3:47] = FREE
    grid = OccupancyGrid(cells, RES)
    labels, doors, _ = cut_rooms(grid, [])
    seg = Segmentation(grid=grid, labels=labels, doors=doors, method="manual")
    n = seg.room_graph.nodes[1]
    assert P.room_at(seg, n["x"], n["y"]) == 0
    route = P.plan_path(seg, 1, 1)
    x, y = route["waypoints"][0]
    assert P.room_at(seg, x, y) == 1


def test_plan_on_example(example):
    G = P.travel_graph(example)
    nodes = sorted(G.nodes)
    for a in nodes:
        for b in nodes:
            if not nx.has_path(G, a, b):
                with pytest.raises(P.NoPathError):
                    P.plan_path(G, a, b)
                continue
            r = P.plan_path(G, a, b)
            assert r["rooms"][0] == a and r["rooms"][-1] == b
            # consecutive rooms are joined by the door passed between them
            for (u, v), d in zip(zip(r["rooms"][:-1], r["rooms"][1:]), r["doors"]):
                assert d in P.doors_between(G, u, v)
            # never shorter than the straight line between the waypoints
            wp = r["waypoints"]
            assert r["length"] >= np.hypot(*np.diff(wp, axis=0).T).sum() - 1e-6


# --------------------------------------------------------------------------
# Travel distances on the coarse grid against the map-grid geodesic
# --------------------------------------------------------------------------

#: The stated tolerance of the coarse travel distances (docs/graph-attributes.md).
TRAVEL_TOLERANCE = 0.06


def hall_with_partition(partition=True):
    """A 6 m x 9 m hall between two small rooms, a one-cell partition wall
    across most of the hall, doors on either side of the partition and far
    apart: the hall is larger than planning.EXACT_CELLS, so its distances
    come from the coarse grid."""
    H, W, wall = 130, 200, 3
    cells = np.full((H, W), OCCUPIED, np.int8)
    cells[wall:H - wall, 40:160] = FREE                  # the hall
    cells[wall:40, wall:37] = FREE                       # west room
    cells[wall:40, 163:W - wall] = FREE                  # east room
    if partition:
        cells[wall:100, 99] = OCCUPIED                   # one-cell partition, open at the bottom
    cells[10:26, 37:40] = FREE                           # door west (top of the hall, left of the partition)
    cells[10:26, 160:163] = FREE                         # door east (right of the partition)
    grid = OccupancyGrid(cells, RES, (0.0, 0.0, 0.0))
    segs = [((9.0, 38.0), (26.0, 38.0)), ((9.0, 161.0), (26.0, 161.0))]
    labels, doors, _ = cut_rooms(grid, segs)
    return Segmentation(grid=grid, labels=labels, doors=doors, method="manual")


def test_coarse_distance_goes_around_a_thin_partition():
    seg = hall_with_partition()
    (hall,) = set(seg.doors[0].rooms) & set(seg.doors[1].rooms)
    assert seg.n_rooms == 3
    room_map = RoomMap(seg)
    assert P.RoomSpace(room_map, hall).mask.size > P.EXACT_CELLS  # the coarse grid is used
    (fast,) = P.room_distances(seg, hall).values()
    (exact,) = P.room_distances(seg, hall, exact=True).values()
    (x0, y0), (x1, y1) = seg.doors[0].midpoint, seg.doors[1].midpoint
    assert exact > np.hypot(x1 - x0, y1 - y0) + 4.0  # the way is down around the partition and back up
    assert fast == pytest.approx(exact, rel=TRAVEL_TOLERANCE)
    G = P.travel_graph(seg)
    assert [L for _, _, L in G.nodes[hall]["door_distances"]] == [fast]
    Gx = P.travel_graph(seg, exact=True)
    assert [L for _, _, L in Gx.nodes[hall]["door_distances"]] == [exact]


def test_doors_in_sight_get_the_exact_distance():
    """Without the partition the two doors see each other: the distance is the map-grid geodesic itself."""
    seg = hall_with_partition(partition=False)
    (hall,) = set(seg.doors[0].rooms) & set(seg.doors[1].rooms)
    assert P.RoomSpace(RoomMap(seg), hall).mask.size > P.EXACT_CELLS
    (fast,) = P.room_distances(seg, hall).values()
    (exact,) = P.room_distances(seg, hall, exact=True).values()
    assert fast == pytest.approx(exact, rel=1e-9)


def test_small_rooms_get_the_exact_distance():
    """A room whose window holds at most EXACT_CELLS cells gets the map-grid geodesic for every pair:
    searched, or the octile distance where two doors see each other (the same number)."""
    cells = np.full((80, 120), OCCUPIED, np.int8)
    cells[30:50, 40:80] = FREE                           # a 1 m x 2 m hall
    cells[37:43, 58:62] = OCCUPIED                       # a pillar in it, between the west and east doors
    cells[5:26, 5:115] = FREE                            # rooms north, south, west and east of it
    cells[54:75, 5:115] = FREE
    cells[30:50, 5:36] = FREE
    cells[30:50, 84:115] = FREE
    cells[26:30, 50:60] = FREE                           # the doors
    cells[50:54, 62:72] = FREE
    cells[35:45, 36:40] = FREE
    cells[35:45, 80:84] = FREE
    segs = [((28.0, 50.0), (28.0, 59.0)), ((52.0, 62.0), (52.0, 71.0)),
            ((35.0, 38.0), (44.0, 38.0)), ((35.0, 82.0), (44.0, 82.0))]
    labels, doors, _ = cut_rooms(OccupancyGrid(cells, RES, (0.0, 0.0, 0.0)), segs)
    seg = Segmentation(grid=OccupancyGrid(cells, RES, (0.0, 0.0, 0.0)), labels=labels, doors=doors,
                       method="manual")
    hall = int(labels[32, 45])
    sp = P.RoomSpace(RoomMap(seg), hall)
    assert len(sp.door_px) == 4 and sp.mask.size <= P.EXACT_CELLS
    ids = sorted(sp.door_px)
    sight = P._in_sight(sp.mask, np.array([sp.door_px[d] for d in ids], float))
    assert 0 < np.triu(sight, 1).sum() < 6  # some pairs in sight, the pillar hides others
    fast, exact = P.room_distances(seg, hall), P.room_distances(seg, hall, exact=True)
    assert len(exact) == 6 and set(fast) == set(exact)
    for k, L in exact.items():
        assert fast[k] == pytest.approx(L, rel=1e-9), k


def _door_cells_one_by_one(room_map, r):
    """The reference of ``RoomSpace``'s door cells: door by door, the cells of its segment on the
    two rooms it joins; of those the ones with a cell of each of the two rooms in their 3 x 3
    neighbourhood (where the rooms meet; all of them when there is none), the one nearest its
    midpoint (the first of equals)."""
    sp = P.RoomSpace(room_map, r)
    r0, _, c0, _ = sp.win
    out = {}
    for d in room_map.doors_of(r):
        a, b = room_map.doors[d][:2]
        L = np.pad(room_map.window_labels({a, b}, sp.win), 1)
        rr, cc = room_map.door_cells(d)
        rr, cc = rr - r0, cc - c0
        ok = L[rr + 1, cc + 1] > 0
        if ok.any():
            around = [set(L[i:i + 3, j:j + 3].ravel().tolist()) for i, j in zip(rr, cc)]
            meet = ok & np.array([{a, b} <= s for s in around])
            pick = meet if meet.any() else ok
            p1, p2 = room_map.doors[d][2:4]
            mr, mc = (p1[0] + p2[0]) / 2 - r0, (p1[1] + p2[1]) / 2 - c0
            i = int(np.argmin((rr[pick] - mr) ** 2 + (cc[pick] - mc) ** 2))
            out[d] = (int(rr[pick][i]), int(cc[pick][i]))
            assert sp.mask[rr[ok], cc[ok]].all()  # the door's cells are traversable
    return sp.door_px, out


def test_door_cells_are_the_cells_nearest_the_midpoints(example):
    """Every room's door cells, all doors at once, as found door by door; from the segmentation and
    from its graph alone (the room polygons rasterised)."""
    checked = 0
    for room_map in (RoomMap(example), RoomMap(example.room_graph)):
        for r in example.room_graph.nodes:
            got, want = _door_cells_one_by_one(room_map, r)
            assert got == want and list(got) == list(want), r
            checked += len(want)
    assert checked >= 2 * example.room_graph.number_of_edges()


def test_door_cells_first_of_equally_near_cells():
    """A door whose midpoint lies between two cells takes the first of them along its segment."""
    seg = corridor_of_rooms(widths_px=(15,), offsets=[0])
    room_map = RoomMap(seg)
    (d,) = room_map.doors
    got, want = _door_cells_one_by_one(room_map, 1)
    assert got == want and d in got
    rr, cc = room_map.door_cells(d)
    p1, p2 = room_map.doors[d][2:4]
    mid = ((p1[0] + p2[0]) / 2, (p1[1] + p2[1]) / 2)
    d2 = (rr - mid[0]) ** 2 + (cc - mid[1]) ** 2
    assert np.count_nonzero(d2 == d2.min()) == 2  # a tie, broken by the order along the segment


def test_coarse_distances_of_a_real_map_within_tolerance(example):
    exact_pairs = 0
    for r in example.room_graph.nodes:
        fast = P.room_distances(example, r)
        exact = P.room_distances(example, r, exact=True)
        assert set(fast) == set(exact)
        for k, L in exact.items():
            assert fast[k] == pytest.approx(L, rel=TRAVEL_TOLERANCE), (r, k)
            exact_pairs += 1
    assert exact_pairs > 0


def test_window_room_test_of_door_cells_is_membership_in_the_rooms():
    # RoomMap.window_room's test "on one of these rooms" (a table over the labels) against np.isin,
    # with labels below, between and above the rooms asked for
    seg = hall_with_partition()
    labels = seg.labels.copy()
    labels[0, :5] = [-1, -7, seg.n_rooms + 5, 0, 1]
    seg.labels = labels
    room_map = RoomMap(seg)
    H, W = labels.shape
    rr, cc = np.divmod(np.arange(H * W), W)
    for r in range(1, seg.n_rooms + 1):
        for rooms in ({r}, {r} | {x for d in seg.doors for x in d.rooms if r in d.rooms}):
            mask, on = room_map.window_room(r, rooms, (0, H, 0, W))
            np.testing.assert_array_equal(mask, labels == r)
            np.testing.assert_array_equal(on(rr, cc), np.isin(labels[rr, cc], sorted(rooms)))


def test_route_across_a_door_whose_segment_runs_on_through_a_wall():
    """A door segment that runs on past the place its two rooms meet, through a wall into a part
    of one room the other does not reach, with its midpoint there: the route crosses it where the
    rooms meet (the cell nearest the midpoint was beyond the wall: no route from the other room)."""
    cells = np.full((50, 66), OCCUPIED, np.int8)
    labels = np.zeros((50, 66), np.int32)
    labels[5:25, 5:61] = 1  # room 1: a band across the top ...
    labels[25:45, 35:61] = 1  # ... and a block below its right half
    labels[25:45, 5:31] = 2  # room 2 below its left half; columns 31-34 a wall between 2 and 1
    cells[labels > 0] = FREE
    grid = OccupancyGrid(cells, RES)
    from topomap.core.doors import Door

    p1, p2 = (25.0, 10.0), (25.0, 60.0)  # midpoint column 35: room 1, beyond the wall
    (x1, x2), (y1, y2) = grid.pixel_to_world(np.array([p1[0], p2[0]]), np.array([p1[1], p2[1]]))
    door = Door(id=0, p1=p1, p2=p2, xy1=(x1, y1), xy2=(x2, y2), width=2.5, rooms=(1, 2))
    seg = Segmentation(grid=grid, labels=labels, doors=[door], method="manual")
    for source in (seg, seg.room_graph):
        start, goal = grid.pixel_to_world(10, 20), grid.pixel_to_world(40, 15)
        route = P.plan_path(source, tuple(map(float, start)), tuple(map(float, goal)))
        assert route["rooms"] == [1, 2] and route["doors"] == [0]
        # start -> (25, 30) -> goal, octile steps in open floor (round the wall would be longer)
        want = (15 + 10 * (np.sqrt(2) - 1) + 15 * np.sqrt(2)) * RES
        assert route["length"] == pytest.approx(want, rel=1e-9)
    assert RoomMap(seg).door_point(0) == (25, 30)  # beside both rooms, nearest the midpoint
