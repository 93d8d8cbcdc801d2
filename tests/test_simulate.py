"""The laser SLAM simulator (topomap.bench.simulate) on small hand-drawn plans."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage as ndi

from _floorplans import draw_plan, home
from topomap.errors import ParameterError
from topomap.bench.simulate import ScanOptions, simulate_scan

#: Every fault off: the clean laser on the bare plan.
CLEAN = dict(glass_share=0.0, drift_xy=0.0, drift_yaw=0.0, plan_furniture=False, furniture_density=0.0,
             closed_doors=0.0, people_per_metre=0.0)


@pytest.fixture(scope="module")
def plan():
    return home()


def _interior(plan, label, margin=2):
    """Cells of room ``label`` at least ``margin`` cells from its edge."""
    return ndi.binary_erosion(plan.rooms == label, iterations=margin)


def test_grid_frame_and_seed(plan):
    a = simulate_scan(plan, seed=3)
    b = simulate_scan(plan, seed=3)
    c = simulate_scan(plan, seed=4)
    assert a.grid.shape == plan.shape
    assert a.grid.resolution == plan.resolution
    assert a.grid.origin == tuple(float(v) for v in plan.origin)
    assert np.array_equal(a.grid.cells, b.grid.cells)
    assert np.array_equal(a.poses, b.poses)
    assert not np.array_equal(a.grid.cells, c.grid.cells)
    assert a.grid.free.sum() > 0.5 * plan.inside.sum()  # most of the home is mapped


def test_walls_stop_rays_without_glass(plan):
    r = simulate_scan(plan, options=ScanOptions(**CLEAN), seed=1)
    outside = ~plan.inside & ~plan.walls
    assert not (r.grid.free & outside).any()
    assert set(r.visited) == {1, 2, 3, 4}
    # the box room with no door, next to the corridor, stays unknown inside
    assert r.grid.unknown[_interior(plan, 5)].all()
    # the walls the robot saw are occupied: every room it entered has occupied cells on its edge
    ring = ndi.binary_dilation(plan.rooms == 2, iterations=2) & plan.walls
    assert r.grid.occupied[ring].sum() > 0.3 * ring.sum() / 4


def test_glass_lets_rays_out(plan):
    opts = ScanOptions(**{**CLEAN, "glass_share": 0.3})
    r = simulate_scan(plan, options=opts, seed=1)
    outside = ~plan.inside & ~plan.walls
    assert r.glass.any() and not (r.glass & ~plan.outer_walls).any()
    assert (r.grid.free & outside).sum() > 100
    # a ray that left through glass crossed a glass cell: every free cell outside lies on the far
    # side of the facade from a pose, i.e. the free space outside touches glass or the grid's edge
    lab, n = ndi.label(r.grid.free & outside | r.glass)
    touching = set(np.unique(lab[r.glass])) - {0}
    assert set(np.unique(lab[r.grid.free & outside])) - {0} <= touching


def test_free_cells_within_range_of_a_pose(plan):
    opts = ScanOptions(**{**CLEAN, "glass_share": 0.3, "range_max": 4.0, "drift_xy": 0.02, "drift_yaw": 0.3})
    r = simulate_scan(plan, options=opts, seed=2)
    rows, cols = np.nonzero(r.grid.free)
    x, y = r.grid.pixel_to_world(rows, cols)
    d = np.hypot(x[:, None] - r.map_poses[None, :, 0], y[:, None] - r.map_poses[None, :, 1]).min(axis=1)
    assert d.max() <= opts.range_max + plan.resolution
    assert not np.allclose(r.poses, r.map_poses)  # the drift moved the poses the map is drawn at


def test_explore_leaves_rooms_unknown(plan):
    r = simulate_scan(plan, options=ScanOptions(**{**CLEAN, "explore": 0.4, "range_max": 3.0}), seed=5)
    assert len(r.visited) == 2
    path_rooms = set(plan.rooms[tuple(np.rint(r.grid.world_to_pixel(r.poses[:, 0], r.poses[:, 1])).astype(int))].tolist())
    assert path_rooms - {0} <= set(r.visited)
    for lab in set(range(1, 6)) - set(r.visited):
        inner = _interior(plan, lab)
        # seen at most through a door: most of an unvisited room stays unknown
        assert r.grid.unknown[inner].mean() > 0.5, lab


def test_closed_doors_block(plan):
    r = simulate_scan(plan, options=ScanOptions(**{**CLEAN, "closed_doors": 1.0}), seed=1)
    assert r.closed_doors == (0, 1, 2)
    assert len(r.visited) == 1  # every door is shut: the robot stays in its start room
    for lab in set(range(1, 6)) - set(r.visited):
        assert r.grid.unknown[_interior(plan, lab)].all(), lab


def test_furniture_occupied_only_where_seen():
    # a room with a shelf box (a plan object) and a closed cupboard room with another
    plan = draw_plan([(0.2, 0.2, 5.0, 4.0), (5.2, 0.2, 7.0, 4.0)], [],
                     objects=(("shelf", 2.0, 2.0, 3.0, 2.4), ("shelf", 5.8, 1.0, 6.4, 2.0)))
    r = simulate_scan(plan, options=ScanOptions(**{**CLEAN, "plan_furniture": True}), seed=1)
    blocked = r.world.blocked
    assert blocked.sum() > 0
    seen = blocked & (plan.rooms == 1)
    hidden = blocked & (plan.rooms == 2)
    assert r.grid.occupied[seen].any()
    assert not r.grid.occupied[hidden].any() and r.grid.unknown[hidden].all()
    # the inside of the shelf is never free: rays stop at its faces
    assert not r.grid.free[ndi.binary_erosion(seen)].any()


def test_random_furniture_and_people(plan):
    opts = ScanOptions(**{**CLEAN, "furniture_density": 0.3, "people_per_metre": 0.2})
    r = simulate_scan(plan, options=opts, seed=1)
    assert len(r.furniture) > 0 and len(r.people) > 0
    for kind, x1, y1, x2, y2 in r.furniture:
        assert kind in ("table", "chair", "bed", "shelf") and x2 > x1 and y2 > y1
        rows, cols = r.grid.world_to_pixel(np.array([x1, x2]), np.array([y1, y2]))
        labs = plan.rooms[int(round(rows.min())) + 1:int(round(rows.max())), int(round(cols.min())) + 1:int(round(cols.max()))]
        assert len(np.unique(labs)) == 1 and labs.flat[0] > 0  # wholly inside one room
    assert not (r.world.blocked & plan.walls).any()


@pytest.mark.parametrize("kw, word", [
    (dict(range_max=0), "range_max"), (dict(range_max=-1.0), "-1.0"), (dict(angle_step=0), "angle_step"),
    (dict(field_of_view=400), "400"), (dict(explore=1.5), "1.5"), (dict(glass_share=-0.1), "-0.1"),
    (dict(hit_probability=0.4), "0.4"), (dict(miss_probability=0.6), "0.6"), (dict(clamp_max=0.5), "0.5"),
    (dict(plan_furniture="yes"), "'yes'"), (dict(pose_spacing="0.3"), "'0.3'"),
    (dict(free_thresh=0.7), "0.7")])
def test_options_validation(kw, word):
    with pytest.raises(ParameterError, match=list(kw)[0]) as err:
        ScanOptions(**kw)
    assert word in str(err.value) and "\n" not in str(err.value)


def test_bad_arguments(plan):
    with pytest.raises(ParameterError, match="seed"):
        simulate_scan(plan, seed=-1)
    with pytest.raises(ParameterError, match="ScanOptions"):
        simulate_scan(plan, options={"range_max": 5})
    with pytest.raises(ParameterError, match="FloorPlan"):
        simulate_scan(plan.walls)


def test_only_doors_of_dead_end_rooms_are_closed():
    from _floorplans import big_home

    plan = big_home(2, 2)  # two corridors joined by a door, two rooms off each
    r = simulate_scan(plan, options=ScanOptions(**{**CLEAN, "closed_doors": 1.0}), seed=2)
    joins = [i for i, d in enumerate(plan.doors) if min(d.rooms) > 0 and
             sum(min(e.rooms) > 0 and set(e.rooms) & set(d.rooms) != set() for e in plan.doors) > 1
             and all(len({x for e in plan.doors if k in e.rooms for x in e.rooms} - {k}) > 1 for k in d.rooms)]
    assert joins, "the plan has a door between two corridors"
    assert not set(joins) & set(r.closed_doors)
    assert len(r.closed_doors) == len(plan.doors) - len(joins)
    corridors = {k for d in (plan.doors[i] for i in joins) for k in d.rooms}
    assert corridors <= set(r.visited)  # the robot still walks both corridors


def test_the_robot_maps_the_largest_part_of_a_home_in_pieces():
    from topomap.bench.simulate import _largest_part

    adj = {1: {2}, 2: {1}, 3: {4}, 4: {3, 5}, 5: {4}}  # two parts no door joins: {1, 2} and {3, 4, 5}
    area = np.array([0, 50, 50, 10, 10, 10])
    assert _largest_part(adj, area) == {1, 2}
    area = np.array([0, 5, 5, 10, 10, 0])  # room 5 has no robot space: left out
    assert _largest_part(adj, area) == {3, 4}


def test_drift_is_bounded_however_long_the_path():
    """The SLAM's residual error stays near drift_xy / drift_yaw on a long path (no random walk
    that grows with the distance: a 400 m path would otherwise shift walls by metres)."""
    from topomap.bench.simulate import scan_poses
    path = np.stack([np.zeros(8001), np.arange(8001.0)], axis=1)  # 400 m at 0.05 m a cell
    opts = ScanOptions(**{**CLEAN, "drift_xy": 0.03, "drift_yaw": 0.5})
    true, believed = scan_poses(path, 0.05, opts, np.random.default_rng(3))
    err_m = np.hypot(*(believed[:, :2] - true[:, :2]).T) * 0.05
    assert err_m[0] == 0.0
    assert np.percentile(err_m, 99) < 0.15            # 3.5 sigma of the 2-D error, not metres
    assert 0.01 < np.sqrt(np.mean(err_m ** 2)) < 0.07  # about sqrt(2) * 0.03
    yaw = np.degrees(np.abs(believed[:, 2] - true[:, 2]))
    assert np.percentile(yaw, 99) < 2.0 and yaw.max() > 0.1


def test_the_scan_truth_is_the_rooms_the_map_shows_whole():
    from topomap.bench.simulate import SHOWN_AREA, shown_doors, shown_rooms

    rooms = np.zeros((60, 90), np.uint16)
    rooms[5:55, 5:40] = 1
    rooms[5:55, 45:85] = 3
    rooms[0:4, 0:4] = 7  # a room with no free cell in the map
    free = np.zeros(rooms.shape, bool)
    free[10:30, 10:30] = True        # room 1: 400 cells = 1 m² free at 0.05 m: shown, and whole
    free[10:29, 50:70] = True        # room 3: 380 cells: not shown
    shown = shown_rooms(rooms, free, resolution=0.05)
    assert SHOWN_AREA == 1.0 and shown.dtype == rooms.dtype
    np.testing.assert_array_equal(shown, np.where(rooms == 1, 1, 0))
    assert set(np.unique(shown_rooms(rooms, free, resolution=0.05, min_area=0.9))) == {0, 1, 3}
    assert set(np.unique(shown_rooms(rooms, free, resolution=0.1))) == {0, 1, 3}  # 4 m², 3.8 m²
    doors = [{"rooms": (1, 3)}, {"rooms": (0, 1)}, {"rooms": (0, 3)}, {"rooms": (1, 1)}]
    assert shown_doors(doors, shown) == [doors[1], doors[3]]
    with pytest.raises(ParameterError, match="shape"):
        shown_rooms(rooms, free[1:], resolution=0.05)
    with pytest.raises(ParameterError, match="min_area"):
        shown_rooms(rooms, free, resolution=0.05, min_area=-1)


def test_a_room_behind_a_closed_door_is_not_in_the_scan_truth(plan):
    from topomap.bench.simulate import shown_doors, shown_rooms

    r = simulate_scan(plan, options=ScanOptions(**{**CLEAN, "closed_doors": 1.0}), seed=1)
    shown = shown_rooms(plan.rooms, r.grid.free, resolution=plan.resolution)
    assert set(np.unique(shown)) - {0} == set(r.visited)
    assert np.array_equal(shown > 0, np.isin(plan.rooms, r.visited))  # the shown rooms whole
    assert shown_doors(plan.doors, shown) == []  # every door leads into a room behind it


def test_furniture_leaves_a_way_through_every_room():
    """Random pieces never cut a room's floor the robot can drive on (clearance from every obstacle)
    into pieces (of more than 0.5 m²): people walk through every part of a room."""
    from _floorplans import draw_plan

    plan = draw_plan([(0.2, 0.2, 9.0, 1.8), (0.2, 2.0, 4.0, 5.0)], [(2.0, 1.9, 0.9, "x")])  # a hall, a room
    opts = ScanOptions(**{**CLEAN, "furniture_density": 1.0})
    placed = 0
    for seed in range(6):
        r = simulate_scan(plan, options=opts, seed=seed)
        placed += len(r.furniture)
        floor = plan.inside & ~plan.walls & ~r.world.blocked
        walk = ndi.distance_transform_edt(floor) * plan.resolution > opts.clearance
        for lab in (1, 2):
            parts, n = ndi.label(walk & (plan.rooms == lab), structure=np.ones((3, 3), bool))
            big = np.bincount(parts.ravel())[1:] * plan.resolution ** 2 > 0.5  # pockets under a table aside
            assert big.sum() == 1, (seed, lab)
    assert placed >= 12  # furniture was placed, not all refused


def test_the_robot_starts_where_it_can_reach_most_of_the_home():
    """The room by the front door may be a pocket a fixture cuts off from the rest: the robot is set
    down in the largest piece of space it can drive on, not trapped in the pocket."""
    from _floorplans import draw_plan

    # room 1 (front door on its west wall) split by a fixture from wall to wall at x = 2.5-2.8 m:
    # the pocket by the door (6.4 m²) is larger than room 1's side of the fixture (3.4 m²), which
    # opens into room 2 (10.6 m²)
    plan = draw_plan([(0.2, 0.2, 4.0, 3.0), (4.2, 0.2, 8.0, 3.0)],
                     [(0.1, 1.5, 0.9, "y"), (4.1, 1.5, 0.9, "y")],
                     objects=(("special", 2.5, 0.2, 2.8, 3.0),))
    r = simulate_scan(plan, options=ScanOptions(**{**CLEAN, "plan_furniture": True}), seed=0)
    assert set(r.visited) == {1, 2}
    assert r.grid.free[plan.rooms == 2].mean() > 0.8
    x = r.poses[:, 0]
    assert (x > 2.8).all()  # never in the pocket


def test_every_beam_stops_at_the_first_wall_that_is_not_glass(plan):
    """Trace each beam of scans taken in every room up to its range: it crosses no wall cell but glass,
    and beams through glass go on past the facade."""
    from topomap.bench.simulate import _beams, build_world, cast_rays

    opts = ScanOptions(**{**CLEAN, "glass_share": 0.5, "range_sigma": 0.0, "no_return_share": 0.0,
                          "field_of_view": 360.0, "angle_step": 2.0})
    world = build_world(plan, opts, np.random.default_rng(1))
    assert world.glass.any()
    poses = []
    for lab in range(1, 6):
        r, c = np.argwhere(_interior(plan, lab, margin=6))[0]
        poses.append((float(r), float(c), 0.3))
    ranges = cast_rays(world.opaque, np.array(poses), plan.resolution, opts, np.random.default_rng(0))
    rel, _idx, _n = _beams(opts)
    # the core of the walls that are not glass (a beam may graze a wall's corner cell: the samples
    # of a beam and this trace round differently; the walls are 4 cells thick, the core 2)
    stone = ndi.binary_erosion(plan.walls & ~world.glass, np.ones((3, 3), bool))
    through_glass = 0
    for (r0, c0, th), rk in zip(poses, ranges):
        for a, rng_m in zip(rel + th, rk):
            end = (rng_m if np.isfinite(rng_m) else opts.range_max) / plan.resolution
            t = np.arange(0.0, max(end - 0.5, 0.0), 0.25)
            rr = np.rint(r0 - np.sin(a) * t).astype(int)
            cc = np.rint(c0 + np.cos(a) * t).astype(int)
            inside = (rr >= 0) & (rr < plan.shape[0]) & (cc >= 0) & (cc < plan.shape[1])
            assert not stone[rr[inside], cc[inside]].any()
            through_glass += bool(world.glass[rr[inside], cc[inside]].any())
            if np.isfinite(rng_m):  # it ends on something opaque
                re, ce = int(np.rint(r0 - np.sin(a) * end)), int(np.rint(c0 + np.cos(a) * end))
                assert world.opaque[max(re - 1, 0):re + 2, max(ce - 1, 0):ce + 2].any()
    assert through_glass > 0
