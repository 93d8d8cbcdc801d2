"""Tests of topomap.bench.datasets: synthetic files in a tmp dir, and the real
benchmark when its directory is present (skipped otherwise; the data set is
never part of the repository)."""

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from topomap.bench.datasets import (
    FREE_GRAY,
    LABELLED_VARIANT,
    VARIANTS,
    BenchmarkMap,
    BenchmarkNotFoundError,
    LabeledMap,
    benchmark_dir,
    detect_layout,
    load_benchmark,
    load_dataset,
    load_labelled,
    select_names,
    load_pairs,
    read_gray,
    read_label_image,
)
from topomap.errors import MapError, MapFileError, ParameterError
from topomap.bench.evaluation import gt_doors_from_images, gt_rooms_from_image, score_segmentation

BENCH = benchmark_dir()
needs_benchmark = pytest.mark.skipif(BENCH is None, reason="benchmark maps not available")


# --------------------------------------------------------------------------
# synthetic benchmark directory
# --------------------------------------------------------------------------

def _drawing(h=30, w=62):
    m = np.full((h, w), 255, np.uint8)
    m[[0, -1], :] = 0
    m[:, [0, -1]] = 0
    m[:, 30:32] = 0
    m[10:18, 30:32] = 255
    g = m.copy()
    g[10:18, 30:32] = 0
    return m, g


def _save(arr, path, mode):
    """Save a gray uint8 array as an image of the given Pillow mode."""
    img = Image.fromarray(arr, "L")
    if mode != "L":
        img = img.convert(mode)
    img.save(path)


@pytest.fixture
def bench_dir(tmp_path):
    m, g = _drawing()
    f = m.copy()
    f[5:8, 5:8] = 0  # a piece of furniture
    # different modes, as in the real data set
    _save(m, tmp_path / "b_map.png", "LA")
    _save(g, tmp_path / "b_map_gt_segmentation.png", "RGB")
    _save(f, tmp_path / "b_map_furnitures.png", "RGBA")
    _save(m, tmp_path / "a_map.png", "P")
    _save(g, tmp_path / "a_map_gt_segmentation.png", "L")
    _save(f, tmp_path / "a_map_furnitures.png", "L")
    (tmp_path / "raw.pgm").write_bytes(b"P5\n1 1\n255\n\x00")  # ignored
    return tmp_path


@pytest.mark.parametrize("variant", ["unfurnished", "furnished"])
def test_load_benchmark_synthetic(bench_dir, variant):
    maps = load_benchmark(bench_dir, variant=variant)
    assert [m.name for m in maps] == ["a_map", "b_map"]
    m, g = _drawing()
    for bm in maps:
        assert isinstance(bm, BenchmarkMap)
        assert bm.variant == variant
        assert bm.map_gray.dtype == np.uint8 and bm.map_gray.shape == (30, 62)
        np.testing.assert_array_equal(bm.gt_gray, g)
        np.testing.assert_array_equal(bm.unfurnished_gray, m)
        assert bm.gt_path.name == bm.name + "_gt_segmentation.png"
        assert bm.resolution == 0.05
        if variant == "furnished":
            assert bm.map_path.name == bm.name + "_furnitures.png"
            assert not bm.scored[6, 6]
        else:
            assert bm.map_path.name == bm.name + ".png"
            assert bm.scored[6, 6]
        assert gt_rooms_from_image(bm.gt_gray).max() == 2
        assert len(gt_doors_from_images(bm.unfurnished_gray, bm.gt_gray)) == 1


def test_load_benchmark_names_filter(bench_dir):
    assert [m.name for m in load_benchmark(bench_dir, names=["b_map"])] == ["b_map"]
    assert [m.name for m in load_benchmark(bench_dir, names="?_map")] == ["a_map", "b_map"]
    assert [m.name for m in load_benchmark(bench_dir, names="b_*,a_map")] == ["a_map", "b_map"]
    # a pattern that matches nothing is an error that names it
    with pytest.raises(BenchmarkNotFoundError, match="no map matches 'nope'"):
        load_benchmark(bench_dir, names=["b_map", "nope"])


def test_select_names():
    names = ["freiburg_full", "freiburg_partial_02", "freiburg_partial_10", "bremen_full"]
    assert select_names(names, None) == sorted(names)
    assert select_names(names, "freiburg_partial_*") == ["freiburg_partial_02", "freiburg_partial_10"]
    assert select_names(names, ["*_full", "bremen_full"]) == ["bremen_full", "freiburg_full"]
    with pytest.raises(BenchmarkNotFoundError):
        select_names(names, " , ")


def _labelled_dir(tmp_path, names=("m1", "m2")):
    """Labelled layout: NAME.png (map_server gray), NAME.yaml (ROSE² thresholds), NAME_gt.png (16-bit)."""
    m, _ = _drawing()
    m = m.copy()
    m[m == 255] = 240           # free only by the YAML's free_thresh 0.098 (gray > 230)
    m[2:4, 2:10] = 205          # unknown
    gt = np.zeros(m.shape, np.uint16)
    gt[1:29, 1:30] = 300        # 16-bit label values
    gt[1:29, 32:61] = 7
    gt[1:29, 30:32] = 0
    for n in names:
        Image.fromarray(m).save(tmp_path / f"{n}.png")
        (tmp_path / f"{n}.yaml").write_text(
            f"image: {n}.png\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n"
            "occupied_thresh: 0.41\nfree_thresh: 0.098\n")
        Image.fromarray(gt).save(tmp_path / f"{n}_gt.png")
    return tmp_path, m, gt


def test_labelled_layout(tmp_path):
    d, m, gt = _labelled_dir(tmp_path)
    (tmp_path / "lonely_gt.png").write_bytes(b"")  # no map, no YAML: not a map
    assert detect_layout(d) == "labelled"
    maps = load_labelled(d)
    assert [bm.name for bm in maps] == ["m1", "m2"]
    bm = maps[0]
    assert bm.variant == LABELLED_VARIANT == "map" and bm.gt_gray is None
    assert bm.load_path == d / "m1.yaml" and bm.load_kwargs == {}
    assert bm.command == "topomap segment m1.yaml"
    np.testing.assert_array_equal(bm.gt_rooms, gt.astype(np.int32))
    # scored on the free cells of the map as read through its YAML (gray > 230)
    np.testing.assert_array_equal(bm.scored, m > 230)
    assert [b.name for b in load_dataset(d, names="*2")] == ["m2"]
    s = score_segmentation(bm.gt_rooms, bm.gt_rooms, scored=bm.scored, protocol="free-cells")
    assert s["precision"] == s["recall"] == 1.0 and s["n_rooms"] == 2


def test_detect_layout(bench_dir):
    assert detect_layout(bench_dir) == "ipa"
    assert [b.variant for b in load_dataset(bench_dir, variant="furnished")] == ["furnished"] * 2
    other = bench_dir / "other"
    other.mkdir()
    (other / "x.png").write_bytes(b"")
    with pytest.raises(BenchmarkNotFoundError, match="no benchmark maps"):
        detect_layout(other)
    with pytest.raises(BenchmarkNotFoundError, match="does not exist"):
        detect_layout(other / "none")
    with pytest.raises(BenchmarkNotFoundError):
        load_labelled(other)


def test_labelled_size_mismatch(tmp_path):
    d, _, _ = _labelled_dir(tmp_path, names=("m1",))
    Image.fromarray(np.zeros((5, 5), np.uint16)).save(d / "m1_gt.png")
    with pytest.raises(MapError, match="m1_gt.png"):
        load_labelled(d)


def test_constants_have_one_home():
    import topomap.bench.benchmark as B
    import topomap.bench.evaluation as E
    import topomap.io as IO

    assert IO.FREE_GRAY == FREE_GRAY == E.FREE_GRAY == 250
    assert B.VARIANTS is VARIANTS == ("unfurnished", "furnished")


def test_load_benchmark_missing_directory(tmp_path):
    missing = tmp_path / "nowhere"
    with pytest.raises(FileNotFoundError, match="nowhere"):
        load_benchmark(missing)
    with pytest.raises(MapFileError):
        load_benchmark(missing)


def test_load_benchmark_empty_directory(tmp_path):
    (tmp_path / "x.png").write_bytes(b"")
    with pytest.raises(BenchmarkNotFoundError) as info:
        load_benchmark(tmp_path)
    assert str(tmp_path) in str(info.value)
    assert isinstance(info.value, OSError)


def test_load_benchmark_missing_map_file(bench_dir):
    (bench_dir / "a_map_furnitures.png").unlink()
    assert len(load_benchmark(bench_dir)) == 2          # unfurnished still fine
    with pytest.raises(MapFileError, match="a_map_furnitures.png"):
        load_benchmark(bench_dir, variant="furnished")


def test_load_benchmark_shape_mismatch(bench_dir):
    _save(np.zeros((5, 5), np.uint8), bench_dir / "a_map.png", "L")
    with pytest.raises(MapError, match="shape"):
        load_benchmark(bench_dir)


def test_load_benchmark_bad_variant(bench_dir):
    with pytest.raises(ParameterError, match="variant"):
        load_benchmark(bench_dir, variant="cluttered")


@pytest.mark.parametrize("mode", ["L", "LA", "RGB", "RGBA", "P"])
def test_read_gray_modes(tmp_path, mode):
    arr = np.array([[0, 205, 255], [250, 100, 255]], np.uint8)
    _save(arr, tmp_path / "x.png", mode)
    np.testing.assert_array_equal(read_gray(tmp_path / "x.png"), arr)


def test_read_gray_missing_and_garbage(tmp_path):
    with pytest.raises(MapFileError):
        read_gray(tmp_path / "missing.png")
    with pytest.raises(MapFileError):
        read_gray(tmp_path)
    (tmp_path / "bad.png").write_bytes(b"not an image")
    with pytest.raises(MapError):
        read_gray(tmp_path / "bad.png")


# --------------------------------------------------------------------------
# label-image pairs
# --------------------------------------------------------------------------

def _labels():
    lab = np.zeros((30, 62), np.int32)
    lab[1:29, 1:30] = 1
    lab[1:29, 32:61] = 300  # needs 16 bits
    return lab


def test_load_pairs_16bit(tmp_path):
    m, _ = _drawing()
    _save(m, tmp_path / "map.png", "L")
    Image.fromarray(_labels().astype(np.uint16)).save(tmp_path / "labels.png")
    (lm,) = load_pairs([(tmp_path / "map.png", str(tmp_path / "labels.png"))])
    assert isinstance(lm, LabeledMap) and lm.name == "map"
    assert lm.labels.dtype == np.int32
    np.testing.assert_array_equal(lm.labels, _labels())
    np.testing.assert_array_equal(lm.map_gray, m)


def test_load_pairs_8bit_scores_perfectly(tmp_path):
    m, _ = _drawing()
    lab = np.where(_labels() == 300, 2, _labels()).astype(np.uint8)
    _save(m, tmp_path / "map.png", "L")
    Image.fromarray(lab, "L").save(tmp_path / "labels.png")
    (lm,) = load_pairs([(tmp_path / "map.png", tmp_path / "labels.png")])
    np.testing.assert_array_equal(lm.labels, lab)
    s = score_segmentation(lm.labels, lab, scored=lm.map_gray >= 250)
    assert s["precision"] == s["recall"] == 1.0


def test_read_label_image_rgb(tmp_path):
    rgb = np.zeros((4, 4, 3), np.uint8)
    rgb[:2] = (255, 0, 0)
    rgb[2:, 2:] = (0, 0, 255)
    Image.fromarray(rgb, "RGB").save(tmp_path / "c.png")
    lab = read_label_image(tmp_path / "c.png")
    # black -> 0; blue (0x0000ff) < red (0xff0000) -> 1, 2
    np.testing.assert_array_equal(lab, [[2, 2, 2, 2], [2, 2, 2, 2], [0, 0, 1, 1], [0, 0, 1, 1]])


def test_load_pairs_errors(tmp_path):
    m, _ = _drawing()
    _save(m, tmp_path / "map.png", "L")
    Image.fromarray(np.zeros((3, 3), np.uint8)).save(tmp_path / "small.png")
    with pytest.raises(MapError, match="shape"):
        load_pairs([(tmp_path / "map.png", tmp_path / "small.png")])
    with pytest.raises(MapFileError):
        load_pairs([(tmp_path / "map.png", tmp_path / "missing.png")])
    with pytest.raises(ParameterError):
        load_pairs([tmp_path / "map.png"])


# --------------------------------------------------------------------------
# benchmark_dir
# --------------------------------------------------------------------------

def test_benchmark_dir_env(tmp_path, monkeypatch):
    monkeypatch.setenv("TOPOMAP_BENCHMARK_DIR", str(tmp_path))
    assert benchmark_dir() == tmp_path
    # a non-existent env dir falls back to the repo-relative location or None
    monkeypatch.setenv("TOPOMAP_BENCHMARK_DIR", str(tmp_path / "nope"))
    d = benchmark_dir()
    assert d is None or (d.is_dir() and d.name == "ipa_room_segmentation")


# --------------------------------------------------------------------------
# the real benchmark (skipped without it)
# --------------------------------------------------------------------------

REAL_NAMES = [
    "Freiburg101_scan", "Freiburg52_scan", "lab_a_scan", "lab_b_scan", "lab_d_scan",
    "lab_f_scan", "lab_ipa", "office_a", "office_b", "office_c", "office_e", "office_f",
    "office_g", "office_i",
]


@needs_benchmark
@pytest.mark.parametrize("variant", ["unfurnished", "furnished"])
def test_real_benchmark_loads(variant):
    maps = load_benchmark(BENCH, variant=variant)
    assert len(maps) == 14
    assert [m.name for m in maps] == sorted(REAL_NAMES)
    for m in maps:
        assert m.map_gray.shape == m.gt_gray.shape
        assert m.map_gray.dtype == np.uint8
        assert Path(m.map_path).exists()


@needs_benchmark
def test_real_benchmark_gt_sanity():
    maps = load_benchmark(BENCH, names=["Freiburg52_scan", "office_f"])
    for m in maps:
        rooms = gt_rooms_from_image(m.gt_gray)
        doors = gt_doors_from_images(m.unfurnished_gray, m.gt_gray)
        # each map has a handful to a few dozen rooms and doors
        assert 5 <= rooms.max() <= 80
        assert 5 <= len(doors) <= 80
        s = score_segmentation(rooms, rooms, scored=m.scored)
        assert s["precision"] == s["recall"] == 1.0
