"""Hostile and odd inputs, second part: concurrent batches, outputs that land together, inputs bounded by
their own size, messages that name the right file. Each test failed before its fix."""

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from topomap import io
from topomap.cli import main

ROOT = Path(__file__).resolve().parents[1]


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def _one_error_line(res, name, code=1):
    """The CLI's output is one error line naming ``name``, exit ``code``."""
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert res.exit_code == code, res.output
    assert len(lines) == 1 and lines[0].startswith("error: ") and str(name) in lines[0], res.output
    assert "internal" not in res.output and " object at 0x" not in res.output and "Traceback" not in res.output
    return lines[0]


def _two_rooms():
    a = np.zeros((60, 100), bool)
    a[4:56, 4:48] = True
    a[4:56, 52:96] = True
    a[24:36, 48:52] = True
    return a


def _maps(tmp_path, names=("a", "b", "c")):
    return [io.save_map(_two_rooms(), tmp_path / n) for n in names]


# --------------------------------------------------------------------------
# Two batches into one -o at once: the second is refused, the first's results stay
# --------------------------------------------------------------------------

_HOLDER = textwrap.dedent("""
    import sys
    import topomap.run.batch as b
    run = b._run_one
    def held(task):  # the batch is running: it waits here until told to go on
        print("running", flush=True)
        sys.stdin.readline()
        return run(task)
    b._run_one = held
    rows = b.segment_many(sys.argv[2:], sys.argv[1])
    print(" ".join(r["status"] for r in rows), flush=True)
""")


def test_two_batches_into_one_folder_the_second_is_refused(tmp_path):
    maps = _maps(tmp_path)
    out = tmp_path / "out"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    first = subprocess.Popen([sys.executable, "-c", _HOLDER, str(out), *map(str, maps)], stdin=subprocess.PIPE,
                             stdout=subprocess.PIPE, text=True, env=env, cwd=tmp_path)
    try:
        assert first.stdout.readline().strip() == "running"
        before = sorted(p.relative_to(out) for p in out.rglob("*"))
        res = _run("segment", *maps, "-o", out)  # a second process-wide batch into the same folder
        line = _one_error_line(res, out)
        assert "another topomap run" in line, line
        assert sorted(p.relative_to(out) for p in out.rglob("*")) == before  # it wrote nothing
    finally:
        out_text, _ = first.communicate("go\ngo\ngo\n", timeout=120)
    assert first.returncode == 0 and out_text.splitlines()[-1] == "ok ok ok", out_text
    assert not (out / ".topomap.lock").exists()  # the lock goes with the batch
    res = _run("segment", *maps, "-o", out)  # the folder is free again: up to date
    assert res.exit_code == 0 and "3 of them up to date" in res.output, res.output


# --------------------------------------------------------------------------
# A map's outputs, the --bag included, land together or not at all
# --------------------------------------------------------------------------

def _tree(folder):
    """Every file of ``folder``: its bytes, and its size and time (the run record: its bytes only)."""
    return {p.name: (p.read_bytes(), None if p.name == "topomap_run.json" else (p.stat().st_size, p.stat().st_mtime_ns))
            for p in folder.iterdir()}


def test_a_bag_that_fails_writes_no_other_output(tmp_path):
    pytest.importorskip("rosbags")
    from topomap.run.batch import FAILED, OK, SKIPPED, segment_many

    (m,) = _maps(tmp_path, ["a"])
    out = tmp_path / "out"
    blocked = tmp_path / "taken.mcap"
    blocked.mkdir()  # the bag's name is a folder now: writing the bag fails
    (row,) = segment_many([m], out, write_options={"bag": str(blocked)})
    assert row["status"] == FAILED and "taken.mcap" in row["error"]
    assert not out.exists()  # no output without its bag, no run record missing beside outputs
    good = tmp_path / "good.mcap"
    (row,) = segment_many([m], out, write_options={"bag": str(good)})  # the folder is not refused
    assert row["status"] == OK and good.is_file()
    earlier, bag_bytes = _tree(out), good.read_bytes()
    # a rerun whose bag fails leaves the earlier outputs, the bag and the run record as they were
    (row,) = segment_many([m], out, overwrite=True, write_options={"bag": str(blocked)})
    assert row["status"] == FAILED
    assert _tree(out) == earlier and good.read_bytes() == bag_bytes
    (row,) = segment_many([m], out, write_options={"bag": str(good)})
    assert row["status"] == SKIPPED


def test_outputs_that_fail_write_no_bag(tmp_path, monkeypatch):
    pytest.importorskip("rosbags")
    from topomap.io import export
    from topomap.run.batch import FAILED, segment_many

    (m,) = _maps(tmp_path, ["a"])

    def broken(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(export, "save_geojson", broken)
    bag = tmp_path / "a.mcap"
    (row,) = segment_many([m], tmp_path / "out", write_options={"bag": str(bag)})
    assert row["status"] == FAILED and "rooms.geojson" in row["error"], row["error"]
    assert not bag.exists() and not (tmp_path / "out").exists()
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []  # no temporary left


# --------------------------------------------------------------------------
# --previous and tour graphs: room IDs bounded, the frame bounded by the map being segmented
# --------------------------------------------------------------------------

def _graph_file(tmp_path, name="g.json", edit=None):
    """rooms.json of the two-room map (``topomap segment``), its node-link data edited by ``edit``."""
    out = tmp_path / "g_out"
    if not (out / "rooms.json").exists():
        res = _run("segment", io.save_map(_two_rooms(), tmp_path / "g"), "-o", out)
        assert res.exit_code == 0, res.output
    data = json.loads((out / "rooms.json").read_text())
    if edit is not None:
        edit(data)
    path = tmp_path / name
    path.write_text(json.dumps(data))
    return path


def _renumber(data, old, new):
    for n in data["nodes"]:
        if n["id"] == old:
            n["id"] = new
    for e in data["edges"]:
        for k in ("source", "target"):
            if e[k] == old:
                e[k] = new


@pytest.mark.parametrize("bad", [1.5, -5, 0, 1e15, 100_000_000, True])
def test_previous_and_tour_graph_room_ids_are_refused_in_one_line(tmp_path, bad):
    g = _graph_file(tmp_path, edit=lambda d: _renumber(d, 1, bad))
    m = io.save_map(_two_rooms(), tmp_path / "m")
    line = _one_error_line(_run("segment", m, "-o", tmp_path / "out", "--previous", g), g)
    assert "room ID" in line and repr(bad) in line, line
    assert not (tmp_path / "out").exists()
    line = _one_error_line(_run("tour", g, "--from", 1, 1), g)
    assert "room ID" in line, line


@pytest.mark.parametrize("bad", [2147483647, 65536, -1, "x"])
def test_previous_next_room_id_is_bounded(tmp_path, bad):
    g = _graph_file(tmp_path, edit=lambda d: d["graph"].__setitem__("next_room_id", bad))
    m = io.save_map(_two_rooms(), tmp_path / "m")
    line = _one_error_line(_run("segment", m, "-o", tmp_path / "out", "--previous", g), g)
    assert "next_room_id" in line, line


def test_previous_graph_with_the_largest_ids_still_matches(tmp_path):
    """IDs up to the bound work, and cost nothing of their size: a new room gets next_room_id."""
    from topomap.io.export import MAX_ROOM_ID

    def edit(d):
        _renumber(d, 2, MAX_ROOM_ID - 1)
        d["nodes"] = [n for n in d["nodes"] if n["id"] != MAX_ROOM_ID - 1]  # that room is new again
        d["edges"] = []
        d["graph"]["next_room_id"] = MAX_ROOM_ID

    g = _graph_file(tmp_path, edit=edit)
    m = io.save_map(_two_rooms(), tmp_path / "m")
    res = _run("segment", m, "-o", tmp_path / "out", "--previous", g)
    assert res.exit_code == 0, res.output
    ids = sorted(n["id"] for n in json.loads((tmp_path / "out" / "rooms.json").read_text())["nodes"])
    assert ids == [1, MAX_ROOM_ID]


def test_previous_graph_claiming_a_huge_frame_costs_the_map_size(tmp_path):
    """40 room polygons over a 7000 x 7000 frame (a few KB): rasterised only where the map is."""
    import shapely
    from topomap.io.export import load_graph
    from topomap.core.identity import _Previous

    def edit(d):
        d["graph"]["shape"] = [7000, 7000]
        wkt = shapely.box(0, 0, 350, 350).wkt
        for n in d["nodes"]:
            n["polygon"] = wkt
        for i in range(3, 41):
            d["nodes"].append(dict(d["nodes"][0], id=i))

    g = _graph_file(tmp_path, edit=edit)
    assert g.stat().st_size < 20_000
    grid = io.from_array(_two_rooms(), resolution=0.05)
    prev = _Previous(load_graph(g), within=grid)
    assert prev.labels.size <= 64 * 104  # the map's 60 x 100 cells and a margin, not 49 M
    m = io.save_map(_two_rooms(), tmp_path / "m")
    res = _run("segment", m, "-o", tmp_path / "out", "--previous", g)
    assert res.exit_code == 0, res.output


def test_previous_graph_of_a_much_finer_frame_is_refused(tmp_path):
    def edit(d):
        d["graph"]["resolution"] = 0.001  # 50 x finer than the map: 2,500 x its cells where they overlap
        d["graph"]["shape"] = [7000, 7000]

    g = _graph_file(tmp_path, edit=edit)
    m = io.save_map(_two_rooms(), tmp_path / "m")
    line = _one_error_line(_run("segment", m, "-o", tmp_path / "out", "--previous", g), g)
    assert "more than 16 times" in line, line


# --------------------------------------------------------------------------
# The map size limit: the memory the job takes against the memory the machine has
# --------------------------------------------------------------------------

def test_the_size_limit_follows_the_memory(monkeypatch):
    from topomap import grid
    from topomap.errors import MapTooLargeError, ParameterError

    assert io.MAX_CELLS is None  # no fixed limit by default
    monkeypatch.delenv("TOPOMAP_MAX_CELLS", raising=False)
    # the decision: 150 bytes per cell + 250 MB (measured worst case) against the memory available
    assert io.cells_for_memory(24e9) == int((24e9 - 250e6) // 150)
    monkeypatch.setattr(grid, "available_memory", lambda: 22_000_000_000)  # this 24 GB machine, idle
    grid.check_image_size("warehouse.png", 8000, 8000)  # 400 m at 5 cm: 64 M cells, about 9.9 GB: accepted
    monkeypatch.setattr(grid, "available_memory", lambda: 8_000_000_000)
    with pytest.raises(MapTooLargeError, match=r"^warehouse.png: image is 8000 x 8000 px = 64,000,000 cells, more "
                                               r"than the 51,666,666 cells the free memory allows \(8.0 GB"):
        grid.check_image_size("warehouse.png", 8000, 8000)
    monkeypatch.setattr(grid, "MEMORY_SHARERS", 2)  # two maps at once share it
    assert io.cell_limit()[0] == io.cells_for_memory(4e9)
    monkeypatch.setattr(grid, "MEMORY_SHARERS", 1)
    monkeypatch.setattr(grid, "available_memory", lambda: None)  # unreadable: the 8 GiB assumption
    assert io.cell_limit()[0] == io.FALLBACK_MAX_CELLS
    # the overrides: the environment, then topomap.io.MAX_CELLS
    monkeypatch.setenv("TOPOMAP_MAX_CELLS", "100")
    with pytest.raises(MapTooLargeError, match=r"<array>: map is 11 x 10 cells = 110, more than TOPOMAP_MAX_CELLS = 100"):
        io.from_array(np.ones((10, 11), bool))
    monkeypatch.setenv("TOPOMAP_MAX_CELLS", "64e6")
    assert io.cell_limit()[0] == 64_000_000
    monkeypatch.setattr(io, "MAX_CELLS", 5)
    assert io.cell_limit() == (5, "topomap.io.MAX_CELLS = 5")
    monkeypatch.setattr(io, "MAX_CELLS", None)
    for bad in ("lots", "-3", "1.5", "inf"):
        monkeypatch.setenv("TOPOMAP_MAX_CELLS", bad)
        with pytest.raises(ParameterError, match="TOPOMAP_MAX_CELLS must be a whole number"):
            io.cell_limit()


def test_available_memory_is_read():
    avail = io.available_memory()
    if not Path("/proc/meminfo").exists():
        pytest.skip("no /proc/meminfo")
    assert isinstance(avail, int) and 0 < avail < 1 << 50


def test_the_size_limit_env_reaches_the_command(tmp_path):
    m = io.save_map(_two_rooms(), tmp_path / "m")
    env = dict(os.environ, PYTHONPATH=str(ROOT), TOPOMAP_MAX_CELLS="5999")
    res = subprocess.run([sys.executable, "-m", "topomap.cli", "segment", str(m), "-o", str(tmp_path / "out")],
                         capture_output=True, text=True, env=env, cwd=tmp_path)
    assert res.returncode == 1 and "TOPOMAP_MAX_CELLS = 5,999" in res.stderr, res.stderr
    assert len(res.stderr.splitlines()) == 1


# --------------------------------------------------------------------------
# --jobs: never more processes than maps or CPU cores
# --------------------------------------------------------------------------

def test_jobs_are_capped_by_the_maps_and_the_cores(tmp_path, monkeypatch):
    import concurrent.futures as cf

    from topomap.run.batch import segment_many, worker_count

    started = []

    class Pool(cf.ThreadPoolExecutor):  # records how many workers a batch asks for; runs them as threads
        def __init__(self, max_workers=None, initializer=None, initargs=()):
            started.append(max_workers)
            super().__init__(max_workers=max_workers)

    monkeypatch.setattr(cf, "ProcessPoolExecutor", Pool)
    monkeypatch.setattr(os, "cpu_count", lambda: 8)
    rows = segment_many(_maps(tmp_path), tmp_path / "out", jobs=24)
    assert [r["status"] for r in rows] == ["ok"] * 3
    assert started == [3]
    assert worker_count(24, 100) == 8 and worker_count(1, 0) == 1


# --------------------------------------------------------------------------
# Bags: the map's size from the message header before decoding; compressed bags bounded
# --------------------------------------------------------------------------

def _occ(ts, width, height, frame="map", fill=0):
    import math

    T = ts.types
    time = T["builtin_interfaces/msg/Time"](sec=1, nanosec=0)
    hdr = dict(stamp=time, frame_id=frame)
    if "seq" in {f for f, _ in ts.fielddefs["std_msgs/msg/Header"][1]}:
        hdr["seq"] = 0
    pose = T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=0.0, y=0.0, z=0.0),
                                       orientation=T["geometry_msgs/msg/Quaternion"](0.0, 0.0, 0.0, math.cos(0)))
    info = T["nav_msgs/msg/MapMetaData"](map_load_time=time, resolution=0.05, width=width, height=height,
                                         origin=pose)
    return T["nav_msgs/msg/OccupancyGrid"](header=T["std_msgs/msg/Header"](**hdr), info=info,
                                           data=np.full(width * height, fill, np.int8))


def _bag(path, width, height, *, storage="mcap", compression=None):
    from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    w = Writer(path, version=9, storage_plugin=StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3)
    if compression is not None:
        w.set_compression(getattr(CompressionMode, compression), CompressionFormat.ZSTD)
    with w:
        conn = w.add_connection("/map", "nav_msgs/msg/OccupancyGrid", typestore=ts)
        w.write(conn, 10**9, ts.serialize_cdr(_occ(ts, width, height), "nav_msgs/msg/OccupancyGrid"))
    return path


def test_map_size_is_read_from_the_message_header():
    pytest.importorskip("rosbags")
    from rosbags.typesys import Stores, get_typestore

    from topomap.io.ros import _map_size

    ts2, ts1 = get_typestore(Stores.ROS2_HUMBLE), get_typestore(Stores.ROS1_NOETIC)
    for frame in ("", "m", "ma", "map", "mapx", "a_longer_frame_name"):
        raw2 = bytes(ts2.serialize_cdr(_occ(ts2, 7, 3, frame), "nav_msgs/msg/OccupancyGrid"))
        raw1 = bytes(ts1.serialize_ros1(_occ(ts1, 7, 3, frame), "nav_msgs/msg/OccupancyGrid"))
        assert _map_size(raw2, True) == (7, 3) and _map_size(raw1, False) == (7, 3)
    assert _map_size(b"\x00\x01", True) is None


def test_bag_map_over_the_cell_bound_is_refused_before_decoding(tmp_path, monkeypatch):
    pytest.importorskip("rosbags")
    from rosbags.highlevel import AnyReader

    from topomap.errors import MapTooLargeError

    bag = _bag(tmp_path / "big", 200, 150)

    def decode(*args, **kwargs):
        raise AssertionError("decoded")

    monkeypatch.setattr(AnyReader, "deserialize", decode)
    monkeypatch.setattr(io, "MAX_CELLS", 10_000)
    with pytest.raises(MapTooLargeError, match=r"big: map is 200 x 150 cells = 30,000, more than "
                                               r"topomap.io.MAX_CELLS = 10,000"):
        io.load_map(bag)


@pytest.mark.parametrize("storage, compression", [("mcap", "STORAGE"), ("sqlite3", "FILE"), ("sqlite3", "MESSAGE"),
                                                  ("mcap", "FILE"), ("mcap", "MESSAGE")])
def test_compressed_bag_that_expands_hugely_is_refused(tmp_path, monkeypatch, storage, compression):
    pytest.importorskip("rosbags")
    import tempfile

    from topomap.io import ros
    from topomap.errors import BagError

    bag = _bag(tmp_path / "bomb", 2000, 2000, storage=storage, compression=compression)  # 4 MB of zeros
    packed = sum(f.stat().st_size for f in bag.iterdir())
    assert packed < 100_000
    grid = io.load_map(bag)  # within the default bound: read
    assert grid.shape == (2000, 2000)
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(scratch))
    monkeypatch.setattr(ros, "MIN_EXPANSION_BYTES", 1 << 20)  # so that 4 MB is "huge" here
    monkeypatch.setattr(ros, "MAX_EXPANSION", 10)
    with pytest.raises(BagError, match=r"bomb: .*expands to more than 1,048,576 bytes .*refused before decompressing"):
        io.load_map(bag)
    assert list(scratch.iterdir()) == []  # nothing decompressed into the temporary folder
    res = _run("segment", bag, "-o", tmp_path / "out")
    _one_error_line(res, bag)


def _ros1_bag(path, width, height, compression):
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC)
    w = Writer(path)
    w.set_compression(getattr(Writer.CompressionFormat, compression))
    with w:
        conn = w.add_connection("/map", "nav_msgs/msg/OccupancyGrid", typestore=ts)
        w.write(conn, 10**9, ts.serialize_ros1(_occ(ts, width, height), "nav_msgs/msg/OccupancyGrid"))
    return path


@pytest.mark.parametrize("compression", ["BZ2", "LZ4"])
def test_compressed_ros1_bag_that_expands_hugely_is_refused(tmp_path, monkeypatch, compression):
    pytest.importorskip("rosbags")
    from topomap.io import ros
    from topomap.errors import BagError

    bag = _ros1_bag(tmp_path / "bomb.bag", 2000, 2000, compression)  # 4 MB of zeros in one chunk
    assert bag.stat().st_size < 100_000
    assert io.load_map(bag).shape == (2000, 2000)  # within the default bound: read
    monkeypatch.setattr(ros, "MIN_EXPANSION_BYTES", 1 << 20)  # so that 4 MB is "huge" here
    monkeypatch.setattr(ros, "MAX_EXPANSION", 10)
    with pytest.raises(BagError, match=r"bomb.bag: a chunk of bomb.bag expands to more than 1,048,576 bytes "
                                       r".*refused before decompressing"):
        io.load_map(bag)
    _one_error_line(_run("segment", bag, "-o", tmp_path / "out"), bag)


def test_ros1_chunk_whose_size_header_lies_is_refused(tmp_path):
    """A chunk that says it holds 1,000 bytes and expands to 4 MB: its size header is not taken on trust."""
    pytest.importorskip("rosbags")
    import struct

    from topomap.errors import BagError

    bag = _ros1_bag(tmp_path / "liar.bag", 2000, 2000, "BZ2")
    raw = bytearray(bag.read_bytes())
    at = raw.index(b"size=") + 5
    assert struct.unpack_from("<I", raw, at)[0] >= 4_000_000
    struct.pack_into("<I", raw, at, 1000)
    bag.write_bytes(bytes(raw))
    with pytest.raises(BagError, match=r"liar.bag: a chunk of liar.bag expands to more than the 1,000 bytes its "
                                       r"header says"):
        io.load_map(bag)


# --------------------------------------------------------------------------
# Messages name the file at fault, and show no internals
# --------------------------------------------------------------------------

@pytest.mark.parametrize("key, value, words", [
    ("resolution", 0, "resolution must be > 0"),
    ("resolution", 1e300, "resolution must be between"),
    ("origin", "[NaN, 0, 0]", "origin must be finite"),
    ("shape", [0, 0], "two whole numbers >= 1"),
    ("shape", [1.5, 2], "1.5 is not a whole number"),
])
def test_a_bad_previous_graph_frame_is_blamed_on_the_graph(tmp_path, key, value, words):
    g = _graph_file(tmp_path, edit=lambda d: d["graph"].__setitem__(key, value))
    m = io.save_map(_two_rooms(), tmp_path / "m")
    for res in (_run("segment", m, "-o", tmp_path / "out", "--previous", g), _run("tour", g, "--from", 1, 1)):
        line = _one_error_line(res, g)
        assert words in line and "<array>" not in line and "m.yaml" not in line, line


def test_a_previous_room_outside_its_frame_is_no_internal_error(tmp_path):
    def edit(d):  # room 1's outline far outside the map frame the graph claims
        d["nodes"][0]["polygon"] = "POLYGON ((1000 1000, 1001 1000, 1001 1001, 1000 1001, 1000 1000))"

    g = _graph_file(tmp_path, edit=edit)
    m = io.save_map(_two_rooms(), tmp_path / "m")
    res = _run("segment", m, "-o", tmp_path / "out", "--previous", g)  # was: "m.yaml: negative dimensions ..."
    assert res.exit_code == 0, res.output
    assert "1 kept, 1 new, 1 vanished" in res.output


def test_an_output_folder_that_is_a_file_is_named_as_such(tmp_path):
    maps = _maps(tmp_path, ["a", "b"])
    out = tmp_path / "out"
    out.mkdir()
    (out / "a").write_text("my notes\n")
    line = _one_error_line(_run("segment", *maps, "-o", out), out / "a")
    assert "exists and is not a folder" in line and "unreadable run record" not in line, line
    assert sorted(p.name for p in out.iterdir()) == ["a"] and (out / "a").read_text() == "my notes\n"


# --------------------------------------------------------------------------
# A YAML whose free_thresh reads map_saver's unknown gray 205 as free: one warning
# --------------------------------------------------------------------------

def _saver_map(tmp_path, free_thresh, unknown=True):
    """A map_saver image (254 free, 0 walls, 205 unknown around) and a YAML with ``free_thresh``."""
    from PIL import Image

    g = np.full((80, 120), 205 if unknown else 0, np.uint8)
    g[10:70, 10:110] = 0
    g[12:68, 12:108] = 254
    g[12:68, 59:61] = 0
    g[35:45, 59:61] = 254
    Image.fromarray(g).save(tmp_path / "depot.pgm")
    (tmp_path / "depot.yaml").write_text(f"image: depot.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n"
                                         f"negate: 0\noccupied_thresh: 0.65\nfree_thresh: {free_thresh}\n")
    return tmp_path / "depot.yaml"


def test_unknown_gray_read_as_free_is_warned(tmp_path, caplog):
    y = _saver_map(tmp_path, 0.25)  # Nav2's depot.yaml
    with caplog.at_level("WARNING", logger="topomap"):
        grid = io.load_map(y)
    assert (grid.cells == io.FREE).sum() > 80 * 120 - 60 * 100  # the unknown ring is read as free (map_server's rule)
    msgs = [r.getMessage() for r in caplog.records if "gray 205" in r.getMessage()]
    assert len(msgs) == 1 and msgs[0].startswith(str(y)) and "free_thresh 0.25" in msgs[0], msgs
    assert "at most 0.195" in msgs[0]
    res = subprocess.run([sys.executable, "-m", "topomap.cli", "segment", str(y), "-o", str(tmp_path / "out")],
                         capture_output=True, text=True, env=dict(os.environ, PYTHONPATH=str(ROOT)), cwd=tmp_path)
    warned = [ln for ln in res.stderr.splitlines() if "gray 205" in ln]  # the command line shows it, once
    assert res.returncode == 0 and len(warned) == 1 and warned[0].startswith("WARNING"), res.stderr


@pytest.mark.parametrize("free_thresh, unknown", [(0.196, True), (0.25, False)])
def test_no_warning_when_205_is_unknown_or_absent(tmp_path, caplog, free_thresh, unknown):
    y = _saver_map(tmp_path, free_thresh, unknown)
    with caplog.at_level("WARNING", logger="topomap"):
        io.load_map(y)
    assert not [r for r in caplog.records if "gray 205" in r.getMessage()]


# --------------------------------------------------------------------------
# map.pgm beside the map.yaml that names it: read through the YAML
# --------------------------------------------------------------------------

def _graph_resolution(out):
    return json.loads((out / "rooms.json").read_text())["graph"]["resolution"]


def test_an_image_beside_its_yaml_is_read_through_it(tmp_path, caplog):
    y = io.save_map(_two_rooms(), tmp_path / "map", resolution=0.1, origin=(2.0, 3.0, 0.0))
    pgm = tmp_path / "map.pgm"
    with caplog.at_level("INFO", logger="topomap"):
        res = _run("segment", pgm, "-o", tmp_path / "out")
    assert res.exit_code == 0, res.output
    assert _graph_resolution(tmp_path / "out") == 0.1  # the YAML's, not the bare image's 0.05
    assert _run("segment", y, "-o", tmp_path / "via_yaml").exit_code == 0
    a, b = (json.loads((tmp_path / d / "rooms.json").read_text()) for d in ("out", "via_yaml"))
    assert a == b  # the same rooms, doors and frame (the map it names is the YAML)
    said = [r.getMessage() for r in caplog.records if "read through" in r.getMessage()]
    assert len(said) == 1 and said[0].startswith(f"{pgm}: read through map.yaml"), said
    # --resolution: the image alone, at that resolution, without a word
    caplog.clear()
    with caplog.at_level("INFO", logger="topomap"):
        assert _run("segment", pgm, "-o", tmp_path / "alone", "--resolution", 0.05).exit_code == 0
    assert _graph_resolution(tmp_path / "alone") == 0.05
    assert not [r for r in caplog.records if "read through" in r.getMessage() or "beside it" in r.getMessage()]
    # the YAML is an input of the run: changing it runs the map again
    y.write_text(y.read_text().replace("resolution: 0.1", "resolution: 0.08"))
    res = _run("segment", pgm, "-o", tmp_path / "out")
    assert res.exit_code == 0 and "skipped" not in res.output and _graph_resolution(tmp_path / "out") == 0.08


def test_an_image_beside_a_yaml_of_another_image_is_warned(tmp_path, caplog):
    io.save_map(_two_rooms(), tmp_path / "other", resolution=0.1)
    io.save_map(_two_rooms(), tmp_path / "map", resolution=0.1)
    (tmp_path / "map.yaml").write_text((tmp_path / "other.yaml").read_text())  # names other.pgm
    with caplog.at_level("WARNING", logger="topomap"):
        res = _run("segment", tmp_path / "map.pgm", "-o", tmp_path / "out")
    assert res.exit_code == 0 and _graph_resolution(tmp_path / "out") == 0.05
    said = [r.getMessage() for r in caplog.records if "beside it" in r.getMessage()]
    assert len(said) == 1 and "names another image ('other.pgm')" in said[0] and "at 0.05 m per cell" in said[0]
