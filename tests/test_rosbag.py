"""ROS bags in, ROS messages and map_server files out (topomap.io.ros), without ROS.

The input bags are written here with rosbags' own writers and message
classes, in the three formats (ROS 1 .bag, ROS 2 sqlite3, ROS 2 MCAP), so
reading is tested against bags topomap did not write.
"""

import array
import importlib.util
import json
import math
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import topomap
from topomap.io import export
from topomap.io import ros
from topomap.errors import BagError, MapError, MapFileNotFoundError, MissingDependencyError, ParameterError
from topomap.io import FREE, OCCUPIED, UNKNOWN, from_array, load_map

rosbags = pytest.importorskip("rosbags", reason="rosbags not installed (pip install -e '.[ros]')")
from rosbags.highlevel import AnyReader  # noqa: E402
from rosbags.rosbag1 import Writer as Writer1  # noqa: E402
from rosbags.rosbag2 import StoragePlugin, Writer as Writer2  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
TS2 = get_typestore(Stores.ROS2_HUMBLE)
TS1 = get_typestore(Stores.ROS1_NOETIC)
FORMATS = ["ros1", "sqlite3", "mcap"]
S = 1_000_000_000  # ns per second

#: What map_saver (ROS 1 and Nav2, default thresholds 25 / 65) makes of a cell value.
EXPECTED = {-128: UNKNOWN, -2: UNKNOWN, -1: UNKNOWN, 0: FREE, 1: FREE, 25: FREE, 26: UNKNOWN, 50: UNKNOWN,
            64: UNKNOWN, 65: OCCUPIED, 99: OCCUPIED, 100: OCCUPIED, 101: UNKNOWN, 127: UNKNOWN}


# --------------------------------------------------------------------------
# Bags written with rosbags directly
# --------------------------------------------------------------------------

def occ_msg(ts, data, width, height, *, res=0.05, x=0.0, y=0.0, yaw=0.0, quat=None, frame="map", stamp=0):
    """A nav_msgs/OccupancyGrid built from rosbags' classes (data in ROS order)."""
    T = ts.types
    time = T["builtin_interfaces/msg/Time"](sec=stamp // S, nanosec=stamp % S)
    hdr = dict(stamp=time, frame_id=frame)
    if "seq" in {f for f, _ in ts.fielddefs["std_msgs/msg/Header"][1]}:
        hdr["seq"] = 0
    q = quat if quat is not None else (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
    pose = T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=x, y=y, z=0.25),
                                       orientation=T["geometry_msgs/msg/Quaternion"](*q))
    info = T["nav_msgs/msg/MapMetaData"](map_load_time=time, resolution=res, width=width, height=height, origin=pose)
    return T["nav_msgs/msg/OccupancyGrid"](header=T["std_msgs/msg/Header"](**hdr), info=info,
                                           data=np.asarray(data, np.int8).ravel())


def string_msg(ts, text):
    return ts.types["std_msgs/msg/String"](data=text)


def write(path, fmt, records):
    """Write ``records`` [(topic, msgtype, build(ts), t_ns)] as a bag of ``fmt``; return its path."""
    path = Path(path)
    if fmt == "ros1":
        path = path.with_suffix(".bag")
        writer, ts, serialize = Writer1(path), TS1, TS1.serialize_ros1
    else:
        plugin = StoragePlugin.MCAP if fmt == "mcap" else StoragePlugin.SQLITE3
        writer, ts, serialize = Writer2(path, version=9, storage_plugin=plugin), TS2, TS2.serialize_cdr
    with writer as w:
        conns = {}
        for topic, typ, build, t in records:
            if topic not in conns:
                conns[topic] = w.add_connection(topic, typ, typestore=ts)
            w.write(conns[topic], t, serialize(build(ts), typ))
    return path


def one_map(tmp_path, fmt, data, width, height, *, topic="/map", t=S, **kw):
    return write(tmp_path / f"run_{fmt}", fmt, [(topic, ros.MAP_TYPE, lambda ts: occ_msg(ts, data, width, height, **kw), t)])


def value_map():
    """(data, width, height): every value of EXPECTED, in ROS order, twice over."""
    vals = list(EXPECTED) * 2
    width = 7
    height = len(vals) // width
    return np.asarray(vals[:width * height], np.int8), width, height


def single_files(bag, fmt):
    """Every path a user can give for ``bag``: the bag, and a ROS 2 bag's storage file."""
    if fmt == "ros1":
        return [bag]
    return [bag, bag / f"{bag.name}.{'mcap' if fmt == 'mcap' else 'db3'}"]


# --------------------------------------------------------------------------
# Reading maps
# --------------------------------------------------------------------------

@pytest.mark.parametrize("fmt", FORMATS)
def test_cell_values_origin_and_yaw(tmp_path, fmt):
    data, w, h = value_map()
    x0, y0, yaw, res = 1.5, -2.0, 0.7, 0.05
    bag = one_map(tmp_path, fmt, data, w, h, res=res, x=x0, y=y0, yaw=yaw, frame="world", stamp=3 * S + 7)
    for path in single_files(bag, fmt):
        grid = load_map(path)
        assert isinstance(grid, ros.RosMap) and grid.shape == (h, w)
        assert grid.resolution == res  # float32 in the message, its shortest decimal back
        assert grid.origin[:2] == (x0, y0) and grid.origin[2] == pytest.approx(yaw, abs=1e-12)
        assert (grid.frame_id, grid.stamp, grid.topic, grid.log_time) == ("world", 3 * S + 7, "/map", S)
        assert grid.source == str(path)
        c, s = math.cos(yaw), math.sin(yaw)
        for j in range(h):          # ROS row j (from the origin), column i
            for i in range(w):
                v = int(data[j * w + i])
                assert grid.cells[h - 1 - j, i] == EXPECTED[v], (v, j, i)
                u, vv = (i + 0.5) * res, (j + 0.5) * res  # ROS: cell centre in the rotated map frame
                px, py = grid.pixel_to_world(h - 1 - j, i)
                assert (px, py) == pytest.approx((x0 + c * u - s * vv, y0 + s * u + c * vv), abs=1e-12)


def test_bag_reads_as_map_saver_then_map_server(tmp_path):
    """The cells equal what map_server reads from the files map_saver writes of the message."""
    rng = np.random.default_rng(3)
    h, w = 9, 11
    data = rng.integers(-128, 128, size=h * w).astype(np.int8)
    data[:10] = [-1, 0, 25, 26, 64, 65, 100, 101, 19, 20]
    bag = one_map(tmp_path, "mcap", data, w, h)
    grid = load_map(bag)
    img = np.where((data >= 0) & (data <= 25), 254, np.where((data >= 65) & (data <= 100), 0, 205))
    img = img.reshape(h, w)[::-1].astype(np.uint8)  # map_saver: image row 0 = top = last ROS row
    (tmp_path / "saved.pgm").write_bytes(b"P5\n%d %d\n255\n" % (w, h) + img.tobytes())
    # the YAML ROS 1's map_saver writes (Nav2's says free_thresh 0.25, which reads gray 205 as free)
    (tmp_path / "saved.yaml").write_text("image: saved.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\n"
                                         "occupied_thresh: 0.65\nfree_thresh: 0.196\n")
    np.testing.assert_array_equal(load_map(tmp_path / "saved.yaml").cells, grid.cells)
    assert {FREE, OCCUPIED, UNKNOWN} == set(np.unique(grid.cells))


def test_thresholds_are_map_savers(tmp_path):
    data = np.array([0, 10, 11, 30, 80, 81, 100, -1], np.int8)
    bag = one_map(tmp_path, "mcap", data, 8, 1)
    cells = load_map(bag, free_thresh=0.10, occupied_thresh=0.81).cells[0]
    np.testing.assert_array_equal(cells, [FREE, FREE, UNKNOWN, UNKNOWN, UNKNOWN, OCCUPIED, OCCUPIED, UNKNOWN])
    with pytest.raises(ParameterError, match="free_thresh"):
        load_map(bag, free_thresh=0.9, occupied_thresh=0.5)
    with pytest.raises(ParameterError, match="negate and mode"):
        load_map(bag, negate=True)


def test_unset_ros1_quaternion_is_yaw_zero_and_tilt_is_refused(tmp_path):
    data, w, h = value_map()
    bag = one_map(tmp_path, "ros1", data, w, h, quat=(0.0, 0.0, 0.0, 0.0))
    assert load_map(bag).origin == (0.0, 0.0, 0.0)
    tilted = (math.sin(0.1), 0.0, 0.0, math.cos(0.1))  # 0.2 rad roll
    bag = write(tmp_path / "tilted", "mcap",
                [("/map", ros.MAP_TYPE, lambda ts: occ_msg(ts, data, w, h, quat=tilted), S)])
    with pytest.raises(MapError, match="tilted") as err:
        load_map(bag)
    assert str(bag) in str(err.value)


def test_resolution_and_origin_arguments_override(tmp_path):
    data, w, h = value_map()
    bag = one_map(tmp_path, "mcap", data, w, h, res=0.05, x=1.0, y=1.0, yaw=0.3)
    grid = load_map(bag, resolution=0.1, origin=(5.0, 6.0, 0.0))
    assert (grid.resolution, grid.origin) == (0.1, (5.0, 6.0, 0.0))


def several_maps(tmp_path, fmt):
    """/chatter at 0.5 s, then maps of width 4, 5, 6 on /map at 1, 2, 3 s."""
    recs = [("/chatter", "std_msgs/msg/String", lambda ts: string_msg(ts, "hello"), S // 2)]
    for k, t in enumerate((1, 2, 3)):
        recs.append(("/map", ros.MAP_TYPE, lambda ts, w=4 + k: occ_msg(ts, np.zeros(w * 3), w, 3), t * S))
    return write(tmp_path / f"several_{fmt}", fmt, recs)


@pytest.mark.parametrize("fmt", FORMATS)
def test_several_messages_last_by_default_time_picks_another(tmp_path, fmt):
    bag = several_maps(tmp_path, fmt)
    assert load_map(bag).shape == (3, 6)
    assert load_map(bag, topic="/map").log_time == 3 * S
    # seconds after the bag's start (0.5 s, the /chatter message): the last map at or before
    assert load_map(bag, time=0.5).shape == (3, 4)
    assert load_map(bag, time=1.49).shape == (3, 4)
    assert load_map(bag, time=1.5).shape == (3, 5)
    assert load_map(bag, time=1000).shape == (3, 6)
    with pytest.raises(BagError, match=r"no message on /map at or before 0.4 s \(the first is at 0.5 s\)"):
        load_map(bag, time=0.4)
    for bad in (-1, float("nan"), "soon", True):
        with pytest.raises(ParameterError, match="time must be"):
            load_map(bag, time=bad)


# --------------------------------------------------------------------------
# Errors: one line, naming the file
# --------------------------------------------------------------------------

def _one_line_naming(exc, path):
    text = str(exc)
    assert "\n" not in text and str(path) in text, text
    return text


@pytest.mark.parametrize("fmt", FORMATS)
def test_missing_topic_other_type_and_no_map_topic(tmp_path, fmt):
    bag = several_maps(tmp_path, fmt)
    with pytest.raises(BagError) as err:
        load_map(bag, topic="/maps")
    assert "no topic /maps" in _one_line_naming(err.value, bag) and "/map (nav_msgs/msg/OccupancyGrid)" in str(err.value)
    with pytest.raises(BagError) as err:
        load_map(bag, topic="/chatter")
    assert "/chatter is std_msgs/msg/String, not nav_msgs/msg/OccupancyGrid" in _one_line_naming(err.value, bag)
    chat = write(tmp_path / f"chat_{fmt}", fmt,
                 [("/chatter", "std_msgs/msg/String", lambda ts: string_msg(ts, "x"), S)])
    with pytest.raises(BagError) as err:
        load_map(chat)
    assert "no nav_msgs/msg/OccupancyGrid topic" in _one_line_naming(err.value, chat)


def test_several_map_topics_need_a_choice(tmp_path):
    mk = lambda ts: occ_msg(ts, np.zeros(4), 2, 2)  # noqa: E731
    bag = write(tmp_path / "two", "mcap", [("/map", ros.MAP_TYPE, mk, S), ("/local_map", ros.MAP_TYPE, mk, S)])
    with pytest.raises(BagError) as err:
        load_map(bag)
    assert "several map topics (/local_map, /map)" in _one_line_naming(err.value, bag)
    assert load_map(bag, topic="/local_map").topic == "/local_map"


@pytest.mark.parametrize("fmt", FORMATS)
def test_empty_bag(tmp_path, fmt):
    empty = write(tmp_path / f"empty_{fmt}", fmt, [])
    with pytest.raises(BagError) as err:
        load_map(empty)
    assert "the bag is empty" in _one_line_naming(err.value, empty)


@pytest.mark.parametrize("name, content", [
    ("junk.mcap", b"\x89MCAP0\r\n" + b"\x00" * 50),
    ("junk.bag", b"#ROSBAG V2.0\n" + b"x" * 100),
    ("junk.db3", b"SQLite format 3\x00" + b"x" * 200),
    ("text.mcap", b"not a bag at all"),
])
def test_corrupt_file(tmp_path, name, content):
    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(BagError) as err:
        load_map(path)
    assert "not a readable bag" in _one_line_naming(err.value, path)


@pytest.mark.parametrize("fmt", ["ros1", "mcap"])
def test_truncated_bag(tmp_path, fmt):
    data, w, h = value_map()
    bag = one_map(tmp_path, fmt, data, w, h)
    src = bag if fmt == "ros1" else bag / f"{bag.name}.mcap"
    cut = tmp_path / f"cut{src.suffix}"
    cut.write_bytes(src.read_bytes()[: src.stat().st_size // 2])
    with pytest.raises(BagError) as err:
        load_map(cut)
    _one_line_naming(err.value, cut)


def test_missing_bag_and_directory_without_metadata(tmp_path):
    with pytest.raises(MapFileNotFoundError) as err:
        load_map(tmp_path / "nope.mcap")
    _one_line_naming(err.value, tmp_path / "nope.mcap")
    (tmp_path / "dir.mcap").mkdir()
    with pytest.raises(BagError, match="without metadata.yaml"):
        load_map(tmp_path / "dir.mcap")


def test_topic_and_time_are_for_bags_only(tmp_path):
    with pytest.raises(ParameterError, match="topic and time apply to ROS bags"):
        load_map(topomap.example_map_path(), topic="/map")


def test_without_rosbags_a_clear_error(tmp_path, monkeypatch):
    data, w, h = value_map()
    bag = one_map(tmp_path, "mcap", data, w, h)
    for mod in [m for m in sys.modules if m == "rosbags" or m.startswith("rosbags.")]:
        monkeypatch.setitem(sys.modules, mod, None)  # import fails as if not installed
    with pytest.raises(MissingDependencyError) as err:
        load_map(bag)
    assert "pip install 'topomap-rooms[ros]'" in _one_line_naming(err.value, bag)
    assert isinstance(err.value, ImportError)


# --------------------------------------------------------------------------
# Messages and bags written by topomap
# --------------------------------------------------------------------------

@pytest.fixture(scope="module")
def seg():
    """The example office, moved and turned (origin with yaw), segmented."""
    g = load_map(topomap.example_map_path())
    return topomap.segment(from_array(g.cells, resolution=g.resolution, origin=(3.0, -1.0, 0.4)))


def check_markers(ma, seg, frame="map"):
    M = TS2.types["visualization_msgs/msg/Marker"]
    G = seg.room_graph
    assert ma.markers[0].action == M.DELETEALL
    by_ns = {}
    for m in ma.markers[1:]:
        assert m.header.frame_id == frame and m.action == M.ADD
        by_ns.setdefault(m.ns, {})[m.id] = m
    assert set(by_ns) == {"rooms", "room_numbers", "doors"}
    assert set(by_ns["rooms"]) == set(by_ns["room_numbers"]) == set(G.nodes) and len(G) == seg.n_rooms > 1
    for n, m in by_ns["rooms"].items():
        poly = G.nodes[n]["polygon"]
        rings = list(poly.geoms) if hasattr(poly, "geoms") else [poly]
        n_seg = sum(len(r.coords) - 1 for p in rings for r in [p.exterior, *p.interiors])
        assert m.type == M.LINE_LIST and len(m.points) == 2 * n_seg
        from shapely.geometry import Point

        assert max(poly.boundary.distance(Point(p.x, p.y)) for p in m.points) < 1e-9
    for n, m in by_ns["room_numbers"].items():
        assert m.type == M.TEXT_VIEW_FACING and m.text == str(n)
        assert (m.pose.position.x, m.pose.position.y) == (G.nodes[n]["x"], G.nodes[n]["y"])
    doors = {d.id: d for d in seg.doors}
    assert set(by_ns["doors"]) == set(doors) and doors
    for i, m in by_ns["doors"].items():
        assert m.type == M.LINE_LIST
        assert [(p.x, p.y) for p in m.points] == [tuple(map(float, doors[i].xy1)), tuple(map(float, doors[i].xy2))]


def test_marker_array_and_label_image(seg):
    check_markers(ros.marker_array(seg), seg)
    check_markers(ros.marker_array(seg, frame_id="building"), seg, "building")
    img = ros.label_image(seg, stamp=5 * S + 1)
    h, w = seg.labels.shape
    assert (img.height, img.width, img.encoding, img.is_bigendian, img.step) == (h, w, "mono16", 0, 2 * w)
    assert (img.header.stamp.sec, img.header.stamp.nanosec) == (5, 1)
    np.testing.assert_array_equal(np.frombuffer(img.data.tobytes(), "<u2").reshape(h, w), seg.labels)
    for bad in (0, -1, float("inf"), "thin"):
        with pytest.raises(ParameterError, match="line_width"):
            ros.marker_array(seg, line_width=bad)


def test_map_message_round_trip(seg):
    msg = ros.map_message(seg.grid, frame_id="map", stamp=2 * S)
    back = ros.grid_from_message(TS2.deserialize_cdr(ros.to_cdr(msg), ros.MAP_TYPE))
    np.testing.assert_array_equal(back.cells, seg.grid.cells)
    assert back.resolution == seg.grid.resolution
    assert back.origin == pytest.approx(seg.grid.origin, abs=1e-12)
    assert (back.frame_id, back.stamp) == ("map", 2 * S)


def test_cdr_round_trip_of_marker_array(seg):
    ma = ros.marker_array(seg)
    back = TS2.deserialize_cdr(ros.to_cdr(ma), ros.MARKER_ARRAY_TYPE)
    check_markers(back, seg)


@pytest.mark.parametrize("name", ["out.mcap", "out.bag", "outdir"])
def test_write_bag_round_trip(tmp_path, seg, name):
    path = ros.write_bag(seg, tmp_path / name, log_time=7 * S)
    assert path == tmp_path / name and path.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temporary left
    with AnyReader([path]) as reader:
        topics = {c.topic: c for c in reader.connections}
        assert {t: c.msgtype for t, c in topics.items()} == {
            "/map": ros.MAP_TYPE, "/topomap/rooms": ros.MARKER_ARRAY_TYPE, "/topomap/labels": ros.IMAGE_TYPE}
        if name == "out.bag":
            assert all(c.ext.latching == 1 for c in topics.values())
        else:
            assert all(c.ext.offered_qos_profiles[0].durability.name == "TRANSIENT_LOCAL" for c in topics.values())
        got = {}
        for conn, t, raw in reader.messages():
            assert t == 7 * S
            got[conn.topic] = reader.deserialize(raw, conn.msgtype)
    check_markers(got["/topomap/rooms"], seg)
    img = got["/topomap/labels"]
    np.testing.assert_array_equal(np.frombuffer(bytes(img.data), "<u2").reshape(img.height, img.width), seg.labels)
    grid = load_map(path)  # the /map of the bag, read back
    np.testing.assert_array_equal(grid.cells, seg.grid.cells)
    assert grid.resolution == seg.grid.resolution and grid.origin == pytest.approx(seg.grid.origin, abs=1e-12)


def test_bag_frame_and_stamp_carried_through(tmp_path):
    g = load_map(topomap.example_map_path())
    data = g.cells[::-1].ravel()
    bag = one_map(tmp_path, "mcap", data, g.shape[1], g.shape[0], frame="level2", stamp=42 * S, t=50 * S)
    s = topomap.segment(load_map(bag))
    out = ros.write_bag(s, tmp_path / "res.mcap")
    with AnyReader([out]) as reader:
        for conn, t, raw in reader.messages():
            m = reader.deserialize(raw, conn.msgtype)
            assert t == 50 * S
            hdr = m.markers[1].header if conn.topic == "/topomap/rooms" else m.header
            assert (hdr.frame_id, hdr.stamp.sec) == ("level2", 42)


def test_write_bag_refuses(tmp_path, seg):
    (tmp_path / "taken").mkdir()
    with pytest.raises(Exception, match="exists already"):
        ros.write_bag(seg, tmp_path / "taken")
    with pytest.raises(ParameterError, match="not .db3"):
        ros.write_bag(seg, tmp_path / "x.db3")
    with pytest.raises(MapFileNotFoundError):
        ros.write_bag(seg, tmp_path / "no" / "x.mcap")
    (tmp_path / "old.mcap").write_bytes(b"old")
    ros.write_bag(seg, tmp_path / "old.mcap")  # a file is replaced, atomically
    assert load_map(tmp_path / "old.mcap").shape == seg.grid.shape


# --------------------------------------------------------------------------
# The example node's message building (the node itself needs rclpy)
# --------------------------------------------------------------------------

def test_example_node_builds_messages_from_an_rclpy_like_message():
    spec = importlib.util.spec_from_file_location("ros2_node_example", ROOT / "examples" / "ros2_node.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)  # no rclpy needed to import it
    g = load_map(topomap.example_map_path())
    h, w = g.shape
    # rclpy message fields: plain attributes, data an array.array('b') (no numpy)
    ns = SimpleNamespace
    msg = ns(header=ns(stamp=ns(sec=12, nanosec=5), frame_id="map"),
             info=ns(map_load_time=ns(sec=0, nanosec=0), resolution=0.05, width=w, height=h,
                     origin=ns(position=ns(x=-1.0, y=2.0, z=0.0),
                               orientation=ns(x=0.0, y=0.0, z=math.sin(0.2), w=math.cos(0.2)))),
             data=array.array("b", g.cells[::-1].ravel().tolist()))
    seg, markers, labels = mod.segment_map_message(msg)
    assert seg.grid.origin == pytest.approx((-1.0, 2.0, 0.4), abs=1e-12)
    np.testing.assert_array_equal(seg.grid.cells, g.cells)
    ma = TS2.deserialize_cdr(markers, ros.MARKER_ARRAY_TYPE)
    check_markers(ma, seg)
    assert ma.markers[1].header.stamp.sec == 12
    img = TS2.deserialize_cdr(labels, ros.IMAGE_TYPE)
    np.testing.assert_array_equal(np.frombuffer(bytes(img.data), "<u2").reshape(h, w), seg.labels)


# --------------------------------------------------------------------------
# map_server label map and GeoJSON frame
# --------------------------------------------------------------------------

def test_label_map_pair_reads_as_map_server_raw(tmp_path, seg):
    from topomap.run.job import write_segmentation

    out = write_segmentation(seg, tmp_path, overlay=False)
    assert out["label_map"] == tmp_path / "labels.yaml" and (tmp_path / "labels.pgm").is_file()
    labels, res, origin = export.load_label_map(tmp_path / "labels.yaml")
    np.testing.assert_array_equal(labels, seg.labels)
    assert (res, origin) == (seg.grid.resolution, seg.grid.origin)
    # map_server (Nav2) raw mode: value 0..100 kept, anything else -1
    cells = load_map(tmp_path / "labels.yaml").cells
    np.testing.assert_array_equal(cells, np.where(seg.labels <= 100, seg.labels, -1))
    assert (seg.labels <= 100).all() and seg.labels.max() >= seg.n_rooms


def test_label_map_above_100_labels_is_unknown_to_map_server(tmp_path):
    labels = np.arange(120, dtype=np.int32).reshape(10, 12)
    yml = export.save_label_map(labels, tmp_path / "many", resolution=0.1)
    np.testing.assert_array_equal(load_map(yml).cells, np.where(labels <= 100, labels, -1))
    np.testing.assert_array_equal(export.load_label_map(yml)[0], labels)


def test_geojson_says_map_frame_metres_not_wgs84(tmp_path, seg):
    path = export.save_geojson(seg.room_graph, tmp_path / "rooms.geojson")
    props = json.loads(path.read_text())["properties"]
    note = props["coordinate_system"]
    assert "metres in the map frame" in note and "not WGS 84" in note
    assert "coordinate_system" not in export.load_geojson(path).graph


# --------------------------------------------------------------------------
# Command line
# --------------------------------------------------------------------------

def run_cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "topomap.cli", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=300)


def test_cli_segment_bag_to_bag(tmp_path):
    g = load_map(topomap.example_map_path())
    bag = write(tmp_path / "office", "sqlite3", [
        ("/map", ros.MAP_TYPE, lambda ts: occ_msg(ts, np.zeros(12), 4, 3), S),
        ("/map", ros.MAP_TYPE, lambda ts: occ_msg(ts, g.cells[::-1].ravel(), g.shape[1], g.shape[0], yaw=0.3), 2 * S)])
    r = run_cli("segment", bag, "--topic", "/map", "-o", tmp_path / "out", "--bag", tmp_path / "res.mcap",
                cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "8 rooms" in r.stdout
    assert {"labels.pgm", "labels.yaml", "labels.png", "rooms.geojson"} <= {p.name for p in (tmp_path / "out").iterdir()}
    back = load_map(tmp_path / "res.mcap")
    np.testing.assert_array_equal(back.cells, g.cells)
    assert back.origin[2] == pytest.approx(0.3)
    r = run_cli("segment", bag, "--time", "0", "-o", tmp_path / "out0", cwd=tmp_path)
    assert r.returncode == 0 and "0 rooms" in r.stdout, r.stdout + r.stderr


def test_cli_errors(tmp_path):
    bag = several_maps(tmp_path, "ros1")
    for args, text in [(("--topic", "/nope"), "no topic /nope"),
                       (("--topic", "/chatter"), "is std_msgs/msg/String"),
                       (("--time", "0.1"), "no message on /map at or before 0.1 s")]:
        r = run_cli("segment", bag, "-o", tmp_path / "o", *args, cwd=tmp_path)
        assert r.returncode == 1, r.stderr
        lines = r.stderr.strip().splitlines()
        assert len(lines) == 1 and str(bag) in lines[0] and text in lines[0], r.stderr
    r = run_cli("segment", bag, bag, "-o", tmp_path / "o", "--bag", tmp_path / "r.mcap", cwd=tmp_path)
    assert r.returncode == 1 and "one map" in r.stderr
    r = run_cli("segment", topomap.example_map_path(), "-o", tmp_path / "o", "--topic", "/map", cwd=tmp_path)
    assert r.returncode == 1 and "apply to ROS bags" in r.stderr
    (tmp_path / "taken").mkdir()
    r = run_cli("segment", bag, "-o", tmp_path / "o2", "--bag", tmp_path / "taken", cwd=tmp_path)
    assert r.returncode == 1 and "exists already" in r.stderr and not (tmp_path / "o2").exists()
