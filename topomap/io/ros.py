"""ROS without a ROS installation: maps from bags, results as ROS messages and bags.

Built on the pure-Python `rosbags <https://pypi.org/project/rosbags/>`_
library (``pip install 'topomap-rooms[ros]'``), imported only when a function here
needs it. It reads and writes ROS 1 bags (``.bag``) and ROS 2 bags (a
directory with ``metadata.yaml`` and sqlite3 ``.db3`` or ``.mcap`` storage,
or a single ``.db3`` / ``.mcap`` file), with the standard message types.

Reading (:func:`read_map`, also reached through :func:`topomap.io.load_map`)
    A ``nav_msgs/OccupancyGrid`` from a bag topic, the last message by
    default. Its cells are classified exactly as ``map_saver`` writes them
    and ``map_server`` reads them back (see :func:`occupancy_cells`); its
    resolution and origin, yaw included, are kept.
Messages (:func:`map_message`, :func:`marker_array`, :func:`label_image`)
    The map, the rooms and doors (``visualization_msgs/MarkerArray``) and
    the room labels (``sensor_msgs/Image``, ``mono16``) as ``rosbags``
    message objects. A ROS 2 node turns them into its own ``rclpy`` messages
    with ``rclpy.serialization.deserialize_message(to_cdr(msg), MsgType)``.
Writing (:func:`write_bag`)
    Those three messages into a new bag that ``ros2 bag play`` (or ``rosbag
    play``) replays for RViz.

All messages are in the map frame: the frame of the grid's origin
(``frame_id`` of the OccupancyGrid read from a bag, ``"map"`` otherwise).
"""

from __future__ import annotations

import io
import math
import os
import shutil
import struct
import tempfile
from contextlib import contextmanager
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from time import time_ns
from typing import Optional

import numpy as np

from ..errors import (BagError, MapError, MapFileError, MapFileNotFoundError, MapTooLargeError,
                      MissingDependencyError, ParameterError, TopomapError, one_line)
from ..grid import FREE, OCCUPIED, UNKNOWN, OccupancyGrid, cell_limit
from ..options import check_length
from .metadata import as_float, check_thresholds, yaml_loader
from .plot import room_colors

__all__ = [
    "MAP_TYPE",
    "MARKER_ARRAY_TYPE",
    "IMAGE_TYPE",
    "MAP_TOPIC",
    "MARKERS_TOPIC",
    "LABELS_TOPIC",
    "SAVER_FREE_THRESH",
    "SAVER_OCCUPIED_THRESH",
    "BAG_SUFFIXES",
    "RosMap",
    "is_bag",
    "occupancy_cells",
    "grid_from_message",
    "read_map",
    "typestore",
    "map_message",
    "marker_array",
    "label_image",
    "to_cdr",
    "check_bag_path",
    "write_bag",
]

MAP_TYPE = "nav_msgs/msg/OccupancyGrid"
MARKER_ARRAY_TYPE = "visualization_msgs/msg/MarkerArray"
IMAGE_TYPE = "sensor_msgs/msg/Image"

#: Topics :func:`write_bag` writes.
MAP_TOPIC = "/map"
MARKERS_TOPIC = "/topomap/rooms"
LABELS_TOPIC = "/topomap/labels"

#: map_saver's default thresholds (ROS 1 ``map_saver --free 25 --occ 65``,
#: Nav2 ``map_saver_cli`` ``free_thresh 0.25``, ``occupied_thresh 0.65``).
SAVER_FREE_THRESH = 0.25
SAVER_OCCUPIED_THRESH = 0.65

#: File suffixes read as bags (a directory with ``metadata.yaml`` is one too).
BAG_SUFFIXES = (".bag", ".mcap", ".db3")

_PLANAR_TOL = 1e-6  # rad: largest roll/pitch of a map origin taken as planar
_LINE_Z = 0.02      # m: outlines and doors drawn just above the map plane in RViz
_TEXT_Z = 0.05


# --------------------------------------------------------------------------
# rosbags, imported on demand
# --------------------------------------------------------------------------

def _rosbags(name: str):
    """The rosbags package, or a one-line MissingDependencyError naming ``name``."""
    try:
        import rosbags.highlevel  # noqa: F401
        import rosbags.rosbag1  # noqa: F401
        import rosbags.rosbag2  # noqa: F401
        import rosbags.typesys  # noqa: F401
    except ImportError:
        raise MissingDependencyError(
            f"{name}: reading and writing ROS bags and messages needs the 'rosbags' package: "
            f"pip install 'topomap-rooms[ros]'") from None
    import rosbags

    return rosbags


@lru_cache(maxsize=None)
def _store(kind: str):
    from rosbags.typesys import Stores, get_typestore

    return get_typestore({"ros1": Stores.ROS1_NOETIC, "ros2": Stores.ROS2_HUMBLE}[kind])


def typestore(*, ros1: bool = False):
    """The ``rosbags`` typestore topomap builds messages with.

    Parameters
    ----------
    ros1 : bool
        ROS 1 (Noetic) definitions instead of ROS 2 (Humble; the messages
        used here serialize the same in every later ROS 2 distribution).

    Returns
    -------
    rosbags.typesys.store.Typestore

    Raises
    ------
    MissingDependencyError
        ``rosbags`` is not installed.
    """
    _rosbags("<ros>")
    return _store("ros1" if ros1 else "ros2")


# --------------------------------------------------------------------------
# Reading a map
# --------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class RosMap(OccupancyGrid):
    """An :class:`~topomap.io.OccupancyGrid` read from a ROS message.

    Attributes
    ----------
    frame_id : str
        ``header.frame_id`` of the message (``"map"`` when it was empty).
    stamp : int
        ``header.stamp`` in nanoseconds.
    topic : str or None
        Bag topic it was read from.
    log_time : int or None
        Time the bag recorded it, nanoseconds since the epoch.
    """

    frame_id: str = "map"
    stamp: int = 0
    topic: Optional[str] = None
    log_time: Optional[int] = None


def is_bag(path) -> bool:
    """Whether :func:`topomap.io.load_map` reads ``path`` as a ROS bag.

    True for a ``.bag``, ``.mcap`` or ``.db3`` path and for a directory
    holding ``metadata.yaml`` (a ROS 2 bag). Looks at the name and the
    directory only; the bag is not opened.
    """
    p = Path(os.fspath(path))
    if p.suffix.lower() in BAG_SUFFIXES:
        return True
    try:
        return p.is_dir() and (p / "metadata.yaml").is_file()
    except OSError:
        return False


def occupancy_cells(data, width: int, height: int, *, free_thresh: float = SAVER_FREE_THRESH,
                    occupied_thresh: float = SAVER_OCCUPIED_THRESH, name: str = "<message>") -> np.ndarray:
    """Three-state cells of ``nav_msgs/OccupancyGrid`` data, as map_server gets them.

    A map in a bag reaches ``map_server`` (ROS 1 and Nav2) through
    ``map_saver``, which writes a cell with value ``v`` as free (gray 254)
    if ``0 <= v <= round(100 * free_thresh)``, as occupied (gray 0) if
    ``round(100 * occupied_thresh) <= v <= 100`` and as unknown (gray 205)
    otherwise: ``-1``, any other negative value, values above 100 and the
    values in between (ROS 1 ``map_server/src/map_saver.cpp`` with
    ``threshold_free = 25``, ``threshold_occupied = 65``; Nav2
    ``nav2_map_server/src/map_io.cpp``, ``tryWriteMapToFile``, trinary mode,
    defaults ``free_thresh = 0.25``, ``occupied_thresh = 0.65``).
    ``map_server`` in trinary mode with the thresholds ROS 1's map_saver
    writes in the YAML (``occupied_thresh: 0.65``, ``free_thresh: 0.196``)
    reads those grays back as ``OCCUPIED``, ``FREE`` and ``UNKNOWN``: the
    cells here are the cells that round trip gives. (Nav2's map_saver
    writes ``free_thresh: 0.25`` instead, and with it map_server reads the
    unknown gray 205, ``p = 50 / 255 = 0.196``, as free, a known pitfall;
    topomap keeps unknown cells unknown.) With the defaults:

    * ``0 .. 25``: ``FREE``;
    * ``65 .. 100``: ``OCCUPIED``;
    * ``26 .. 64``, ``-1``, any other negative value, ``101 .. 127``: ``UNKNOWN``.

    Parameters
    ----------
    data : sequence of int
        ``width * height`` values, row-major from the cell at the origin
        (the ROS order: row 0 is the bottom row, ``y`` up).
    width, height : int
        ``info.width`` and ``info.height``.
    free_thresh, occupied_thresh : float
        map_saver's thresholds, probabilities in ``[0, 1]``.
    name : str
        Used in messages.

    Returns
    -------
    (height, width) ndarray of int8
        ``FREE`` (0), ``OCCUPIED`` (100), ``UNKNOWN`` (-1), row 0 at the top
        (image order, as :class:`~topomap.io.OccupancyGrid` holds them).

    Raises
    ------
    MapError
        Empty, or not ``width * height`` values.
    MapTooLargeError
        More than :func:`topomap.io.cell_limit` cells.
    """
    occ_t, free_t = check_thresholds(name, occupied_thresh, free_thresh)
    w, h = int(width), int(height)
    if w <= 0 or h <= 0:
        raise MapError(f"{name}: the map is empty ({w} x {h} cells)")
    limit, why = cell_limit()
    if w * h > limit:
        raise MapTooLargeError(f"{name}: map is {w:,} x {h:,} cells = {w * h:,}, more than {why}")
    if isinstance(data, (bytes, bytearray, memoryview)):
        v = np.frombuffer(data, np.int8)
    else:
        v = np.asarray(data)
        if v.dtype.kind not in "iu":
            raise MapError(f"{name}: map data must be integers (int8), got dtype {v.dtype}")
    v = v.ravel()
    if v.size != w * h:
        raise MapError(f"{name}: map data has {v.size} values, width x height = {w} x {h} = {w * h}")
    free_max = int(round(100 * free_t))  # map_saver: std::rint(free_thresh * 100.0)
    occ_min = int(round(100 * occ_t))
    v = v.astype(np.int16)
    cells = np.full(v.shape, UNKNOWN, np.int8)
    cells[(v >= 0) & (v <= free_max)] = FREE
    cells[(v >= occ_min) & (v <= 100)] = OCCUPIED
    return cells.reshape(h, w)[::-1].copy()


def _yaw(q, name: str) -> float:
    """Yaw of quaternion ``q`` (x, y, z, w); refuses a tilted map plane."""
    x, y, z, w = (float(q.x), float(q.y), float(q.z), float(q.w))
    n = math.sqrt(x * x + y * y + z * z + w * w)
    if not math.isfinite(n):
        raise MapError(f"{name}: map origin orientation is not finite ({x}, {y}, {z}, {w})")
    if n == 0.0:  # an unset ROS 1 quaternion: tf and map_saver read it as yaw 0
        return 0.0
    x, y, z, w = x / n, y / n, z / n, w / n
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    if abs(roll) > _PLANAR_TOL or abs(pitch) > _PLANAR_TOL:
        raise MapError(f"{name}: map origin is tilted out of the x-y plane (roll {roll:.3g} rad, "
                       f"pitch {pitch:.3g} rad); topomap needs a planar map")
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def _float32_decimal(v) -> float:
    """The shortest decimal of a float32 value (0.05 stays 0.05, not 0.0500000007)."""
    return float(str(np.float32(v)))


def _stamp_ns(stamp) -> int:
    """Nanoseconds of a ``builtin_interfaces/Time`` stamp."""
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def grid_from_message(msg, *, source: Optional[str] = None, free_thresh: float = SAVER_FREE_THRESH,
                      occupied_thresh: float = SAVER_OCCUPIED_THRESH, resolution=None, origin=None,
                      topic: Optional[str] = None, log_time: Optional[int] = None) -> RosMap:
    """The grid of a ``nav_msgs/OccupancyGrid`` message (rosbags or rclpy).

    Parameters
    ----------
    msg : nav_msgs/OccupancyGrid
        Any object with the message's fields (``header``, ``info``,
        ``data``): a ``rosbags`` message, or an ``rclpy`` one in a node.
    source : str, optional
        Name used in messages (default ``<message>``).
    free_thresh, occupied_thresh : float
        map_saver's thresholds (see :func:`occupancy_cells`).
    resolution : float, optional
        Overrides ``info.resolution`` (m/px).
    origin : (x, y[, yaw]), optional
        Overrides ``info.origin``.
    topic, log_time
        Recorded in the result (see :class:`RosMap`).

    Returns
    -------
    RosMap
        ``cells`` classified by :func:`occupancy_cells`; ``resolution`` the
        message's float32 value as its shortest decimal; ``origin`` ``(x, y,
        yaw)`` of ``info.origin``, yaw from its quaternion (an all-zero
        quaternion, ROS 1's unset default, is yaw 0). The origin's ``z`` is
        dropped, as map_saver does. The yaw is honoured everywhere: every
        world coordinate topomap gives (rooms, doors, GeoJSON, markers) is
        in the map frame.

    Raises
    ------
    MapError
        Empty map, wrong data length, or an origin tilted out of the x-y
        plane (roll or pitch above 1e-6 rad), which map_saver would silently
        flatten and topomap refuses.
    ParameterError
        Resolution not > 0, non-finite origin, bad thresholds.
    """
    name = source or "<message>"
    try:
        info = msg.info
        header = msg.header
        data = msg.data
        o = info.origin
        res = _float32_decimal(info.resolution) if resolution is None else resolution
        org = (float(o.position.x), float(o.position.y), _yaw(o.orientation, name)) if origin is None else origin
        frame = str(header.frame_id) or "map"
        stamp = _stamp_ns(header.stamp)
        width, height = int(info.width), int(info.height)
    except TopomapError:
        raise
    except (AttributeError, TypeError, ValueError) as exc:
        raise MapError(one_line(f"{name}: not a nav_msgs/OccupancyGrid message ({exc})")) from None
    cells = occupancy_cells(data, width, height, free_thresh=free_thresh, occupied_thresh=occupied_thresh,
                            name=name)
    return RosMap(cells, res, org, source, frame_id=frame, stamp=stamp, topic=topic, log_time=log_time)


#: A compressed bag may expand to at most this many times its bytes on disk (or
#: :data:`MIN_EXPANSION_BYTES`, whichever is more): zstd and lz4 give a map a few
#: ten times at most; a small file that claims gigabytes is refused before any of
#: it is decompressed into memory or the temporary folder.
MAX_EXPANSION = 1000
MIN_EXPANSION_BYTES = 64 << 20

_MCAP_MAGIC = b"\x89MCAP0\r\n"
_ROS1_MAGIC = b"#ROSBAG V2.0\n"


def _decompressor(kind: str, raw):
    """A file object reading ``raw`` (a binary file object) decompressed by ``kind`` ('zstd', 'lz4'),
    or None for no compression."""
    if kind in ("", None):
        return None
    if kind == "zstd":
        try:
            from compression import zstd
        except ImportError:
            from backports import zstd
        return zstd.open(raw, "rb")
    if kind == "lz4":
        import lz4.frame

        return lz4.frame.open(raw, "rb")
    if kind == "bz2":
        import bz2

        return bz2.open(raw, "rb")
    return None  # an unknown compression: rosbags refuses it


def _expanded(stream, limit: int) -> int:
    """Bytes ``stream`` decompresses to, reading at most ``limit + 1`` of them (1 MiB at a time)."""
    n = 0
    with stream:
        while n <= limit:
            block = stream.read(min(1 << 20, limit + 1 - n))
            if not block:
                break
            n += len(block)
    return n


class _Budget:
    """The bytes a bag may decompress to in all: :data:`MAX_EXPANSION` times its packed bytes, at least
    :data:`MIN_EXPANSION_BYTES`; :meth:`spend` raises BagError past it."""

    def __init__(self, name: str, packed: int):
        self.name, self.packed = name, packed
        self.limit = max(MAX_EXPANSION * packed, MIN_EXPANSION_BYTES)
        self.total = 0

    @property
    def left(self) -> int:
        return self.limit - self.total

    def spend(self, n: int, what: str) -> None:
        self.total += n
        if self.total > self.limit:
            raise BagError(f"{self.name}: {what} expands to more than {self.limit:,} bytes ({MAX_EXPANSION} "
                           f"times the bag's {self.packed:,} bytes): refused before decompressing it")

    def chunk(self, kind: str, data: bytes, claimed: int, what: str) -> None:
        """Spend a chunk of compression ``kind`` whose header claims ``claimed`` bytes: refused when the
        claim is over the budget, or when ``data`` really expands to more than it claims."""
        if claimed > self.left:
            self.spend(claimed, what)
        stream = _decompressor(kind, io.BytesIO(data))
        if stream is not None:  # its size header may lie: count what it really expands to
            try:
                real = _expanded(stream, claimed)
            except Exception:  # noqa: BLE001 - corrupt data: rosbags reports it
                real = 0
            if real > claimed:
                raise BagError(f"{self.name}: {what} expands to more than the {claimed:,} bytes its header says")
        self.spend(claimed, what)


def _bag_files(p: Path, name: str):
    """``(files, compression mode, compression format)`` of bag ``p``: the file itself, or the files a
    ROS 2 bag directory's ``metadata.yaml`` lists."""
    if not p.is_dir():
        return [p], "", ""
    import yaml

    meta_path = p / "metadata.yaml"
    if meta_path.stat().st_size > 1 << 20:
        raise BagError(f"{name}: metadata.yaml is {meta_path.stat().st_size:,} bytes, more than 1 MiB")
    try:
        meta = yaml.load(meta_path.read_bytes(), Loader=yaml_loader())["rosbag2_bagfile_information"]
        files = [p / Path(str(f)).name for f in meta.get("relative_file_paths") or []]
        mode = str(meta.get("compression_mode") or "").lower()
        fmt = str(meta.get("compression_format") or "").lower()
    except Exception as exc:  # noqa: BLE001 - any odd metadata
        raise BagError(one_line(f"{name}: not a readable bag (metadata.yaml: "
                                f"{one_line(exc) or type(exc).__name__})")) from None
    return [f for f in files if f.is_file()], mode, fmt


def _check_expansion(p: Path, name: str):
    """BagError when bag ``p`` decompresses to more than :data:`MAX_EXPANSION` times its bytes: ROS 2
    file compression (each ``.zstd`` file), ROS 2 message compression (each message, in sqlite3 or MCAP),
    MCAP chunks and ROS 1 chunks (bz2, lz4; each chunk, its size header checked against its data).
    Streams, bounded memory."""
    files, mode, fmt = _bag_files(p, name)
    budget = _Budget(name, sum(f.stat().st_size for f in files))
    for f in files:
        if mode == "file" and fmt == "zstd":
            with open(f, "rb") as raw:
                budget.spend(_expanded(_decompressor("zstd", raw), budget.left), f"{f.name} (file compression)")
        elif mode == "message" and fmt == "zstd" and f.suffix == ".db3":
            _check_messages(f, budget)
        else:
            with open(f, "rb") as fh:
                magic = fh.read(len(_ROS1_MAGIC))
                if magic.startswith(_MCAP_MAGIC):
                    fh.seek(len(_MCAP_MAGIC))
                    _check_mcap_chunks(fh, f.name, budget, messages=mode == "message" and fmt == "zstd")
                elif magic == _ROS1_MAGIC:
                    _check_ros1_chunks(fh, f.name, budget)


def _check_messages(f: Path, budget: _Budget) -> None:
    """Spend every zstd-compressed message of the sqlite3 bag ``f``."""
    import sqlite3  # only a bag of zstd-compressed messages needs it (a C module some Pythons lack)

    con = sqlite3.connect(f"file:{f}?mode=ro", uri=True)
    try:
        for (data,) in con.execute("SELECT data FROM messages"):
            budget.spend(_expanded(_decompressor("zstd", io.BytesIO(data)), budget.left), f"a message of {f.name}")
    except sqlite3.Error:
        pass  # not a bag database: rosbags says so
    finally:
        con.close()


def _check_mcap_chunks(fh, name: str, budget: _Budget, messages: bool = False) -> None:
    """Spend every chunk of the MCAP file ``fh`` (read past its magic) and, with ``messages`` (a ROS 2 bag
    of zstd-compressed messages), every message in it."""
    while True:
        head = fh.read(9)
        if len(head) < 9:
            break
        op, length = struct.unpack("<BQ", head)
        if op == 0x05 and messages:
            _spend_message(fh.read(min(length, budget.packed)), name, budget)
            continue
        if op != 0x06:  # not a chunk
            fh.seek(length, 1)
            continue
        rec = fh.read(min(length, budget.packed))
        if len(rec) < 32:
            break
        claimed = struct.unpack_from("<Q", rec, 16)[0]
        (clen,) = struct.unpack_from("<I", rec, 28)
        kind = rec[32:32 + clen].decode("ascii", "replace")
        data = rec[32 + clen + 8:]
        budget.chunk(kind, data, claimed, f"an MCAP chunk of {name}")
        if messages:  # the chunk's records, at most its claimed size (within the budget: checked above)
            stream = _decompressor(kind, io.BytesIO(data))
            if stream is not None:
                with stream:
                    data = stream.read(claimed)
            _spend_chunk_messages(data, name, budget)


def _spend_chunk_messages(records: bytes, name: str, budget: _Budget) -> None:
    """Spend every message among the MCAP ``records`` of a chunk."""
    pos = 0
    while pos + 9 <= len(records):
        op, length = struct.unpack_from("<BQ", records, pos)
        if op == 0x05:
            _spend_message(records[pos + 9:pos + 9 + length], name, budget)
        pos += 9 + length


def _spend_message(content: bytes, name: str, budget: _Budget) -> None:
    """Spend the zstd-compressed data of an MCAP message record (after its channel, sequence and two
    times: 22 bytes)."""
    try:
        size = _expanded(_decompressor("zstd", io.BytesIO(content[22:])), budget.left)
    except Exception:  # noqa: BLE001 - corrupt data: rosbags reports it
        size = 0
    budget.spend(size, f"a message of {name}")


def _check_ros1_chunks(fh, name: str, budget: _Budget) -> None:
    """Spend every chunk of the ROS 1 bag ``fh`` (read past its magic line): records of a header (fields
    ``name=value``, each behind its length) and data, each behind its length; a chunk (``op`` 5) names
    its ``compression`` and its uncompressed ``size``."""
    while True:
        head = fh.read(4)
        if len(head) < 4:
            break
        header = fh.read(min(struct.unpack("<I", head)[0], budget.packed))
        fields, pos = {}, 0
        while pos + 4 <= len(header):
            (n,) = struct.unpack_from("<I", header, pos)
            key, _, value = header[pos + 4:pos + 4 + n].partition(b"=")
            fields[key] = value
            pos += 4 + n
        size = fh.read(4)
        if len(size) < 4:
            break
        (length,) = struct.unpack("<I", size)
        if fields.get(b"op") != b"\x05" or len(fields.get(b"size", b"")) != 4:
            fh.seek(length, 1)
            continue
        kind = fields.get(b"compression", b"none").decode("ascii", "replace")
        claimed = struct.unpack("<I", fields[b"size"])[0]
        budget.chunk("" if kind == "none" else kind, fh.read(min(length, budget.packed)), claimed,
                     f"a chunk of {name}")


def _map_size(raw: bytes, ros2: bool):
    """``(width, height)`` an OccupancyGrid message's header claims (``raw``: CDR, or ROS 1
    serialised), read before the message is decoded; None when it cannot be read."""
    try:
        if ros2:
            end = "<" if raw[1] & 1 else ">"
            pos = 4 + 8  # encapsulation, stamp
            (n,) = struct.unpack_from(end + "I", raw, pos)
            pos += 4 + n
            pos = 4 + -(-(pos - 4) // 4) * 4  # aligned to 4 (CDR alignment counts from after the encapsulation)
            pos += 8 + 4  # map_load_time, resolution
            return struct.unpack_from(end + "II", raw, pos)
        pos = 4 + 8  # seq, stamp
        (n,) = struct.unpack_from("<I", raw, pos)
        pos += 4 + n + 8 + 4
        return struct.unpack_from("<II", raw, pos)
    except (struct.error, IndexError):
        return None


def _topic_list(topics: dict) -> str:
    return ", ".join(f"{t} ({ty})" for t, ty in sorted(topics.items())) or "none"


def read_map(path, *, topic: Optional[str] = None, time: Optional[float] = None,
             free_thresh: Optional[float] = None, occupied_thresh: Optional[float] = None,
             resolution=None, origin=None) -> RosMap:
    """Read a ``nav_msgs/OccupancyGrid`` from a ROS 1 or ROS 2 bag.

    Parameters
    ----------
    path : str or os.PathLike
        A ROS 1 ``.bag``; a ROS 2 bag directory (``metadata.yaml`` with
        sqlite3 or MCAP storage); or a single ``.mcap`` or ``.db3`` file.
    topic : str, optional
        The map topic. Default: the bag's only ``nav_msgs/OccupancyGrid``
        topic (an error names them when there are several).
    time : float, optional
        Seconds after the start of the bag (its earliest message on any
        topic, as ``ros2 bag info`` / ``rosbag info`` count): the last map
        message recorded at or before it is read, i.e. the map as it was at
        that moment. Default: the last message on the topic.
    free_thresh, occupied_thresh : float, optional
        map_saver's thresholds (default 0.25, 0.65; see
        :func:`occupancy_cells`).
    resolution, origin : optional
        Override the message's, as they override a map YAML's.

    Returns
    -------
    RosMap
        With the message's ``frame_id``, ``stamp``, the ``topic`` and the
        recording time (``log_time``); see :func:`grid_from_message`.

    Raises
    ------
    MapFileNotFoundError
        No such file or directory.
    BagError
        Not a readable bag (corrupt, truncated, unknown format), an empty
        bag, no such topic, a topic of another type, several map topics and
        no ``topic``, no map message at or before ``time``.
    MapError, ParameterError
        The message holds no usable map (see :func:`grid_from_message`), or
        ``time`` is not a number >= 0.
    MissingDependencyError
        ``rosbags`` is not installed (``pip install 'topomap-rooms[ros]'``).
    """
    p = Path(os.fspath(path))
    name = str(p)
    if time is not None and as_float(name, "time", time) < 0:
        raise ParameterError(f"{name}: time must be seconds >= 0 after the start of the bag, got {time!r}")
    if topic is not None and (not isinstance(topic, str) or not topic.strip()):
        raise ParameterError(f"{name}: topic must be a topic name such as '/map', got {topic!r}")
    free_t = SAVER_FREE_THRESH if free_thresh is None else free_thresh
    occ_t = SAVER_OCCUPIED_THRESH if occupied_thresh is None else occupied_thresh
    check_thresholds(name, occ_t, free_t)
    if not p.exists():
        raise MapFileNotFoundError(f"{name}: no such bag")
    _rosbags(name)
    from rosbags.highlevel import AnyReader

    try:
        if p.is_dir() and not (p / "metadata.yaml").is_file():
            raise BagError(f"{name}: a directory without metadata.yaml is not a ROS 2 bag")
        if not p.is_dir() and p.suffix.lower() not in BAG_SUFFIXES:
            raise BagError(f"{name}: not a bag name (use .bag, .mcap, .db3 or a ROS 2 bag directory)")
        _check_expansion(p, name)
        with AnyReader([p], default_typestore=_store("ros2")) as reader:
            topics = {c.topic: c.msgtype for c in reader.connections}
            if not topics or reader.message_count == 0:
                raise BagError(f"{name}: the bag is empty (no messages)")
            if topic is None:
                maps = sorted(t for t, ty in topics.items() if ty == MAP_TYPE)
                if not maps:
                    raise BagError(one_line(f"{name}: no {MAP_TYPE} topic in the bag (topics: "
                                            f"{_topic_list(topics)})"))
                if len(maps) > 1:
                    raise BagError(one_line(f"{name}: several map topics ({', '.join(maps)}); "
                                            f"choose one with topic= (--topic)"))
                topic = maps[0]
            elif topic not in topics:
                raise BagError(one_line(f"{name}: no topic {topic} in the bag (topics: {_topic_list(topics)})"))
            elif topics[topic] != MAP_TYPE:
                raise BagError(f"{name}: topic {topic} is {topics[topic]}, not {MAP_TYPE}")
            conns = [c for c in reader.connections if c.topic == topic]
            start = reader.start_time
            limit = None if time is None else start + int(round(as_float(name, "time", time) * 1e9))
            chosen = first = None
            for conn, t, raw in reader.messages(connections=conns):
                first = t if first is None else first
                if limit is not None and t > limit:
                    break
                chosen = (conn, t, raw)
            if chosen is None:
                if first is None:
                    raise BagError(f"{name}: topic {topic} has no messages")
                raise BagError(f"{name}: no message on {topic} at or before {float(time):g} s "
                               f"(the first is at {(first - start) / 1e9:g} s)")
            conn, t, raw = chosen
            size = _map_size(raw, reader.is2)
            if size is not None:  # the cell bound from the message's header, before the message is decoded
                limit, why = cell_limit()
                if size[0] * size[1] > limit:
                    raise MapTooLargeError(f"{name}: map is {size[0]:,} x {size[1]:,} cells = "
                                           f"{size[0] * size[1]:,}, more than {why}")
            msg = reader.deserialize(raw, conn.msgtype)
    except TopomapError:
        raise
    except PermissionError as exc:
        raise MapFileError(f"{name}: cannot read bag: {exc.strerror or exc}") from None
    except Exception as exc:  # noqa: BLE001 - rosbags raises ReaderError, struct.error, KeyError, ...
        detail = one_line(exc) or type(exc).__name__
        raise BagError(one_line(f"{name}: not a readable bag ({detail})")) from None
    return grid_from_message(msg, source=name, free_thresh=free_t, occupied_thresh=occ_t,
                             resolution=resolution, origin=origin, topic=topic, log_time=t)


# --------------------------------------------------------------------------
# Building messages
# --------------------------------------------------------------------------

_NUMPY = {"bool": np.bool_, "byte": np.uint8, "char": np.uint8, "int8": np.int8, "uint8": np.uint8,
          "int16": np.int16, "uint16": np.uint16, "int32": np.int32, "uint32": np.uint32,
          "int64": np.int64, "uint64": np.uint64, "float32": np.float32, "float64": np.float64}


def _default(ts, desc):
    from rosbags.typesys.store import Nodetype

    kind, arg = desc
    if kind == Nodetype.BASE:
        t = arg[0]
        return "" if t == "string" else False if t == "bool" else 0.0 if t.startswith("float") else 0
    if kind == Nodetype.NAME:
        return _new(ts, arg)
    sub, n = arg
    if sub[0] == Nodetype.BASE and sub[1][0] in _NUMPY:
        return np.zeros(n if kind == Nodetype.ARRAY else 0, _NUMPY[sub[1][0]])
    return [_default(ts, sub) for _ in range(n if kind == Nodetype.ARRAY else 0)]


def _new(ts, typename: str, **values):
    """A message of ``typename`` from ``ts``; fields not given get ROS defaults."""
    _, fields = ts.fielddefs[typename]
    known = {f for f, _ in fields}
    extra = set(values) - known
    if extra:  # a field this distribution's message lacks (e.g. ROS 1 Header has seq, ROS 2 not)
        for k in extra:
            values.pop(k)
    for f, desc in fields:
        if f not in values:
            values[f] = _default(ts, desc)
    return ts.types[typename](**values)


def _stamp(ts, ns: int):
    return _new(ts, "builtin_interfaces/msg/Time", sec=int(ns // 1_000_000_000), nanosec=int(ns % 1_000_000_000))


def _header(ts, frame_id: str, ns: int):
    return _new(ts, "std_msgs/msg/Header", stamp=_stamp(ts, ns), frame_id=frame_id)


def _frame_and_stamp(grid, frame_id, stamp):
    frame = frame_id if frame_id is not None else getattr(grid, "frame_id", None) or "map"
    ns = stamp if stamp is not None else getattr(grid, "stamp", 0)
    if isinstance(ns, (bool, np.bool_)) or not isinstance(ns, (int, np.integer)) or ns < 0:
        raise ParameterError(f"{grid.name}: stamp must be an integer >= 0 (nanoseconds), got {ns!r}")
    if not isinstance(frame, str) or not frame:
        raise ParameterError(f"{grid.name}: frame_id must be a non-empty string, got {frame!r}")
    return frame, int(ns)


def _store_or_ros2(typestore):
    """``typestore`` when given, else the ROS 2 one (rosbags required)."""
    if typestore is not None:
        return typestore
    _rosbags("<ros>")
    return _store("ros2")


def _pose(ts, x=0.0, y=0.0, z=0.0, yaw=0.0):
    return _new(ts, "geometry_msgs/msg/Pose",
                position=_new(ts, "geometry_msgs/msg/Point", x=float(x), y=float(y), z=float(z)),
                orientation=_new(ts, "geometry_msgs/msg/Quaternion", x=0.0, y=0.0,
                                 z=math.sin(yaw / 2), w=math.cos(yaw / 2)))


def map_message(grid, *, frame_id: Optional[str] = None, stamp: Optional[int] = None, typestore=None):
    """The grid as a ``nav_msgs/OccupancyGrid`` message.

    Cells become ``0`` (free), ``100`` (occupied), ``-1`` (unknown), rows
    in ROS order (bottom row first); ``info.origin`` carries the grid's
    ``(x, y, yaw)``. Reading the message back (:func:`grid_from_message`)
    gives the same cells, resolution and origin.

    Parameters
    ----------
    grid : OccupancyGrid
    frame_id : str, optional
        Default the grid's own (:class:`RosMap`), else ``"map"``.
    stamp : int, optional
        ``header.stamp`` and ``info.map_load_time``, nanoseconds; default
        the grid's own, else 0.
    typestore : rosbags Typestore, optional
        Message definitions (default :func:`typestore`, ROS 2).

    Returns
    -------
    rosbags message of type ``nav_msgs/msg/OccupancyGrid``
    """
    ts = _store_or_ros2(typestore)
    frame, ns = _frame_and_stamp(grid, frame_id, stamp)
    h, w = grid.shape
    ox, oy, yaw = grid.origin
    info = _new(ts, "nav_msgs/msg/MapMetaData", map_load_time=_stamp(ts, ns), resolution=float(grid.resolution),
                width=int(w), height=int(h), origin=_pose(ts, ox, oy, 0.0, yaw))
    data = np.ascontiguousarray(grid.cells[::-1], dtype=np.int8).ravel()
    return _new(ts, MAP_TYPE, header=_header(ts, frame, ns), info=info, data=data)


def _rings(geom):
    """Coordinate arrays of every boundary ring of a Polygon/MultiPolygon."""
    if geom is None or geom.is_empty:
        return []
    polys = list(geom.geoms) if hasattr(geom, "geoms") else [geom]
    return [np.asarray(r.coords, float)[:, :2] for p in polys for r in [p.exterior, *p.interiors]]


def marker_array(seg, *, frame_id: Optional[str] = None, stamp: Optional[int] = None, line_width: float = 0.05,
                 text_height: float = 0.5, typestore=None):
    """Rooms and doors as a ``visualization_msgs/MarkerArray`` for RViz.

    In order: one ``DELETEALL`` marker (a new array replaces what an earlier
    one drew), then per room (namespace ``rooms``, id = room ID) a
    ``LINE_LIST`` of its outline (every ring of its polygon, holes
    included), per room (namespace ``room_numbers``) a ``TEXT_VIEW_FACING``
    with the room ID at its centroid, and per door (namespace ``doors``, id
    = door ID) a ``LINE_LIST`` from one door post to the other. Coordinates
    are map-frame metres (the room graph's ``polygon``, ``x``, ``y`` and
    ``x1, y1, x2, y2``), lines a little above the map plane. Rooms get the
    colours of :func:`topomap.io.plot.room_colors`; doors are red.

    Parameters
    ----------
    seg : Segmentation
    frame_id : str, optional
        ``header.frame_id`` of every marker; default the map's
        (:class:`RosMap`), else ``"map"``.
    stamp : int, optional
        ``header.stamp``, nanoseconds; default the map's, else 0.
    line_width : float
        Outline width, metres (doors are drawn twice as wide).
    text_height : float
        Height of the room numbers, metres.
    typestore : rosbags Typestore, optional
        Message definitions (default :func:`typestore`, ROS 2;
        ``typestore(ros1=True)`` for ROS 1).

    Returns
    -------
    rosbags message of type ``visualization_msgs/msg/MarkerArray``
    """
    ts = _store_or_ros2(typestore)
    frame, ns = _frame_and_stamp(seg.grid, frame_id, stamp)
    for key, v in (("line_width", line_width), ("text_height", text_height)):
        if check_length(key, v) == 0:
            raise ParameterError(f"{key} must be a length > 0 m, got {v!r}")
    Marker = ts.types["visualization_msgs/msg/Marker"]
    G = seg.room_graph
    colors = room_colors(seg.n_rooms)

    def point(x, y, z):
        return _new(ts, "geometry_msgs/msg/Point", x=float(x), y=float(y), z=float(z))

    def color(r, g, b, a=1.0):
        return _new(ts, "std_msgs/msg/ColorRGBA", r=float(r), g=float(g), b=float(b), a=float(a))

    def marker(namespace, marker_id, kind, pose=None, **kw):
        return _new(ts, "visualization_msgs/msg/Marker", header=_header(ts, frame, ns), ns=namespace,
                    id=int(marker_id), type=kind, action=Marker.ADD, pose=pose or _pose(ts), **kw)

    markers = [_new(ts, "visualization_msgs/msg/Marker", header=_header(ts, frame, ns), action=Marker.DELETEALL,
                    pose=_pose(ts))]
    rooms = sorted(G.nodes)
    for n in rooms:
        d = G.nodes[n]
        pts = []
        for ring in _rings(d.get("polygon")):
            for (x1, y1), (x2, y2) in zip(ring[:-1], ring[1:]):
                pts += [point(x1, y1, _LINE_Z), point(x2, y2, _LINE_Z)]
        if pts:
            c = colors[n] if n < len(colors) else (0.5, 0.5, 0.5, 1.0)
            markers.append(marker("rooms", n, Marker.LINE_LIST, points=pts, color=color(*c[:3]),
                                  scale=_new(ts, "geometry_msgs/msg/Vector3", x=float(line_width), y=0.0, z=0.0)))
    for n in rooms:
        d = G.nodes[n]
        markers.append(marker("room_numbers", n, Marker.TEXT_VIEW_FACING, pose=_pose(ts, d["x"], d["y"], _TEXT_Z),
                              text=str(n), color=color(0.0, 0.0, 0.0),
                              scale=_new(ts, "geometry_msgs/msg/Vector3", x=0.0, y=0.0, z=float(text_height))))
    for a, b, k, d in sorted(G.edges(keys=True, data=True), key=lambda e: e[2]):
        markers.append(marker("doors", d.get("door", k), Marker.LINE_LIST,
                              points=[point(d["x1"], d["y1"], _LINE_Z), point(d["x2"], d["y2"], _LINE_Z)],
                              color=color(1.0, 0.0, 0.0),
                              scale=_new(ts, "geometry_msgs/msg/Vector3", x=2.0 * float(line_width), y=0.0,
                                         z=0.0)))
    return _new(ts, MARKER_ARRAY_TYPE, markers=markers)


def label_image(seg, *, frame_id: Optional[str] = None, stamp: Optional[int] = None, typestore=None):
    """The room labels as a ``sensor_msgs/Image``, encoding ``mono16``.

    The image has the map's size and its pixels are the cells of the map:
    ``labels[row, col]`` (row 0 at the top, as in ``labels.png`` and a
    map_server PGM), little-endian 16-bit; 0 = not a room, ``1..n_rooms``
    the rooms, higher values fragments (see
    :class:`~topomap.core.segmentation.Segmentation`). The cell of pixel ``(row,
    col)`` is the OccupancyGrid cell ``(height - 1 - row, col)`` of the map;
    its map-frame position is ``seg.grid.pixel_to_world(row, col)``.

    Parameters
    ----------
    seg : Segmentation
    frame_id, stamp, typestore
        As for :func:`marker_array`.

    Returns
    -------
    rosbags message of type ``sensor_msgs/msg/Image``

    Raises
    ------
    ParameterError
        More than 65535 labels.
    """
    ts = _store_or_ros2(typestore)
    frame, ns = _frame_and_stamp(seg.grid, frame_id, stamp)
    labels = np.asarray(seg.labels)
    if labels.size and (labels.min() < 0 or labels.max() > 65535):
        raise ParameterError(f"{seg.grid.name}: labels must be in 0..65535 for a mono16 image")
    h, w = labels.shape
    data = np.frombuffer(np.ascontiguousarray(labels, dtype="<u2").tobytes(), np.uint8).copy()
    return _new(ts, IMAGE_TYPE, header=_header(ts, frame, ns), height=int(h), width=int(w), encoding="mono16",
                is_bigendian=0, step=int(2 * w), data=data)


def to_cdr(msg, *, typestore=None) -> bytes:
    """CDR bytes of a ROS 2 message built here (what ``rclpy`` (de)serializes).

    In a ROS 2 node::

        from rclpy.serialization import deserialize_message
        from visualization_msgs.msg import MarkerArray
        out = deserialize_message(ros.to_cdr(ros.marker_array(seg)), MarkerArray)
    """
    ts = _store_or_ros2(typestore)
    return bytes(ts.serialize_cdr(msg, msg.__msgtype__))


# --------------------------------------------------------------------------
# Writing a bag
# --------------------------------------------------------------------------

def check_bag_path(path) -> str:
    """Check that :func:`write_bag` can write ``path``; return the bag kind.

    Returns ``"mcap"``, ``"ros1"`` or ``"sqlite3"`` (see :func:`write_bag`).
    Run before a long computation whose results go into the bag.

    Raises
    ------
    ParameterError
        A ``.db3`` or ``.yaml`` name.
    MapFileNotFoundError
        The directory it goes into does not exist.
    MapFileError
        A bag directory of that name exists, or a directory where a bag
        file should be.
    MissingDependencyError
        ``rosbags`` is not installed.
    """
    p = Path(os.fspath(path))
    suffix = p.suffix.lower()
    if suffix in (".db3", ".yaml", ".yml"):
        raise ParameterError(f"{p}: name the bag OUT.mcap (ROS 2, MCAP), OUT.bag (ROS 1) or OUT "
                             f"(a ROS 2 sqlite3 bag directory), not {suffix}")
    kind = {".bag": "ros1", ".mcap": "mcap"}.get(suffix, "sqlite3")
    if not p.parent.is_dir():
        raise MapFileNotFoundError(f"{p}: output directory {str(p.parent)!r} does not exist")
    if kind == "sqlite3" and p.exists():
        raise MapFileError(f"{p}: exists already; a bag directory is not overwritten (remove it first)")
    if kind != "sqlite3" and p.is_dir():
        raise MapFileError(f"{p}: is a directory")
    _rosbags(str(p))
    return kind


def write_bag(seg, path, *, frame_id: Optional[str] = None, stamp: Optional[int] = None,
              log_time: Optional[int] = None) -> Path:
    """Write the map, the rooms and the labels of ``seg`` into a new bag.

    Three topics, one message each, every one in the map frame:

    * ``/map``, ``nav_msgs/OccupancyGrid``: the map (:func:`map_message`);
    * ``/topomap/rooms``, ``visualization_msgs/MarkerArray``: the rooms and
      doors (:func:`marker_array`);
    * ``/topomap/labels``, ``sensor_msgs/Image`` (``mono16``): the labels
      (:func:`label_image`).

    The ROS 2 topics are recorded with a reliable, transient-local QoS
    (depth 1) and the ROS 1 ones as latched, so RViz's Map display (which
    asks for transient local) gets the map when the bag is played.

    Parameters
    ----------
    seg : Segmentation
    path : str or os.PathLike
        ``OUT.mcap``: a ROS 2 bag as one MCAP file (``ros2 bag play
        OUT.mcap``; Humble needs ``-s mcap``). ``OUT.bag``: a ROS 1 bag.
        Any other name: a ROS 2 bag directory with sqlite3 storage. A file
        is replaced atomically; an existing directory is not overwritten.
    frame_id, stamp
        As for :func:`marker_array`.
    log_time : int, optional
        Recording time of the messages, nanoseconds since the epoch; default
        the map's own (:class:`RosMap` read from a bag), else now.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    MapFileError
        The target directory cannot be written, or the bag directory exists.
    ParameterError
        A ``.db3`` / ``.yaml`` name, bad ``frame_id`` / ``stamp``.
    MissingDependencyError
        ``rosbags`` is not installed.
    """
    with staged_bag(seg, path, frame_id=frame_id, stamp=stamp, log_time=log_time) as p:
        pass
    return p


@contextmanager
def staged_bag(seg, path, *, frame_id: Optional[str] = None, stamp: Optional[int] = None,
               log_time: Optional[int] = None):
    """Write the bag of :func:`write_bag` to a temporary beside ``path``; rename it into place when the
    ``with`` block ends without an error, else remove it.

    So a bag and other outputs land together or not at all: write the bag
    first (its errors come before anything else is written), the other
    files inside the block. Yields the final path; the errors are those of
    :func:`write_bag` (an error of the block itself passes through unchanged).
    """
    p = Path(os.fspath(path))
    kind = check_bag_path(p)
    from rosbags.rosbag1 import Writer as Writer1
    from rosbags.rosbag2 import StoragePlugin, Writer as Writer2

    ts = _store("ros1" if kind == "ros1" else "ros2")
    when = log_time if log_time is not None else getattr(seg.grid, "log_time", None)
    when = int(time_ns() if when is None else when)
    msgs = [(MAP_TOPIC, MAP_TYPE, map_message(seg.grid, frame_id=frame_id, stamp=stamp, typestore=ts)),
            (MARKERS_TOPIC, MARKER_ARRAY_TYPE, marker_array(seg, frame_id=frame_id, stamp=stamp, typestore=ts)),
            (LABELS_TOPIC, IMAGE_TYPE, label_image(seg, frame_id=frame_id, stamp=stamp, typestore=ts))]
    try:
        tmpdir = Path(tempfile.mkdtemp(prefix=f".{p.name}.", suffix=".tmp", dir=p.parent))
    except OSError as exc:
        raise MapFileError(f"{p}: cannot write bag: {exc.strerror or exc}") from None
    try:
        try:
            if kind == "ros1":
                out = tmpdir / p.name
                with Writer1(out) as w:
                    for topic, typ, msg in msgs:
                        conn = w.add_connection(topic, typ, typestore=ts, latching=1)
                        w.write(conn, when, ts.serialize_ros1(msg, typ))
            else:
                from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, \
                    QosTime

                zero = QosTime(0, 0)
                qos = Qos(QosHistory.KEEP_LAST, 1, QosReliability.RELIABLE, QosDurability.TRANSIENT_LOCAL, zero,
                          zero, QosLiveliness.AUTOMATIC, zero, False)
                bagdir = tmpdir / (p.stem if kind == "mcap" else p.name)
                plugin = StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3
                with Writer2(bagdir, version=8, storage_plugin=plugin) as w:  # 8: QoS as older distros read it
                    for topic, typ, msg in msgs:
                        conn = w.add_connection(topic, typ, typestore=ts, offered_qos_profiles=[qos])
                        w.write(conn, when, ts.serialize_cdr(msg, typ))
                out = bagdir / f"{bagdir.name}.mcap" if kind == "mcap" else bagdir
        except TopomapError:
            raise
        except OSError as exc:
            raise MapFileError(f"{p}: cannot write bag: {exc.strerror or exc}") from None
        yield p  # the caller's other outputs; an error there removes the bag unwritten
        try:
            os.replace(out, p)
        except OSError as exc:
            raise MapFileError(f"{p}: cannot write bag: {exc.strerror or exc}") from None
    finally:
        shutil.rmtree(tmpdir, ignore_errors=True)
