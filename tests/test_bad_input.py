"""Bad and extreme input through the library: load_map/from_array + segment.

Every case gives either a valid result (checked: every free cell in exactly
one room, room graph built) or a TopomapError whose message is ONE line that
names the file and what is wrong. The same cases run through the CLI in
tests/test_cli.py (``CASES`` is shared). The list with the outcome of each
case is in docs/errors.md.
"""

import struct
import zlib

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from PIL import Image

import _testdata as T
from topomap import io as tio
from topomap.errors import (
    MapError,
    MapFileError,
    MapFileNotFoundError,
    MapTooLargeError,
    ParameterError,
    TopomapError,
)
from topomap.io import from_array, load_map
from topomap.core.segmentation import METHODS, Segmentation, segment


# --------------------------------------------------------------------------
# Builders: each writes its input into a directory and returns the path
# --------------------------------------------------------------------------

def _chunk(tag, data):
    return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data))


def forged_png(width, height):
    """A tiny PNG whose IHDR claims ``width`` x ``height`` (8-bit gray), with a 1-row IDAT."""
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    idat = zlib.compress(b"\x00" + b"\xfe" * min(width, 16))
    return b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", ihdr) + _chunk(b"IDAT", idat) + _chunk(b"IEND", b"")


def png(d, name, a, mode=None):
    p = d / name
    Image.fromarray(a, mode).save(p) if mode else Image.fromarray(a).save(p)
    return p


def pgm(d, name, a):
    p = d / name
    p.write_bytes(tio.pgm_bytes(a))
    return p


def text(d, name, s):
    p = d / name
    p.write_text(s)
    return p


def yaml_for(d, name, image="map.pgm", **over):
    """A map_server YAML next to a valid two-room map.pgm, with keys overridden (None = dropped)."""
    pgm(d, "map.pgm", T.gray(T.two_rooms().array))
    meta = {"image": image, "resolution": "0.05", "origin": "[0.0, 0.0, 0.0]", "negate": "0",
            "occupied_thresh": "0.65", "free_thresh": "0.196"}
    meta.update(over)
    return text(d, name, "".join(f"{k}: {v}\n" for k, v in meta.items() if v is not None))


def truncated_png(d, name):
    full = png(d, "full.png", T.gray(T.two_rooms().array))
    data = full.read_bytes()
    p = d / name
    p.write_bytes(data[: len(data) // 2])
    return p


def pgm16(d, name):
    """16-bit binary PGM (maxval 65535) of the two-room map."""
    a = T.gray(T.two_rooms().array).astype(">u2") * 257
    p = d / name
    p.write_bytes(b"P5\n%d %d\n65535\n" % (a.shape[1], a.shape[0]) + a.tobytes())
    return p


def rgba_transparent(d, name):
    """The two-room map as RGBA; the west room is fully transparent (alpha 0)."""
    g = T.gray(T.two_rooms().array)
    alpha = np.full(g.shape, 255, np.uint8)
    alpha[:, :67] = 0
    return png(d, name, np.dstack([g, g, g, alpha]), "RGBA")


def negated(d, name):
    """The two-room map drawn white-on-black (free 0, walls 254) with ``negate: 1``."""
    pgm(d, "neg.pgm", 254 - T.gray(T.two_rooms().array))
    return text(d, name, "image: neg.pgm\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 1\n"
                "occupied_thresh: 0.65\nfree_thresh: 0.196\n")


def mkdir(d, name):
    (d / name).mkdir()
    return d / name


def raw(d, name, data):
    p = d / name
    p.write_bytes(data)
    return p


G = T.gray

# name -> (builder(dir, name) -> path, expected)
# expected: ("ok", n_rooms, n_doors or None) or (exception class, regex on the message)
CASES = {
    "missing.png": (lambda d, n: d / n, (MapFileNotFoundError, "image file not found")),
    "adir.png": (mkdir, (MapFileError, "is a directory")),
    "empty.png": (lambda d, n: raw(d, n, b""), (MapError, r"empty \(0 bytes\)")),
    "text.png": (lambda d, n: text(d, n, "I am not a picture\n"), (MapError, "not an image file")),
    "truncated.png": (truncated_png, (MapError, "truncated or corrupt")),
    "zero_size.pgm": (lambda d, n: raw(d, n, b"P5\n0 0\n255\n"), (MapError, "zero size|cannot decode|not an image")),
    "zero_size.png": (lambda d, n: raw(d, n, forged_png(0, 0)), (MapError, "zero size|cannot decode|not an image")),
    "huge.png": (lambda d, n: raw(d, n, forged_png(100_000, 100_000)),
                 (MapTooLargeError, r"10,000,000,000 cells, more than the [\d,]+ cells the free memory allows")),
    "one_free_pixel.png": (lambda d, n: png(d, n, np.full((1, 1), 254, np.uint8)), ("ok", 1, 0)),
    "one_wall_pixel.png": (lambda d, n: png(d, n, np.zeros((1, 1), np.uint8)), ("ok", 0, 0)),
    "all_free.png": (lambda d, n: png(d, n, np.full((60, 80), 254, np.uint8)), ("ok", 1, 0)),
    "all_occupied.png": (lambda d, n: png(d, n, np.zeros((60, 80), np.uint8)), ("ok", 0, 0)),
    "all_unknown.pgm": (lambda d, n: pgm(d, n, np.full((60, 80), 205, np.uint8)), ("ok", 0, 0)),
    "one_room.png": (lambda d, n: png(d, n, G(T.one_room().array)), ("ok", 1, 0)),
    "disconnected.png": (lambda d, n: png(d, n, G(T.disconnected_regions().array)), ("ok", 3, 0)),
    "two_rooms.pgm": (lambda d, n: pgm(d, n, G(T.two_rooms().array)), ("ok", 2, 1)),
    "not_yaml.yaml": (lambda d, n: text(d, n, "image: [unclosed\n  - : :\n"), (MapError, "not valid YAML at line 2")),
    "list.yaml": (lambda d, n: text(d, n, "- a\n- b\n"), (MapError, "must be a mapping")),
    "no_image.yaml": (lambda d, n: yaml_for(d, n, image=None), (MapError, "lacks the required key 'image'")),
    "no_resolution.yaml": (lambda d, n: yaml_for(d, n, resolution=None),
                           (MapError, "lacks the required key 'resolution'")),
    "no_origin.yaml": (lambda d, n: yaml_for(d, n, origin=None), (MapError, "lacks the required key 'origin'")),
    "res_text.yaml": (lambda d, n: yaml_for(d, n, resolution="fine"),
                      (ParameterError, "resolution must be a number, got 'fine'")),
    "origin_text.yaml": (lambda d, n: yaml_for(d, n, origin="home"), (ParameterError, "origin must be")),
    "image_number.yaml": (lambda d, n: yaml_for(d, n, image="42"), (MapError, "'image' must be a file name")),
    "res_zero.yaml": (lambda d, n: yaml_for(d, n, resolution="0"), (ParameterError, "resolution must be > 0")),
    "res_negative.yaml": (lambda d, n: yaml_for(d, n, resolution="-0.05"),
                          (ParameterError, "resolution must be > 0")),
    "image_missing.yaml": (lambda d, n: yaml_for(d, n, image="nothere.pgm"),
                           (MapFileNotFoundError, "image 'nothere.pgm' not found")),
    "negate.yaml": (negated, ("ok", 2, 1)),
    "sixteen_bit.pgm": (pgm16, ("ok", 2, 1)),
    "rgba_transparent.png": (rgba_transparent, ("ok", 1, 0)),
    "billion_laughs.yaml": (lambda d, n: text(d, n, BILLION_LAUGHS), (MapError, "aliases .* not allowed")),
    "alias_image.yaml": (lambda d, n: yaml_for(d, n, image="&i map.pgm", mode="*i"),
                         (MapError, "aliases .* not allowed")),
    "big.yaml": (lambda d, n: text(d, n, "image: map.pgm\n#" + "x" * (tio.MAX_YAML_BYTES + 1) + "\n"),
                 (MapError, "more than 1,048,576")),
    "deep.yaml": (lambda d, n: text(d, n, "a: " + "[" * 5000 + "]" * 5000 + "\n"), (MapError, "not valid YAML")),
    "typo_key.yaml": (lambda d, n: yaml_for(d, n, occupied_tresh="0.7"),
                      (ParameterError, r"unknown key 'occupied_tresh' \(did you mean 'occupied_thresh'\?\)")),
    "res_tiny.yaml": (lambda d, n: yaml_for(d, n, resolution="1e-9"),
                      (ParameterError, "resolution must be between 0.001 and 10 m per cell, got 1e-09")),
    "res_huge.yaml": (lambda d, n: yaml_for(d, n, resolution="1e200"),
                      (ParameterError, "resolution must be between 0.001 and 10 m per cell, got 1e\\+200")),
    "origin_huge.yaml": (lambda d, n: yaml_for(d, n, origin="[1e308, 0, 0]"),
                         (ParameterError, "origin x and y must be within")),
}

#: Nested anchors: expanding ``image`` would make 9**9 strings (a "billion laughs").
BILLION_LAUGHS = ("a: &a [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n"
                  + "".join(f"{c}: &{c} [{', '.join(['*' + p] * 9)}]\n" for p, c in zip("abcdefgh", "bcdefghi"))
                  + "image: *i\nresolution: 0.05\norigin: [0, 0, 0]\n")

ERROR_CASES = [k for k, v in CASES.items() if v[1][0] != "ok"]
OK_CASES = [k for k, v in CASES.items() if v[1][0] == "ok"]


def build(tmp_path, name):
    make, expected = CASES[name]
    return make(tmp_path, name), expected


def check_valid(seg, grid):
    """The labelling invariant and a consistent room graph."""
    assert isinstance(seg, Segmentation)
    lab = seg.labels
    assert lab.shape == grid.shape and lab.dtype == np.int32
    assert ((lab > 0) == grid.free).all()
    n = seg.n_rooms
    top = int(lab.max())
    # every free cell in exactly one room (1..n) or one reported fragment (n+1..top)
    assert set(np.unique(lab[lab > 0])) == set(range(1, top + 1))
    assert 0 <= n <= top and seg.n_fragments == top - n
    G = seg.room_graph
    assert sorted(G.nodes) == list(range(1, n + 1))
    assert G.number_of_edges() == len(seg.doors)
    assert G.graph["n_fragments"] == top - n
    assert G.graph["fragment_area"] == pytest.approx((lab > n).sum() * grid.resolution ** 2)
    assert all(max(d.rooms) <= n for d in seg.doors)


def assert_one_line(exc, fname):
    msg = str(exc)
    assert msg and "\n" not in msg and "\r" not in msg, msg
    assert fname in msg, msg
    return msg


# --------------------------------------------------------------------------
# Files
# --------------------------------------------------------------------------

@pytest.mark.parametrize("name", ERROR_CASES)
def test_bad_file_raises_one_line_error(tmp_path, name):
    path, (exc, pattern) = build(tmp_path, name)
    with pytest.raises(TopomapError) as ei:
        segment(load_map(path))
    assert isinstance(ei.value, exc), repr(ei.value)
    assert_one_line(ei.value, name)
    assert ei.match(pattern)
    if issubclass(exc, MapFileError):
        assert isinstance(ei.value, OSError)
    else:
        assert isinstance(ei.value, ValueError)


@pytest.mark.parametrize("method", sorted(METHODS))
@pytest.mark.parametrize("name", OK_CASES)
def test_odd_but_valid_file_segments(tmp_path, name, method):
    path, (_, n_rooms, n_doors) = build(tmp_path, name)
    grid = load_map(path)
    seg = segment(grid, method=method)
    check_valid(seg, grid)
    if method == "paper":
        assert seg.n_rooms == n_rooms
        assert len(seg.doors) == n_doors
    elif n_doors == 0:  # no walls between the rooms: every method sees the components
        # (the default method: as rooms, or as fragments when under min_room_area)
        assert seg.n_rooms + seg.n_fragments == n_rooms
        if method == "topomap":
            area = np.bincount(seg.labels.ravel())[1:] * grid.resolution ** 2
            small = area < seg.options.min_room_area
            assert seg.n_rooms == int((~small).sum()) and not small[:seg.n_rooms].any()


def test_huge_refused_up_front_without_decoding(tmp_path, monkeypatch):
    """The size is checked from the header: the decoder is never asked for pixels."""
    path = raw(tmp_path, "huge.png", forged_png(100_000, 100_000))
    from PIL import ImageFile

    def boom(self, *a, **k):
        raise AssertionError("decoded a too-large image")

    monkeypatch.setattr(ImageFile.ImageFile, "load", boom)
    with pytest.raises(MapTooLargeError, match="10,000,000,000 cells"):
        load_map(path)


def test_max_cells_is_the_documented_limit(tmp_path, monkeypatch):
    path = png(tmp_path, "small.png", G(T.two_rooms().array))
    monkeypatch.setattr(tio, "MAX_CELLS", 134 * 70 - 1)
    with pytest.raises(MapTooLargeError, match=r"134 x 70 px = 9,380 cells.*MAX_CELLS = 9,379") as ei:
        load_map(path)
    assert_one_line(ei.value, "small.png")
    monkeypatch.setattr(tio, "MAX_CELLS", 134 * 70)
    assert load_map(path).shape == (70, 134)


def test_negate_inverts(tmp_path):
    path, _ = build(tmp_path, "negate.yaml")
    grid = load_map(path)
    assert (grid.free == T.two_rooms().array).all()
    # the same picture without negate is the complement: walls read as free
    plain = load_map(tmp_path / "neg.pgm")
    assert (plain.free == ~T.two_rooms().array).all()


def test_sixteen_bit_is_the_8bit_map(tmp_path):
    path, _ = build(tmp_path, "sixteen_bit.pgm")
    grid = load_map(path)
    assert (grid.free == T.two_rooms().array).all()


def test_rgba_transparent_pixels_are_unknown(tmp_path):
    path, _ = build(tmp_path, "rgba_transparent.png")
    grid = load_map(path)
    assert grid.unknown[:, :67].all()
    assert (grid.free[:, 67:] == T.two_rooms().array[:, 67:]).all()


def test_disconnected_regions_each_a_room(tmp_path):
    m = T.disconnected_regions()
    seg = segment(from_array(m.array))
    assert seg.n_rooms == 3 and seg.doors == []
    areas = sorted(d["area"] for _, d in seg.room_graph.nodes(data=True))
    assert areas == pytest.approx(sorted([2.5 * 2.5, 2.5 * 2.5, 1.0 * 1.0]))


# --------------------------------------------------------------------------
# Arrays
# --------------------------------------------------------------------------

BAD_ARRAYS = [
    ("0-d", np.array(5, np.int8), "must be 2-D, got ndim=0"),
    ("1-d", np.zeros(10, bool), "must be 2-D, got ndim=1"),
    ("3-d", np.zeros((4, 4, 3), np.uint8), "must be 2-D, got ndim=3"),
    ("empty", np.zeros((0, 5), bool), "empty"),
    ("float", np.zeros((4, 4)), "unsupported array dtype float64"),
    ("uint16", np.zeros((4, 4), np.uint16), "unsupported array dtype uint16"),
    ("complex", np.zeros((4, 4), complex), "unsupported array dtype complex128"),
    ("str", np.full((2, 2), "a"), "unsupported array dtype <U1"),
    ("object", np.array([[None, 1], [2, 3]], object), "unsupported array dtype object"),
    ("ragged", [[1, 2], [3]], "cannot convert list to an array|unsupported|2-D"),
]


@pytest.mark.parametrize("label, a, pattern", BAD_ARRAYS, ids=[b[0] for b in BAD_ARRAYS])
def test_bad_arrays(label, a, pattern):
    with pytest.raises(MapError, match=pattern) as ei:
        from_array(a)
    assert_one_line(ei.value, "<array>")
    with pytest.raises(MapError) as ei:
        from_array(a, source="robot.npy")
    assert_one_line(ei.value, "robot.npy")


@pytest.mark.parametrize("res", [0, -0.05, float("nan"), float("inf"), "abc", None])
def test_bad_resolution_for_arrays(res):
    with pytest.raises(ParameterError, match="resolution") as ei:
        from_array(np.ones((3, 3), bool), resolution=res)
    assert "\n" not in str(ei.value)


def test_segment_wants_a_grid_and_a_known_method():
    with pytest.raises(ParameterError, match="needs an OccupancyGrid"):
        segment(np.ones((3, 3), bool))
    with pytest.raises(ParameterError, match="unknown method 'magic'"):
        segment(from_array(np.ones((3, 3), bool)), method="magic")


# --------------------------------------------------------------------------
# Fuzz: from_array + segment on random small arrays
# --------------------------------------------------------------------------

_DTYPES = st.sampled_from([np.dtype(bool), np.dtype(np.uint8), np.dtype(np.int8)])


@st.composite
def small_arrays(draw):
    dtype = draw(_DTYPES)
    shape = draw(hnp.array_shapes(min_dims=2, max_dims=2, min_side=1, max_side=24))
    if dtype == np.int8:
        elems = st.sampled_from([0, 100, -1, 50, 65, 64, 99, -128, 127])
    elif dtype == np.uint8:
        elems = st.sampled_from([0, 254, 205, 255, 1, 100, 200, 210])
    else:
        elems = None
    return draw(hnp.arrays(dtype, shape, elements=elems))


@pytest.mark.parametrize("method", sorted(METHODS))
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(a=small_arrays())
def test_fuzz_from_array_and_segment(method, a):
    """Anything but a TopomapError or a valid Segmentation is a bug."""
    try:
        grid = from_array(a)
        seg = segment(grid, method=method)
    except TopomapError as exc:
        assert "\n" not in str(exc)
        return
    check_valid(seg, grid)


# --------------------------------------------------------------------------
# Round two: hostile and odd input (limits, warnings, outputs)
# --------------------------------------------------------------------------

def test_unknown_yaml_key_without_a_close_match_warns(tmp_path, caplog):
    p = yaml_for(tmp_path, "m.yaml", comment_by_tool="slam_toolbox")
    with caplog.at_level("WARNING", logger="topomap.io"):
        grid = load_map(p)
    assert grid.shape == T.two_rooms().array.shape
    assert any("unknown key 'comment_by_tool' ignored" in r.getMessage() and str(p) in r.getMessage()
               for r in caplog.records)


@pytest.mark.parametrize("res,warns", [(0.05, False), (0.005, False), (0.5, False), (0.002, True), (5, True)])
def test_unusual_resolution_warns(tmp_path, caplog, res, warns):
    p = yaml_for(tmp_path, "m.yaml", resolution=str(res))
    with caplog.at_level("WARNING", logger="topomap.io"):
        load_map(p)
    hits = [r for r in caplog.records if "outside what indoor maps use" in r.getMessage()]
    assert bool(hits) == warns


@pytest.mark.parametrize("res", [1e-9, 0.0009, 10.5, 1e200])
def test_absurd_resolution_refused_for_arrays_and_images(tmp_path, res):
    with pytest.raises(ParameterError, match="between 0.001 and 10 m per cell"):
        from_array(T.two_rooms().array, resolution=res)
    p = png(tmp_path, "m.png", G(T.two_rooms().array))
    with pytest.raises(ParameterError, match="between 0.001 and 10 m per cell") as ei:
        load_map(p, resolution=res)
    assert_one_line(ei.value, "resolution")


def test_check_resolution_names_the_option():
    assert tio.check_resolution(0.05) == 0.05
    for bad in (0, -1, float("nan"), "x", True, 1e-9):
        with pytest.raises(ParameterError, match="^--resolution must be"):
            tio.check_resolution(bad)


def test_array_over_the_limit_refused(monkeypatch):
    monkeypatch.setattr(tio, "MAX_CELLS", 99)
    with pytest.raises(MapTooLargeError, match=r"<array>: map is 10 x 10 cells = 100, more than .*MAX_CELLS = 99"):
        from_array(np.ones((10, 10), bool))


def test_thin_corridor_protrusion_does_not_grow_with_its_length():
    """A 3-cell-high corridor: the door-judging kernel is cut to the map (it used to be (2r+1)**2, r ~ length)."""
    from topomap.core.doors import protrusion, protrusion_at

    free = np.zeros((3, 4000), bool)
    free[1, 1:-1] = True
    posts = [(0, 10), (2, 3990)]
    got = protrusion_at(free, posts, 1500.0, 700)  # would need (2 * 1500 + 1)**2 floats per window before
    assert got.shape == (2,) and np.all((got >= 0) & (got <= 1))
    # the same values as the whole-map filter (small case, where the full kernel fits)
    small = free[:, :200]
    ref = protrusion(small, 60)
    pts = [(0, 5), (2, 190), (0, 100)]
    want = []
    for r, c in pts:
        a, b, e, f = max(r - 20, 0), min(r + 21, 3), max(c - 20, 0), min(c + 21, 200)
        sub = np.where(small[a:b, e:f], 0.0, ref[a:b, e:f])
        want.append(sub.max())
    np.testing.assert_allclose(protrusion_at(small, pts, 60, 20), want, atol=1e-6)


@pytest.mark.parametrize("res,warns", [(0.05, None), (0.001, "less than a small room"),
                                       (10, "more than any building")])
def test_free_area_outside_a_building_warns(tmp_path, caplog, res, warns):
    p = png(tmp_path, "m.png", G(np.kron(T.two_rooms().array, np.ones((2, 2), bool))))  # 72.7 m² at 0.05
    with caplog.at_level("WARNING", logger="topomap.io"):
        load_map(p, resolution=res)
    hits = [r.getMessage() for r in caplog.records if "free space" in r.getMessage()]
    assert (hits and warns in hits[0] and str(p) in hits[0]) if warns else not hits
