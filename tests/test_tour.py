"""Room tours (topomap.planning.tour, re-exported as topomap.planning.plan_tour) on maps whose best tour is known."""

import itertools
import json

import numpy as np
import pytest
from click.testing import CliRunner

from topomap.errors import NoPathError, NotInRoomError
from topomap.io.export import load_graph, save_graph
from topomap.io import FREE, OCCUPIED, OccupancyGrid
from topomap.planning import plan_tour, travel_graph
from topomap.core.segmentation import Segmentation, cut_rooms
from topomap.planning.tour import solve_order, stop_distances, tour_length, tour_lower_bound

RES = 0.05


def comb(k=5, room=30, wall=3, corridor=16, door=12, island=False):
    """A corridor along the top with ``k`` rooms below it, each with one door
    in the middle of its north wall; optionally a closed-off room east of the
    building. Segmented from the known door segments (no detection), so the
    corridor is room 1 and the rooms are 2..k+1 west to east."""
    H = wall + corridor + wall + room + wall
    W = k * (room + wall) + wall + (room + wall if island else 0)
    cells = np.full((H, W), OCCUPIED, np.int8)
    cells[wall:wall + corridor, wall:k * (room + wall)] = FREE
    r0 = wall + corridor + wall
    segs = []
    for i in range(k):
        c0 = wall + i * (room + wall)
        cells[r0:r0 + room, c0:c0 + room] = FREE
        g0 = c0 + (room - door) // 2
        cells[wall + corridor:r0, g0:g0 + door] = FREE
        mid = wall + corridor + wall // 2
        segs.append(((float(mid), g0 - 1.0), (float(mid), float(g0 + door))))
    if island:
        c0 = k * (room + wall) + wall
        cells[r0:r0 + room, c0:c0 + room - wall] = FREE
    grid = OccupancyGrid(cells, RES, (0.0, 0.0, 0.0))
    labels, doors, _ = cut_rooms(grid, segs)
    return Segmentation(grid=grid, labels=labels, doors=doors, method="manual")


def west_end(seg, wall=3, corridor=16):
    x, y = seg.grid.pixel_to_world(wall + corridor // 2, wall + 1)
    return float(x), float(y)


def brute_force(D, closed):
    n = D.shape[0] - 1
    return min(tour_length(D, p, closed=closed) for p in itertools.permutations(range(1, n + 1)))


def euclid(P):
    return np.linalg.norm(P[:, None] - P[None], axis=-1)


@pytest.mark.parametrize("n", [1, 2, 4, 7])
@pytest.mark.parametrize("closed", [False, True])
def test_held_karp_equals_brute_force(n, closed):
    rng = np.random.default_rng(n + 10 * closed)
    for _ in range(5):
        D = euclid(rng.random((n + 1, 2)) * 10)
        order, method = solve_order(D, closed=closed)
        assert method == "held-karp" and sorted(order) == list(range(1, n + 1))
        assert tour_length(D, order, closed=closed) == pytest.approx(brute_force(D, closed))
        assert tour_lower_bound(D) <= brute_force(D, closed) + 1e-9


def test_heuristic_on_points_in_convex_position():
    # no 2-opt move improves a tour without crossings, and on points in
    # convex position the only such closed tour is the polygon itself
    n = 25
    rng = np.random.default_rng(3)
    angles = rng.permutation(np.linspace(0, 2 * np.pi, n, endpoint=False))
    P = np.c_[np.cos(angles), np.sin(angles)] * 5
    D = euclid(P)
    order, method = solve_order(D, closed=True, exact_limit=12)
    assert method.startswith("nearest-neighbour")
    perimeter = 2 * n * 5 * np.sin(np.pi / n)
    assert tour_length(D, order, closed=True) == pytest.approx(perimeter)


def test_points_on_a_line():
    # from one end the best open tour walks to the other end: the MST's weight
    x = np.array([0.0, 3.0, 1.0, 7.0, 2.0, 5.0])
    D = np.abs(x[:, None] - x[None])
    order, _ = solve_order(D)
    assert [x[i] for i in order] == sorted(x[1:])
    assert tour_length(D, order) == pytest.approx(7.0) == tour_lower_bound(D)
    order, _ = solve_order(D, exact_limit=0)
    assert tour_length(D, order) == pytest.approx(7.0)


@pytest.fixture(scope="module")
def combseg():
    return comb()


def test_comb_from_the_west_end(combseg):
    seg = combseg
    assert seg.n_rooms == 6 and len(seg.doors) == 5
    tour = plan_tour(seg, west_end(seg))
    assert tour["order"] == [1, 2, 3, 4, 5, 6] and tour["method"] == "held-karp"
    # every door twice (in and out), the last one once: the tour ends in the last room
    by_room = {max(d.rooms): d.id for d in seg.doors}
    assert tour["doors"] == [by_room[r] for r in (2, 2, 3, 3, 4, 4, 5, 5, 6)]
    assert tour["rooms"] == [1, 2, 1, 3, 1, 4, 1, 5, 1, 6]
    assert tour["length"] == pytest.approx(sum(tour["legs"]))
    assert len(tour["waypoints"]) == 1 + len(tour["doors"]) + 5
    # the same as the optimum over the stops' distances, and the heuristic agrees here
    sd = stop_distances(seg, west_end(seg))
    assert tour["length"] == pytest.approx(brute_force(sd["D"], False))
    heur = plan_tour(seg, west_end(seg), exact_limit=0)
    assert heur["order"] == tour["order"] and heur["length"] == pytest.approx(tour["length"])
    assert tour_lower_bound(sd["D"]) <= tour["length"]


def test_comb_round_trip_and_subset(combseg):
    seg = combseg
    tour = plan_tour(seg, west_end(seg), return_to_start=True)
    # back to the start: every door in and out once (any order that walks the
    # corridor east on the way out and west on the way back is as short)
    assert tour["order"][0] == 1 and sorted(tour["order"]) == [1, 2, 3, 4, 5, 6]
    assert sorted(tour["doors"]) == sorted(2 * [d.id for d in seg.doors])
    assert tour["length"] == pytest.approx(brute_force(stop_distances(seg, west_end(seg))["D"], True))
    assert len(tour["legs"]) == 6 and tour["rooms"][-1] == 1
    assert np.allclose(tour["waypoints"][-1], west_end(seg))
    sub = plan_tour(seg, west_end(seg), rooms=[5, 3])
    assert sub["order"] == [1, 3, 5]
    # from the middle room: its neighbours on one side first, then the other side
    start = (seg.room_graph.nodes[4]["interior_x"], seg.room_graph.nodes[4]["interior_y"])
    mid = plan_tour(seg, 4)
    assert mid["order"][0] == 4 and np.allclose(mid["waypoints"][0], start)
    assert mid["length"] == pytest.approx(brute_force(stop_distances(seg, 4)["D"], False))


def test_tour_from_a_saved_graph(combseg, tmp_path):
    seg = combseg
    path = save_graph(travel_graph(seg), tmp_path / "rooms.graphml")
    G = load_graph(path)
    a, b = plan_tour(seg, west_end(seg)), plan_tour(G, west_end(seg))
    assert a["order"] == b["order"] and a["doors"] == b["doors"]
    assert a["length"] == pytest.approx(b["length"])


def test_unreachable_rooms():
    seg = comb(k=3, island=True)
    assert seg.n_rooms == 5
    tour = plan_tour(seg, west_end(seg))
    assert tour["unreachable"] == [5] and sorted(tour["order"]) == [1, 2, 3, 4]
    with pytest.raises(NoPathError, match="rooms 5 cannot be reached"):
        plan_tour(seg, west_end(seg), rooms=[2, 5])
    with pytest.raises(NotInRoomError, match="no room 9"):
        plan_tour(seg, west_end(seg), rooms=[9])
    with pytest.raises(NotInRoomError):
        plan_tour(seg, (-5.0, -5.0))
    # doors too narrow for the robot: nothing but the start room is reachable
    narrow = plan_tour(seg, west_end(seg), robot_width=1.0)
    assert narrow["order"] == [1] and narrow["length"] == 0.0 and narrow["unreachable"] == [2, 3, 4, 5]


def test_cli_tour(combseg, tmp_path):
    from topomap.cli import main

    seg = combseg
    path = save_graph(travel_graph(seg), tmp_path / "rooms.graphml")
    x, y = west_end(seg)
    run = CliRunner().invoke
    res = run(main, ["tour", str(path), "--from", str(x), str(y), "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    assert out["order"] == [1, 2, 3, 4, 5, 6]
    res = run(main, ["tour", str(path), "--from", str(x), str(y), "--rooms", "6,2", "--return"])
    assert res.exit_code == 0 and "order: 1 -> 2 -> 6 -> start" in res.output.replace("6 -> 2", "2 -> 6")
    bad = run(main, ["tour", str(path), "--from", str(x), str(y), "--rooms", "two"])
    assert bad.exit_code == 1 and "--rooms" in bad.output
