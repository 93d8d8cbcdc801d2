"""Tests of topomap.io: loading, saving, classification and error messages."""

import os
import re
import struct
import zlib

import numpy as np
import pytest
from PIL import Image

from topomap import io as tio
from topomap.errors import (
    MapError,
    MapFileError,
    MapFileNotFoundError,
    MapTooLargeError,
    ParameterError,
    TopomapError,
)
from topomap.io import FREE, OCCUPIED, UNKNOWN, OccupancyGrid, from_array, load_map, save_map

GRAY3 = np.array([[0, 254, 205], [254, 0, 205]], np.uint8)
CELLS3 = np.array([[OCCUPIED, FREE, UNKNOWN], [FREE, OCCUPIED, UNKNOWN]], np.int8)


def write_pgm(path, gray):
    path.write_bytes(tio.pgm_bytes(gray))
    return path


def write_yaml(path, text):
    path.write_text(text)
    return path


def good_yaml(image="map.pgm", **over):
    meta = {"image": image, "resolution": "0.05", "origin": "[1.0, 2.0, 0.0]", "negate": "0",
            "occupied_thresh": "0.65", "free_thresh": "0.196"}
    meta.update({k: v for k, v in over.items()})
    return "".join(f"{k}: {v}\n" for k, v in meta.items() if v is not None)


def assert_one_line(excinfo, fname):
    msg = str(excinfo.value)
    assert "\n" not in msg and "\r" not in msg, msg
    assert fname in msg, msg
    return msg


@pytest.fixture
def mapdir(tmp_path):
    write_pgm(tmp_path / "map.pgm", GRAY3)
    return tmp_path


# --------------------------------------------------------------------------
# Bad files
# --------------------------------------------------------------------------

def _truncated_png(tmp):
    p = tmp / "trunc.png"
    Image.fromarray(np.full((50, 60), 254, np.uint8)).save(tmp / "full.png")
    data = (tmp / "full.png").read_bytes()
    p.write_bytes(data[: len(data) // 2])
    return p


def _zero_size_pgm(tmp):
    p = tmp / "zero.pgm"
    p.write_bytes(b"P5\n0 0\n255\n")
    return p


BAD_FILES = [
    ("missing.pgm", lambda t: t / "missing.pgm", MapFileNotFoundError, "not found"),
    ("missing.yaml", lambda t: t / "missing.yaml", MapFileNotFoundError, "not found"),
    ("adir.png", lambda t: (t / "adir.png").mkdir() or t / "adir.png", MapFileError, "directory"),
    ("empty.pgm", lambda t: (t / "empty.pgm").write_bytes(b"") and None or t / "empty.pgm",
     MapError, "empty"),
    ("empty.yaml", lambda t: (t / "empty.yaml").write_bytes(b"") and None or t / "empty.yaml",
     MapError, "empty"),
    ("text.png", lambda t: write_yaml(t / "text.png", "hello, I am text\n"), MapError, "not an image"),
    ("trunc.png", _truncated_png, MapError, "truncated|cannot decode"),
    ("zero.pgm", _zero_size_pgm, MapError, "zero size|cannot decode|not an image"),
    ("notyaml.yaml", lambda t: write_yaml(t / "notyaml.yaml", "image: [unclosed\n  - : :\n"),
     MapError, "not valid YAML"),
    ("list.yaml", lambda t: write_yaml(t / "list.yaml", "- 1\n- 2\n"), MapError, "mapping"),
    ("scalar.yml", lambda t: write_yaml(t / "scalar.yml", "just a string\n"), MapError, "mapping"),
    ("binary.yaml", lambda t: (t / "binary.yaml").write_bytes(b"\xff\xfe\x00\x81garbage")
     and None or t / "binary.yaml", MapError, "not valid YAML"),
]


@pytest.mark.parametrize("fname, make, exc, pattern", BAD_FILES, ids=[b[0] for b in BAD_FILES])
def test_bad_files(tmp_path, fname, make, exc, pattern):
    path = make(tmp_path)
    with pytest.raises(exc, match=pattern) as ei:
        load_map(path)
    assert_one_line(ei, fname)
    assert isinstance(ei.value, TopomapError)


def test_missing_is_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError):
        load_map(tmp_path / "nope.png")
    with pytest.raises(OSError):
        load_map(tmp_path / "nope.png")


BAD_YAML = [
    ("no-image", {"image": None}, MapError, "'image'"),
    ("no-resolution", {"resolution": None}, MapError, "'resolution'"),
    ("no-origin", {"origin": None}, MapError, "'origin'"),
    ("res-abc", {"resolution": "abc"}, ParameterError, "resolution must be a number.*abc"),
    ("res-zero", {"resolution": "0"}, ParameterError, "resolution must be > 0"),
    ("res-neg", {"resolution": "-0.05"}, ParameterError, "resolution must be > 0"),
    ("res-nan", {"resolution": ".nan"}, ParameterError, "resolution must be finite"),
    ("res-inf", {"resolution": ".inf"}, ParameterError, "resolution must be finite"),
    ("res-list", {"resolution": "[1, 2]"}, ParameterError, "resolution"),
    ("res-bool", {"resolution": "true"}, ParameterError, "resolution"),
    ("origin-short", {"origin": "[1]"}, ParameterError, r"origin.*\[1\]"),
    ("origin-long", {"origin": "[1, 2, 3, 4]"}, ParameterError, "origin"),
    ("origin-str", {"origin": "here"}, ParameterError, "origin"),
    ("origin-nan", {"origin": "[.nan, 0, 0]"}, ParameterError, "origin"),
    ("origin-mixed", {"origin": "[1, abc, 0]"}, ParameterError, "origin"),
    ("image-missing", {"image": "nothere.pgm"}, MapFileNotFoundError, "nothere.pgm"),
    ("image-number", {"image": "42"}, MapError, "image"),
    ("image-list", {"image": "[a, b]"}, MapError, "image"),
    ("image-dir", {"image": "."}, MapFileError, "directory"),
    ("occ-big", {"occupied_thresh": "1.5"}, ParameterError, r"occupied_thresh must be in \[0, 1\]"),
    ("free-neg", {"free_thresh": "-0.1"}, ParameterError, r"free_thresh must be in \[0, 1\]"),
    ("free-ge-occ", {"free_thresh": "0.7"}, ParameterError, "free_thresh .* must be < occupied_thresh"),
    ("thresh-str", {"occupied_thresh": "high"}, ParameterError, "occupied_thresh must be a number"),
    ("negate-2", {"negate": "2"}, ParameterError, "negate must be 0 or 1"),
    ("mode-bad", {"mode": "fancy"}, ParameterError, "mode must be one of"),
]


@pytest.mark.parametrize("case, over, exc, pattern", BAD_YAML, ids=[b[0] for b in BAD_YAML])
def test_bad_yaml(mapdir, case, over, exc, pattern):
    path = write_yaml(mapdir / f"{case}.yaml", good_yaml(**over))
    with pytest.raises(exc, match=pattern) as ei:
        load_map(path)
    assert_one_line(ei, f"{case}.yaml")


def test_yaml_image_not_an_image(mapdir):
    write_yaml(mapdir / "junk.pgm", "not a picture\n")
    path = write_yaml(mapdir / "m.yaml", good_yaml(image="junk.pgm"))
    with pytest.raises(MapError, match="not an image") as ei:
        load_map(path)
    msg = assert_one_line(ei, "m.yaml")
    assert "junk.pgm" in msg


@pytest.mark.parametrize("kwargs, pattern", [
    ({"resolution": 0}, "resolution must be > 0"),
    ({"resolution": float("nan")}, "resolution must be finite"),
    ({"resolution": "x"}, "resolution must be a number"),
    ({"origin": (1,)}, "origin"),
    ({"occupied_thresh": 0.1}, "free_thresh .* must be < occupied_thresh"),
    ({"free_thresh": 2}, r"free_thresh must be in \[0, 1\]"),
    ({"mode": 3}, "mode must be one of"),
    ({"negate": "maybe"}, "negate must be 0 or 1"),
])
def test_bad_keyword_arguments(mapdir, kwargs, pattern):
    with pytest.raises(ParameterError, match=pattern) as ei:
        load_map(mapdir / "map.pgm", **kwargs)
    assert "\n" not in str(ei.value)


def test_too_large_checked_from_header(tmp_path, monkeypatch):
    # header claims 30000 x 20000 but the data is tiny: refused before decoding
    p = tmp_path / "huge.pgm"
    p.write_bytes(b"P5\n30000 20000\n255\n" + b"\x00" * 100)
    with pytest.raises(MapTooLargeError, match="600,000,000 cells") as ei:
        load_map(p)
    assert_one_line(ei, "huge.pgm")
    p = tmp_path / "big.pgm"
    p.write_bytes(b"P5\n3000 2000\n255\n" + b"\x00" * 100)
    monkeypatch.setattr(tio, "MAX_CELLS", 1_000_000)
    with pytest.raises(MapTooLargeError, match="3000 x 2000 px = 6,000,000 cells") as ei:
        load_map(p)
    assert_one_line(ei, "big.pgm")
    monkeypatch.setattr(tio, "MAX_CELLS", 5)
    with pytest.raises(MapTooLargeError, match="MAX_CELLS") as ei:
        load_map(write_pgm(tmp_path / "six.pgm", GRAY3))
    assert_one_line(ei, "six.pgm")


def test_decompression_bomb_becomes_our_error(tmp_path, monkeypatch):
    monkeypatch.setattr(Image, "MAX_IMAGE_PIXELS", 2)
    monkeypatch.setattr(tio, "MAX_CELLS", 5)
    p = write_pgm(tmp_path / "bomb.pgm", GRAY3)
    with pytest.raises(MapTooLargeError, match="6 cells") as ei:
        load_map(p)
    assert_one_line(ei, "bomb.pgm")
    # within our limit, Pillow's stricter limit does not stop the load
    monkeypatch.setattr(tio, "MAX_CELLS", 100)
    assert load_map(p).shape == (2, 3)
    assert Image.MAX_IMAGE_PIXELS == 2
    monkeypatch.setattr(Image, "MAX_IMAGE_PIXELS", 5)  # warning zone: ignored, loads
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert load_map(p).shape == (2, 3)


def test_truncated_png_chunk(tmp_path):
    # a PNG whose IDAT is corrupt (bad zlib stream)
    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data))
    ihdr = struct.pack(">IIBBBBB", 4, 4, 8, 0, 0, 0, 0)
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", b"\x78\x9cgarbage") + chunk(b"IEND", b"")
    p = tmp_path / "corrupt.png"
    p.write_bytes(png)
    with pytest.raises(MapError) as ei:
        load_map(p)
    assert_one_line(ei, "corrupt.png")


# --------------------------------------------------------------------------
# Valid edge cases
# --------------------------------------------------------------------------

@pytest.mark.parametrize("value, state", [(254, FREE), (0, OCCUPIED), (205, UNKNOWN), (255, FREE)])
@pytest.mark.parametrize("shape", [(1, 1), (3, 5)])
def test_uniform_maps_are_valid(tmp_path, value, state, shape):
    p = write_pgm(tmp_path / "u.pgm", np.full(shape, value, np.uint8))
    g = load_map(p)
    assert g.shape == shape
    assert (g.cells == state).all()
    assert g.gray.dtype == np.uint8 and (g.gray == value).all()
    assert g.resolution == 0.05 and g.origin == (0.0, 0.0, 0.0)
    assert g.source == str(p) and g.name == str(p)


def test_trinary_thresholds_exact():
    v = np.arange(256, dtype=np.uint8).reshape(16, 16)
    cells = tio.classify_gray(v)
    p = (255 - np.arange(256)) / 255.0
    expect = np.where(p > 0.65, OCCUPIED, np.where(p < 0.196, FREE, UNKNOWN)).reshape(16, 16)
    np.testing.assert_array_equal(cells, expect)
    # map_saver's values round-trip
    assert tio.classify_gray(np.array([[254, 0, 205]], np.uint8)).tolist() == [[FREE, OCCUPIED, UNKNOWN]]


def _all_grays():
    return np.arange(256, dtype=np.uint8).reshape(16, 16)


def test_bare_image_is_read_as_a_floor_plan(tmp_path):
    """No YAML: free from gray 250 up, map_saver's 205 unknown, every other gray occupied."""
    v = _all_grays()
    write_pgm(tmp_path / "plan.pgm", v)
    g = load_map(tmp_path / "plan.pgm")
    flat = np.arange(256)
    expect = np.where(flat >= 250, FREE, np.where(flat == 205, UNKNOWN, OCCUPIED)).reshape(16, 16)
    np.testing.assert_array_equal(g.cells, expect)
    np.testing.assert_array_equal(tio.classify_plan(v), expect)
    assert tio.FREE_GRAY == 250
    # an anti-aliased wall fringe (206..249) is wall, not free as map_server's defaults say
    assert (g.cells[(v >= 206) & (v <= 249)] == OCCUPIED).all()
    assert (tio.classify_gray(v)[(v >= 206) & (v <= 249)] == FREE).all()
    # negate inverts the gray values first
    np.testing.assert_array_equal(load_map(tmp_path / "plan.pgm", negate=True).cells,
                                  tio.classify_plan(255 - v))


def test_bare_image_with_thresholds_reads_as_map_server(tmp_path):
    v = _all_grays()
    write_pgm(tmp_path / "plan.pgm", v)
    for kw in ({"free_thresh": 0.196}, {"occupied_thresh": 0.65}, {"mode": "trinary"}):
        np.testing.assert_array_equal(load_map(tmp_path / "plan.pgm", **kw).cells,
                                      tio.classify_gray(v), err_msg=str(kw))
    g = load_map(tmp_path / "plan.pgm", free_thresh=0.1, occupied_thresh=0.5)
    np.testing.assert_array_equal(g.cells, tio.classify_gray(v, free_thresh=0.1, occupied_thresh=0.5))


def test_map_saver_image_reads_the_same_with_and_without_its_yaml(mapdir):
    # GRAY3 holds map_saver's three values; good_yaml has map_server's defaults
    bare = load_map(mapdir / "map.pgm")
    yml = load_map(write_yaml(mapdir / "map.yaml", good_yaml()))
    np.testing.assert_array_equal(bare.cells, yml.cells)
    np.testing.assert_array_equal(bare.cells, CELLS3)


def test_a_yaml_keeps_map_servers_thresholds(tmp_path):
    v = _all_grays()
    write_pgm(tmp_path / "map.pgm", v)
    g = load_map(write_yaml(tmp_path / "map.yaml", good_yaml()))
    np.testing.assert_array_equal(g.cells, tio.classify_gray(v))
    g = load_map(write_yaml(tmp_path / "m2.yaml", good_yaml(free_thresh="0.098", occupied_thresh="0.41")))
    np.testing.assert_array_equal(g.cells, tio.classify_gray(v, free_thresh=0.098, occupied_thresh=0.41))
    assert (g.cells[v > 230] == FREE).all() and (g.cells[v <= 230] != FREE).all()


def test_pgm_and_png_and_yaml_agree(mapdir):
    Image.fromarray(GRAY3).save(mapdir / "map.png")
    a = load_map(mapdir / "map.pgm")
    b = load_map(mapdir / "map.png")
    c = load_map(write_yaml(mapdir / "map.yaml", good_yaml()))
    for g in (a, b, c):
        np.testing.assert_array_equal(g.cells, CELLS3)
        np.testing.assert_array_equal(g.gray, GRAY3)
    assert c.origin == (1.0, 2.0, 0.0) and c.resolution == 0.05
    assert c.source == str(mapdir / "map.yaml")


def test_image_kwargs(mapdir):
    g = load_map(mapdir / "map.pgm", resolution=0.1, origin=(1, 2))
    assert g.resolution == 0.1 and g.origin == (1.0, 2.0, 0.0)


def test_keywords_override_yaml(mapdir):
    p = write_yaml(mapdir / "map.yaml", good_yaml())
    g = load_map(p, resolution=0.2, origin=(5, 6, 0.5), negate=True)
    assert g.resolution == 0.2 and g.origin == (5.0, 6.0, 0.5)
    np.testing.assert_array_equal(g.cells[0], [FREE, OCCUPIED, OCCUPIED])
    # missing keys are fine when given as arguments
    p2 = write_yaml(mapdir / "bare.yaml", "image: map.pgm\n")
    g2 = load_map(p2, resolution=0.1, origin=(0, 0, 0))
    assert g2.resolution == 0.1


def test_yaml_with_absolute_image_path_and_subdir(tmp_path):
    (tmp_path / "sub").mkdir()
    write_pgm(tmp_path / "sub" / "m.pgm", GRAY3)
    p = write_yaml(tmp_path / "a.yaml", good_yaml(image=str(tmp_path / "sub" / "m.pgm")))
    np.testing.assert_array_equal(load_map(p).cells, CELLS3)
    p = write_yaml(tmp_path / "b.yml", good_yaml(image="sub/m.pgm"))
    np.testing.assert_array_equal(load_map(str(p)).cells, CELLS3)


def test_negate(mapdir):
    p = write_yaml(mapdir / "neg.yaml", good_yaml(negate=1))
    g = load_map(p)
    # p = v / 255: 0 -> free, 254 -> occupied, 205 -> p = 0.80 -> occupied
    np.testing.assert_array_equal(g.cells, [[FREE, OCCUPIED, OCCUPIED], [OCCUPIED, FREE, OCCUPIED]])
    np.testing.assert_array_equal(g.gray, GRAY3)


def test_mode_raw(tmp_path):
    gray = np.array([[0, 1, 50], [100, 101, 255]], np.uint8)
    write_pgm(tmp_path / "raw.pgm", gray)
    g = load_map(write_yaml(tmp_path / "raw.yaml", good_yaml(image="raw.pgm", mode="raw")))
    np.testing.assert_array_equal(g.cells, [[0, 1, 50], [100, UNKNOWN, UNKNOWN]])


def test_mode_scale_is_trinary(mapdir):
    g = load_map(write_yaml(mapdir / "s.yaml", good_yaml(mode="scale")))
    np.testing.assert_array_equal(g.cells, CELLS3)


def test_16bit_pgm(tmp_path):
    v16 = GRAY3.astype(np.uint16) * 257
    p = tmp_path / "deep.pgm"
    p.write_bytes(b"P5\n3 2\n65535\n" + v16.astype(">u2").tobytes())
    g = load_map(p)
    np.testing.assert_array_equal(g.gray, GRAY3)
    np.testing.assert_array_equal(g.cells, CELLS3)


def test_16bit_png(tmp_path):
    v16 = GRAY3.astype(np.uint16) * 257
    Image.fromarray(v16).save(tmp_path / "deep.png")
    g = load_map(tmp_path / "deep.png")
    np.testing.assert_array_equal(g.gray, GRAY3)


def test_rgba_transparency(tmp_path):
    rgba = np.zeros((2, 3, 4), np.uint8)
    rgba[..., :3] = GRAY3[..., None]
    rgba[..., 3] = 255
    rgba[0, 1, 3] = 0     # transparent free pixel -> unknown
    rgba[1, 0, 3] = 128   # half transparent: keeps its value
    Image.fromarray(rgba, "RGBA").save(tmp_path / "a.png")
    g = load_map(tmp_path / "a.png")
    expect = CELLS3.copy()
    expect[0, 1] = UNKNOWN
    np.testing.assert_array_equal(g.cells, expect)
    np.testing.assert_array_equal(g.gray, GRAY3)


@pytest.mark.parametrize("mode", ["1", "L", "LA", "RGB", "RGBA", "P", "I", "I;16", "F"])
def test_image_modes(tmp_path, mode):
    img = Image.fromarray(GRAY3).convert("RGB").convert(mode) if mode not in ("I;16",) else \
        Image.fromarray(GRAY3.astype(np.uint16) * 257)
    ext = "tiff" if mode in ("I", "F") else "png"
    path = tmp_path / f"m.{ext}"
    img.save(path)
    g = load_map(path)
    assert g.shape == (2, 3) and g.gray.dtype == np.uint8
    if mode == "1":
        np.testing.assert_array_equal(g.cells, np.where(GRAY3 > 127, FREE, OCCUPIED))
    elif mode == "I":  # 32-bit integer images are taken as 16-bit data
        assert (g.gray <= 1).all()
    elif mode == "P":
        # the web palette turns 205 into 204: no longer map_saver's unknown
        # gray, so a bare image reads it as a drawn obstacle
        np.testing.assert_array_equal(g.gray, [[0, 255, 204], [255, 0, 204]])
        np.testing.assert_array_equal(g.cells, np.where(CELLS3 == UNKNOWN, OCCUPIED, CELLS3))
    else:
        np.testing.assert_array_equal(g.cells, CELLS3)


# --------------------------------------------------------------------------
# Coordinates
# --------------------------------------------------------------------------

def test_pixel_world_round_trip_with_origin(tmp_path):
    write_pgm(tmp_path / "m.pgm", np.full((40, 60), 254, np.uint8))
    g = load_map(write_yaml(tmp_path / "m.yaml", good_yaml(image="m.pgm", origin="[-3.0, 2.0, 0.0]")))
    # lower-left pixel centre
    x, y = g.pixel_to_world(39, 0)
    assert x == pytest.approx(-3.0 + 0.025) and y == pytest.approx(2.0 + 0.025)
    # top-right pixel centre
    x, y = g.pixel_to_world(0, 59)
    assert x == pytest.approx(-3.0 + 2.975) and y == pytest.approx(2.0 + 1.975)
    rows, cols = np.mgrid[0:40, 0:60]
    r, c = g.world_to_pixel(*g.pixel_to_world(rows, cols))
    np.testing.assert_allclose(r, rows, atol=1e-9)
    np.testing.assert_allclose(c, cols, atol=1e-9)
    assert g.world_to_pixel(-3.0, 2.0) == pytest.approx((39.5, -0.5))


def test_pixel_world_round_trip_with_yaw(tmp_path):
    write_pgm(tmp_path / "m.pgm", np.full((10, 20), 254, np.uint8))
    g = load_map(write_yaml(tmp_path / "m.yaml", good_yaml(image="m.pgm", origin=f"[1.0, -2.0, {np.pi / 2!r}]")))
    # yaw 90 deg: image +col axis points to world +y
    x, y = g.pixel_to_world(9, 0)
    assert x == pytest.approx(1.0 - 0.025) and y == pytest.approx(-2.0 + 0.025)
    x2, y2 = g.pixel_to_world(9, 4)
    assert x2 == pytest.approx(x) and y2 == pytest.approx(y + 0.2)
    rows, cols = np.mgrid[0:10, 0:20]
    r, c = g.world_to_pixel(*g.pixel_to_world(rows + 0.3, cols - 0.2))
    np.testing.assert_allclose(r, rows + 0.3, atol=1e-9)
    np.testing.assert_allclose(c, cols - 0.2, atol=1e-9)


# --------------------------------------------------------------------------
# Saving
# --------------------------------------------------------------------------

def test_save_load_round_trip(tmp_path):
    g = OccupancyGrid(CELLS3, 0.1, (1.5, -2.0, 0.25))
    out = save_map(g, tmp_path / "out")
    assert out == tmp_path / "out.yaml"
    assert (tmp_path / "out.pgm").read_bytes().startswith(b"P5\n3 2\n255\n")
    h = load_map(out)
    np.testing.assert_array_equal(h.cells, g.cells)
    assert h.resolution == 0.1 and h.origin == g.origin
    np.testing.assert_array_equal(h.gray, [[0, 254, 205], [254, 0, 205]])
    assert not [p for p in os.listdir(tmp_path) if p.endswith(".tmp")]


def test_save_raw_labels_round_trip(tmp_path):
    labels = np.array([[0, 1, 2], [3, 99, 100]], np.uint8)
    out = save_map(labels, tmp_path / "labels.yaml", mode="raw", resolution=0.05)
    g = load_map(out)
    np.testing.assert_array_equal(g.cells, labels)
    np.testing.assert_array_equal(g.gray, labels)
    # raw from cells: unknown written as 255
    out = save_map(CELLS3, tmp_path / "cells", mode="raw")
    np.testing.assert_array_equal(load_map(out).cells, CELLS3)


def test_save_bool_and_overwrite(tmp_path):
    free = np.array([[True, False], [False, True]])
    out = save_map(free, tmp_path / "b", origin=(1, 1))
    out2 = save_map(free, tmp_path / "b", origin=(1, 1))
    assert out == out2
    g = load_map(out)
    np.testing.assert_array_equal(g.free, free)
    assert g.origin == (1.0, 1.0, 0.0)


def test_save_failure_leaves_nothing(tmp_path, monkeypatch):
    with pytest.raises(MapFileNotFoundError, match="does not exist") as ei:
        save_map(CELLS3, tmp_path / "nodir" / "m")
    assert "\n" not in str(ei.value)

    def boom(src, dst):
        raise PermissionError(13, "Permission denied")
    monkeypatch.setattr(os, "replace", boom)
    with pytest.raises(MapFileError, match="cannot write map") as ei:
        save_map(CELLS3, tmp_path / "m")
    assert_one_line(ei, "m")
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("bad, pattern", [
    (np.zeros((2, 2, 2), np.int8), "2-D"),
    (np.zeros((0, 3), np.int8), "empty"),
    (np.zeros((2, 2), np.float64), "dtype float64"),
])
def test_save_bad_arrays(tmp_path, bad, pattern):
    with pytest.raises(MapError, match=pattern):
        save_map(bad, tmp_path / "x")


# --------------------------------------------------------------------------
# from_array
# --------------------------------------------------------------------------

def test_from_array_uint8_gray():
    g = from_array(GRAY3)
    np.testing.assert_array_equal(g.cells, CELLS3)
    assert g.gray is not None and g.name == "<array>"
    g = from_array(GRAY3, negate=True)
    assert g.cells[0, 0] == FREE


def test_from_array_bool_and_int():
    np.testing.assert_array_equal(from_array(np.array([[True, False]])).cells, [[FREE, OCCUPIED]])
    np.testing.assert_array_equal(from_array(np.array([[0, 100, -1, 64, 65]], np.int16)).cells,
                                  [[FREE, OCCUPIED, UNKNOWN, FREE, OCCUPIED]])


@pytest.mark.parametrize("bad, pattern", [
    (np.zeros(5, np.uint8), r"ndim=1 \(shape \(5,\)\)"),
    (np.zeros((2, 2, 3), np.uint8), r"ndim=3 \(shape \(2, 2, 3\)\)"),
    (np.zeros((0, 4), np.int8), r"empty \(shape \(0, 4\)\)"),
    (np.zeros((2, 2), np.float32), "dtype float32"),
    (np.zeros((2, 2), np.uint16), "dtype uint16"),
    (np.array([["a", "b"]]), "dtype <U1"),
    ([[1, 2], [3]], "cannot convert list"),
])
def test_from_array_errors(bad, pattern):
    with pytest.raises(MapError, match=pattern) as ei:
        from_array(bad, source="mine.npy")
    assert_one_line(ei, "mine.npy")


@pytest.mark.parametrize("kwargs, pattern", [
    ({"resolution": -1}, "resolution must be > 0"),
    ({"resolution": "abc"}, "resolution must be a number"),
    ({"origin": (1,)}, "origin"),
    ({"origin": ("a", 2)}, "origin"),
    ({"origin": (float("nan"), 0)}, "origin must be finite"),
])
def test_from_array_bad_params(kwargs, pattern):
    with pytest.raises(ParameterError, match=pattern):
        from_array(GRAY3, **kwargs)


def test_messages_name_the_file_in_one_line_even_with_weird_exceptions(tmp_path):
    # Pillow's own messages may span lines; ours never do
    p = tmp_path / "x.pgm"
    p.write_bytes(b"P5\n3 2\n255\n\x00")  # too little pixel data
    with pytest.raises(MapError) as ei:
        load_map(p)
    msg = assert_one_line(ei, "x.pgm")
    assert re.match(re.escape(str(p)) + ": ", msg)


# --------------------------------------------------------------------------
# Hostile graph files, outputs and temporaries
# --------------------------------------------------------------------------

def _saved_graph(tmp_path, name="g.json"):
    import _testdata as T
    from topomap.io.export import save_graph
    from topomap.planning import travel_graph
    from topomap.core.segmentation import segment

    G = travel_graph(segment(from_array(T.two_rooms().array, resolution=T.RES)))
    return save_graph(G, tmp_path / name), G


def _edit_json(path, edit):
    import json

    d = json.loads(path.read_text())
    edit(d)
    path.write_text(json.dumps(d))
    return path


@pytest.mark.parametrize("fmt", ["json", "graphml", "geojson"])
def test_graph_claiming_a_huge_map_refused_before_planning(tmp_path, fmt):
    from topomap.errors import MapTooLargeError
    from topomap.io.export import load_graph, save_graph

    _, G = _saved_graph(tmp_path)
    G.graph["shape"] = (1_000_000, 1_000_000)
    p = save_graph(G, tmp_path / f"big.{fmt}")
    with pytest.raises(MapTooLargeError, match=r"claims a map of 1,000,000 x 1,000,000 cells .*MAX_CELLS") as ei:
        load_graph(p)
    assert str(p) in str(ei.value)


def test_deeply_nested_json_graph_is_a_format_error(tmp_path):
    from topomap.errors import GraphFormatError
    from topomap.io.export import load_graph

    p = tmp_path / "deep.json"
    p.write_text("[" * 200_000 + "]" * 200_000)
    with pytest.raises(GraphFormatError, match="nested too deeply") as ei:
        load_graph(p)
    assert str(p) in str(ei.value)


def test_graphml_with_entities_refused(tmp_path):
    from topomap.errors import GraphFormatError
    from topomap.io.export import load_graph

    p = tmp_path / "lol.graphml"
    p.write_text('<?xml version="1.0"?><!DOCTYPE g [<!ENTITY a "lol"><!ENTITY b "&a;&a;&a;">]>'
                 '<graphml xmlns="http://graphml.graphdrawing.org/xmlns"><graph edgedefault="undirected">'
                 '<node id="&b;"/></graph></graphml>')
    with pytest.raises(GraphFormatError, match="DOCTYPE or entity"):
        load_graph(p)


@pytest.mark.parametrize("lead", [70_000, 2_000_000])
def test_graphml_entity_behind_a_long_comment_refused(tmp_path, lead):
    """A DOCTYPE is refused wherever it stands, not only in the first 64 KB: behind a long
    comment an internal entity would otherwise reach the room names."""
    from topomap.errors import GraphFormatError
    from topomap.io.export import load_graph

    p = tmp_path / "late.graphml"
    p.write_text('<?xml version="1.0"?><!--' + "x" * lead + '--><!DOCTYPE g [<!ENTITY a "INJECTED">]>'
                 '<graphml xmlns="http://graphml.graphdrawing.org/xmlns"><graph edgedefault="undirected">'
                 '<node id="&a;"/></graph></graphml>')
    with pytest.raises(GraphFormatError, match="DOCTYPE or entity") as ei:
        load_graph(p)
    assert str(p) in str(ei.value) and len(str(ei.value).splitlines()) == 1


def test_graphml_without_namespace_still_reads(tmp_path):
    from topomap.io.export import load_graph

    p = tmp_path / "bare.graphml"
    p.write_text('<?xml version="1.0"?><graphml><graph edgedefault="undirected">'
                 '<node id="1"/><node id="2"/><edge source="1" target="2"/></graph></graphml>')
    G = load_graph(p)
    assert sorted(G.nodes) == [1, 2] and G.number_of_edges() == 1


@pytest.mark.parametrize("bad", [[1, 2], {"type": "FeatureCollection", "features": [[1]]},
                                 {"type": "FeatureCollection", "features": [{"properties": {"kind": "room"}}]}])
def test_odd_geojson_is_a_format_error(tmp_path, bad):
    import json

    from topomap.errors import GraphFormatError
    from topomap.io.export import load_graph

    p = tmp_path / "odd.geojson"
    p.write_text(json.dumps(bad))
    with pytest.raises(GraphFormatError) as ei:
        load_graph(p)
    assert str(p) in str(ei.value)


def test_door_without_p1_is_a_planning_error_naming_the_door(tmp_path):
    from topomap.errors import PlanningError
    from topomap.io.export import load_graph
    from topomap.planning import plan_path

    p, G = _saved_graph(tmp_path)
    _edit_json(p, lambda d: [e.pop("p1") for e in d["edges"]])
    H = load_graph(p)
    with pytest.raises(PlanningError, match=r"door \d+-\d+ lacks the attribute 'p1'"):
        plan_path(H, (0.3, 0.3), (1.0, 1.0))


def test_nan_written_as_null_and_read_back(tmp_path):
    import json
    import math

    from topomap.io.export import load_graph, save_graph

    _, G = _saved_graph(tmp_path)
    u, v, k = next(iter(G.edges(keys=True)))
    G.edges[u, v, k]["width"] = float("nan")
    G.graph["threshold"] = float("inf")
    p = save_graph(G, tmp_path / "nan.geojson")
    json.loads(p.read_text(), parse_constant=lambda c: pytest.fail(f"bare {c} in the file"))
    H = load_graph(p)
    assert math.isnan(H.edges[u, v, k]["width"]) and H.graph["threshold"] is None


def test_atomic_write_names_the_file_not_the_temporary(tmp_path):
    from topomap.errors import MapFileError
    from topomap.io import atomic_write

    target = tmp_path / "labels.png"
    with pytest.raises(ValueError) as ei:
        with atomic_write(target, None) as tmp:
            raise ValueError(f"{tmp}: 70000 rooms do not fit a 16-bit PNG")
    assert str(ei.value) == f"{target}: 70000 rooms do not fit a 16-bit PNG"
    with pytest.raises(MapFileError, match=r"labels.png: cannot write: No space left on device") as ei:
        with atomic_write(target) as fh:
            raise OSError(28, "No space left on device", fh.name)
    assert ".tmp" not in str(ei.value)
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "afile").write_text("x")
    with pytest.raises(MapFileError, match="cannot create the output folder"):
        with atomic_write(tmp_path / "afile" / "x.json", "w") as fh:
            fh.write("{}")


def test_stale_temporaries_of_killed_runs_removed(tmp_path):
    import os
    import subprocess
    import sys

    from topomap.io import atomic_write

    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True,
                          text=True).stdout.strip()
    stale = tmp_path / f".labels.png.topomap-p{dead}.k2j3h4g5.tmp"
    live = tmp_path / f".rooms.json.topomap-p{os.getppid()}.a1b2c3d4.tmp"  # a running process (our parent)
    # the user's own files, whatever their names look like, old ones too
    users = [tmp_path / n for n in (".notes.tmp", ".notes.txt.download.tmp", f".draft.p{dead}.autosave.tmp",
                                    ".overlay.png.zz9x8c7v.tmp")]
    for f in (stale, live, *users):
        f.write_text("x")
        os.utime(f, (0, 0))  # old
    with atomic_write(tmp_path / "out.txt", "w") as fh:
        fh.write("ok")
    assert sorted(f.name for f in tmp_path.iterdir()) == sorted([live.name, *(f.name for f in users), "out.txt"])


def test_cli_refuses_empty_or_file_output(tmp_path):
    from click.testing import CliRunner

    import _testdata as T
    from topomap.cli import main

    m = tmp_path / "m.png"
    Image.fromarray(T.gray(T.two_rooms().array)).save(m)
    r = CliRunner().invoke(main, ["segment", str(m), "-o", ""])
    assert r.exit_code == 1 and "-o/--out must name an output folder" in r.stderr
    r = CliRunner().invoke(main, ["segment", str(m), "-o", str(m)])
    assert r.exit_code == 1 and f"-o {m}: exists and is not a folder" in r.stderr
    r = CliRunner().invoke(main, ["segment", str(m), "-o", str(tmp_path / "o"), "--resolution", "1e-9"])
    assert r.exit_code == 1 and "--resolution must be between 0.001 and 10" in r.stderr
    assert not (tmp_path / "o").exists()


def test_cli_plan_names_the_graph_file(tmp_path):
    from click.testing import CliRunner

    from topomap.cli import main

    p, _ = _saved_graph(tmp_path)
    _edit_json(p, lambda d: [d["graph"].pop(k) for k in ("shape", "resolution", "origin")])
    r = CliRunner().invoke(main, ["plan", str(p), "--from", "0.3", "0.3", "--to", "1", "1"])
    assert r.exit_code == 1, r.output
    line, = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert line.startswith(f"error: {p}: ") and "lacks the map frame" in line


def test_map_name_not_utf8_segments_in_a_batch(tmp_path):
    """A file name with a byte that is not UTF-8 (str with a surrogate escape): outputs, summary.csv, messages."""
    import sys

    from click.testing import CliRunner

    import _testdata as T
    from topomap.cli import main

    if sys.getfilesystemencoding().lower() != "utf-8":
        pytest.skip("needs a UTF-8 file system encoding")
    odd = tmp_path / os.fsdecode(b"caf\xe9.png")
    try:
        Image.fromarray(T.gray(T.two_rooms().array)).save(odd, format="PNG")
    except (OSError, UnicodeError):
        pytest.skip("the file system refuses a name that is not UTF-8")
    other = tmp_path / "b.png"
    Image.fromarray(T.gray(T.two_rooms().array)).save(other)
    r = CliRunner().invoke(main, ["segment", str(odd), str(other), "-o", str(tmp_path / "o")])
    assert r.exit_code == 0, r.output
    assert b"caf\xe9" in (tmp_path / "o" / "summary.csv").read_bytes()
