"""Hostile and odd inputs, third part: what the command line reads before it loads a map, messages that
name the file, outputs left as they were. Each test failed before its fix."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from topomap import io
from test_hostile2 import _one_error_line, _run, _two_rooms  # the same checks as there

ROOT = Path(__file__).resolve().parents[1]


def _cli(*args, cwd, timeout=120):
    """``topomap ARGS`` in its own process: (exit code, stderr lines)."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    res = subprocess.run([sys.executable, "-m", "topomap.cli", *map(str, args)], capture_output=True, text=True,
                         env=env, cwd=cwd, timeout=timeout)
    return res.returncode, [ln for ln in res.stderr.splitlines() if ln.strip()]


# --------------------------------------------------------------------------
# The run record's look at a map YAML is bounded like load_map's
# --------------------------------------------------------------------------

@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs")
def test_a_fifo_named_like_a_yaml_is_refused_not_waited_on(tmp_path):
    os.mkfifo(tmp_path / "pipe.yaml")  # nobody writes into it: reading it would wait for ever
    code, err = _cli("segment", "pipe.yaml", "-o", "out", cwd=tmp_path, timeout=60)  # was: a hang
    assert code == 1 and len(err) == 1 and err[0].startswith("error: pipe.yaml: "), err
    assert not (tmp_path / "out").exists()


def test_the_inputs_of_a_yaml_are_read_within_the_yaml_bound(tmp_path):
    from topomap.run.record import input_files

    y = tmp_path / "m.yaml"
    # a YAML over MAX_YAML_BYTES (a 300 MB one took 1 GB and 2.5 minutes before load_map refused it)
    y.write_text("image: other.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n#" + "x" * io.MAX_YAML_BYTES + "\n")
    assert input_files(y) == [y.absolute()]
    y.write_text("image: &i other.pgm\nmode: *i\n")  # aliases: refused by load_map, not expanded here
    assert input_files(y) == [y.absolute()]
    y.write_text("image: other.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n")
    assert input_files(y) == [y.absolute(), (tmp_path / "other.pgm").absolute()]
    res = _run("segment", y, "-o", tmp_path / "out")
    _one_error_line(res, y)


def test_an_image_name_with_a_nul_byte_is_named_in_the_error(tmp_path):
    io.save_map(_two_rooms(), tmp_path / "map")
    y = tmp_path / "nul.yaml"
    y.write_text('image: "map\\0.pgm"\nresolution: 0.05\norigin: [0, 0, 0]\n')
    line = _one_error_line(_run("segment", y, "-o", tmp_path / "out"), y)  # was: "error: embedded null byte"
    assert "'image' must be a file name" in line, line
    assert not (tmp_path / "out").exists()


# --------------------------------------------------------------------------
# Map YAMLs: a key given twice, bytes that are not UTF-8, a FIFO or device as the image
# --------------------------------------------------------------------------

def _yaml(tmp_path, name, text):
    io.save_map(_two_rooms(), tmp_path / "map")
    p = tmp_path / name
    p.write_bytes(text if isinstance(text, bytes) else text.encode())
    return p


@pytest.mark.parametrize("text, where", [
    ("image: map.pgm\nresolution: 0.05\nresolution: 0.1\norigin: [0, 0, 0]\n", "'resolution' given twice (lines 2 and 3)"),
    ("{image: map.pgm, resolution: 0.05, origin: [0, 0, 0], image: map.pgm}\n", "'image' given twice (line 1)"),
])
def test_a_key_given_twice_is_refused(tmp_path, text, where):
    """PyYAML keeps the last value, map_server (yaml-cpp) the first: the two would read different maps."""
    from topomap.errors import MapError

    y = _yaml(tmp_path, "dup.yaml", text)
    with pytest.raises(MapError, match=r"dup.yaml: not valid YAML at line \d: key " + where.replace("(", r"\(")
                       .replace(")", r"\)")):
        io.load_map(y)  # was: read at 0.1 m per cell
    _one_error_line(_run("segment", y, "-o", tmp_path / "out"), y)
    # twice in a value's own mapping (an unknown key's) is not the map's business
    y.write_text("image: map.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnotes: {a: 1, a: 2}\n")
    assert io.load_map(y).shape == (60, 100)


@pytest.mark.parametrize("raw, words", [
    (b"image: map.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n# caf\xe9\n", "byte 0xe9 at offset 55 is not UTF-8"),
    (b"image: map.pgm\nresolution: 0.05\x07\n", "character U+0007 at offset 31 is not allowed"),
])
def test_bytes_yaml_cannot_read_are_shown(tmp_path, raw, words):
    y = _yaml(tmp_path, "bytes.yaml", raw)
    line = _one_error_line(_run("segment", y, "-o", tmp_path / "out"), y)  # was: "not valid YAML: ReaderError"
    assert words in line, line


@pytest.mark.skipif(not hasattr(os, "mkfifo") or not os.path.exists("/dev/zero"), reason="no FIFOs or /dev/zero")
def test_a_fifo_or_device_is_not_called_empty(tmp_path):
    from topomap.errors import MapFileError

    os.mkfifo(tmp_path / "pipe.pgm")
    y = _yaml(tmp_path, "dev.yaml", "image: /dev/zero\nresolution: 0.05\norigin: [0, 0, 0]\n")
    for path, name in ((tmp_path / "pipe.pgm", "pipe.pgm"), (y, "/dev/zero"), (Path("/dev/zero"), "/dev/zero")):
        with pytest.raises(MapFileError, match="is not a regular file") as ei:  # was: "is empty (0 bytes)"
            io.load_map(path)
        assert name in str(ei.value) and "\n" not in str(ei.value)


# --------------------------------------------------------------------------
# More rooms than the 16-bit label files hold: refused before the room graph and the rest
# --------------------------------------------------------------------------

def test_rooms_beyond_the_label_files_are_refused_right_after_segmenting(tmp_path, monkeypatch):
    """A 1000 x 1000 one-cell checkerboard at 1 m per cell is 500,000 rooms: the job used to build the room
    graph, travel distances and pictures of all of them (7 GB, 5 minutes) before labels.png refused them."""
    from topomap.io import export
    from topomap.run import job

    def boom(*args, **kwargs):
        raise AssertionError("built the room graph of rooms that cannot be written")

    monkeypatch.setattr(export, "MAX_FILE_LABEL", 1)  # the two-room map has room IDs up to 2
    monkeypatch.setattr(job, "travel_graph", boom)
    monkeypatch.setattr("topomap.core.roomgraph.room_graph", boom)
    m = io.save_map(_two_rooms(), tmp_path / "m")
    line = _one_error_line(_run("segment", m, "-o", tmp_path / "out"), m)
    assert "labels.png: room IDs up to 2 do not fit a 16-bit PNG" in line, line
    assert not (tmp_path / "out").exists()


# --------------------------------------------------------------------------
# export --nav2 never replaces the room graph it reads or a file of its output folder
# --------------------------------------------------------------------------

@pytest.mark.parametrize("source, nav2", [("rooms.json", "rooms.json"), ("rooms.graphml", "rooms.json"),
                                          ("rooms.graphml", "labels.png"), ("rooms.graphml", "topomap_run.json"),
                                          ("rooms.graphml", "../out/rooms.geojson")])
def test_nav2_export_never_replaces_its_input_or_the_folders_files(tmp_path, source, nav2):
    out = tmp_path / "out"
    assert _run("segment", io.save_map(_two_rooms(), tmp_path / "m"), "-o", out).exit_code == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    line = _one_error_line(_run("export", out / source, "--nav2", out / nav2), out / nav2)  # was: exit 0,
    assert "would replace" in line, line  # rooms.json replaced by the route graph, plan and edit broken
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    res = _run("export", out / "rooms.graphml", tmp_path / "g.json", "--nav2", tmp_path / "g.json")  # OUTPUT too
    assert "would replace OUTPUT" in _one_error_line(res, tmp_path / "g.json") and not (tmp_path / "g.json").exists()
    res = _run("export", out / source, "--nav2", out / "nav2.geojson")  # beside them: fine, and noted
    assert res.exit_code == 0, res.output


# --------------------------------------------------------------------------
# Settings the run record cannot hold (JSON has no NaN): refused as options, before anything runs
# --------------------------------------------------------------------------

@pytest.mark.parametrize("at", ["nan", "inf", "-1"])
def test_a_bag_time_that_is_not_a_time_is_refused_as_the_option(tmp_path, at):
    m = io.save_map(_two_rooms(), tmp_path / "m")
    line = _one_error_line(_run("segment", m, "-o", tmp_path / "out", "--time", at), "--time")
    assert "must be seconds >= 0" in line and "JSON" not in line, line  # was: "Out of range float values are
    assert not (tmp_path / "out").exists()  # not JSON compliant: nan" (the run record)


@pytest.mark.parametrize("options", [dict(resolution=float("inf")), dict(write_options={"at": float("nan")})])
def test_segment_many_refuses_settings_json_cannot_hold(tmp_path, options):
    from topomap.errors import ParameterError
    from topomap.run.batch import segment_many

    m = io.save_map(_two_rooms(), tmp_path / "m")
    with pytest.raises(ParameterError, match="must be"):
        segment_many([m], tmp_path / "out", **options)
    assert not (tmp_path / "out").exists()


# --------------------------------------------------------------------------
# Room graph files: a door to a room the file does not have
# --------------------------------------------------------------------------

def _segment_out(tmp_path):
    out = tmp_path / "out"
    assert _run("segment", io.save_map(_two_rooms(), tmp_path / "m"), "-o", out).exit_code == 0
    return out


def _door_to_room_77(out, fmt):
    import json

    if fmt == "graphml":
        text = (out / "rooms.graphml").read_text()
        assert 'target="2"' in text
        return text.replace('target="2"', 'target="77"')
    data = json.loads((out / f"rooms.{fmt}").read_text())
    if fmt == "json":
        data["edges"][0]["target"] = 77
    else:
        (door,) = [f for f in data["features"] if f["properties"].get("kind") == "door"]
        door["properties"]["rooms"] = [1, 77]
    return json.dumps(data)


@pytest.mark.parametrize("fmt", ["graphml", "json", "geojson"])
def test_a_door_to_a_room_the_file_lacks_is_refused(tmp_path, fmt):
    out = _segment_out(tmp_path)
    g = tmp_path / f"g.{fmt}"
    g.write_text(_door_to_room_77(out, fmt))
    for res in (_run("tour", g, "--from-room", 1), _run("export", g, tmp_path / "x.json")):
        line = _one_error_line(res, g)  # was: tour exit 3 "internal error: KeyError: 'x'"; export "3 rooms"
        assert "joins room" in line and "77" in line and "not a room of the graph" in line, line
    assert not (tmp_path / "x.json").exists()


@pytest.mark.parametrize("keep, ok", [(("id", "polygon", "area", "cells"), True), (("id",), False)])
def test_a_room_without_its_position_is_no_internal_error(tmp_path, keep, ok):
    """A hand-made room with its outline but no x, y or interior point is visited at a cell of it; one with
    nothing is refused in one line (both were exit 3: KeyError 'x')."""
    import json

    out = _segment_out(tmp_path)
    data = json.loads((out / "rooms.json").read_text())
    data["nodes"][1] = {k: v for k, v in data["nodes"][1].items() if k in keep}
    g = tmp_path / "g.json"
    g.write_text(json.dumps(data))
    res = _run("tour", g, "--from-room", 2)
    if ok:
        assert res.exit_code == 0 and "order: 2 -> 1" in res.output, res.output
    else:
        assert "room 2 has no cells" in _one_error_line(res, g)
