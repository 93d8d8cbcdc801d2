"""Vector floor plans read into a FloorPlan: the ground truth's invariants on hand-drawn plans."""

import math

import numpy as np
import pytest

from topomap.errors import MapFileNotFoundError, ParameterError, PlanFormatError
from topomap.bench.floorplan import ground_truth_problems, read_plan
from topomap.io import FREE, OCCUPIED, UNKNOWN

# two rooms and a corridor (units: 1 = 1 cm once the doors are scaled to 0.8 m), an entrance,
# a closet behind its own door off room A, a gap of 25 units (0.27 m) in the wall between A and B
PLAN = """\
0\t0\t600\t0\twall\t1\t1
600\t0\t600\t400\twall\t1\t1
600\t400\t0\t400\twall\t1\t1
0\t400\t0\t0\twall\t1\t1
0\t250\t600\t250\twall\t1\t1
300\t0\t300\t225\twall\t1\t1
0\t100\t100\t100\twall\t1\t1
100\t0\t100\t100\twall\t1\t1
100\t250\t180\t250\tdoor\t1\t1
400\t250\t480\t250\tdoor\t1\t1
20\t100\t80\t100\tdoor\t1\t1
250\t400\t330\t400\tdoor\t1\t1
150\t150\t200\t180\tbedroom\t1\t1
400\t150\t450\t180\tbedroom\t1\t1
30\t30\t60\t60\tcloset\t1\t1
250\t300\t300\t330\tcorridor\t1\t1
200\t20\t230\t50\ttoilet\t1\t1
"""


def _write(tmp_path, text, name="plan.txt"):
    p = tmp_path / name
    p.write_text(text)
    return p


@pytest.fixture
def plan(tmp_path):
    return read_plan(_write(tmp_path, PLAN))


def test_scale_rule(plan):
    # door segments 80, 80, 60, 80 units: the 25th percentile is 75 -> 0.8 m
    assert plan.scale == pytest.approx(0.8 / 75)
    widths = sorted(d.width for d in plan.doors)
    assert widths[0] == pytest.approx(60 * 0.8 / 75)


def test_invariants_rooms_doors_closet(plan):
    assert ground_truth_problems(plan) == []
    # room A (with its closet), room B (the wall gap of 10 units closed), the corridor
    assert plan.n_rooms == 3
    kinds = sorted(plan.kinds.values())
    assert kinds == [("bedroom",), ("closet", "bedroom"), ("corridor",)] or \
        sorted(map(sorted, plan.kinds.values())) == [["bedroom"], ["bedroom", "closet"], ["corridor"]]
    assert plan.quirks["closets_merged"] == 1
    assert plan.quirks["gaps_extended"] + plan.quirks["gaps_bridged"] == 1
    pairs = sorted(d.rooms for d in plan.doors)
    assert sum(a == 0 for a, _ in pairs) == 1          # the entrance
    assert sum(a == b for a, b in pairs) == 1          # the closet door, inside room A
    assert np.array_equal(plan.rooms > 0, plan.inside)
    assert not np.any(plan.inside & plan.walls)
    assert np.all(plan.outer_walls <= plan.walls) and plan.outer_walls.any()
    # the home is the 600 x 400 units box less its walls: the inner half (0.075 m) of the 2000
    # units of facade, the whole 0.15 m of the 1025 units of inner wall; +-40 % for the cells
    box = 600 * 400 * plan.scale ** 2
    loss = 2000 * plan.scale * 0.075 + 1025 * plan.scale * 0.15
    assert box - 1.4 * loss < plan.area < box - 0.6 * loss


def test_doors_lie_on_wall_lines_and_are_open(plan):
    H = plan.shape[0]
    for d in plan.doors:
        for x, y in (d.p1, d.p2):
            # every door end is on the line y = 250 or 400 or 100 of the plan (horizontal walls)
            assert d.p1[1] == pytest.approx(d.p2[1])
        m = (np.array(d.p1) + np.array(d.p2)) / 2
        r = int(round(H - m[1] / plan.resolution - 0.5))
        c = int(round(m[0] / plan.resolution - 0.5))
        assert plan.inside[r, c] and not plan.walls[r, c]


def test_grid_and_save(plan, tmp_path):
    g = plan.grid()
    assert np.array_equal(g.cells == OCCUPIED, plan.walls)
    assert np.array_equal(g.cells == FREE, plan.inside)
    assert g.cells[0, 0] == UNKNOWN
    yml = plan.save(tmp_path / "m")
    from topomap.io import load_map
    back = load_map(yml)
    assert np.array_equal(back.cells, g.cells)


def test_wall_gap_left_open_leaks(tmp_path):
    # without the gap closing, rooms A and B are one
    p = read_plan(_write(tmp_path, PLAN), max_gap=0.0)
    assert p.n_rooms == 2


@pytest.mark.parametrize("text, msg", [
    ("", "empty"),
    ("   \n\n", "no elements"),
    ("0\t0\t1\twall\n", "line 1"),
    ("0\t0\tx\t1\twall\n", "not a number"),
    ("0\t0\t10\t0\tdoor\n", "no walls"),
    ("0\t0\t10\t0\twall\n", "no doors and its walls span no area"),
])
def test_bad_input(tmp_path, text, msg):
    p = _write(tmp_path, text, "bad.txt")
    with pytest.raises(PlanFormatError, match=msg) as e:
        read_plan(p)
    assert "bad.txt" in str(e.value) and "\n" not in str(e.value)


def test_a_plan_without_doors_is_scaled_by_the_size_of_a_home(tmp_path):
    doorless = "".join(line + "\n" for line in PLAN.splitlines() if "\tdoor\t" not in line)
    path = _write(tmp_path, doorless)
    p = read_plan(path)
    # the walls span 600 x 400 units: a home's 62 m² box
    assert p.scale == pytest.approx(math.sqrt(62.0 / (600 * 400)))
    assert p.quirks["scale_from_area"] == 1 and p.doors == ()
    assert ground_truth_problems(p) == []
    assert p.n_rooms >= 2  # the rooms, each a part of its own (no door joins them)
    assert read_plan(path, home_area=24.0).scale == pytest.approx(0.01)  # 24 m² over 240,000 units²
    with_doors = read_plan(_write(tmp_path, PLAN, "doors.txt"), home_area=24.0)
    assert with_doors.scale == pytest.approx(0.8 / 75) and with_doors.quirks["scale_from_area"] == 0
    assert read_plan(path, scale=0.02).scale == 0.02
    with pytest.raises(ParameterError, match="home_area"):
        read_plan(path, home_area=0)


def test_missing_file(tmp_path):
    with pytest.raises(MapFileNotFoundError):
        read_plan(tmp_path / "nope.txt")


def test_real_plans():
    from topomap.bench.datasets import _shared_dataset
    d = _shared_dataset("r2v_floorplans")
    if d is None or not (d / "plans").is_dir():
        pytest.skip("r2v_floorplans not present")
    for path in sorted((d / "plans").glob("*.txt"))[:4]:
        p = read_plan(path)
        assert ground_truth_problems(p) == [], path.name
        assert p.n_rooms >= 2 and len(p.doors) >= 2
