"""The ``topomap`` command line on bad input, batches and failed writes.

Exit codes (topomap/cli.py, docs/errors.md): 0 success; 1 a map or input
could not be processed; 2 bad usage; 3 an internal error. An error is ONE
line on stderr (``error: <file>: <problem>``); a traceback only with --debug.
"""

import json
import os
import subprocess
import sys

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

import _testdata as T
from test_bad_input import ERROR_CASES, OK_CASES, build, png
from topomap import cli
from topomap.cli import main


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def stderr_lines(result):
    return [ln for ln in result.stderr.splitlines() if ln.strip()]


@pytest.fixture(autouse=True)
def _reset_debug():
    yield
    cli._State.debug = False


@pytest.mark.parametrize("name", ERROR_CASES)
def test_bad_map_one_line_exit_1(tmp_path, name):
    path, _ = build(tmp_path, name)
    out = tmp_path / "out"
    r = invoke("segment", path, "-o", out)
    assert r.exit_code == 1, (r.stdout, r.stderr)
    lines = stderr_lines(r)
    assert len(lines) == 1, r.stderr
    assert lines[0].startswith("error: ") and name in lines[0], lines
    assert "Traceback" not in r.stderr
    assert r.stdout == ""
    assert not out.exists() or not any(out.iterdir())


@pytest.mark.parametrize("name", ["missing.png", "text.png", "not_yaml.yaml", "huge.png"])
def test_debug_prints_traceback(tmp_path, name):
    path, _ = build(tmp_path, name)
    r = invoke("--debug", "segment", path, "-o", tmp_path / "out")
    assert r.exit_code == 1
    assert "Traceback (most recent call last)" in r.stderr
    assert stderr_lines(r)[-1].startswith("error: ")


#: Free regions under the default method's smallest room (1 m²) are
#: fragments, not rooms: (rooms, fragments) where that changes the count.
DEFAULT_METHOD_COUNTS = {"one_free_pixel.png": (0, 1)}


@pytest.mark.parametrize("name", OK_CASES)
def test_odd_but_valid_map_exit_0(tmp_path, name):
    path, (_, n_rooms, n_doors) = build(tmp_path, name)
    n_rooms, n_frag = DEFAULT_METHOD_COUNTS.get(name, (n_rooms, 0))
    out = tmp_path / "out"
    r = invoke("segment", path, "-o", out)
    assert r.exit_code == 0, r.stderr
    assert f"{cli._count(n_rooms, 'room')}, {cli._count(n_doors, 'door')}" in r.stdout
    assert ("fragment" in r.stdout) == (n_frag > 0)
    assert {"labels.png", "overlay.png", "rooms.graphml", "rooms.json"} <= {p.name for p in out.iterdir()}
    labels = np.asarray(Image.open(out / "labels.png"))
    assert labels.max() == n_rooms + n_frag
    data = json.loads((out / "rooms.json").read_text())
    assert len(data["nodes"]) == n_rooms and len(data["edges"]) == n_doors
    assert data["graph"]["n_fragments"] == n_frag


@pytest.mark.parametrize("res", ["0", "-0.05", "nan"])
def test_bad_resolution_option(tmp_path, res):
    path = png(tmp_path, "ok.png", T.gray(T.two_rooms().array))
    r = invoke("segment", path, "--resolution", res, "-o", tmp_path / "out")
    assert r.exit_code == 1
    lines = stderr_lines(r)
    assert len(lines) == 1 and "--resolution must be > 0" in lines[0], r.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("args", [["segment"], ["segment", "x.png"], ["segment", "x.png", "-o", "o", "--method", "magic"],
                                  ["segment", "x.png", "-o", "o", "--resolution", "abc"], ["nosuchcommand"]])
def test_usage_errors_exit_2(tmp_path, args):
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 2, (r.stdout, r.stderr)
    assert "Traceback" not in r.stderr


def test_internal_error_exit_3(tmp_path, monkeypatch):
    path = png(tmp_path, "ok.png", T.gray(T.two_rooms().array))

    def bug(*a, **k):
        raise KeyError("oops")

    from topomap.core.segmentation import METHODS

    monkeypatch.setitem(METHODS, "topomap", bug)
    r = invoke("segment", path, "-o", tmp_path / "out")
    assert r.exit_code == 3
    lines = stderr_lines(r)
    assert len(lines) == 1 and lines[0].startswith("internal error:") and "--debug" in lines[0]


# --------------------------------------------------------------------------
# Batches and half-written outputs
# --------------------------------------------------------------------------

def test_batch_skips_the_bad_map(tmp_path):
    a = png(tmp_path, "a.png", T.gray(T.two_rooms().array))
    bad = tmp_path / "bad.png"
    bad.write_text("not a picture")
    c = png(tmp_path, "c.png", T.gray(T.corridor_with_rooms().array))
    out = tmp_path / "out"
    r = invoke("segment", a, bad, c, "-o", out)
    assert r.exit_code == 1
    errors = [ln for ln in stderr_lines(r) if ln.startswith("error")]
    assert len(errors) == 1 and "bad.png" in errors[0] and "not an image" in errors[0]
    assert "Traceback" not in r.stderr
    assert "2 of 3 maps segmented" in r.stdout
    assert sorted(p.name for p in out.iterdir()) == ["a", "c", "summary.csv"]
    for stem, n in (("a", 2), ("c", 4)):
        assert np.asarray(Image.open(out / stem / "labels.png")).max() == n
        assert (out / stem / "overlay.png").stat().st_size > 0


def test_batch_all_good_exit_0(tmp_path):
    a = png(tmp_path, "a.png", T.gray(T.two_rooms().array))
    b = png(tmp_path, "b.png", T.gray(T.one_room().array))
    r = invoke("segment", a, b, "-o", tmp_path / "out")
    assert r.exit_code == 0 and "2 of 2 maps segmented" in r.stdout


def _snapshot(d):
    return {p.name: p.read_bytes() for p in sorted(d.iterdir())}


def test_failed_overlay_leaves_no_partial_file_and_keeps_earlier_outputs(tmp_path, monkeypatch):
    out = tmp_path / "out"
    first = png(tmp_path, "first.png", T.gray(T.two_rooms().array))
    assert invoke("segment", first, "-o", out).exit_code == 0
    before = _snapshot(out)

    def broken_overlay(data, path):
        with open(path, "wb") as fh:  # half a picture, then a crash
            fh.write(data[:6])
        raise OSError("disk full")

    monkeypatch.setattr("topomap.io.export.save_bytes", broken_overlay)
    second = png(tmp_path, "second.png", T.gray(T.corridor_with_rooms().array))
    r = invoke("segment", second, "-o", out, "--overwrite")
    assert r.exit_code == 1
    lines = stderr_lines(r)
    assert len(lines) == 1 and "disk full" in lines[0], r.stderr
    assert _snapshot(out) == before  # nothing clobbered, no temporary file left
    assert [p.name for p in out.iterdir() if p.name.startswith(".")] == []


def test_failed_overlay_drawing_writes_nothing(tmp_path, monkeypatch):
    out = tmp_path / "out"
    assert invoke("segment", png(tmp_path, "first.png", T.gray(T.two_rooms().array)), "-o", out).exit_code == 0
    before = _snapshot(out)

    def broken(seg, **kw):
        raise OSError("no display")

    monkeypatch.setattr("topomap.io.plot.overlay_png", broken)
    r = invoke("segment", png(tmp_path, "second.png", T.gray(T.one_room().array)), "-o", out, "--overwrite")
    assert r.exit_code == 1 and "no display" in r.stderr
    assert _snapshot(out) == before


@pytest.mark.parametrize("victim", ["save_labels", "save_graphml", "save_json"])
def test_any_failed_writer_keeps_earlier_outputs(tmp_path, monkeypatch, victim):
    from topomap.io import export

    out = tmp_path / "out"
    assert invoke("segment", png(tmp_path, "first.png", T.gray(T.two_rooms().array)), "-o", out).exit_code == 0
    before = _snapshot(out)

    def broken(*a, **k):
        raise OSError(f"{victim} failed")

    monkeypatch.setattr(export, victim, broken)
    r = invoke("segment", png(tmp_path, "second.png", T.gray(T.one_room().array)), "-o", out, "--overwrite")
    assert r.exit_code == 1
    assert _snapshot(out) == before


def test_batch_with_failed_write_goes_on(tmp_path, monkeypatch):
    from topomap.io import export

    real = export.save_json

    def flaky(G, path):
        if G.graph["map"].endswith("b.png"):
            raise OSError("no space left on device")
        return real(G, path)

    monkeypatch.setattr(export, "save_json", flaky)
    paths = [png(tmp_path, f"{s}.png", T.gray(T.two_rooms().array)) for s in "abc"]
    out = tmp_path / "out"
    r = invoke("segment", *paths, "-o", out)
    assert r.exit_code == 1
    assert "2 of 3 maps segmented" in r.stdout
    assert not (out / "b").exists() or list((out / "b").iterdir()) == []
    for s in "ac":
        assert (out / s / "rooms.json").exists()


# --------------------------------------------------------------------------
# A real process (entry point, stderr, exit status)
# --------------------------------------------------------------------------

def _run(*args, cwd):
    exe = os.path.join(os.path.dirname(sys.executable), "topomap")
    cmd = [exe] if os.path.exists(exe) else [sys.executable, "-m", "topomap.cli"]
    return subprocess.run(cmd + [str(a) for a in args], cwd=cwd, capture_output=True, text=True, timeout=120)


def test_subprocess_missing_file(tmp_path):
    p = _run("segment", "nothere.png", "-o", "out", cwd=tmp_path)
    assert p.returncode == 1
    assert p.stderr.strip() == "error: nothere.png: image file not found"
    assert not (tmp_path / "out").exists()


def test_subprocess_batch_and_debug(tmp_path):
    png(tmp_path, "a.png", T.gray(T.two_rooms().array))
    (tmp_path / "bad.png").write_bytes(b"")
    p = _run("segment", "a.png", "bad.png", "-o", "out", cwd=tmp_path)
    assert p.returncode == 1
    assert [ln for ln in p.stderr.splitlines() if ln.startswith("error")] == [
        "error: bad.png: image file is empty (0 bytes)"]
    assert "Traceback" not in p.stderr
    assert (tmp_path / "out" / "a" / "labels.png").exists()
    p = _run("--debug", "segment", "bad.png", "-o", "out2", cwd=tmp_path)
    assert p.returncode == 1 and "Traceback (most recent call last)" in p.stderr


def test_cli_method_choices_match_library():
    """The CLI lists the methods without importing the library; it must not drift."""
    from topomap.cli import _method_names
    from topomap.core.segmentation import METHODS

    assert sorted(_method_names()) == sorted(METHODS)
    assert _method_names()[0] == "topomap"


def test_segment_with_each_method_name(tmp_path):
    from click.testing import CliRunner

    from topomap.io.example import example_map_path
    from topomap.cli import main

    r = CliRunner().invoke(main, ["segment", str(example_map_path()), "-o", str(tmp_path / "o"),
                                  "--method", "topomap"])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "o" / "labels.png").exists()


def test_segment_profile_prints_every_stage(tmp_path):
    from click.testing import CliRunner

    from topomap.io.example import example_map_path
    from topomap.cli import main

    r = CliRunner().invoke(main, ["segment", str(example_map_path()), "-o", str(tmp_path / "o"), "--profile"])
    assert r.exit_code == 0, r.output
    err = r.stderr if hasattr(r, "stderr") else r.output
    for stage in ["start", "import", "warmup", "load", "preprocess", "skeletons", "graphs", "doors", "rooms", "total",
                  "room_graph", "travel", "overlay", "write_labels", "write_graphml", "write_json", "write_geojson",
                  "write_overlay", "write", "job"]:
        assert f" {stage} " in err, (stage, err)
    t = {k: int(v) for k, v in __import__("re").findall(r"(\w+) (\d+) ms", err)}
    # the map's job is its stages: load, segmentation, room graph, then everything written
    parts = t["load"] + t["total"] + t["room_graph"] + t["write"]
    assert abs(t["job"] - parts) <= max(5, 0.05 * t["job"]), t  # ms rounding; nothing unaccounted
    steps = t["travel"] + t["overlay"] + sum(v for k, v in t.items() if k.startswith("write_"))
    assert steps <= t["write"] + 7, t


def test_profile_start_and_import_once_per_batch(tmp_path):
    a = png(tmp_path, "a.png", T.gray(T.two_rooms().array))
    b = png(tmp_path, "b.png", T.gray(T.one_room().array))
    r = invoke("segment", a, b, "-o", tmp_path / "out", "--profile")
    assert r.exit_code == 0
    lines = [ln for ln in stderr_lines(r) if " ms" in ln]
    assert len(lines) == 2
    assert " import " in lines[0] and " import " not in lines[1]
    assert " job " in lines[0] and " job " in lines[1]


@pytest.mark.parametrize("flags, absent", [(["--no-overlay"], {"overlay.png"}),
                                           (["--no-geojson"], {"rooms.geojson"}),
                                           (["--no-overlay", "--no-geojson"], {"overlay.png", "rooms.geojson"})])
def test_optional_outputs_can_be_left_out(tmp_path, flags, absent):
    out = tmp_path / "out"
    r = invoke("segment", png(tmp_path, "m.png", T.gray(T.two_rooms().array)), "-o", out, *flags)
    assert r.exit_code == 0, r.stderr
    from topomap.run.batch import RECORD
    from topomap.io.export import OUTPUT_FILES

    every = set(OUTPUT_FILES.values()) | {RECORD}
    assert {p.name for p in out.iterdir()} == every - absent
    assert np.asarray(Image.open(out / "labels.png")).max() == 2


def test_no_overlay_does_not_draw(tmp_path, monkeypatch):
    def broken(seg, **kw):
        raise OSError("no display")

    monkeypatch.setattr("topomap.io.plot.overlay_png", broken)
    r = invoke("segment", png(tmp_path, "m.png", T.gray(T.one_room().array)), "-o", tmp_path / "o", "--no-overlay")
    assert r.exit_code == 0, r.stderr


def test_overlay_is_the_map_size(tmp_path):
    m = T.two_rooms().array
    out = tmp_path / "out"
    assert invoke("segment", png(tmp_path, "m.png", T.gray(m)), "-o", out).exit_code == 0
    img = Image.open(out / "overlay.png")
    assert img.size == (m.shape[1], m.shape[0])


def test_package_functions_are_not_shadowed_by_submodules():
    """``topomap.segment`` is the function, whatever submodules were imported."""
    import importlib

    import topomap

    for mod in ["io", "segmentation", "skeleton", "doors", "rooms", "roomgraph", "planning", "export",
                "plot", "evaluation", "datasets", "benchmark", "baselines", "cli"]:
        importlib.import_module(f"topomap.{mod}")
    for name in topomap.__all__:
        obj = getattr(topomap, name)
        assert not isinstance(obj, type(topomap)), name
    assert callable(topomap.segment) and topomap.segment.__name__ == "segment"


def test_segment_summary_reports_fragments(tmp_path):
    """A speck of free space is a fragment, not a room; the summary line
    counts it (and its area) apart from the rooms."""
    from click.testing import CliRunner

    from topomap.cli import main

    free = np.zeros((60, 80), bool)
    free[5:55, 5:45] = True  # 2.0 m x 2.5 m = 5 m² at 0.05 m/px
    free[10, 60] = True  # a one-cell speck
    p = tmp_path / "speck.png"
    Image.fromarray(np.where(free, 254, 0).astype(np.uint8)).save(p)
    r = CliRunner().invoke(main, ["segment", str(p), "-o", str(tmp_path / "o")])
    assert r.exit_code == 0, r.output
    assert "1 room, 0 doors, 1 fragment (0.0025 m²)" in r.output
