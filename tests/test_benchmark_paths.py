"""The benchmark runs the user's path: the CLI's loader, the CLI's labels.

``topomap segment FILE --resolution 0.05`` (a bare image) and ``topomap
segment NAME.yaml`` give exactly the labels the benchmark scores; a labelled
data set (NAME.png + NAME.yaml + NAME_gt.png) is picked by what the folder
holds; every room a method reports is counted.
"""

from __future__ import annotations

import os

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from topomap.bench.benchmark import run_benchmark, segment_map
from topomap.cli import main
from topomap.bench.datasets import (BenchmarkNotFoundError, benchmark_dir, load_benchmark,
                              load_labelled, real_maps_dir)
from topomap.core.segmentation import METHODS, Segmentation


def _plan():
    """Two rooms with anti-aliased walls (gray fringe 120..249) and a gray outside (178)."""
    g = np.full((120, 200), 178, np.uint8)
    g[8:112, 8:192] = 0
    g[10:110, 10:95] = 255
    g[10:110, 105:190] = 255
    g[50:70, 95:105] = 255
    for k, v in ((0, 230), (1, 160)):   # fringe rings just inside the walls
        g[10 + k, 10:190][g[10 + k, 10:190] == 255] = v
        g[109 - k, 10:190][g[109 - k, 10:190] == 255] = v
    gt = g.copy()
    gt[gt < 250] = 0
    gt[50:70, 99:101] = 0
    return g, gt


@pytest.fixture(scope="module")
def plan_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp("plans")
    g, gt = _plan()
    Image.fromarray(g).save(d / "plan.png")
    Image.fromarray(g).convert("RGB").save(d / "plan_furnitures.png")
    Image.fromarray(gt).save(d / "plan_gt_segmentation.png")
    return d


def _cli_labels(path, tmp_path, method, *extra):
    out = tmp_path / f"out_{method}_{os.path.basename(path)}"  # one folder per map (no replacing of results)
    res = CliRunner().invoke(main, ["segment", str(path), "-o", str(out), "--method", method, *extra])
    assert res.exit_code == 0, res.output
    return np.asarray(Image.open(out / "labels.png")).astype(np.int64)


@pytest.mark.parametrize("method", ["topomap", "paper", "voronoi"])
def test_cli_and_benchmark_labels_are_identical(plan_dir, tmp_path, method):
    for variant in ("unfurnished", "furnished"):
        (bm,) = load_benchmark(plan_dir, variant=variant)
        grid, seg, secs = segment_map(bm, method)
        assert secs > 0 and seg.timings["load"] > 0
        np.testing.assert_array_equal(
            _cli_labels(bm.map_path, tmp_path, method, "--resolution", "0.05"), seg.labels)
        # the fringe is a wall: free cells are the white ones only
        np.testing.assert_array_equal(grid.free, np.asarray(bm.map_gray) >= 250)


@pytest.mark.skipif(benchmark_dir() is None, reason="benchmark maps not available")
@pytest.mark.parametrize("method", ["topomap", "paper"])
def test_cli_and_benchmark_labels_are_identical_on_a_real_map(tmp_path, method):
    (bm,) = load_benchmark(benchmark_dir(), variant="unfurnished", names=["office_c"])
    _, seg, _ = segment_map(bm, method)
    np.testing.assert_array_equal(
        _cli_labels(bm.map_path, tmp_path, method, "--resolution", "0.05"), seg.labels)


def _labelled(d):
    g, gt_gray = _plan()
    g = g.copy()
    g[g == 255] = 240  # free only through the YAML (gray > 230)
    labels = np.zeros(g.shape, np.uint16)
    labels[10:110, 10:99] = 1000
    labels[10:110, 101:190] = 2
    labels[gt_gray < 250] = 0
    for n in ("site_a_01", "site_a_02", "site_b_full"):
        Image.fromarray(g).save(d / f"{n}.png")
        (d / f"{n}.yaml").write_text(f"image: {n}.png\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\n"
                                     "negate: 0\noccupied_thresh: 0.41\nfree_thresh: 0.098\n")
        Image.fromarray(labels).save(d / f"{n}_gt.png")
    return d


def test_labelled_data_set(tmp_path):
    d = _labelled(tmp_path)
    rows = run_benchmark(d, methods="topomap,watershed", maps="site_a_*")
    assert [(r["method"], r["variant"], r["map"]) for r in rows] == [
        (m, "map", n) for m in ("topomap", "watershed") for n in ("site_a_01", "site_a_02")]
    for r in rows:
        assert r["error"] == "" and r["n_true_rooms"] == 2
        assert r["ceiling_recall_free"] == 1.0 and r["ceiling_precision_free"] == 1.0
        assert np.isnan(r["door_f1"])  # a label image has no door lines
    top = [r for r in rows if r["method"] == "topomap"]
    assert all(r["precision_free"] > 0.95 and r["recall_free"] > 0.95 for r in top), top
    with pytest.raises(BenchmarkNotFoundError, match="site_c"):
        run_benchmark(d, methods="topomap", maps=["site_c_*"])


def test_cli_and_benchmark_labels_are_identical_through_a_yaml(tmp_path):
    (tmp_path / "data").mkdir()
    d = _labelled(tmp_path / "data")
    (bm,) = load_labelled(d, names=["site_b_full"])
    _, seg, _ = segment_map(bm, "topomap")
    np.testing.assert_array_equal(_cli_labels(bm.load_path, tmp_path, "topomap"), seg.labels)


@pytest.mark.skipif(real_maps_dir() is None, reason="real labelled maps not available")
def test_real_labelled_map_runs():
    (r,) = run_benchmark(real_maps_dir(), methods="topomap", maps="freiburg079_partial_02")
    assert r["error"] == "" and r["variant"] == "map"
    assert r["ceiling_precision_free"] == 1.0 and r["n_true_rooms"] > 0
    assert 0 < r["precision_free"] <= 1 and 0 < r["recall_free"] <= 1


def _speck_method(grid, **params):
    """The right room, the left room, and a 3 x 3 speck reported as a room of its own."""
    labels = np.zeros(grid.shape, np.int32)
    labels[:, :100][grid.free[:, :100]] = 1
    labels[:, 100:][grid.free[:, 100:]] = 2
    labels[20:23, 20:23] = 3
    return Segmentation(grid=grid, labels=labels, doors=[], method="speck", timings={})


def test_a_speck_reported_as_a_room_is_counted(plan_dir, monkeypatch):
    monkeypatch.setitem(METHODS, "speck", _speck_method)
    (r,) = run_benchmark(plan_dir, methods="speck", variants="unfurnished")
    # the metric ignores the speck (<= 100 cells); the room count does not
    assert r["n_segments"] == 2 and r["n_true_rooms"] == 2
    assert r["n_rooms"] == 3
