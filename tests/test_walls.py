"""Openings in straight walls (topomap.core.walls), on small hand-drawn maps."""

import numpy as np
import pytest

from topomap.core import walls as W
from topomap.io import from_array
from topomap.core.segmentation import segment

RES = 0.05


def _corridor_with_room(opening_m):
    """A corridor (rows 40..69) under a room (rows 5..34): the wall between them
    (rows 35..39) has a gap of ``opening_m`` metres in the middle, as wide as
    the corridor or wider, so the clearance does not narrow there."""
    free = np.zeros((75, 200), bool)
    free[5:35, 60:140] = True      # room above
    free[40:70, 5:195] = True      # corridor
    gap = int(round(opening_m / RES))
    c0 = 100 - gap // 2
    free[35:40, c0:c0 + gap] = True
    return free


def _occupied(free):
    return ~free


def test_gap_between_collinear_wall_pieces_is_an_opening():
    free = _corridor_with_room(2.0)
    ops = W.wall_openings(_occupied(free), free, min_wall_px=20, min_gap_px=10, max_gap_px=60, side_px=10)
    # the corridor's upper face (row 40, occupied row 39) has a 2 m gap: found
    # once from each side at most, and lying along the wall's line
    assert ops, "no opening found"
    for p, q in ops:
        assert abs(p[0] - q[0]) <= 1.5 and 34 <= min(p[0], q[0]) <= 40
        assert abs(abs(p[1] - q[1]) - 40) <= 3


def test_wall_corner_and_wall_end_on_are_no_openings():
    free = np.zeros((80, 80), bool)
    free[5:75, 5:75] = True  # one room, closed walls
    assert W.wall_openings(~free, free, min_wall_px=20, min_gap_px=10, max_gap_px=60, side_px=10) == []


def test_gap_wider_than_max_is_no_opening():
    free = _corridor_with_room(2.0)
    assert W.wall_openings(~free, free, min_wall_px=20, min_gap_px=10, max_gap_px=30, side_px=10) == []


def test_wide_doorway_onto_corridor_separates_the_room():
    # a 2.5 m doorway onto a 1.5 m corridor: wider than the corridor, so no
    # bottleneck of clearance, but an opening in the wall's line
    free = _corridor_with_room(2.5)
    seg = segment(from_array(free, resolution=RES))
    assert seg.n_rooms == 2
    assert len(seg.doors) >= 1
    top = seg.labels[20, 100]
    assert top != seg.labels[55, 30] and top == seg.labels[10, 65]
    off = segment(from_array(free, resolution=RES), openings=False, gaps=False)
    assert off.n_rooms == 1  # what the clearance alone gives
    # the gap in the room's thin wall shows the doorway as well (TopomapOptions.gaps)
    assert segment(from_array(free, resolution=RES), openings=False).n_rooms == 2


def test_rise_resolved_from_the_straightness_of_the_walls():
    from topomap.options import TopomapOptions

    o = TopomapOptions()
    assert o.resolved(0.05, 0.9).rise == pytest.approx(0.1 * (np.sqrt(2) / 2 + 0.5))
    assert o.resolved(0.05, 0.5).rise == o.scan_rise == 0.25
    assert o.resolved(0.05).rise == pytest.approx(0.1 * (np.sqrt(2) / 2 + 0.5))  # no walls measured
    assert TopomapOptions(rise=0.3).resolved(0.05, 0.1).rise == 0.3  # given: used as it is
    seg = segment(from_array(_corridor_with_room(2.5), resolution=RES))
    assert seg.intermediates.straight_share >= seg.params["straight_walls"]
    assert seg.params["rise"] == pytest.approx(0.1 * (np.sqrt(2) / 2 + 0.5))


def _first_maps(directory, load, names):
    from pathlib import Path

    return [bm.load() for bm in load(Path(directory), names=names)]


def test_scanned_maps_measure_as_scanned_and_plans_as_drawn():
    """On the real laser SLAM maps of the benchmark the walls are not
    straight (scan_rise is used); on its drawn floor plans they are."""
    from topomap.bench.datasets import benchmark_dir, load_benchmark, load_labelled, real_maps_dir

    real, ipa = real_maps_dir(), benchmark_dir()
    if real is None or ipa is None:
        pytest.skip("benchmark data sets not found")
    for grid in _first_maps(real, load_labelled, ["freiburg079_full", "bremen_cartesium_partial_10"]):
        seg = segment(grid)
        assert seg.intermediates.straight_share < seg.params["straight_walls"], grid.name
        assert seg.params["rise"] == seg.params["scan_rise"]
    for grid in _first_maps(ipa, load_benchmark, ["office_c", "lab_ipa"]):
        seg = segment(grid)
        assert seg.intermediates.straight_share >= seg.params["straight_walls"], grid.name


def test_plans_and_scans_measure_the_same_on_a_finer_grid():
    """office_e and a SLAM map upsampled 4x (0.0125 m/px; every length in
    metres the same) measure as at 0.05 m/px: the walls are measured on a
    0.05 m grid (on its own grid the plan measured 0.63, as if scanned)."""
    from topomap.bench.datasets import benchmark_dir, load_benchmark, load_labelled, real_maps_dir
    from topomap.io import OccupancyGrid

    real, ipa = real_maps_dir(), benchmark_dir()
    if real is None or ipa is None:
        pytest.skip("benchmark data sets not found")
    for grid in (_first_maps(ipa, load_benchmark, ["office_e"])
                 + _first_maps(real, load_labelled, ["bremen_cartesium_partial_10"])):
        fine = OccupancyGrid(np.kron(grid.cells, np.ones((4, 4), np.int8)), grid.resolution / 4, grid.origin,
                             grid.source)
        a, b = segment(grid), segment(fine)
        drawn = a.intermediates.straight_share >= a.params["straight_walls"]
        assert (b.intermediates.straight_share >= b.params["straight_walls"]) == drawn, grid.name
        assert b.params["rise"] == pytest.approx(a.params["rise"]), grid.name
        assert b.params["furniture_size"] == a.params["furniture_size"], grid.name


def test_straight_share_counts_face_cells_on_lines():
    free = np.zeros((40, 80), bool)
    free[10:30, 10:70] = True
    faces = W.wall_faces(~free, free)
    lines = W.wall_lines(faces, min_length_px=20)
    assert W.straight_share(faces, lines) > 0.9
    assert W.straight_share(faces, np.zeros((0, 4))) == 0.0
    assert W.straight_share(np.zeros((5, 5), bool), lines) == 1.0


def _long_wall_with_doorway(speck: bool):
    """Two rooms (rows 5..44 and 50..89, 2 m deep) either side of a 7 m wall
    (rows 45..49) with a 1 m doorway (cols 70..89), optionally with a
    one-cell speck in the doorway (an open door leaf, a person)."""
    free = np.zeros((95, 150), bool)
    free[5:45, 5:145] = True
    free[50:90, 5:145] = True
    free[45:50, 70:90] = True
    if speck:
        free[47, 80] = False
    return free


@pytest.mark.parametrize("speck", [False, True])
def test_gap_in_a_long_wall_is_an_opening_even_with_a_speck(speck):
    free = _long_wall_with_doorway(speck)
    faces = W.wall_faces(~free, free)
    lines = W.wall_lines(faces, min_length_px=20)
    walls = W.long_walls(lines, max_gap_px=60, offset_px=4, min_span_px=80)
    assert walls, "no long wall found"
    ops = W.long_wall_gaps(~free, free, walls, min_gap_px=10, max_gap_px=60, depth_px=24)
    assert ops, "the doorway was not found"
    for p, q in ops:
        assert 44 <= p[0] <= 51 and 44 <= q[0] <= 51          # on the wall
        assert 66 <= min(p[1], q[1]) <= 71 and 88 <= max(p[1], q[1]) <= 93  # across the doorway


def test_long_wall_gap_in_front_of_a_niche_is_no_opening():
    free = _long_wall_with_doorway(False)
    free[50:90, 5:145] = False
    free[50:60, 65:95] = True  # a 0.5 m deep niche behind the gap
    faces = W.wall_faces(~free, free)
    walls = W.long_walls(W.wall_lines(faces, min_length_px=20), max_gap_px=60, offset_px=4, min_span_px=80)
    assert W.long_wall_gaps(~free, free, walls, min_gap_px=10, max_gap_px=60, depth_px=24) == []


def test_segment_between_the_side_walls_of_a_corridor_is_across_them():
    # a corridor 2 m wide (rows 20..59) between two 8 m walls
    free = np.zeros((80, 170), bool)
    free[20:60, 5:165] = True
    faces = W.wall_faces(~free, free)
    walls = W.long_walls(W.wall_lines(faces, min_length_px=20), max_gap_px=60, offset_px=4, min_span_px=80)
    assert len(walls) >= 2
    assert W.across_walls((19.5, 80), (60.5, 80), walls, tol_px=4)       # across the corridor
    assert not W.across_walls((19.5, 80), (40, 80), walls, tol_px=4)     # from a wall into the corridor
    assert not W.across_walls((40, 30), (40, 70), walls, tol_px=4)       # along it


def test_wall_directions_follow_a_rotated_building():
    free = np.zeros((200, 200), bool)
    import cv2
    box = cv2.boxPoints(((100, 100), (120, 80), 20.0)).astype(np.int32)
    m = np.zeros((200, 200), np.uint8)
    cv2.fillPoly(m, [box], 1)
    free = m > 0
    lines = W.wall_lines(W.wall_faces(~free, free), min_length_px=20)
    th = np.degrees(W.wall_directions(lines))
    assert min(abs(th - 20), abs(th - 70)) <= 2.5


@pytest.mark.parametrize("factor", [2, 4])
def test_the_same_rooms_at_a_finer_resolution(factor):
    import topomap
    from topomap.io import OccupancyGrid

    g = topomap.load_map(topomap.example_map_path())
    fine = OccupancyGrid(np.kron(g.cells, np.ones((factor, factor), np.int8)), g.resolution / factor, g.origin,
                         g.source)
    a, b = topomap.segment(g), topomap.segment(fine)
    assert (b.n_rooms, len(b.doors)) == (a.n_rooms, len(a.doors))


def _partition(hits_on_line):
    """A 5 m x 8 m room (rows 4..103) with a 0.2 m partition (cols 84..87)
    standing 2.5 m up from the south wall; the laser's hits on the rest of
    its line are given as occupied cells of a separate ``hits`` mask (specks
    that the obstacle mask looks through as clutter)."""
    free = np.zeros((108, 172), bool)
    free[4:104, 4:168] = True
    free[54:104, 84:88] = False
    hits = ~free
    for r in hits_on_line:
        hits[r, 85] = True
    return free, hits


@pytest.mark.parametrize("hits_on_line, found", [((14, 22, 31, 40, 47), True), ((), False), ((30,), False)])
def test_partition_gap_needs_hits_on_its_line(hits_on_line, found):
    free, hits = _partition(hits_on_line)
    faces = W.wall_faces(~free, free)
    lines = W.wall_lines(faces, min_length_px=20)
    ops = W.partition_gaps(~free, free, lines, min_wall_px=30, min_gap_px=10, max_gap_px=60, min_hits_px=4,
                           depth_px=24, hits=hits)
    assert bool(ops) == found
    for p, q in ops:
        # from the partition's end up to the north wall's first cell, on its line
        assert sorted([round(p[0]), round(q[0])]) == [3, 54]
        assert 83 <= p[1] <= 88 and 83 <= q[1] <= 88


def test_short_wall_piece_is_no_partition():
    # the same gap seen from a piece shorter than min_wall_px: a cupboard's side
    free, hits = _partition((14, 22, 31, 40, 47))
    faces = W.wall_faces(~free, free)
    lines = W.wall_lines(faces, min_length_px=20)
    assert W.partition_gaps(~free, free, lines, min_wall_px=60, min_gap_px=10, max_gap_px=60, min_hits_px=4,
                            depth_px=24, hits=hits) == []


def test_face_runs_follow_the_main_directions():
    faces = np.zeros((60, 120), bool)
    faces[20, 10:60] = True          # 50 cells
    faces[20, 62:80] = True          # after a 2-cell gap: the same run
    faces[40, 10:25] = True          # 15 cells: shorter than the minimum
    faces[5:50, 100] = True          # 45 cells, the other direction
    faces[30, 30:45:3] = True        # dots 3 cells apart: no run
    lines = np.array([[20, 10, 20, 80], [5, 100, 50, 100]], float)
    runs = W.face_runs(faces, min_length_px=20, lines=lines)
    def covers(a_lo, a_hi, b0, b1, axis):
        # a run within the band a_lo..a_hi across it, from b0 to b1 along it (to a cell)
        for seg in runs:
            a, b = (seg[[0, 2]], seg[[1, 3]]) if axis == "row" else (seg[[1, 3]], seg[[0, 2]])
            if a.min() >= a_lo and a.max() <= a_hi and b.min() <= b0 + 1 and b.max() >= b1 - 1:
                return True
        return False
    assert covers(18.5, 21.5, 10, 79, "row")     # row 20, across its 2-cell gap
    assert covers(98.5, 101.5, 5, 49, "col")     # column 100
    # nothing on row 40 (too short) nor row 30 (dots 3 cells apart)
    assert not any(25 <= min(r1, r2) and max(r1, r2) <= 45 and abs(r1 - r2) < 3 for r1, c1, r2, c2 in runs)


def _lines_near(lines, p, q, tol=1.5):
    """The segments of ``lines`` with both ends within ``tol`` cells of the segment ``p``-``q``'s ends."""
    p, q = np.asarray(p, float), np.asarray(q, float)
    out = []
    for seg in np.asarray(lines).reshape(-1, 4):
        a, b = seg[:2], seg[2:]
        if (np.hypot(*(a - p)) <= tol and np.hypot(*(b - q)) <= tol) or (
                np.hypot(*(a - q)) <= tol and np.hypot(*(b - p)) <= tol):
            out.append(seg)
    return out


def test_straight_lines_bridge_scan_gaps_keep_doorways_and_angled_walls():
    faces = np.zeros((120, 160), bool)
    faces[20, 10:60] = True           # a wall face ...
    faces[20, 64:100] = True          # ... on after a 4-cell scan gap: one line
    faces[20, 112:150] = True         # after a 12-cell doorway: a line of its own
    faces[30:110, 5] = True           # the other main direction
    rr = np.arange(60, 100)
    faces[rr, 40 + (rr - 60)] = True  # a wall at 45 degrees (a wing built at an angle)
    hough = np.array([[20, 10, 20, 150], [30, 5, 109, 5], [60, 40, 99, 79]], float)
    lines = W.straight_lines(faces, min_length_px=20, max_gap_px=5, hough=hough)
    assert _lines_near(lines, (20, 10), (20, 99))          # across the scan gap
    assert _lines_near(lines, (20, 112), (20, 149))        # the doorway is not bridged
    assert not _lines_near(lines, (20, 10), (20, 149), tol=3)
    assert _lines_near(lines, (30, 5), (109, 5))
    assert _lines_near(lines, (60, 40), (99, 79), tol=0.1)  # the angled Hough line, as it is
    # a narrower gap setting splits the wall at its scan gap
    short = W.straight_lines(faces, min_length_px=20, max_gap_px=2, hough=hough)
    assert not _lines_near(short, (20, 10), (20, 99))
    assert _lines_near(short, (20, 10), (20, 59)) and _lines_near(short, (20, 64), (20, 99))


def test_straight_lines_change_only_where_the_map_changes():
    """Each face cell counts only for the lines through it: a wall added far away
    leaves the other lines as they were (a random Hough sample need not)."""
    faces = np.zeros((200, 200), bool)
    faces[20, 10:90] = True
    faces[60, 30:70] = True
    faces[10:90, 150] = True
    hough = np.array([[20, 10, 20, 89], [10, 150, 89, 150]], float)
    before = W.straight_lines(faces, min_length_px=20, max_gap_px=5, hough=hough)
    faces[180, 20:180] = True  # a new wall, far from the others
    after = W.straight_lines(faces, min_length_px=20, max_gap_px=5, hough=hough)
    old = {tuple(s) for s in before.tolist()}
    new = {tuple(s) for s in after.tolist()}
    assert old <= new
    assert all(min(s[0], s[2]) >= 178 for s in new - old)  # only lines of the new wall
    assert new - old


def test_partition_face_on_a_free_standing_table_is_no_partition():
    # the partition's lower part cut off the south wall: a free-standing
    # obstacle 1.6 m long (rows 54..85), a table's side, with the same hits
    free, hits = _partition((14, 22, 31, 40, 47))
    free[86:104, 84:88] = True
    hits[86:104, 84:88] = False
    faces = W.wall_faces(~free, free)
    lines = W.wall_lines(faces, min_length_px=20)
    kw = dict(min_wall_px=30, min_gap_px=10, max_gap_px=60, min_hits_px=4, depth_px=24, hits=hits)
    assert W.partition_gaps(~free, free, lines, **kw)                       # any obstacle: found
    assert W.partition_gaps(~free, free, lines, min_structure_px=40, **kw) == []  # 2 m structure: not


def _across_reference(p, q, index, tol, min_angle=np.deg2rad(60.0), past=None):
    # the definition, one segment and one wall at a time
    v = q - p
    d = v / max(float(np.hypot(*v)), 1e-9)
    hit, inside = [False, False], [False, False]
    for u, n, rho, t0, t1 in index.classes:
        if abs(float(d @ u)) > np.cos(min_angle):
            continue
        for k, x in enumerate((p, q)):
            r, t = float(x @ n), float(x @ u)
            hit[k] |= any(abs(r - rh) <= tol and a - tol <= t <= b + tol for rh, a, b in zip(rho, t0, t1))
            if past is not None:
                inside[k] |= any(abs(r - rh) <= tol and a + past <= t <= b - past for rh, a, b in zip(rho, t0, t1))
    return hit[0] and hit[1] and (past is None or inside[0] or inside[1])


def test_across_walls_many_follows_the_definition():
    rng = np.random.default_rng(3)
    walls = []
    for k in range(12):                       # horizontal and vertical walls, some near each other
        u = np.array([0.0, 1.0]) if k % 2 else np.array([1.0, 0.0])
        n = np.array([-u[1], u[0]])
        rho = float(rng.integers(0, 100))
        a = float(rng.integers(0, 60))
        walls.append((rho * n, u, n, [[a, a + float(rng.integers(20, 80))]]))
    index = W.WallIndex(walls)
    # ends on the walls' lines (or near them) half of the time
    P, Q = rng.uniform(0, 120, (400, 2)), rng.uniform(0, 120, (400, 2))
    for X in (P, Q):
        on = rng.random(len(X)) < 0.5
        w = rng.integers(0, len(walls), len(X))
        for i in np.flatnonzero(on):
            origin, u, n, runs = walls[w[i]]
            X[i] = origin + rng.uniform(runs[0][0], runs[0][1]) * u + rng.uniform(-4, 4) * n
    many = W.across_walls_many(P, Q, index, tol_px=3.0)
    want = [_across_reference(p, q, index, 3.0) for p, q in zip(P, Q)]
    assert list(many) == want
    assert 0 < sum(want) < len(want)
    many = W.across_walls_many(P, Q, index, tol_px=3.0, past_px=10.0)
    want_past = [_across_reference(p, q, index, 3.0, past=10.0) for p, q in zip(P, Q)]
    assert list(many) == want_past
    assert 0 < sum(want_past) < sum(want)


def test_a_corridor_mouth_is_not_across_the_corridor():
    # a corridor 2 m wide (rows 20..59) between two 8 m walls (columns 5..164)
    free = np.zeros((80, 170), bool)
    free[20:60, 5:165] = True
    faces = W.wall_faces(~free, free)
    walls = W.long_walls(W.wall_lines(faces, min_length_px=20), max_gap_px=60, offset_px=4, min_span_px=80)
    kw = dict(tol_px=4, past_px=10)
    assert W.across_walls_many([(19.5, 80)], [(60.5, 80)], walls, **kw)[0]    # its middle: across it
    assert not W.across_walls_many([(19.5, 163)], [(60.5, 163)], walls, **kw)[0]   # both walls end here: its mouth
    assert W.across_walls_many([(19.5, 163)], [(60.5, 163)], walls, tol_px=4)[0]   # without past_px: across


def test_furniture_rows_need_mostly_furniture_in_separate_pieces():
    obstacle = np.zeros((40, 100), bool)
    obstacle[10, 5:95] = True               # a wall along row 10
    obstacle[20, 5:95] = True               # and one along row 20
    obstacle[30, 5:95] = True               # and one along row 30
    part = np.zeros_like(obstacle)
    part[10, 5:35] = True                   # row 10: a third of it one piece of furniture
    part[20, 5:30] = part[20, 40:70] = True  # row 20: two thirds, two pieces
    part[30, 5:95] = True                   # row 30: all furniture, but one piece (a counter)
    u, n = np.array([0.0, 1.0]), np.array([-1.0, 0.0])
    walls = [(np.array([r, 0.0]), u, n, [[5.0, 94.0]]) for r in (10.0, 20.0, 30.0, 36.0)]  # 36: empty
    rows = W.furniture_rows(walls, obstacle, part, band_px=1)
    assert rows.tolist() == [False, True, False, False]
    assert W.furniture_rows(walls, obstacle, part, band_px=1, min_pieces=1).tolist() == [False, True, True, False]


def test_wall_faces_are_obstacle_cells_with_a_free_4_neighbour():
    rng = np.random.default_rng(3)
    for _ in range(50):
        h, w = rng.integers(1, 30, 2)
        free = rng.random((h, w)) < rng.random()
        obstacle = rng.random((h, w)) < 0.5          # may overlap free: only the neighbours count
        want = np.zeros((h, w), bool)
        for r in range(h):
            for c in range(w):
                nb = [(r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1)]
                want[r, c] = obstacle[r, c] and any(0 <= a < h and 0 <= b < w and free[a, b] for a, b in nb)
        assert np.array_equal(W.wall_faces(obstacle, free), want)


def _chains(lo, hi, max_gap):
    """Pieces [lo, hi] of one line, one at a time by their start: the runs
    of each chain (pieces within a cell of each other merge; a gap of at
    most ``max_gap`` starts the next run of the chain, a wider one the next
    chain)."""
    chains, runs = [], []
    for a, b in sorted(zip(lo, hi)):
        if runs and a <= runs[-1][1] + 1.0:
            runs[-1][1] = max(runs[-1][1], b)
        elif runs and a - runs[-1][1] <= max_gap:
            runs.append([a, b])
        else:
            if runs:
                chains.append(runs)
            runs = [[a, b]]
    return chains + [runs]


def test_long_walls_chain_the_pieces_of_each_line_in_order():
    # pieces along a few rows (far apart: one group per row), projected on
    # the main direction as long_walls does, chained one at a time
    rng = np.random.default_rng(5)
    for _ in range(30):
        rows = rng.choice([10.0, 40.0, 70.0, 100.0], 60)
        lo = np.round(rng.uniform(0, 400, 60), 1)
        hi = lo + rng.choice([0.5, 1.0, 3.0, 12.0, 40.0], 60)
        segs = np.c_[rows, lo, rows, hi]
        segs[::2] = segs[::2][:, [2, 3, 0, 1]]                  # either end first
        segs = np.r_[segs, [[0, 0, 300, 0]]]                    # a wall of the other direction
        walls = W.long_walls(segs, max_gap_px=15, offset_px=4, min_span_px=50)
        got = sorted([[float(a), float(b)] for a, b in runs] for origin, u, n, runs in walls if abs(u[1]) > 0.9)
        (u, sel), = [(u, sel) for u, sel in W._main_classes(segs, np.deg2rad(12.0)) if abs(u[1]) > 0.9]
        t1, t2 = segs[sel, :2] @ u, segs[sel, 2:] @ u
        want = []
        for row in np.unique(rows):
            on = rows[sel] == row
            for runs in _chains(np.minimum(t1, t2)[on].tolist(), np.maximum(t1, t2)[on].tolist(), 15):
                span = runs[-1][1] - runs[0][0]
                if span >= 50 and sum(b - a for a, b in runs) >= 0.5 * span:
                    want.append(runs)
        assert got == sorted(want)
        for origin, u_, n, runs in walls:                       # on its row
            if abs(u_[1]) > 0.9:
                assert min(abs(float(origin @ n) - (-u_[1] * r)) for r in (10, 40, 70, 100)) < 4


def _spans_passage_by_definition(obstacle, p, q, depth_px, slack=1.25):
    """:func:`topomap.core.walls._spans_passage` segment by segment, every run sampled to its cap."""
    H, W = obstacle.shape
    out = []
    for a, b in zip(p, q):
        v = b - a
        L = np.hypot(*v)
        d = v / max(L, 1e-9)
        n = np.array([-d[1], d[0]])
        cap = int(np.ceil(slack * L)) + 2

        def run(start, step):
            for i in range(1, cap + 1):
                r, c = np.rint(start + i * step).astype(int)
                if not (0 <= r < H and 0 <= c < W) or obstacle[r, c]:
                    return i - 1
            return cap

        sides = []
        for side in (n, -n):
            sides.append(any(run(c - d, -d) + run(c, d) + 1 <= slack * L
                             for c in ((a + b) / 2 + t * side for t in np.array([0.25, 0.5, 0.75, 1.0]) * depth_px)))
        out.append(all(sides))
    return np.array(out, bool)


def test_spans_passage_follows_the_definition():
    """The batched runs of _spans_passage (sampled only as far as a narrow passage
    needs, the runs back only where the run on leaves room) answer as each segment's
    own runs do, near the map's edges too."""
    rng = np.random.default_rng(3)
    obstacle = rng.random((60, 80)) < 0.04
    obstacle[20:40, 10:70] = False
    obstacle[19, 10:70] = obstacle[40, 10:70] = True  # a corridor
    p = rng.uniform([-5, -5], [65, 85], (300, 2))
    ang = rng.uniform(0, 2 * np.pi, 300)
    q = p + rng.uniform(0, 30, 300)[:, None] * np.stack([np.sin(ang), np.cos(ang)], 1)
    p[:40] = np.stack([np.full(40, 30.0), rng.uniform(10, 60, 40)], 1)  # across the corridor
    q[:40] = p[:40] + [[rng.uniform(8, 14), 0.3]]
    got = W._spans_passage(obstacle, p, q, 6.0)
    want = _spans_passage_by_definition(obstacle, p, q, 6.0)
    assert got.any() and not got.all()
    np.testing.assert_array_equal(got, want)
