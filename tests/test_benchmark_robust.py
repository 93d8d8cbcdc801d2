"""``topomap benchmark`` on hostile data sets: a decompression bomb, a YAML that does not fit its truth."""

import struct
import zlib

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from topomap.bench.benchmark import run_benchmark
from topomap.cli import main
from topomap.io.export import read_gray, read_label_image
from topomap.errors import MapTooLargeError

from test_benchmark_paths import _labelled


def _bomb(path, side=100_000):
    """A PNG of a few hundred bytes whose header claims ``side`` x ``side`` pixels (1-bit gray)."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    raw = zlib.compress(b"\x00" * (1 + side // 8) * 4)  # a few rows; the decoder never gets there
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", side, side, 1, 0, 0, 0, 0))
                     + chunk(b"IDAT", raw) + chunk(b"IEND", b""))
    return path


def _one_line_error(args):
    res = CliRunner().invoke(main, ["benchmark"] + [str(a) for a in args])
    assert res.exit_code == 1, res.output  # an input error, not 3 (internal error)
    lines = res.output.strip().splitlines()
    assert len(lines) == 1, res.output
    return lines[0]


def test_readers_refuse_a_bomb(tmp_path):
    bomb = _bomb(tmp_path / "b.png")
    for read in (read_gray, read_label_image):
        with pytest.raises(MapTooLargeError, match="b.png"):
            read(bomb)


@pytest.mark.parametrize("victim", ["site_a_02_gt.png", "site_a_02.png"])
def test_bomb_in_a_labelled_data_set(tmp_path, victim):
    d = _labelled(tmp_path)
    _bomb(d / victim)
    line = _one_line_error([d, "--methods", "watershed"])
    assert line.startswith("error: ") and str(d / victim) in line


def test_bomb_in_an_ipa_data_set(tmp_path):
    free = np.zeros((40, 60), np.uint8)
    free[5:35, 5:55] = 255
    for suffix in (".png", "_furnitures.png", "_gt_segmentation.png"):
        Image.fromarray(free).save(tmp_path / f"m{suffix}")
    _bomb(tmp_path / "m_furnitures.png")
    assert str(tmp_path / "m_furnitures.png") in _one_line_error([tmp_path, "--variant", "furnished"])
    res = CliRunner().invoke(main, ["benchmark", str(tmp_path), "--methods", "watershed",
                                    "--variant", "unfurnished"])
    assert res.exit_code == 0, res.output  # the other variant does not read it


def test_a_bomb_named_by_a_yaml_is_an_error_row(tmp_path):
    d = _labelled(tmp_path)
    _bomb(d / "huge.png")
    y = d / "site_a_02.yaml"
    y.write_text(y.read_text().replace("site_a_02.png", "huge.png"))
    rows = run_benchmark(d, methods="watershed")
    bad = {r["map"]: r["error"] for r in rows}
    assert bad["site_a_01"] == bad["site_b_full"] == ""
    assert "MapTooLargeError" in bad["site_a_02"] and "huge.png" in bad["site_a_02"]


@pytest.mark.parametrize("jobs", [1, 2])
def test_a_yaml_naming_another_image_keeps_the_good_rows(tmp_path, jobs):
    d = _labelled(tmp_path)
    Image.fromarray(np.full((50, 60), 254, np.uint8)).save(d / "other.png")
    y = d / "site_a_02.yaml"
    y.write_text(y.read_text().replace("site_a_02.png", "other.png"))
    rows = run_benchmark(d, methods="watershed", jobs=jobs)
    by = {r["map"]: r for r in rows}
    assert sorted(by) == ["site_a_01", "site_a_02", "site_b_full"]
    for good in ("site_a_01", "site_b_full"):
        assert by[good]["error"] == "" and by[good]["precision"] > 0.9
    err = by["site_a_02"]["error"]
    assert str(y) in err and "60 x 50 cells" in err and "site_a_02_gt.png" in err
    res = CliRunner().invoke(main, ["benchmark", str(d), "--methods", "watershed"])
    assert res.exit_code == 1
    assert "| watershed | map | 2 |" in res.output  # the two good maps scored
    assert "1 of 3 runs failed" in res.output


def test_a_broken_yaml_keeps_the_good_rows(tmp_path):
    d = _labelled(tmp_path)
    (d / "site_b_full.yaml").write_text("image: [unclosed\n")
    rows = run_benchmark(d, methods="watershed")
    assert [r["map"] for r in rows if not r["error"]] == ["site_a_01", "site_a_02"]
    (r,) = [r for r in rows if r["error"]]
    assert r["map"] == "site_b_full" and "site_b_full.yaml" in r["error"] and "YAML" in r["error"]
