"""Every room has an interior point, inside its cells: node attributes, labels drawn there,
and plan / tour given a room ID go there."""

import json

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings

import _testdata as T
from test_whole_graph import fuzzed
from topomap.io import export as E
from topomap.planning import paths as P
from topomap.io import FREE, OCCUPIED, OccupancyGrid, from_array
from topomap.core.roomgraph import interior_points
from topomap.core.segmentation import Segmentation, cut_rooms, segment

RES = 0.05


def _seg_of(free):
    cells = np.where(free, FREE, OCCUPIED).astype(np.int8)
    grid = OccupancyGrid(cells, RES)
    labels, doors, _ = cut_rooms(grid, [])
    return Segmentation(grid=grid, labels=labels, doors=doors, method="manual")


def _ring():
    """A ring corridor 6 cells wide round a solid block: its centroid is in the block."""
    a = np.zeros((60, 80), bool)
    a[5:55, 5:75] = True
    a[11:49, 11:69] = False
    return a


def _l_shape():
    a = np.zeros((50, 50), bool)
    a[3:47, 3:13] = True
    a[37:47, 3:47] = True
    return a


@pytest.mark.parametrize("make", [_ring, _l_shape])
def test_interior_point_inside_where_the_centroid_is_not(make):
    seg = _seg_of(make())
    n = seg.room_graph.nodes[1]
    assert P.room_at(seg, n["x"], n["y"]) == 0  # the centroid is off the room
    assert P.room_at(seg, n["interior_x"], n["interior_y"]) == 1
    r, c = int(n["interior_row"]), int(n["interior_col"])
    assert seg.labels[r, c] == 1
    x, y = seg.grid.pixel_to_world(r, c)
    assert (x, y) == pytest.approx((n["interior_x"], n["interior_y"]))


def test_interior_point_of_a_rectangle_is_its_middle():
    labels = np.zeros((30, 50), np.int32)
    labels[2:23, 3:44] = 1  # 21 x 41 cells: the middle cell is (12, 23)
    labels[25:28, 3:10] = 2  # a thin room: every cell is on its edge
    rows, cols = interior_points(labels, 2, np.array([[0, 0], [12.0, 23.0], [26.0, 6.0]]))
    assert (rows[1], cols[1]) == (12, 23)
    assert labels[rows[2], cols[2]] == 2 and (rows[2], cols[2]) == (26, 6)
    assert rows[0] == -1 and cols[0] == -1
    # a label without cells, and fragments (above n) are no room
    labels[0, 0] = 5
    rows, cols = interior_points(labels, 3)
    assert rows[3] == -1 and labels[rows[1], cols[1]] == 1


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(a=fuzzed)
def test_interior_point_in_its_room_on_fuzzed_maps(a):
    seg = segment(from_array(a, resolution=T.RES))
    for i, n in seg.room_graph.nodes(data=True):
        assert seg.labels[int(n["interior_row"]), int(n["interior_col"])] == i
        assert P.room_at(seg, n["interior_x"], n["interior_y"]) == i


@pytest.mark.parametrize("ext", ["graphml", "json", "geojson"])
def test_interior_point_round_trips_typed(tmp_path, ext):
    seg = _seg_of(_l_shape())
    G = seg.room_graph
    back = E.load_graph(E.save_graph(G, tmp_path / f"rooms.{ext}"))
    for k in ("interior_x", "interior_y", "interior_row", "interior_col"):
        assert type(back.nodes[1][k]) is float and back.nodes[1][k] == G.nodes[1][k]
    # a room ID stands for the interior point, from the saved graph too
    route = P.plan_path(back, 1, 1)
    assert tuple(route["waypoints"][0]) == pytest.approx((G.nodes[1]["interior_x"], G.nodes[1]["interior_y"]))


def test_plan_from_room_id_starts_at_the_interior_point():
    seg = _seg_of(_ring())
    n = seg.room_graph.nodes[1]
    route = P.plan_path(seg, 1, (n["interior_x"], n["interior_y"]))
    assert route["length"] == 0 and route["rooms"] == [1]
    # the room's own point as a goal is in the room (the centroid was "not in the free space of any room")
    with pytest.raises(P.NotInRoomError):
        P.plan_path(seg, 1, (n["x"], n["y"]))


def test_overlay_label_drawn_inside_its_room():
    from topomap.io.plot import _BOX, _overlay_indexed

    seg = _seg_of(_l_shape())
    idx, _ = _overlay_indexed(seg)
    rr, cc = np.nonzero(idx == _BOX)
    assert rr.size
    assert seg.labels[int(round(rr.mean())), int(round(cc.mean()))] == 1  # the label's box is on the room


# --------------------------------------------------------------------------
# CLI: plan / tour from and to a room ID
# --------------------------------------------------------------------------

def _run(*args):
    from topomap.cli import main

    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    from test_planning import corridor_of_rooms

    seg = corridor_of_rooms()
    d = tmp_path_factory.mktemp("saved")
    E.write_outputs(seg, d, P.travel_graph(seg))
    return d, seg


def test_cli_plan_room_ids(saved):
    d, seg = saved
    r = _run("plan", d / "rooms.graphml", "--from-room", 1, "--to-room", 5, "--json")
    assert r.exit_code == 0, r.output
    out = json.loads(r.stdout)
    assert out["rooms"] == [1, 2, 3, 4, 5] and out["doors"] == [0, 1, 2, 3]
    G = seg.room_graph
    assert out["waypoints"][0] == pytest.approx([G.nodes[1]["interior_x"], G.nodes[1]["interior_y"]])
    assert out["waypoints"][-1] == pytest.approx([G.nodes[5]["interior_x"], G.nodes[5]["interior_y"]])
    # a room and a point mixed
    x, y = G.nodes[5]["interior_x"], G.nodes[5]["interior_y"]
    r = _run("plan", d / "rooms.json", "--from-room", 2, "--to", x, y)
    assert r.exit_code == 0 and "rooms: 2 -> 3 -> 4 -> 5" in r.stdout


def test_cli_plan_room_id_errors(saved):
    d, _ = saved
    r = _run("plan", d / "rooms.graphml", "--from-room", 1, "--from", 0, 0, "--to-room", 5)
    assert r.exit_code == 2 and "--from-room" in r.output
    r = _run("plan", d / "rooms.graphml", "--to-room", 5)
    assert r.exit_code == 2
    r = _run("plan", d / "rooms.graphml", "--from-room", 99, "--to-room", 5)
    assert r.exit_code == 1 and "room 99 does not exist" in r.output
    r = _run("plan", d / "rooms.graphml", "--from-room", "1.5", "--to-room", 5)
    assert r.exit_code == 2


def test_cli_tour_from_room(saved):
    d, seg = saved
    r = _run("tour", d / "rooms.graphml", "--from-room", 3, "--json")
    assert r.exit_code == 0, r.output
    out = json.loads(r.stdout)
    assert out["order"][0] == 3 and sorted(out["order"]) == [1, 2, 3, 4, 5] and not out["unreachable"]
    r = _run("tour", d / "rooms.graphml")
    assert r.exit_code == 2


def _interior_cell_by_cell(labels, n, centroids):
    """interior_points by its rule, cell by cell: the clearance (OpenCV's 5 x 5 chamfer distance to the
    nearest cell on a room's edge or of no room), each room's cells within half a cell of its largest,
    the one nearest its centroid, the first in a row-major scan of equals."""
    from topomap._fast import edt

    L = np.where((labels > 0) & (labels <= n), labels, 0)
    P = np.pad(L, 1)
    inner = (L > 0) & (P[:-2, 1:-1] == L) & (P[2:, 1:-1] == L) & (P[1:-1, :-2] == L) & (P[1:-1, 2:] == L)
    clear = edt(np.pad(inner, 1), exact=False)[1:-1, 1:-1]
    rows = np.full(n + 1, -1)
    cols = np.full(n + 1, -1)
    for i in range(1, n + 1):
        rr, cc = np.nonzero(L == i)
        if rr.size == 0:
            continue
        v = clear[rr, cc]
        near = np.flatnonzero(v >= v.max() - np.float32(0.5))
        d2 = (rr[near] - centroids[i, 0]) ** 2 + (cc[near] - centroids[i, 1]) ** 2
        k = near[np.flatnonzero(d2 == d2.min())[0]]
        rows[i], cols[i] = rr[k], cc[k]
    return rows, cols


@pytest.mark.parametrize("seed", range(40))
def test_interior_points_follow_their_rule_cell_by_cell(seed):
    """Blocky random rooms (with labels above n: fragments, and a label without cells) on maps whose
    rooms reach the border or not: the same cells as the rule applied cell by cell."""
    rng = np.random.default_rng(seed)
    h, w = (int(v) for v in rng.integers(20, 70, 2))
    coarse = rng.integers(0, 8, (h // 5 + 1, w // 5 + 1))
    labels = np.kron(coarse, np.ones((5, 5), np.int32))[:h, :w].astype(np.int32)
    labels[rng.random((h, w)) < 0.05] = 0  # specks of no room
    if seed % 2:
        labels[:, :3] = 0  # rooms off the left border
    n = 6  # label 7: fragments
    labels[labels == 3] = 0  # room 3 without cells
    cen = np.array([[0.0, 0.0]] + [list(np.argwhere(labels == i).mean(axis=0)) if (labels == i).any()
                                   else [0.0, 0.0] for i in range(1, n + 1)])
    rows, cols = interior_points(labels, n, cen)
    want_rows, want_cols = _interior_cell_by_cell(labels, n, cen)
    np.testing.assert_array_equal(rows, want_rows)
    np.testing.assert_array_equal(cols, want_cols)
