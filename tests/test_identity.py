"""Stable room IDs across map updates: topomap.core.identity and segment(previous=...)."""

import json

import numpy as np
import networkx as nx
import pytest
from click.testing import CliRunner

import topomap
from topomap.errors import ParameterError
from topomap.io.export import load_graph, save_graph
from topomap.core.identity import TrackedSegmentation, match_rooms
from topomap.io import FREE, OCCUPIED, OccupancyGrid
from topomap.planning import room_at
from topomap.api import segment
from topomap.core.segmentation import Segmentation

RES = 0.05


def seg_of(labels, *, res=RES, origin=(0.0, 0.0, 0.0), room_count=None):
    """A Segmentation made of a hand-drawn label image (free = labelled)."""
    labels = np.asarray(labels, np.int32)
    cells = np.where(labels > 0, FREE, OCCUPIED).astype(np.int8)
    return Segmentation(grid=OccupancyGrid(cells, res, origin), labels=labels, doors=[], method="hand",
                        room_count=room_count)


def boxes(shape, rects):
    """Labels 1.. for the half-open pixel rectangles ``(r0, r1, c0, c1)``."""
    L = np.zeros(shape, np.int32)
    for k, (r0, r1, c0, c1) in enumerate(rects, start=1):
        L[r0:r1, c0:c1] = k
    return L


A, B, C = (2, 20, 2, 20), (2, 20, 22, 40), (22, 40, 2, 20)  # three rooms of 18 x 18 cells


def id_at(seg, r, c):
    return int(seg.labels[r, c])


def test_renumbered_rooms_keep_their_ids():
    prev = seg_of(boxes((42, 42), [A, B, C]))
    new = seg_of(boxes((42, 42), [C, B, A]))  # same rooms, numbered the other way round
    out, ch = match_rooms(prev, new)
    assert isinstance(out, TrackedSegmentation)
    for r, c in ((5, 5), (5, 30), (30, 5)):
        assert id_at(out, r, c) == id_at(prev, r, c)
    assert ch.kept == (1, 2, 3) and not (ch.new or ch.vanished or ch.split or ch.merged)
    assert new.labels[5, 5] == 3  # the input is not modified


def test_new_room_never_reuses_a_vanished_id():
    prev = seg_of(boxes((42, 42), [A, B, C]))
    D = (22, 40, 22, 40)
    new = seg_of(boxes((42, 42), [A, B, D]))  # C gone, D appeared
    out, ch = match_rooms(prev, new)
    assert ch.vanished == (3,) and ch.new == (4,) and ch.kept == (1, 2)
    assert id_at(out, 30, 30) == 4 and out.room_ids == (1, 2, 4) and out.next_room_id == 5
    # C comes back: it is a new room again, with a new ID (5), and D keeps 4
    again, ch2 = match_rooms(out, seg_of(boxes((42, 42), [A, B, C, D])))
    assert id_at(again, 30, 5) == 5 and id_at(again, 30, 30) == 4 and ch2.new == (5,)
    # the counter survives a saved room graph
    G = again.room_graph
    assert G.graph["next_room_id"] == 6
    assert sorted(G.nodes) == [1, 2, 4, 5] and again.n_rooms == 4


def test_split_and_merge_are_reported():
    prev = seg_of(boxes((42, 42), [(2, 20, 2, 40), C, (22, 40, 22, 40)]))  # 1 = A+B, 2 = C, 3 = D
    L = boxes((42, 42), [(2, 20, 2, 28), (2, 20, 28, 40)])  # room 1 cut in a large and a small piece
    L[22:40, 2:40] = 3  # C and D one room
    L[22:40, 20:22] = 3
    new = seg_of(L)
    out, ch = match_rooms(prev, new)
    big, small = id_at(out, 5, 5), id_at(out, 5, 35)
    assert big == 1 and small == 4  # the larger piece keeps the ID, the other is a new ID
    assert ch.split == {1: (1, 4)}
    merged = id_at(out, 30, 30)
    assert merged in (2, 3) and ch.merged == {merged: (2, 3)}
    assert ch.explains(1, 4) and ch.explains(2, merged) and ch.explains(3, merged)
    assert not ch.explains(1, merged)
    assert set(ch.vanished) | set(ch.kept) | {2, 3} >= {1, 2, 3}


def test_other_origin_and_resolution():
    prev = seg_of(boxes((42, 42), [A, B, C]))
    # the new map: half the resolution, 10 more cells (0.5 m) on the left and on top
    fine = np.zeros((52, 52), np.int32)
    fine[10:, 10:] = boxes((42, 42), [C, A, B])
    coarse = fine[::2, ::2]
    # its lower-left corner is where the old one's is, 0.5 m further left
    new = seg_of(coarse, res=2 * RES, origin=(-0.5, 0.0, 0.0))
    out, ch = match_rooms(prev, new)
    assert ch.kept == (1, 2, 3) and not ch.new
    for x, y in ((0.5, 1.5), (1.5, 1.5), (0.5, 0.5)):
        assert room_at(out, x, y) == room_at(prev, x, y) != 0


def test_fragments_follow_the_largest_id():
    prev = seg_of(boxes((42, 42), [A, B, C]))
    L = boxes((42, 42), [C, A])
    L[40, 40] = 3  # a speck: a fragment after the 2 rooms
    new = seg_of(L, room_count=2)
    out, ch = match_rooms(prev, new)
    assert out.room_ids == (1, 3) and ch.vanished == (2,)
    assert out.n_rooms == 2 and out.n_fragments == 1 and out.labels[40, 40] == 4
    assert out.room_labels[40, 40] == 0 and out.fragment_area == pytest.approx(RES ** 2)
    # every free cell in exactly one room or fragment, as before
    assert np.array_equal(out.labels > 0, new.labels > 0)
    assert sorted(out.room_graph.nodes) == [1, 3]
    assert out.room_graph.graph["n_fragments"] == 1


def test_user_attributes_carry_over_through_a_saved_graph(tmp_path):
    prev = seg_of(boxes((42, 42), [A, B, C]))
    G = prev.room_graph
    G.nodes[2]["name"] = "kitchen"
    G.nodes[3]["no_go"] = True
    path = save_graph(G, tmp_path / "rooms.graphml")
    new = seg_of(boxes((42, 42), [B, A]))  # C gone
    out, ch = match_rooms(load_graph(path), new)
    H = out.room_graph
    assert H.nodes[2]["name"] == "kitchen" and "no_go" not in H.nodes[1]
    assert ch.vanished == (3,)
    # and from the Segmentation itself (its built graph holds the name)
    out2, _ = match_rooms(prev, new)
    assert out2.room_graph.nodes[2]["name"] == "kitchen"


def test_segment_previous_on_the_example_map():
    grid = topomap.load_map(topomap.example_map_path())
    first = segment(grid)
    # the same building with 8 more cells of unknown on top and on the left:
    # another image, the same map frame
    cells = np.full((grid.shape[0] + 8, grid.shape[1] + 8), -1, np.int8)
    cells[8:, 8:] = grid.cells
    shifted = OccupancyGrid(cells, grid.resolution, (grid.origin[0] - 8 * grid.resolution, grid.origin[1], 0.0))
    again = segment(shifted, previous=first.room_graph)
    assert again.changes.kept == tuple(sorted(first.room_graph.nodes))
    for r, d in first.room_graph.nodes(data=True):
        rr, cc = np.argwhere(first.labels == r)[0]
        x, y = grid.pixel_to_world(rr, cc)
        assert again.room_at(float(x), float(y)) == r


def test_cli_previous(tmp_path):
    from topomap.cli import main

    ex = str(topomap.example_map_path())
    run = CliRunner().invoke
    assert run(main, ["segment", ex, "-o", str(tmp_path / "a")]).exit_code == 0
    G = load_graph(tmp_path / "a" / "rooms.graphml")
    G.nodes[1]["name"] = "hall"
    save_graph(G, tmp_path / "a" / "rooms.graphml")
    res = run(main, ["segment", ex, "-o", str(tmp_path / "b"), "--previous", str(tmp_path / "a" / "rooms.graphml")])
    assert res.exit_code == 0, res.output
    assert "kept" in res.output
    changes = json.loads((tmp_path / "b" / "changes.json").read_text())
    assert changes["kept"] == sorted(G.nodes) and changes["next_room_id"] == max(G.nodes) + 1
    H = load_graph(tmp_path / "b" / "rooms.graphml")
    assert H.nodes[1]["name"] == "hall" and H.graph["next_room_id"] == max(G.nodes) + 1
    bad = run(main, ["segment", ex, "-o", str(tmp_path / "c"), "--previous", str(tmp_path / "nope.graphml")])
    assert bad.exit_code == 1 and "nope.graphml" in bad.output
    assert not (tmp_path / "c").exists()


def test_every_room_gone():
    prev = seg_of(boxes((42, 42), [A, B, C]))
    out, ch = match_rooms(prev.room_graph, seg_of(np.zeros((42, 42), np.int32)))
    assert ch.vanished == (1, 2, 3) and ch.kept == () and out.room_ids == () and out.n_rooms == 0
    assert out.next_room_id == 4 and out.room_graph.number_of_nodes() == 0


def test_bad_previous():
    new = seg_of(boxes((42, 42), [A]))
    with pytest.raises(ParameterError, match="previous must be"):
        match_rooms(42, new)
    with pytest.raises(ParameterError, match="min_overlap"):
        match_rooms(new, new, min_overlap=0)
    G = nx.MultiGraph()
    G.add_node(1, area=1.0)
    with pytest.raises(ParameterError, match="room 1 has no polygon"):
        match_rooms(G, new)


def test_planning_pictures_and_files_with_gaps_in_the_ids(tmp_path):
    from topomap.run.job import write_segmentation
    from topomap.planning import plan_path, plan_tour, travel_graph

    grid = topomap.load_map(topomap.example_map_path())
    first = segment(grid)
    G = nx.relabel_nodes(first.room_graph, {r: 10 * r for r in first.room_graph.nodes})
    seg = segment(grid, previous=G)
    ids = tuple(sorted(G.nodes))
    assert seg.room_ids == ids and seg.n_rooms == len(ids) and seg.next_room_id == max(ids) + 1
    assert set(np.unique(seg.labels)) - {0} == set(ids) | set(range(max(ids) + 1, max(ids) + 1 + seg.n_fragments))
    assert all(set(d.rooms) <= set(ids) for d in seg.doors)
    T = travel_graph(seg)
    assert sorted(T.nodes) == list(ids)
    route = plan_path(seg, ids[0], ids[-1])
    assert route["start_room"] == ids[0] and route["goal_room"] == ids[-1] and set(route["rooms"]) <= set(ids)
    tour = plan_tour(T, ids[0])
    assert sorted(tour["order"]) == list(ids)
    files = write_segmentation(seg, tmp_path)  # labels.png, graphs and the overlay picture
    H = load_graph(files["graphml"])
    assert sorted(H.nodes) == list(ids) and H.graph["next_room_id"] == max(ids) + 1


# --------------------------------------------------------------------------
# Doors that last: segment(grid, previous=...) keeps the cuts of the previous map
# --------------------------------------------------------------------------

#: Options under which the door stage refuses the door of ``two_rooms`` (no
#: wall protrudes enough at its posts): what a fresh run on another version
#: of the map may decide, for reasons measured far from the door.
REFUSE = dict(protrusion_min=1.0, flat_min=1.0, rule="frac", openings=False, mouths=False, gaps=False)


def _two_rooms(carve=(), fill=()):
    """The two 3 m rooms joined by a 0.9 m door (tests/_testdata.py), with
    rectangles ``carve`` made free and ``fill`` made occupied."""
    from _testdata import two_rooms
    from topomap.io import from_array

    m = two_rooms()
    a = m.array.copy()
    for r0, r1, c0, c1 in carve:
        a[r0:r1, c0:c1] = True
    for r0, r1, c0, c1 in fill:
        a[r0:r1, c0:c1] = False
    return from_array(a, resolution=m.resolution)


LEFT, RIGHT = (35, 30), (35, 100)  # a cell in each room


def test_a_flickering_door_keeps_both_rooms_and_their_ids(tmp_path):
    grid = _two_rooms()
    a = segment(grid)
    assert a.n_rooms == 2 and segment(grid, **REFUSE).n_rooms == 1
    ids = (id_at(a, *LEFT), id_at(a, *RIGHT))
    # map 2: the run refuses the door; the previous door is still a narrow passage, so it is cut
    b = segment(grid, previous=a, **REFUSE)
    assert (id_at(b, *LEFT), id_at(b, *RIGHT)) == ids and len(b.doors) == 1
    assert b.changes.kept == tuple(sorted(ids)) and not (b.changes.split or b.changes.merged)
    # map 3: found again; from the saved room graph of map 2 as well
    path = save_graph(b.room_graph, tmp_path / "rooms.graphml")
    for prev in (b, path):
        c = segment(grid, previous=prev)
        assert (id_at(c, *LEFT), id_at(c, *RIGHT)) == ids and not (c.changes.split or c.changes.merged)
    # matching alone follows the flicker: a merge, then a split with a new ID
    b0, ch_b = match_rooms(a, segment(grid, **REFUSE))
    c0, ch_c = match_rooms(b0, segment(grid))
    assert b0.n_rooms == 1 and ch_b.merged and ch_c.split
    assert (id_at(c0, *LEFT), id_at(c0, *RIGHT)) != ids


def test_a_previous_door_is_cut_again_only_where_its_posts_still_are():
    a = segment(_two_rooms())
    # one post 0.05 m further out (the door 0.95 m wide): within prior_post_shift
    near = segment(_two_rooms(carve=[(25, 26, 65, 69)]), previous=a, **REFUSE)
    assert near.n_rooms == 2 and near.changes.kept == (1, 2)
    # one post 0.3 m further out: another doorway
    far = segment(_two_rooms(carve=[(20, 26, 65, 69)]), previous=a, **REFUSE)
    assert far.n_rooms == 1 and far.changes.merged
    # the wall between the rooms gone: no passage left
    gone = segment(_two_rooms(carve=[(5, 65, 65, 69)]), previous=a, **REFUSE)
    assert gone.n_rooms == 1 and gone.changes.merged
    # and with the prior turned off, the refused door stays refused
    assert segment(_two_rooms(), previous=a, prior_post_shift=0, **REFUSE).n_rooms == 1


def _changed_area_near_door(g1, g2, door, reach=1.5):
    """Area (m²) of cells within ``reach`` of the door's midpoint that are free in one map only."""
    rr, cc = np.mgrid[0:g1.shape[0], 0:g1.shape[1]]
    x, y = g1.pixel_to_world(rr, cc)
    near = np.hypot(x - door.midpoint[0], y - door.midpoint[1]) <= reach
    return float((near & (g1.free != g2.free)).sum()) * g1.resolution ** 2


def test_a_new_cut_inside_an_unchanged_room_is_dropped():
    door = segment(_two_rooms()).doors[0]
    # the previous map: the same place, with a desk by the door; the run there found one room
    small = _two_rooms(fill=[(44, 65, 40, 62)])
    prev = segment(small, **REFUSE)
    assert prev.n_rooms == 1
    assert _changed_area_near_door(small, _two_rooms(), door) < 1.0  # less than prior_changed_area
    new = segment(_two_rooms(), previous=prev)
    assert new.n_rooms == 1 and new.changes.kept == (1,) and not new.doors
    assert segment(_two_rooms(), previous=prev, prior_changed_area=0).n_rooms == 2
    # a larger change near the door (a block of 1.5 m² gone): the new cut is taken, a split
    big = _two_rooms(fill=[(20, 50, 35, 55)])
    prev = segment(big, **REFUSE)
    assert prev.n_rooms == 1 and _changed_area_near_door(big, _two_rooms(), door) > 1.0
    new = segment(_two_rooms(), previous=prev)
    assert new.n_rooms == 2 and new.changes.split == {1: tuple(sorted(new.room_ids))}


def test_previous_with_a_method_without_door_stage():
    # the baselines have no door stage: their rooms are matched only
    grid = _two_rooms()
    first = segment(grid, method="watershed")
    again = segment(grid, method="watershed", previous=first)
    assert again.changes.kept == tuple(range(1, first.n_rooms + 1)) and "prior doors" not in again.timings
    assert "prior doors" in segment(grid, previous=segment(grid)).timings


def test_a_narrowed_door_is_still_cut():
    a = segment(_two_rooms())
    # the upper post redrawn 0.35 m inwards (the opening now 0.55 m): the same
    # door between the same walls, cut again although no wall is where its post was
    narrow = segment(_two_rooms(fill=[(26, 33, 65, 69)]), previous=a, **REFUSE)
    assert narrow.n_rooms == 2 and narrow.changes.kept == (1, 2)
    (d,) = narrow.doors
    assert d.width == pytest.approx(0.6, abs=0.06)  # between the walls met, not the old posts
    # widened by 0.3 m instead: the wall moved away from the post, no door kept
    assert segment(_two_rooms(carve=[(20, 26, 65, 69)]), previous=a, **REFUSE).n_rooms == 1


def test_a_wall_piece_in_a_previous_doorway_leaves_both_openings_cut():
    wide = [(16, 55, 65, 69)]  # a 1.9 m opening
    a = segment(_two_rooms(carve=wide))
    assert a.n_rooms == 2
    # a 0.2 m wall drawn from the middle of it 1.5 m into the right room (a
    # wall, not clutter: longer than min_wall_length): two openings of 0.85 m, both cut
    pillar = _two_rooms(carve=wide, fill=[(34, 38, 65, 95)])
    assert segment(pillar, **REFUSE).n_rooms == 1  # what a run without the prior gives
    b = segment(pillar, previous=a, **REFUSE)
    assert b.n_rooms == 2 and b.changes.kept == (1, 2)
    assert id_at(b, *LEFT) == id_at(a, *LEFT) and id_at(b, *RIGHT) == id_at(a, *RIGHT)


def _adjusted(segments):
    """DoorPrior.adjust on the two rooms with the door of a first run as the prior."""
    from topomap.core.identity import DoorPrior
    from topomap.options import TopomapOptions

    grid = _two_rooms()
    prior = DoorPrior(segment(grid))
    return prior.adjust(grid, segments, TopomapOptions(), walls=~grid.free, space=grid.free)


def test_a_previous_door_is_added_unless_a_new_cut_closes_it():
    door = ((25.0, 66.5), (44.0, 66.5))  # the first run's door, pixels
    # the new run found it: nothing added
    assert _adjusted([door]) == [door]
    # a new cut at the door that stops 0.2 m short of the lower post leaves the
    # rooms joined: the previous door is cut again beside it
    short = ((25.0, 66.5), (40.0, 66.5))
    out = _adjusted([short])
    assert len(out) == 2 and out[0] == short
    (r1, c1), (r2, c2) = out[1]
    assert abs(c1 - 66.5) <= 1 and abs(c2 - 66.5) <= 1 and {round(r1), round(r2)} == {25, 44}
    # a cut that shares one post with the door but runs off into the right room
    # is not that door: the door is cut again, and the cut, inside a room the
    # previous map had whole and that did not change, is dropped
    out = _adjusted([((25.0, 66.5), (25.0, 100.0))])
    assert len(out) == 1 and np.allclose(out[0], [(25, 66), (44, 66)])


def test_same_door_needs_each_through_the_middle_of_the_other():
    from topomap.core.identity import _same_doors

    P, Q = np.array([[0.0, 0.0]]), np.array([[20.0, 0.0]])  # a previous door, 20 px
    cuts = [((0.0, 3.0), (20.0, 3.0)),    # the same door redrawn 3 px away
            ((0.0, 0.0), (5.0, 20.0)),    # one post shared, then another way
            ((30.0, 0.0), (50.0, 0.0))]   # the next opening along the wall
    A = np.array([c[0] for c in cuts])
    B = np.array([c[1] for c in cuts])
    assert _same_doors(A, B, P, Q, 5.0)[:, 0].tolist() == [True, False, False]
    assert _same_doors(A, B, P, Q, 2.0)[:, 0].tolist() == [False, False, False]


def test_a_piece_of_a_room_is_a_link_from_a_room_area_up():
    # one room of 9 m²; the new map (130 rows) has 60 more rows below it, the same frame
    prev = seg_of(boxes((70, 62), [(1, 61, 1, 61)]), origin=(0.0, 60 * RES, 0.0))
    for strip_cols, linked in (((6, 56), True), ((6, 26), False)):
        L = np.zeros((130, 62), np.int32)
        L[1:61, 1:61] = 1
        c0, c1 = strip_cols
        L[53:61, c0:c1] = 2  # 8 x 50 cells = 1.0 m² (8 x 20 = 0.4 m²) of the old room ...
        L[61:128, 1:61] = 2  # ... and 10 m² the previous map did not know: under a tenth of the new room
        out, ch = match_rooms(prev, seg_of(L))
        assert id_at(out, 5, 5) == 1 and id_at(out, 100, 30) == 2  # the old room keeps its ID
        if linked:
            assert ch.split == {1: (1, 2)} and ch.new == () and ch.explains(1, 2)
        else:
            assert ch.split == {} and ch.new == (2,) and not ch.explains(1, 2)
    with pytest.raises(ParameterError, match="min_room_area"):
        match_rooms(prev, prev, min_room_area=0)


def test_a_post_redrawn_beside_the_door_line_is_still_a_post():
    from topomap.core.identity import _passage_along

    walls = np.zeros((30, 40), bool)
    walls[:, :6] = walls[:, 20:] = True  # the door: row 10 from col 5 to col 20
    walls[8:11, 20:25] = False  # the right wall's end redrawn: no wall on the line within 0.2 m of the post
    (a, b) = _passage_along(walls, ~walls, (10.0, 5.0), (10.0, 20.0), 3.0)
    assert np.hypot(*(b - (11.0, 20.0))) <= 1.5 and walls[int(b[0]), int(b[1])]  # the wall cell beside it
    assert np.hypot(*(a - (10.0, 5.0))) <= 1.0
    walls[4:17, 20:25] = False  # no wall within 0.15 m of the post: the wall moved away
    assert _passage_along(walls, ~walls, (10.0, 5.0), (10.0, 20.0), 3.0) is None


def test_a_door_ending_on_clutter_goes_on_to_the_wall():
    from topomap.core.identity import _through_clutter

    walls = np.zeros((40, 40), bool)
    walls[:, :3] = walls[:, 37:] = True
    door = ((20.0, 2.0), (20.0, 25.0))  # from the left wall to a piece of furniture at col 25
    a, b = _through_clutter(walls, door, 40.0)
    assert tuple(a) == (20.0, 2.0) and tuple(b) == (20.0, 37.0)  # on to the right wall
    a, b = _through_clutter(walls, door, 30.0)  # the wall farther than the widest door: the end stays
    assert tuple(a) == (20.0, 2.0) and tuple(b) == (20.0, 25.0)
