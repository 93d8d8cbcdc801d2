"""Fuzzing the loader: any input either loads or raises a TopomapError.

Anything else escaping :func:`topomap.io.load_map` (a Pillow, yaml, numpy
or built-in exception) is a bug, and so is a multi-line message.
"""

import io as _pyio
import math
from contextlib import contextmanager

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from PIL import Image

from topomap import io as tio
from topomap.errors import TopomapError
from topomap.io import OccupancyGrid, load_map

SETTINGS = settings(max_examples=200, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])

GRAY = np.array([[0, 254, 205, 100], [254, 254, 0, 205], [205, 0, 254, 30]], np.uint8)


def _png(img):
    buf = _pyio.BytesIO()
    img.save(buf, format="PNG")
    return buf.getvalue()


VALID = {
    "pgm": tio.pgm_bytes(GRAY),
    "png": _png(Image.fromarray(GRAY)),
    "rgba.png": _png(Image.fromarray(np.dstack([GRAY, GRAY, GRAY, GRAY]), "RGBA")),
    "16.png": _png(Image.fromarray(GRAY.astype(np.uint16) * 257)),
    "yaml": b"image: map.pgm\nresolution: 0.05\norigin: [-1.0, 2.0, 0.0]\nnegate: 0\n"
            b"occupied_thresh: 0.65\nfree_thresh: 0.196\n",
}


@contextmanager
def small_limit():
    saved = tio.MAX_CELLS
    tio.MAX_CELLS = 1_000_000  # keep fuzzed headers from allocating big images
    try:
        yield
    finally:
        tio.MAX_CELLS = saved


@pytest.fixture(scope="module")
def fuzzdir(tmp_path_factory):
    d = tmp_path_factory.mktemp("fuzz")
    (d / "map.pgm").write_bytes(VALID["pgm"])
    return d


def check_load(path, **kwargs):
    """Load; return the grid or None. Fail on any non-topomap exception."""
    with small_limit():
        try:
            g = load_map(path, **kwargs)
        except TopomapError as exc:
            msg = str(exc)
            assert msg and "\n" not in msg and "\r" not in msg, repr(msg)
            assert path.name in msg, msg
            return None
    assert isinstance(g, OccupancyGrid)
    assert g.cells.dtype == np.int8 and g.cells.ndim == 2 and g.cells.size > 0
    assert g.gray is not None and g.gray.dtype == np.uint8 and g.gray.shape == g.cells.shape
    assert g.cells.size <= 1_000_000
    assert set(np.unique(g.cells)) <= set(range(-1, 101))
    assert g.resolution > 0 and math.isfinite(g.resolution)
    assert len(g.origin) == 3 and all(math.isfinite(v) for v in g.origin)
    return g


SUFFIXES = ["png", "pgm", "yaml", "bmp", "tif", "gif", "jpg", "ppm", "webp", "bin"]


@SETTINGS
@given(data=st.binary(max_size=2048), suffix=st.sampled_from(SUFFIXES))
def test_random_bytes(fuzzdir, data, suffix):
    p = fuzzdir / f"random.{suffix}"
    p.write_bytes(data)
    check_load(p)


@st.composite
def mutated(draw):
    kind = draw(st.sampled_from(sorted(VALID)))
    data = bytearray(VALID[kind])
    for _ in range(draw(st.integers(1, 6))):
        op = draw(st.sampled_from(["flip", "set", "truncate", "insert", "delete", "dup"]))
        if not data:
            break
        i = draw(st.integers(0, len(data) - 1))
        if op == "flip":
            data[i] ^= 1 << draw(st.integers(0, 7))
        elif op == "set":
            data[i] = draw(st.integers(0, 255))
        elif op == "truncate":
            del data[i:]
        elif op == "insert":
            data[i:i] = draw(st.binary(min_size=1, max_size=16))
        elif op == "delete":
            del data[i:i + draw(st.integers(1, 16))]
        else:
            data[i:i] = data[i:i + draw(st.integers(1, 32))]
    suffix = "yaml" if kind == "yaml" else kind.split(".")[-1]
    return kind, suffix, bytes(data)


@SETTINGS
@given(case=mutated())
def test_mutated_valid_files(fuzzdir, case):
    kind, suffix, data = case
    p = fuzzdir / f"mutant.{suffix}"
    p.write_bytes(data)
    check_load(p)


yaml_scalars = st.one_of(
    st.none(), st.booleans(), st.integers(-10**20, 10**20),
    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=12),
)
yaml_values = st.recursive(yaml_scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=5), inner, max_size=3)), max_leaves=8)
KEYS = ["image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh", "mode"]
good_values = {
    "image": st.just("map.pgm"),
    "resolution": st.floats(0.001, 1.0),
    "origin": st.lists(st.floats(-100, 100), min_size=3, max_size=3),
    "negate": st.sampled_from([0, 1]),
    "occupied_thresh": st.floats(0.5, 1.0),
    "free_thresh": st.floats(0.0, 0.49),
    "mode": st.sampled_from(["trinary", "scale", "raw"]),
}


@st.composite
def yaml_docs(draw):
    doc = {}
    for key in KEYS:
        choice = draw(st.sampled_from(["good", "good", "bad", "absent"]))
        if choice == "good":
            doc[key] = draw(good_values[key])
        elif choice == "bad":
            doc[key] = draw(yaml_values)
    return doc


@SETTINGS
@given(doc=yaml_docs())
def test_structured_yaml(fuzzdir, doc):
    p = fuzzdir / "structured.yaml"
    p.write_text(yaml.safe_dump(doc))
    check_load(p)


@SETTINGS
@given(kwargs=st.fixed_dictionaries({}, optional={
    "resolution": yaml_values, "origin": yaml_values, "negate": yaml_values,
    "occupied_thresh": yaml_values, "free_thresh": yaml_values, "mode": yaml_values}))
def test_fuzzed_keyword_arguments(fuzzdir, kwargs):
    p = fuzzdir / "kw.yaml"
    p.write_bytes(VALID["yaml"])
    with small_limit():
        try:
            g = load_map(p, **kwargs)
        except TopomapError as exc:
            assert "\n" not in str(exc)
            return
    assert g.shape == GRAY.shape


def test_all_valid_seeds_load(fuzzdir):
    for kind, data in VALID.items():
        suffix = "yaml" if kind == "yaml" else kind.split(".")[-1]
        p = fuzzdir / f"seed.{suffix}"
        p.write_bytes(data)
        g = check_load(p)
        assert g is not None and g.shape == GRAY.shape, kind
