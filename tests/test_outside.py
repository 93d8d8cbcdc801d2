"""The outside of the building (topomap.core.outside): free space a laser saw beyond the facade."""

import numpy as np
import pytest

import topomap
from topomap.core import outside as O
from topomap.io import FREE, OCCUPIED, UNKNOWN, OccupancyGrid


def _facade_map():
    """Two rooms side by side (a 0.9 m door between them), each with a 1.2 m window in the outer
    wall; the rays through the windows fan out 4.5 m beyond the facade and the two fans meet."""
    c = np.full((220, 300), UNKNOWN, np.int8)
    c[20:122, 20:282] = OCCUPIED
    c[22:120, 22:280] = FREE
    c[22:120, 149:152] = OCCUPIED
    c[60:78, 149:152] = FREE
    rr, cc = np.mgrid[0:220, 0:300]
    fans = np.zeros(c.shape, bool)
    for c0 in (60, 210):
        c[120:122, c0:c0 + 24] = FREE
        fans |= (rr >= 122) & (rr < 212) & (np.abs(cc - (c0 + 12)) <= 12 + (rr - 122) * 0.9) & (c == UNKNOWN)
    c[fans] = FREE
    return OccupancyGrid(c, 0.05), fans


def test_fans_beyond_the_facade_are_outside_and_join_no_rooms():
    grid, fans = _facade_map()
    seg = topomap.segment(grid)
    assert seg.n_rooms == 2
    assert [d.rooms for d in seg.doors] == [(1, 2)]           # only the door between the rooms
    assert len(seg.outside) >= 1
    out = np.isin(seg.labels, seg.outside)
    assert out[fans].mean() > 0.95                              # the fans are outside ...
    assert not out[:120].any()                                  # ... and nothing inside the facade
    assert (seg.labels[grid.free] > 0).all()                    # every free cell still labelled
    assert seg.outside_area == pytest.approx(out.sum() * 0.05 ** 2)
    G = seg.room_graph
    assert sorted(G.nodes) == [1, 2] and G.graph["outside_area"] == pytest.approx(seg.outside_area)


def test_without_the_stage_the_fans_join_the_rooms():
    grid, _ = _facade_map()
    seg = topomap.segment(grid, outside_enclosure=0)
    assert seg.outside == () and seg.outside_area == 0.0
    assert seg.n_rooms == 3 and len(seg.doors) == 3             # the fans a room joined to both


def _room_with_wide_opening(rays: bool):
    """A 7.8 x 4.9 m room whose facade has a 3.5 m opening (wider than any door: the doors stage
    cuts nothing there); beyond it the laser left either a solid fan of free space 5.9 m deep or
    seven single rays (a room glimpsed through its door leaves such rays)."""
    c = np.full((240, 200), UNKNOWN, np.int8)
    c[20:122, 20:182] = OCCUPIED
    c[22:120, 22:180] = FREE
    c[120:122, 65:135] = FREE
    rr, cc = np.mgrid[0:240, 0:200]
    beyond = np.zeros(c.shape, bool)
    if rays:
        t = np.arange(110)
        for a in np.linspace(-0.6, 0.6, 7):
            r, k = (121 + t * np.cos(a)).astype(int), (100 + t * np.sin(a)).astype(int)
            ok = (r < 240) & (k >= 0) & (k < 200)
            beyond[r[ok], k[ok]] = True
    else:
        beyond = (rr >= 122) & (np.abs(cc - 100) <= 35 + (rr - 122) * 0.6)
    beyond &= c == UNKNOWN
    c[beyond] = FREE
    return OccupancyGrid(c, 0.05), beyond


def test_a_solid_fan_joined_to_its_room_is_cut_out_of_it():
    grid, fan = _room_with_wide_opening(rays=False)
    seg = topomap.segment(grid)
    out = np.isin(seg.labels, seg.outside)
    assert seg.n_rooms == 1 and seg.outside                     # the room stays, the fan is outside
    assert out[fan].mean() > 0.95                               # with its band along the facade
    assert not out[:120].any()                                  # nothing inside the facade
    assert (seg.labels[grid.free] > 0).all()
    assert (topomap.segment(grid, outside_enclosure=0).room_labels[fan] > 0).all()   # the stage off: the room's


def test_single_rays_beyond_a_room_stay_in_it():
    grid, rays = _room_with_wide_opening(rays=True)
    seg = topomap.segment(grid)
    assert seg.n_rooms == 1 and seg.outside == ()
    assert (seg.room_labels[rays] > 0).all()                   # no evidence of outside: a glimpse


def test_outside_fans_are_solid_pieces_within_one_room():
    labels = np.zeros((40, 60), np.int32)
    labels[:, :30], labels[:, 30:] = 1, 2
    encl = np.full(labels.shape, 8.0, np.float32)
    encl[5:35, 10:50] = 1.0                                     # low enclosure across both rooms
    clearance = np.full(labels.shape, 3.0)
    clearance[20, 15] = 10.0                                    # a wide cell in room 1 only
    fans = O.outside_fans(labels, 2, encl, clearance, threshold=2.4, min_cells=100, width_px=10)
    assert fans[5:35, 10:29].all() and not fans[:, 29:].any()   # room 1's piece; none across the border
    assert not O.outside_fans(labels, 2, encl, clearance, threshold=2.4, min_cells=1000, width_px=10).any()
    encl[5:35, 5:10] = 3.0                                      # beside the piece, more open than enclosed
    encl[5:35, 0:5] = 5.0
    grown = O.outside_fans(labels, 2, encl, clearance, threshold=2.4, min_cells=100, width_px=10, grow_threshold=4.0)
    assert grown[5:35, 5:29].all() and not grown[:, :5].any() and not grown[:, 29:].any()
    assert (O.outside_fans(labels, 2, encl, clearance, threshold=2.4, min_cells=100, width_px=10) == fans).all()
    assert O.outside_regions(labels, 2, encl, threshold=2.4, fans=fans).tolist() == [False, False, False]
    assert O.outside_regions(labels, 2, encl, threshold=2.4, fans=labels == 1).tolist() == [False, True, False]


def test_a_room_half_explored_or_with_clutter_is_no_outside():
    c = np.full((140, 140), UNKNOWN, np.int8)
    c[20:102, 20:102] = OCCUPIED
    c[22:100, 22:100] = FREE
    c[22:100, 99:102] = FREE                                    # one side never seen: free meets unknown
    c[40:44, 40:46] = UNKNOWN                                   # a box seen in part
    c[70:73, 60:62] = UNKNOWN
    seg = topomap.segment(OccupancyGrid(c, 0.05))
    assert seg.n_rooms == 1 and seg.outside == ()


def test_enclosure_counts_directions_that_end_at_obstacles():
    c = np.full((60, 60), UNKNOWN, np.int8)
    c[10:50, 10:50] = OCCUPIED
    c[12:48, 12:48] = FREE
    free, occ = c == FREE, c == OCCUPIED
    e = O.enclosure(free, occ, 0.05, open_area=1.0, window=0.25, cell=0.05)
    assert np.allclose(e[free], 8)                              # a closed room: walls every way
    c[12:48, 48:60] = FREE                                      # its east wall gone: free to the map's edge
    free, occ = c == FREE, c == OCCUPIED
    e = O.enclosure(free, occ, 0.05, open_area=1.0, window=0.05, cell=0.05)
    assert e[30, 20] == 7                                       # only due east reaches the map's edge
    assert e[30, 55] <= 5                                       # out there, E, NE and SE do


def test_open_unknown_is_large_or_at_the_edge():
    c = np.full((80, 80), FREE, np.int8)
    c[30:33, 30:33] = UNKNOWN                                   # 0.0225 m²: clutter
    c[50:80, 0:10] = UNKNOWN                                    # at the map's edge
    c[5:30, 50:75] = UNKNOWN                                    # 1.56 m² inside: unexplored
    opn = O.open_unknown(c == FREE, c == OCCUPIED, 0.05, min_area=1.0)
    assert not opn[30:33, 30:33].any() and opn[50:80, 0:10].all() and opn[5:30, 50:75].all()


def test_drop_outside_renumbers_rooms_fragments_and_doors():
    from topomap.core.doors import Door

    labels = np.array([[1, 1, 2, 2, 3, 3, 4, 5]], np.int32)     # rooms 1-3, fragments 4, 5
    doors = [Door(0, (0, 1), (0, 2), rooms=(1, 2)), Door(1, (0, 3), (0, 4), rooms=(2, 3)),
             Door(2, (0, 1), (0, 4), rooms=(1, 3))]
    is_out = np.array([False, False, True, False])
    new, kept, n, outside = O.drop_outside(labels, doors, 3, is_out)
    assert new.tolist() == [[1, 1, 5, 5, 2, 2, 3, 4]] and n == 2 and outside == (5,)
    assert [(d.id, d.rooms) for d in kept] == [(0, (1, 2))]    # the doors of the outside room dropped


def test_drop_outside_cuts_fans_out_of_the_rooms_kept():
    labels = np.array([[1, 1, 1, 2, 2, 3, 4]], np.int32)        # rooms 1-3, fragment 4
    fans = np.array([[0, 1, 1, 0, 1, 0, 0]], bool)              # room 2 is dropped whole
    is_out = np.array([False, False, True, False])
    new, kept, n, outside = O.drop_outside(labels, [], 3, is_out, fans=fans)
    assert new.tolist() == [[1, 5, 5, 4, 4, 2, 3]] and n == 2 and outside == (4, 5)
    new, _, n, outside = O.drop_outside(labels, [], 3, np.zeros(4, bool), fans=fans)
    assert new.tolist() == [[1, 5, 5, 2, 6, 3, 4]] and n == 3 and outside == (5, 6)


def test_drop_outside_keeps_a_room_in_one_piece():
    labels = np.array([[1, 1, 1, 1, 1, 1, 1, 2]], np.int32)
    fans = np.array([[0, 0, 0, 0, 1, 0, 0, 0]], bool)            # the fan cuts room 1 in two
    new, _, n, outside = O.drop_outside(labels, [], 2, np.zeros(3, bool), fans=fans)
    assert new.tolist() == [[1, 1, 1, 1, 3, 3, 3, 2]] and n == 2 and outside == (3,)   # the smaller piece goes with it


def _first_hit_by_walking(free, hit, d):
    H, W = free.shape
    out = np.zeros((H, W), bool)
    for r in range(H):
        for c in range(W):
            i, j = r, c
            while 0 <= i < H and 0 <= j < W and free[i, j]:
                i, j = i + d[0], j + d[1]
            out[r, c] = 0 <= i < H and 0 <= j < W and bool(hit[i, j])
    return out


@pytest.mark.parametrize("shape", [(7, 11), (11, 7), (9, 9)])
def test_first_hit_matches_walking_each_ray(shape):
    rng = np.random.default_rng(sum(shape))
    state = rng.choice(3, size=shape, p=[0.7, 0.2, 0.1])     # free, hit, open
    free, hit = state == 0, state == 1
    for d in O.DIRECTIONS:
        assert np.array_equal(O._first_hit(free, hit, d), _first_hit_by_walking(free, hit, d)), d


def test_blocks_reduce_like_the_definition():
    from topomap.core.skeleton import downsample

    rng = np.random.default_rng(5)
    m = rng.random((13, 10)) < 0.6
    for k in (2, 3):
        pad = np.zeros((-(-13 // k) * k, -(-10 // k) * k), bool)
        pad[:13, :10] = m
        blocks = pad.reshape(pad.shape[0] // k, k, pad.shape[1] // k, k)
        assert np.array_equal(downsample(m, k, keep="all"), blocks.all(axis=(1, 3)))
        assert np.array_equal(downsample(m, k, keep="any"), blocks.any(axis=(1, 3)))


def test_no_building_no_outside():
    """Free space and nothing else (no wall anywhere): every direction ends at the map's edge, yet
    there is no building to be outside of."""
    seg = topomap.segment(OccupancyGrid(np.zeros((60, 80), np.int8), 0.05))
    assert seg.n_rooms == 1 and seg.outside == ()


def test_walls_drawn_in_gray_are_obstacles_not_the_unknown():
    """A SLAM map saved with its probabilities draws walls in grays the thresholds leave unknown
    (Willow Garage's map): they bound the room; only the map's unknown gray is the open unknown."""
    gray = np.full((120, 200), 205, np.uint8)
    gray[20:100, 20:180] = 150                                  # walls: seen, p about 0.4
    gray[23:97, 23:177] = 254                                   # the room
    c = np.where(gray == 254, FREE, UNKNOWN).astype(np.int8)
    free, occ = c == FREE, c == OCCUPIED
    unknown = O.unknown_cells(free, occ, gray)
    assert not unknown[20:100, 20:180].any() and unknown[:20].all()
    e = O.enclosure(free, occ, 0.05, open_area=1.0, window=0.5, gray=gray)
    assert np.allclose(e[free], 8)
    e_no_gray = O.enclosure(free, occ, 0.05, open_area=1.0, window=0.5)
    assert e_no_gray[free].max() == 0                           # without the grays: nothing bounds it
    seg = topomap.segment(OccupancyGrid(c, 0.05, gray=gray))
    assert seg.n_rooms == 1 and seg.outside == ()


def test_the_command_line_says_how_much_of_the_fragments_is_outside():
    from topomap.cli import _summary

    row = {"rooms": 2, "doors": 1, "fragments": 3, "fragment_area_m2": 45.5, "outside_area_m2": 45.27}
    assert _summary(row) == "2 rooms, 1 door, 3 fragments (45.5 m², 45.27 m² of it outside the building)"
    assert _summary({**row, "outside_area_m2": 0.0}) == "2 rooms, 1 door, 3 fragments (45.5 m²)"
