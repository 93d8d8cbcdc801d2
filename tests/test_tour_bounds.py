"""Tours of many rooms are bounded in work: the heuristic's moves are capped, and above
TREE_LIMIT rooms no distance matrix is made (a walk of a spanning tree instead)."""

import numpy as np
import networkx as nx
import pytest

from topomap import planning as P
from topomap.planning import tour as TR
from topomap.core.doors import Door
from topomap.io import FREE, OCCUPIED, OccupancyGrid
from topomap.core.segmentation import Segmentation


def grid_of_rooms(k, cell=12, res=0.05):
    """``k`` x ``k`` square rooms of ``cell`` cells, 1-cell walls, a 4-cell door to the right and
    below each room."""
    S = cell + 1
    H = W = k * S + 1
    labels = np.zeros((H, W), np.int32)
    segs = []
    for i in range(k):
        for j in range(k):
            r0, c0, a = 1 + i * S, 1 + j * S, i * k + j + 1
            labels[r0:r0 + cell, c0:c0 + cell] = a
            if j + 1 < k:
                labels[r0 + 4:r0 + 8, c0 + cell] = a
                segs.append(((r0 + 3.0, c0 + cell + 0.0), (r0 + 8.0, c0 + cell + 0.0), (a, a + 1)))
            if i + 1 < k:
                labels[r0 + cell, c0 + 4:c0 + 8] = a
                segs.append(((r0 + cell + 0.0, c0 + 3.0), (r0 + cell + 0.0, c0 + 8.0), (a, a + k)))
    grid = OccupancyGrid(np.where(labels > 0, FREE, OCCUPIED).astype(np.int8), res)
    doors = []
    for n, (p1, p2, rooms) in enumerate(segs):
        (x1, x2), (y1, y2) = grid.pixel_to_world(np.array([p1[0], p2[0]]), np.array([p1[1], p2[1]]))
        doors.append(Door(id=n, p1=p1, p2=p2, xy1=(x1, y1), xy2=(x2, y2), width=0.25, rooms=rooms))
    return Segmentation(grid=grid, labels=labels, doors=doors, method="manual")


@pytest.fixture(scope="module")
def rooms49():
    return P.travel_graph(grid_of_rooms(7))


def test_heuristic_moves_within_budget():
    rng = np.random.default_rng(1)
    for n, kicks_expected in ((60, True), (TR.KICK_LIMIT + 40, False)):
        pts = rng.random((n + 1, 2)) * 50
        D = np.hypot(*(pts[:, None, :] - pts[None, :, :]).transpose(2, 0, 1))
        stats = {}
        order = TR._improve(D, TR._nearest_neighbour(D), False, stats=stats)
        assert sorted(order) == list(range(1, n + 1))
        m = n + 2  # the cycle with the start and the stop glued to it
        assert stats["budget"] == TR.MOVES_BASE + TR.MOVES_PER_STOP * m
        assert 0 < stats["moves"] <= stats["budget"]
        assert stats["searches"] == (TR.KICKS + 1 if kicks_expected else 1)
        assert TR.tour_length(D, order) <= TR.tour_length(D, TR._nearest_neighbour(D)) + 1e-9
    # a budget spent stops the kicks: one move allowed, one search
    stats = {}
    old = TR.MOVES_BASE, TR.MOVES_PER_STOP
    try:
        TR.MOVES_BASE, TR.MOVES_PER_STOP = 1, 0
        TR._improve(D, TR._nearest_neighbour(D)[::-1], False, stats=stats)
    finally:
        TR.MOVES_BASE, TR.MOVES_PER_STOP = old
    assert stats["moves"] == 1 and stats["searches"] == 1


def test_stop_distances_are_the_shortest_routes(rooms49):
    sd = TR.stop_distances(rooms49, 1)
    H = sd["graph"]
    names = [("start",)] + [("room", r) for r in sd["stops"]]
    for i in (0, 5, 17):
        dist = nx.single_source_dijkstra_path_length(H, names[i], weight="length")
        for j, b in enumerate(names):
            assert sd["D"][i, j] == pytest.approx(dist[b], abs=1e-9)
        route = sd["paths"][(i, 30)]
        assert route[0] == names[i] and route[-1] == names[30]
        assert sum(H.edges[u, v]["length"] for u, v in zip(route[:-1], route[1:])) == pytest.approx(sd["D"][i, 30])


@pytest.mark.parametrize("closed", [False, True])
def test_many_rooms_walk_a_spanning_tree(rooms49, monkeypatch, closed):
    """Above TREE_LIMIT rooms: no distance matrix (no search per stop), every room once, each leg a
    real route along the door graph, the tour at most twice the tree's weight."""
    calls = {"stop_distances": 0}
    real = TR.stop_distances

    def counted(*a, **k):
        calls["stop_distances"] += 1
        return real(*a, **k)

    monkeypatch.setattr(TR, "stop_distances", counted)
    monkeypatch.setattr(TR, "TREE_LIMIT", 20)
    tour = TR.plan_tour(rooms49, 1, return_to_start=closed)
    assert calls["stop_distances"] == 0 and tour["method"] == "spanning-tree-walk"
    assert sorted(tour["order"]) == list(range(1, 50)) and not tour["unreachable"]
    assert len(tour["legs"]) == 48 + closed and tour["length"] == pytest.approx(sum(tour["legs"]))
    # the doors passed join the rooms passed, one after the other
    G = rooms49
    ends = {int(d["door"]): {a, b} for a, b, d in G.edges(data=True)}
    rooms = tour["rooms"]
    k = 0
    for d in tour["doors"]:
        while rooms[k] not in ends[d] or rooms[k + 1] not in ends[d]:
            k += 1
    # no shorter than the optimum's bound, no longer than twice a spanning tree of the door graph
    sd = real(rooms49, 1)
    assert tour["length"] >= TR.tour_lower_bound(sd["D"]) - 1e-9
    H = sd["graph"]
    mst = sum(d["length"] for _, _, d in nx.minimum_spanning_edges(H, weight="length", data=True))
    assert tour["length"] <= 2 * mst + 1e-6
    # against the matrix heuristic on the same rooms
    monkeypatch.setattr(TR, "TREE_LIMIT", 1000)
    matrix = TR.plan_tour(rooms49, 1, return_to_start=closed)
    assert matrix["method"].startswith("nearest-neighbour") and tour["length"] <= 2.5 * matrix["length"]


def test_tree_walk_unreachable_rooms_and_named_rooms(monkeypatch):
    seg = grid_of_rooms(5)
    seg.doors = [d for d in seg.doors if 13 not in d.rooms]  # room 13 walled in
    for k, d in enumerate(seg.doors):
        d.id = k
    G = P.travel_graph(seg)
    monkeypatch.setattr(TR, "TREE_LIMIT", 5)
    tour = TR.plan_tour(G, 1)
    assert tour["method"] == "spanning-tree-walk" and tour["unreachable"] == [13]
    assert sorted(tour["order"]) == [r for r in range(1, 26) if r != 13]
    with pytest.raises(P.NoPathError, match="13"):
        TR.plan_tour(G, 1, rooms=list(range(2, 20)))
