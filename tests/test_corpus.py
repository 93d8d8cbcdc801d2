"""``topomap simulate``: case folders of a plan, its simulated robot map and the ground truth."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from topomap.cli import main
from topomap.bench.corpus import CASE_FILES, case_seed, scan_options
from topomap.errors import ParameterError
from topomap.io import load_map

# A 6 m x 4 m flat in plan units (a door of 40 units comes out at 0.8 m): two rooms, a door between
# them and an entrance door in the outer wall.
TWO_ROOMS = "".join(f"{a}\t{b}\t{c}\t{d}\t{kind}\t1\t1\n" for a, b, c, d, kind in (
    (0, 0, 300, 0, "wall"), (300, 0, 300, 200, "wall"), (300, 200, 0, 200, "wall"), (0, 200, 0, 0, "wall"),
    (150, 0, 150, 200, "wall"), (150, 80, 150, 120, "door"), (50, 200, 90, 200, "door"),
    (30, 30, 100, 100, "bedroom"), (180, 30, 260, 100, "living_room")))


@pytest.fixture
def plans(tmp_path):
    paths = []
    for name, text in (("flat", TWO_ROOMS), ("wide", TWO_ROOMS.replace("300", "400"))):
        p = tmp_path / f"{name}.txt"
        p.write_text(text)
        paths.append(p)
    return paths


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_a_case_holds_every_file_on_one_grid(plans, tmp_path):
    out = tmp_path / "case"
    r = _run("simulate", plans[0], "-o", out, "--seed", 3)
    assert r.exit_code == 0, r.output
    assert "2 rooms, 2 doors" in r.output
    assert sorted(p.name for p in out.iterdir()) == sorted(CASE_FILES)
    scan, plan = load_map(out / "map.yaml"), load_map(out / "plan.yaml")
    gt = np.array(Image.open(out / "gt_rooms.png"))
    assert scan.shape == plan.shape == gt.shape
    assert scan.resolution == plan.resolution == 0.05
    assert set(np.unique(gt)) == {0, 1, 2}
    assert plan.free[gt > 0].all()  # every true room lies in the plan's free space
    assert not plan.free[0].any()  # the outside of the home is no free space of the plan
    doors = json.loads((out / "gt_doors.json").read_text())["doors"]
    assert sorted(tuple(d["rooms"]) for d in doors) == [(0, 1), (1, 2)] or \
        sorted(tuple(d["rooms"]) for d in doors) == [(0, 2), (1, 2)]
    assert all(abs(d["width"] - 0.8) < 1e-6 for d in doors)
    kinds = {tuple(r["kinds"]) for r in json.loads((out / "gt_rooms.json").read_text())["rooms"]}
    assert kinds == {("bedroom",), ("living_room",)}
    record = json.loads((out / "simulation.json").read_text())
    assert record["seed"] == 3 and record["options"]["glass_share"] == 0.15


def test_the_same_seed_gives_the_same_map_another_seed_another(plans, tmp_path):
    for name, seed in (("a", 5), ("b", 5), ("c", 6)):
        assert _run("simulate", plans[0], "-o", tmp_path / name, "--seed", seed).exit_code == 0
    read = lambda n, f="map.pgm": (tmp_path / n / f).read_bytes()  # noqa: E731
    assert read("a") == read("b")
    assert read("a") != read("c")
    for f in ("gt_rooms_scan.png", "gt_doors_scan.json", "gt_rooms.json"):  # the scan's truth as well
        assert read("a", f) == read("b", f)


def test_an_up_to_date_case_is_skipped_and_other_options_run_again(plans, tmp_path):
    out = tmp_path / "case"
    assert _run("simulate", plans[0], "-o", out).exit_code == 0
    r = _run("simulate", plans[0], "-o", out)
    assert "up to date, skipped" in r.output
    r = _run("simulate", plans[0], "-o", out, "--no-drift")
    assert r.exit_code == 0 and "skipped" not in r.output
    assert json.loads((out / "simulation.json").read_text())["options"]["drift_xy"] == 0.0


def test_several_plans_get_a_folder_each_and_read_as_a_data_set(plans, tmp_path):
    out = tmp_path / "corpus"
    r = _run("simulate", *plans, "-o", out, "--jobs", 2)
    assert r.exit_code == 0, r.output
    assert "2 of 2 plans simulated" in r.output
    assert sorted(p.name for p in out.iterdir()) == ["flat", "wide"]
    r = _run("benchmark", out, "--methods", "topomap", "--variant", "both", "--out", tmp_path / "rows.json")
    assert r.exit_code == 0, r.output
    rows = json.loads((tmp_path / "rows.json").read_text())
    rows = rows["rows"] if isinstance(rows, dict) else rows
    assert sorted((row["map"], row["variant"]) for row in rows) == [
        ("flat", "plan"), ("flat", "scan"), ("wide", "plan"), ("wide", "scan")]


def test_each_plan_of_a_corpus_has_its_own_fixed_seed():
    assert case_seed(0, "a") == case_seed(0, "a")
    assert case_seed(0, "a") != case_seed(0, "b")
    assert case_seed(0, "a") != case_seed(1, "a")


def test_bad_plans_and_options_are_one_line_errors(plans, tmp_path):
    bad = tmp_path / "bad.txt"
    bad.write_text("this is not a plan\n")
    r = _run("simulate", bad, "-o", tmp_path / "o1")
    assert r.exit_code == 1
    assert "bad.txt" in r.output and len(r.output.strip().splitlines()) == 1
    assert not (tmp_path / "o1").exists() or not any((tmp_path / "o1").iterdir())
    r = _run("simulate", bad, plans[0], "-o", tmp_path / "o2")  # one bad plan: the others still run
    assert r.exit_code == 1 and (tmp_path / "o2" / "flat" / "map.yaml").is_file()
    r = _run("simulate", plans[0], "-o", tmp_path / "o3", "--option", "range_max=far")
    assert r.exit_code == 1 and "range_max" in r.output
    r = _run("simulate", plans[0], "-o", tmp_path / "o4", "--glass", "1.5")
    assert r.exit_code == 1 and "glass_share" in r.output
    with pytest.raises(ParameterError, match="bogus"):
        scan_options(extra=["bogus=1"])


def test_the_scan_has_its_own_ground_truth_the_rooms_it_shows(plans, tmp_path):
    out = tmp_path / "case"
    # the living room is a dead end with no outside door: its door closed, the robot never sees it
    r = _run("simulate", plans[0], "-o", out, "--closed-doors", 1, "--seed", 2)
    assert r.exit_code == 0, r.output
    gt = np.array(Image.open(out / "gt_rooms.png"))
    scan_gt = np.array(Image.open(out / "gt_rooms_scan.png"))
    free = load_map(out / "map.yaml").free
    rooms = {x["id"]: x for x in json.loads((out / "gt_rooms.json").read_text())["rooms"]}
    (seen,) = [k for k, x in rooms.items() if x["shown"]]
    (hidden,) = [k for k, x in rooms.items() if not x["shown"]]
    assert rooms[seen]["kinds"] == ["bedroom"] and rooms[hidden]["kinds"] == ["living_room"]
    assert np.array_equal(scan_gt, np.where(gt == seen, seen, 0))  # the shown room whole, nothing else
    assert rooms[hidden]["scan_area"] < 1.0 <= rooms[seen]["scan_area"]
    assert rooms[seen]["scan_area"] == pytest.approx((free & (gt == seen)).sum() * 0.05 ** 2)
    doors = json.loads((out / "gt_doors.json").read_text())["doors"]
    scan_doors = json.loads((out / "gt_doors_scan.json").read_text())["doors"]
    assert len(doors) == 2 and scan_doors == [d for d in doors if hidden not in d["rooms"]]
    assert [tuple(d["rooms"]) for d in scan_doors] == [(0, seen)]
