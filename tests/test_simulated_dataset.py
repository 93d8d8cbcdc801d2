"""The simulated-corpus layout of topomap.bench.datasets: one folder per case (map, plan, ground truth)."""

import json
import math
import shutil

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from topomap.bench.benchmark import run_benchmark
from topomap.cli import main
from topomap.bench.datasets import (BenchmarkNotFoundError, detect_layout, door_cells, load_dataset,
                              load_simulated, read_doors)
from topomap.errors import MapError, MapFileError, ParameterError
from topomap.io import FREE, OCCUPIED, UNKNOWN, load_map, save_map

RES = 0.05
H, W = 80, 120
ORIGIN = (-3.0, 1.5, 0.0)  # not (0, 0): a door placed with the wrong frame misses
DOOR_ROWS, DOOR_COL = (35, 47), 60  # the gap in the wall between the rooms (cols 58..61)


def _world(row, col):
    """Centre of cell (row, col) in map-frame metres (ROS convention), written out by hand."""
    return [ORIGIN[0] + (col + 0.5) * RES, ORIGIN[1] + (H - row - 0.5) * RES]


def _cells(scan):
    c = np.full((H, W), OCCUPIED, np.int8)
    c[:2, :] = c[-2:, :] = UNKNOWN  # outside the building
    c[5:75, 5:58] = FREE
    c[5:75, 62:115] = FREE
    c[DOOR_ROWS[0]:DOOR_ROWS[1], 58:62] = FREE
    if scan:  # what a robot map adds: unknown patches, a clutter speck
        c[10:14, 10:30] = UNKNOWN
        c[60, 90] = OCCUPIED
    return c


def _gt():
    g = np.zeros((H, W), np.uint16)
    g[5:75, 5:60] = 1
    g[5:75, 60:115] = 2
    g[_cells(False) == OCCUPIED] = 0
    return g


def _door(row0=DOOR_ROWS[0], row1=DOOR_ROWS[1] - 1, col=DOOR_COL, rooms=(1, 2), i=1):
    return {"id": i, "p1": _world(row0, col), "p2": _world(row1, col), "width": (row1 - row0 + 1) * RES,
            "rooms": list(rooms)}


def write_case(folder, doors=None):
    folder.mkdir(parents=True)
    save_map(_cells(True), folder / "map", resolution=RES, origin=ORIGIN)
    save_map(_cells(False), folder / "plan", resolution=RES, origin=ORIGIN)
    Image.fromarray(_gt()).save(folder / "gt_rooms.png")
    doors = [_door()] if doors is None else doors
    (folder / "gt_doors.json").write_text(json.dumps({"doors": doors}))
    (folder / "gt_rooms.json").write_text(json.dumps({"rooms": [
        {"id": 1, "kinds": ["bedroom"], "area": float((_gt() == 1).sum() * RES ** 2)},
        {"id": 2, "kinds": ["kitchen"], "area": float((_gt() == 2).sum() * RES ** 2)}]}))
    (folder / "simulation.json").write_text(json.dumps({"plan": folder.name, "seed": 0}))
    return folder


@pytest.fixture
def corpus(tmp_path):
    d = tmp_path / "corpus"
    write_case(d / "house_a")
    # the door 2 m off its doorway (in the wall of the right room's far side)
    write_case(d / "house_b", doors=[_door(col=DOOR_COL + 40)])
    return d


def test_layout_and_both_variants(corpus):
    assert detect_layout(corpus) == "simulated"
    for variant, stem in (("scan", "map"), ("plan", "plan")):
        maps = load_simulated(corpus, variant=variant)
        assert [m.name for m in maps] == ["house_a", "house_b"]
        m = maps[0]
        assert m.variant == variant and m.load_path == corpus / "house_a" / f"{stem}.yaml"
        grid = m.load()
        ref = load_map(corpus / "house_a" / f"{stem}.yaml")
        np.testing.assert_array_equal(grid.cells, ref.cells)  # the user's load
        assert grid.origin == ORIGIN and m.gt_rooms.shape == grid.shape
        assert set(np.unique(m.gt_rooms)) == {0, 1, 2}
        np.testing.assert_array_equal(m.scored, grid.free)
    assert load_dataset(corpus)[0].variant == "scan"
    assert [m.name for m in load_dataset(corpus, variant="plan", names="*_b")] == ["house_b"]
    with pytest.raises(ParameterError, match="'plan' or 'scan'"):
        load_simulated(corpus, variant="furnished")


def test_doors_in_metres_become_the_doorway_cells(corpus):
    (d,) = read_doors(corpus / "house_a" / "gt_doors.json")
    assert d["rooms"] == (1, 2)
    grid = load_map(corpus / "house_a" / "map.yaml")
    (cells,) = door_cells([d], grid)
    assert cells.tolist() == [[r, DOOR_COL] for r in range(DOOR_ROWS[0], DOOR_ROWS[1])]


def test_benchmark_rows_score_the_doors(corpus):
    rows = run_benchmark(corpus, methods="topomap,watershed", variants="both")
    assert [(r["method"], r["variant"], r["map"]) for r in rows] == [
        (m, v, c) for m in ("topomap", "watershed") for v in ("plan", "scan") for c in ("house_a", "house_b")]
    for r in rows:
        assert r["error"] == "" and r["n_true_rooms"] == 2
    top = {(r["variant"], r["map"]): r for r in rows if r["method"] == "topomap"}
    for v in ("plan", "scan"):
        a, b = top[(v, "house_a")], top[(v, "house_b")]
        assert a["n_rooms"] == 2 and a["precision"] > 0.95 and a["recall"] > 0.95
        # the true door is found where it is ...
        assert (a["door_tp"], a["door_fp"], a["door_fn"]) == (1, 0, 0)
        assert a["door_precision"] == a["door_recall"] == 1.0 and a["adjacency_f1"] == 1.0
        # ... and not where it is not: the door of house_b is listed 2 m away from the doorway
        assert (b["door_tp"], b["door_fp"], b["door_fn"]) == (0, 1, 1)
    ws = [r for r in rows if r["method"] == "watershed"]
    assert all(r["door_recall"] == 0.0 and r["n_doors"] == 0 for r in ws)


def test_doors_to_the_outside_are_not_scored(tmp_path):
    d = tmp_path / "c"
    write_case(d / "one", doors=[_door(), _door(row0=5, row1=10, col=2, rooms=(1, 0), i=2)])
    (r,) = run_benchmark(d, methods="topomap", variants="plan")
    assert (r["door_tp"], r["door_fn"]) == (1, 0)


def test_cli_variants(corpus, tmp_path):
    out = tmp_path / "r.csv"
    res = CliRunner().invoke(main, ["benchmark", str(corpus), "--methods", "topomap", "--variant", "plan",
                                    "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert "| topomap | plan | 2 |" in res.output and "| scan |" not in res.output
    res = CliRunner().invoke(main, ["benchmark", str(corpus), "--methods", "watershed"])
    assert res.exit_code == 0, res.output
    assert "| watershed | plan | 2 |" in res.output and "| watershed | scan | 2 |" in res.output
    res = CliRunner().invoke(main, ["benchmark", str(corpus), "--variant", "furnished"])
    assert res.exit_code == 1 and "variant 'furnished'" in res.output
    assert len(res.output.strip().splitlines()) == 1


def _cli_error(corpus, variant="both"):
    res = CliRunner().invoke(main, ["benchmark", str(corpus), "--methods", "watershed", "--variant", variant])
    assert res.exit_code == 1, res.output
    lines = res.output.strip().splitlines()
    assert len(lines) == 1, res.output
    return lines[0]


@pytest.mark.parametrize("text, msg", [
    ("{not json", "not valid JSON"),
    ('{"rooms": []}', "list 'doors'"),
    ('{"doors": [{"p1": [0, 1], "p2": "x"}]}', "door 0: p2"),
    ('{"doors": [{"p1": [0, NaN], "p2": [1, 1]}]}', "door 0: p1 must be finite"),
    ('{"doors": [{"p1": [0, 1], "p2": [1, 1], "rooms": ["a", 2]}]}', "rooms must be integer"),
    ('{"doors": [{"p1": [0, 1], "p2": [1, 1], "rooms": "12"}]}', "rooms must be integer"),
    ('{"doors": [{"p1": [0, 1], "p2": [1, 1], "rooms": [1.5, 2]}]}', "rooms must be integer"),
    ('[1, 2]', "list 'doors'"),
])
def test_bad_door_files(corpus, text, msg):
    bad = corpus / "house_b" / "gt_doors.json"
    bad.write_text(text)
    with pytest.raises(MapError, match=msg):
        read_doors(bad)
    line = _cli_error(corpus)
    assert str(bad) in line and msg in line


def test_missing_files(corpus):
    (corpus / "house_b" / "gt_doors.json").unlink()
    with pytest.raises(MapFileError, match="gt_doors.json: file does not exist"):
        load_simulated(corpus)
    assert str(corpus / "house_b" / "gt_doors.json") in _cli_error(corpus)
    shutil.rmtree(corpus / "house_b")
    (corpus / "house_a" / "map.yaml").unlink()
    assert len(load_simulated(corpus, variant="plan")) == 1  # the plan variant needs no scan
    line = _cli_error(corpus, "scan")
    assert str(corpus / "house_a" / "map.yaml") in line and "missing scan map" in line


def test_bad_label_image(corpus):
    bad = corpus / "house_a" / "gt_rooms.png"
    bad.write_bytes(b"not a png")
    assert str(bad) in _cli_error(corpus)
    Image.fromarray(np.zeros((5, 5), np.uint16)).save(bad)
    line = _cli_error(corpus)
    assert str(bad) in line and "differs from map" in line


def test_not_a_corpus(tmp_path):
    (tmp_path / "case").mkdir()
    (tmp_path / "case" / "map.yaml").write_text("image: map.pgm\n")
    with pytest.raises(BenchmarkNotFoundError, match="case folders"):
        detect_layout(tmp_path)


def test_ipa_variants_are_refused_on_a_corpus_and_the_other_way(corpus, tmp_path):
    with pytest.raises(ParameterError, match="variant 'unfurnished'"):
        run_benchmark(corpus, methods="watershed", variants="unfurnished")
    ipa = tmp_path / "ipa"
    ipa.mkdir()
    free = np.where(_cells(False) == FREE, 255, 0).astype(np.uint8)
    Image.fromarray(free).save(ipa / "m.png")
    Image.fromarray(free).save(ipa / "m_furnitures.png")
    Image.fromarray(free).save(ipa / "m_gt_segmentation.png")
    with pytest.raises(ParameterError, match="variant 'scan'"):
        run_benchmark(ipa, methods="watershed", variants=["scan"])
    assert math.isfinite(run_benchmark(ipa, methods="watershed", variants="both")[0]["precision"])


def test_the_section_script(corpus, tmp_path):
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
    import simulated

    out, rows = tmp_path / "s.md", tmp_path / "rows.csv"
    assert simulated.main([str(corpus), "--methods", "topomap,watershed", "--jobs", "1", "--out", str(out),
                           "--csv", str(rows)]) == 0
    text = out.read_text()
    assert "`python benchmarks/simulated.py CORPUS --jobs 1 --methods topomap,watershed`" in text
    assert str(corpus) not in text  # no machine path in the page
    # house_a's door found, house_b's listed 2 m off: pooled door P = R = 1 of 2
    # both cases are of the held-out plans (plan_split)
    assert "| topomap | plan | held-out | 2 | " in text and "| 4 / 4 | 50.0 | 50.0 |" in text
    assert "| watershed | scan | held-out | 2 | " in text and "| – | 0.0 |" in text
    assert "| dev |" not in text
    assert rows.read_text().count("\n") == 1 + 2 * 2 * 2
    again = tmp_path / "again.md"  # the section written again from the saved rows
    assert simulated.main([str(corpus), "--methods", "topomap,watershed", "--jobs", "1", "--rows", str(rows),
                           "--out", str(again)]) == 0
    assert again.read_text().split("| method |")[1] == text.split("| method |")[1]
    assert simulated.main([str(corpus), "--maps", "house_a", "--methods", "topomap", "--jobs", "1",
                           "--out", str(out)]) == 0
    assert "`CORPUS`), 1 case, commit" in out.read_text() and "--maps 'house_a'" in out.read_text()
    shutil.copytree(corpus / "house_a", corpus / "house_d")  # a case of the dev plans
    assert simulated.main([str(corpus), "--split", "dev", "--methods", "topomap", "--jobs", "1",
                           "--out", str(out)]) == 0
    text = out.read_text()
    assert "--split dev" in text and "`CORPUS`), 1 case, commit" in text
    assert "1 of the corpus's 3 (1 dev, 0 held-out)" in text
    assert "| topomap | plan | dev | 1 | " in text and "held-out" not in text.split("| --- |")[-1]
    with pytest.raises(SystemExit, match="no case of the dev plans"):
        simulated.main([str(corpus), "--split", "dev", "--maps", "house_a", "--out", str(out)])


def test_plan_split_is_a_fixed_rule_on_the_name():
    from topomap.bench.datasets import SPLITS, plan_split

    # pinned: the halves must never change between versions (tuning on dev, reporting on held-out)
    assert [plan_split(n) for n in ("a", "house_a", "house_d")] == ["dev", "held-out", "dev"]
    assert plan_split("plans/house_a.txt") == plan_split("house_a.txt") == plan_split("house_a")
    halves = [plan_split(f"plan_{i:04d}") for i in range(1000)]
    assert set(halves) == set(SPLITS) and 450 < halves.count("dev") < 550
    with pytest.raises(ParameterError, match="plan name"):
        plan_split(3)
    with pytest.raises(ParameterError, match="empty"):
        plan_split(".txt")


def test_the_scan_is_scored_on_the_rooms_it_shows(tmp_path):
    corpus = tmp_path / "c"
    case = write_case(corpus / "half")
    cells = _cells(True)
    cells[5:75, 62:115] = UNKNOWN  # room 2 never seen but a 10 x 10 cell patch (0.25 m²)
    cells[40:50, 70:80] = FREE
    save_map(cells, case / "map", resolution=RES, origin=ORIGIN)
    # a corpus without the scan's own files: derived from gt_rooms.png, gt_doors.json and the map
    (scan,) = load_simulated(corpus, variant="scan")
    (plan,) = load_simulated(corpus, variant="plan")
    assert set(np.unique(plan.gt_rooms)) == {0, 1, 2} and len(plan.gt_doors) == 1
    np.testing.assert_array_equal(scan.gt_rooms, np.where(_gt() == 1, 1, 0))  # room 1 whole, no room 2
    assert scan.gt_doors == ()  # the door into room 2 is not a door of the map's rooms
    rows = {r["variant"]: r for r in run_benchmark(corpus, methods="topomap", variants="both")}
    assert rows["plan"]["n_true_rooms"] == 2 and rows["scan"]["n_true_rooms"] == 1
    assert rows["scan"]["ceiling_precision"] == 1.0 and rows["scan"]["ceiling_recall"] > 0.9
    # the case's own files win: here they list both rooms and the door
    Image.fromarray(_gt()).save(case / "gt_rooms_scan.png")
    (case / "gt_doors_scan.json").write_text(json.dumps({"doors": [_door()]}))
    (scan,) = load_simulated(corpus, variant="scan")
    assert set(np.unique(scan.gt_rooms)) == {0, 1, 2} and len(scan.gt_doors) == 1
    assert scan.gt_path == case / "gt_rooms_scan.png"
    (case / "gt_doors_scan.json").unlink()
    with pytest.raises(MapFileError, match="gt_doors_scan.json"):
        load_simulated(corpus, variant="scan")
