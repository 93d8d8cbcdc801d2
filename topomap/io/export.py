"""Saving and loading results: label image, room graph, overlay picture.

Formats of the room–door graph (:func:`topomap.core.roomgraph.room_graph`,
usually annotated by :func:`topomap.planning.travel_graph`):

GraphML (:func:`save_graphml`, :func:`load_graphml`)
    Readable by ``networkx.read_graphml``, Gephi, igraph, yEd: only scalar
    attributes (str, int, float, bool). Geometry is a WKT string (written
    with the shortest exact decimal of every coordinate, so it reads back
    bit for bit), tuples and lists are JSON strings, ``None`` is ``""``.
    :func:`load_graphml` restores the types from :data:`GRAPH_TYPES`,
    :data:`NODE_TYPES` and :data:`EDGE_TYPES` (floats, int room IDs and door
    keys, tuples, shapely geometry), osmnx style. The document is written as
    text (:func:`graphml_bytes`): the one networkx's own writer makes, byte
    for byte.
JSON (:func:`save_json`, :func:`load_json`)
    networkx node-link data (``"edges"`` key) with the same scalar encoding;
    loading gives a graph equal to the original.
GeoJSON (:func:`to_geojson`, :func:`save_geojson`, :func:`load_geojson`)
    A FeatureCollection in **map-frame metres** (the frame of the map YAML's
    ``origin``, not WGS84 longitude/latitude as RFC 7946 assumes; GIS tools
    should treat it as a local Cartesian CRS): one Polygon/MultiPolygon
    feature per room (``"kind": "room"``) and one LineString per door
    (``"kind": "door"``), every attribute in ``properties`` as plain JSON
    (tuples as arrays); the graph attributes are the collection's foreign
    member ``"properties"``, which also states the frame in plain words
    (:data:`GEOJSON_COORDINATES`, key ``"coordinate_system"``).
    :func:`load_geojson` rebuilds the graph.

The label image is also written as a ROS map_server pair (:func:`save_label_map`,
``labels.pgm`` + ``labels.yaml`` in :func:`write_outputs`).

Every file is written to a temporary name in the target directory and renamed
into place (:func:`atomic_write`), so a failed run never leaves a partial file
and never clobbers an earlier output.
"""

from __future__ import annotations

import contextvars
import io
import json
import math
import numbers
import re
import struct
import time
import warnings
import zlib
from collections.abc import Hashable
from contextlib import ExitStack
from pathlib import Path

import numpy as np
import networkx as nx
from networkx.readwrite.graphml import GraphMLReader

from ..errors import (GraphFormatError, MapError, MapFileError, MapFileNotFoundError, MapTooLargeError,
                      ParameterError, TopomapError, first_line, one_line)
from ..core.result import MAX_FILE_LABEL, MAX_ROOM_ID, check_room_ids
from ..grid import cell_limit, check_image_size
from .files import atomic_write, renamed_error
from .maps import FREE_THRESH, OCCUPIED_THRESH, pgm_header, yaml_text
from .metadata import as_origin, as_resolution

__all__ = ["atomic_write", "save_labels", "label_png_bytes", "file_labels", "MAX_FILE_LABEL", "MAX_ROOM_ID", "check_room_ids", "save_graphml",
           "save_json", "to_graphml_graph", "node_link", "write_outputs", "save_bytes", "geometry_wkt", "restore_types", "load_graphml", "load_json",
           "to_geojson", "from_geojson", "save_geojson", "load_geojson", "save_label_map", "load_label_map",
           "save_graph", "load_graph", "label_map_bytes", "graphml_bytes", "GRAPH_TYPES", "NODE_TYPES",
           "EDGE_TYPES", "FORMATS", "GEOJSON_COORDINATES", "graph_format", "read_label_image", "read_gray"]

#: What the coordinates of topomap's GeoJSON are, written into every file's
#: collection ``properties`` as ``"coordinate_system"``.
GEOJSON_COORDINATES = ("x, y in metres in the map frame (the frame of the map's origin: the map YAML's "
                       "origin, or the OccupancyGrid's info.origin and frame_id); not WGS 84 "
                       "longitude/latitude")


def save_labels(labels, path) -> Path:
    """Write the label image as a 16-bit PNG (0 = not a room), same size as the map.

    ``labels``: a :class:`~topomap.core.segmentation.Segmentation` or an (M, N)
    array of labels. ``path``: a file name (written atomically) or a binary
    file object (written as it is; the caller owns the file, as
    :func:`write_outputs`). Labels above the largest room ID are fragments;
    when the labels of a segmentation do not fit 16 bits, every fragment
    gets the one label after the largest room ID (:func:`file_labels`).
    """
    return _write(label_png_bytes(file_labels(labels, _name(path, "labels.png"), "PNG")), path)


def file_labels(seg, name: str = "<labels>", kind: str = "PNG") -> np.ndarray:
    """The labels a 16-bit label file holds for ``seg``.

    Parameters
    ----------
    seg : Segmentation or (M, N) ndarray of int
        A segmentation, or a label image (0 = not a room).
    name, kind : str
        The file and its format, for messages.

    Returns
    -------
    (M, N) ndarray of int
        ``seg.labels`` itself when every label is at most
        :data:`MAX_FILE_LABEL`; else (a segmentation with fragments: free
        regions too small to be a room, which are in no room graph) the
        labels with every fragment set to ``top_room_id + 1``, so that the
        rooms keep their IDs and a label above the largest room ID is still
        a fragment.

    Raises
    ------
    ParameterError
        Not a non-empty 2-D array, a negative label, or room IDs beyond
        65534 (65535 for a label array).
    """
    is_seg = hasattr(seg, "labels") and hasattr(seg, "top_room_id")
    labels = np.asarray(seg.labels if is_seg else seg)
    if labels.ndim != 2 or labels.size == 0:
        raise ParameterError(f"{name}: a label image must be a non-empty 2-D array, got shape {labels.shape}")
    if labels.min(initial=0) < 0:
        raise ParameterError(f"{name}: labels must be >= 0, got {int(labels.min())}")
    top = int(labels.max(initial=0))
    if top <= MAX_FILE_LABEL:
        return labels
    rooms = int(seg.top_room_id) if is_seg else top
    if rooms >= MAX_FILE_LABEL:
        raise ParameterError(f"{name}: room IDs up to {rooms} do not fit a 16-bit {kind} "
                             f"(at most {MAX_FILE_LABEL - 1} with fragments, {MAX_FILE_LABEL} without)")
    return np.minimum(labels, rooms + 1)


#: Rows of the label image filtered and compressed at a time by :func:`label_png_bytes` (about 1 MB).
_PNG_BLOCK_BYTES = 1 << 20


def label_png_bytes(labels: np.ndarray) -> bytes:
    """A 16-bit greyscale PNG of ``labels`` (each in 0..65535), as :func:`save_labels` writes it.

    Every row is stored with the PNG "Up" filter (its difference to the row above: a label image
    is mostly zeros then) and compressed at zlib level 1, a block of rows at a time: time and
    memory are linear in the cells, about twice as fast as Pillow's encoder at its fastest level
    (which tries every filter on every row) and as small.
    """
    H, W = labels.shape
    be = np.ascontiguousarray(labels, dtype=">u2").view(np.uint8).reshape(H, 2 * W)  # PNG: big-endian
    z = zlib.compressobj(1)
    parts = []
    step = max(1, _PNG_BLOCK_BYTES // (2 * W + 1))
    for a in range(0, H, step):
        b = min(a + step, H)
        raw = np.empty((b - a, 2 * W + 1), np.uint8)
        raw[:, 0] = 2  # the filter type of each row: Up
        if a == 0:
            raw[0, 1:] = be[0]  # the row above the first is zeros
            np.subtract(be[1:b], be[:b - 1], out=raw[1:, 1:])
        else:
            np.subtract(be[a:b], be[a - 1:b - 1], out=raw[:, 1:])
        parts.append(z.compress(raw))
    parts.append(z.flush())

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    head = struct.pack(">IIBBBBB", W, H, 16, 0, 0, 0, 0)  # 16-bit greyscale, no interlace
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", head) + chunk(b"IDAT", b"".join(parts)) + chunk(b"IEND", b"")


def _is_file(path) -> bool:
    return hasattr(path, "write")


def _name(path, default: str = "<buffer>") -> str:
    """The file name of ``path`` for messages (``default`` for a file object that has none, as io.BytesIO)."""
    return str(getattr(path, "name", default)) if _is_file(path) else str(path)


def _write(data: bytes, path) -> Path:
    """``data`` into ``path``: a file name (written atomically) or a binary file object (written as it is)."""
    if _is_file(path):
        path.write(data)
        return Path(_name(path))
    with atomic_write(path) as fh:
        fh.write(data)
    return Path(path)


# --------------------------------------------------------------------------
# Scalar encoding and type restoration
# --------------------------------------------------------------------------

def _num(v) -> str:
    """Shortest decimal that reads back as exactly ``v`` (no exponent)."""
    t = repr(float(v))  # shortest round-trip decimal; positional unless tiny or huge
    if "e" in t or "n" in t:
        return np.format_float_positional(float(v), unique=True, trim="-")
    return t[:-2] if t.endswith(".0") else t


_POINT_ZERO = re.compile(r"\.0(?=[ ,)]|$)")


def _ring(coords) -> str:
    return _wkt_ring(_ring_json(coords))


def _ring_json(coords) -> str:
    """The GeoJSON text of a 2-D ring, ``[[x, y], ...]`` (json's C encoder: every float as ``repr``)."""
    return json.dumps(np.asarray(coords, float).reshape(-1, 2).tolist())


def _wkt_ring(text: str) -> str:
    """WKT ``(x y, x y, ...)`` of a ring's :func:`_ring_json` text (exact decimals, no exponent)."""
    wkt = text[2:-2].replace("], [", "|").replace(", ", " ").replace("|", ", ")
    if "e" in wkt or "N" in wkt or "I" in wkt:  # an exponent, NaN or Infinity: token by token
        toks = [_num(v) for v in np.asarray(json.loads(text), float).reshape(-1).tolist()]
        wkt = ", ".join(map(" ".join, zip(toks[::2], toks[1::2])))
    return "(" + _POINT_ZERO.sub("", wkt) + ")"


#: Inside :func:`write_outputs`: ``{id(geometry): (geometry, coordinates text, WKT or None)}``, so the
#: GraphML / JSON WKT and the GeoJSON coordinates of a room's outline encode its floats once.
_RING_MEMO = contextvars.ContextVar("topomap_ring_memo", default=None)

#: Coordinates encoded per block in :func:`_coords_json`: Python objects for this many points at
#: a time, whatever the size of the outline.
_CHUNK = 1 << 15


def _coords_json(geom) -> str:
    """GeoJSON ``coordinates`` text of a 2-D, non-empty Polygon or MultiPolygon (memoised in write_outputs).

    The same text as ``json.dumps`` of the nested lists of its rings' coordinates, but made a block of
    whole polygons (or of one polygon's rings) at a time (:func:`_rings_texts`): time and memory are
    linear in the coordinates, with Python objects for one block's rings and points at a time only.
    """
    import shapely

    memo = _RING_MEMO.get()
    if memo is not None:
        hit = memo.get(id(geom))
        if hit is not None and hit[0] is geom:
            return hit[1]
    multi = geom.geom_type == "MultiPolygon"
    parts = shapely.get_parts(geom) if multi else np.array([geom], dtype=object)
    n_rings = shapely.get_num_interior_rings(parts) + 1
    ring_end = np.cumsum(shapely.get_num_coordinates(shapely.get_rings(parts)))  # coordinates, ring by ring
    part_end = np.cumsum(n_rings)  # rings, part by part
    xy = shapely.get_coordinates(geom)
    del parts
    texts = []
    k, n = 0, len(part_end)
    while k < n:
        r0 = part_end[k - 1] if k else 0
        c0 = ring_end[r0 - 1] if r0 else 0
        # whole polygons up to _CHUNK coordinates, at least one
        k1 = max(int(np.searchsorted(ring_end[part_end - 1], c0 + _CHUNK, side="right")), k + 1)
        r1 = part_end[k1 - 1]
        if k1 > k + 1 or ring_end[r1 - 1] - c0 <= _CHUNK:
            rings = _rings_texts(xy[c0:ring_end[r1 - 1]], np.r_[c0, ring_end[r0:r1]] - c0)
            polys = np.r_[0, part_end[k:k1] - r0]
            texts.append(", ".join("[" + ", ".join(rings[polys[j]:polys[j + 1]]) + "]" for j in range(k1 - k)))
        else:  # one polygon of more coordinates: its rings in blocks of up to _CHUNK coordinates
            inner = []
            r = r0
            while r < r1:
                c = ring_end[r - 1] if r else 0
                rb = min(max(int(np.searchsorted(ring_end, c + _CHUNK, side="right")), r + 1), r1)
                inner.append(", ".join(_rings_texts(xy[c:ring_end[rb - 1]], np.r_[c, ring_end[r:rb]] - c)))
                r = rb
            texts.append("[" + ", ".join(inner) + "]")
            del inner
        k = k1
    del xy
    text = "[" + ", ".join(texts) + "]"
    if not multi:
        text = text[1:-1]
    if memo is not None:
        memo[id(geom)] = (geom, text, None)
    return text


def _memo_outlines(geoms) -> None:
    """Put the :func:`_coords_json` texts of ``geoms`` into the memo of :func:`write_outputs`, made for
    many outlines at once.

    The 2-D, non-empty Polygons and MultiPolygons are taken in blocks of whole geometries of up to
    :data:`_CHUNK` coordinates (a larger one: :func:`_coords_json` alone): one shapely call per block
    for its rings and coordinates and one spelling of its distinct floats (:func:`_rings_texts`), the
    same texts as one geometry at a time, and their WKT (:func:`geometry_wkt`) from the same spelling:
    no text replacements on the WKT. Anything else is left to :func:`_coords_json`.
    """
    import shapely

    memo = _RING_MEMO.get()
    if memo is None:
        return
    todo = [g for g in geoms if _is_geom(g) and g.geom_type in ("Polygon", "MultiPolygon") and not g.is_empty
            and not g.has_z and id(g) not in memo]
    if not todo:
        return
    size = shapely.get_num_coordinates(np.array(todo, dtype=object))
    ends = np.cumsum(size)
    k = 0
    while k < len(todo):
        k1 = max(int(np.searchsorted(ends, (ends[k - 1] if k else 0) + _CHUNK, side="right")), k + 1)
        block = np.array(todo[k:k1], dtype=object)
        parts, part_geom = shapely.get_parts(block, return_index=True)
        if k1 == k + 1 or shapely.is_empty(parts).any():  # one large geometry, or an empty part: alone
            for g in todo[k:k1]:
                _coords_json(g)
            k = k1
            continue
        rings, ring_part = shapely.get_rings(parts, return_index=True)
        texts, wkts = _rings_texts(shapely.get_coordinates(rings),
                                   np.r_[0, np.cumsum(shapely.get_num_coordinates(rings))], wkt=True)
        rb = np.r_[0, np.cumsum(np.bincount(ring_part, minlength=len(parts)))].tolist()  # each part's rings
        part_texts = ["[" + ", ".join(texts[a:b]) + "]" for a, b in zip(rb[:-1], rb[1:])]
        part_wkts = ["(" + ", ".join(wkts[a:b]) + ")" for a, b in zip(rb[:-1], rb[1:])]
        pb = np.r_[0, np.cumsum(np.bincount(part_geom, minlength=k1 - k))].tolist()  # each geometry's parts
        for j, g in enumerate(todo[k:k1]):
            if g.geom_type == "MultiPolygon":
                memo[id(g)] = (g, "[" + ", ".join(part_texts[pb[j]:pb[j + 1]]) + "]",
                               "MULTIPOLYGON (" + ", ".join(part_wkts[pb[j]:pb[j + 1]]) + ")")
            else:
                memo[id(g)] = (g, part_texts[pb[j]], "POLYGON " + part_wkts[pb[j]])
        k = k1


def _rings_texts(xy, bounds, wkt: bool = False):
    """``json.dumps`` of each ring ``xy[bounds[j]:bounds[j + 1]]`` (``[[x, y], ...]``) of the points ``xy``;
    with ``wkt``, also each ring's WKT ``(x y, x y, ...)`` (as :func:`_wkt_ring`): ``(json texts, wkt texts)``.

    Every distinct float is spelt once (json's spelling, from one ``json.dumps`` of the distinct
    values): an outline's corners share few x and few y values (the map's cell edges). The texts are
    then cut from one ``str.join`` of the points' spellings (:func:`_cut_rings`).
    """
    bits, inv = np.unique(np.ascontiguousarray(xy, float).view(np.int64), return_inverse=True)  # bit for bit
    text = json.dumps(bits.view(float).tolist())
    spelt = text[1:-1].split(", ") if bits.size else []
    inv = inv.reshape(-1, 2)
    bounds = np.asarray(bounds, np.int64)
    texts = _cut_rings(spelt, inv, bounds, ", ", "], [", "[[", "]]")
    if not wkt:
        return texts
    # WKT spells each float as _num does: json's (repr) without a trailing ".0"; exponents, NaN, infinity by _num
    if "e" in text or "N" in text or "I" in text:
        wk = [_num(v) for v in bits.view(float).tolist()]
    else:
        wk = [t.removesuffix(".0") for t in spelt]
    return texts, _cut_rings(wk, inv, bounds, " ", ", ", "(", ")")


def _cut_rings(spelt, inv, bounds, sep, pair_sep, head, tail) -> list:
    """Texts ``head + "x<sep>y<pair_sep>x<sep>y" + tail`` of the rings ``inv[bounds[j]:bounds[j + 1]]``
    (pairs of indices into the spellings ``spelt``), for :func:`_rings_texts`.

    Each point's two spellings, with their separators (a ring's first with ``head``, its last with
    ``tail`` and a NUL, which no number has), are joined into one text and split at the NULs: no
    Python string or list per point, so no garbage-collector passes over thousands of small lists
    (as a ``", ".join`` per point would make).
    """
    tok = np.empty(2 * len(inv), dtype=object)
    tok[0::2] = np.array([t + sep for t in spelt] or [""], dtype=object)[inv[:, 0]]
    tok[1::2] = np.array([t + pair_sep for t in spelt] or [""], dtype=object)[inv[:, 1]]
    full = bounds[:-1] < bounds[1:]  # rings of no points: "head + tail", put back after the split
    first, last = bounds[:-1][full], bounds[1:][full] - 1
    tok[2 * first] = np.array([head + t + sep for t in spelt] or [""], dtype=object)[inv[first, 0]]
    tok[2 * last + 1] = np.array([t + tail + "\0" for t in spelt] or [""], dtype=object)[inv[last, 1]]
    texts = "".join(tok.tolist()).split("\0")
    texts.pop()  # after the last NUL
    for j in np.flatnonzero(~full).tolist():
        texts.insert(j, head + tail)
    return texts


def _poly_rings(p) -> list:
    """:func:`_ring_json` texts of a 2-D Polygon's exterior and interiors."""
    return [_ring_json(r.coords) for r in [p.exterior, *p.interiors]]


def _poly_wkt(p) -> str:
    return "(" + ", ".join(map(_wkt_ring, _poly_rings(p))) + ")"


def _polygonal_wkt(geom) -> str:
    """WKT of a 2-D, non-empty Polygon or MultiPolygon: memoised by :func:`_memo_outlines`, else from its
    :func:`_coords_json` text."""
    memo = _RING_MEMO.get()
    if memo is not None:
        hit = memo.get(id(geom))
        if hit is not None and hit[0] is geom and hit[2] is not None:
            return hit[2]
    text = _coords_json(geom)
    if "e" in text or "N" in text or "I" in text:  # an exponent, NaN or Infinity: ring by ring
        parts = geom.geoms if geom.geom_type == "MultiPolygon" else [geom]
        body = ", ".join(map(_poly_wkt, parts))
        return f"{geom.geom_type.upper()} " + (f"({body})" if geom.geom_type == "MultiPolygon" else body)
    # separators between elements ("], [") marked, the commas left are inside points; then the
    # boundaries of polygons, of rings and of points (longest first), and the outer brackets
    depth = 4 if geom.geom_type == "MultiPolygon" else 3
    wkt = text[depth:-depth].replace("], [", "]|[").replace(", ", " ")
    if depth == 4:
        wkt = wkt.replace("]]]|[[[", ")), ((")
    wkt = "(" * (depth - 1) + wkt.replace("]]|[[", "), (").replace("]|[", ", ") + ")" * (depth - 1)
    return f"{geom.geom_type.upper()} " + _POINT_ZERO.sub("", wkt)


def geometry_wkt(geom) -> str:
    """WKT of a shapely geometry with every coordinate exact.

    shapely's own ``wkt`` rounds to a fixed number of decimals; this writer
    uses the shortest decimal that reads back to the same float, so
    ``shapely.wkt.loads(geometry_wkt(g)) == g``. 2-D Point, LineString,
    Polygon and MultiPolygon are written this way, anything else by
    ``shapely.to_wkt``.
    """
    import shapely

    t = geom.geom_type
    if geom.is_empty:
        return f"{t.upper()} EMPTY"
    if geom.has_z:
        return shapely.to_wkt(geom, rounding_precision=-1)
    if t == "Point":
        return f"POINT ({_num(geom.x)} {_num(geom.y)})"
    if t == "LineString":
        return "LINESTRING " + _ring(geom.coords)
    if t in ("Polygon", "MultiPolygon"):
        return _polygonal_wkt(geom)
    return shapely.to_wkt(geom, rounding_precision=-1)


def _is_geom(v) -> bool:
    t = type(v)  # the class's attributes: hasattr(v, "wkt") would compute the WKT
    return hasattr(t, "geom_type") and hasattr(t, "wkt")


def _plain(v):
    """Plain JSON value of ``v``: tuples/arrays as lists, numpy scalars as Python, geometry as WKT."""
    t = type(v)
    if t is float:  # most attributes: Python floats, checked without a numpy call
        return v if math.isfinite(v) else None
    if t is int or t is str or t is bool:
        return v
    if v is None or isinstance(v, (bool, str)):
        return v
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        return float(v) if np.isfinite(v) else None  # JSON has no NaN or Infinity: null
    if _is_geom(v):
        return geometry_wkt(v)
    if isinstance(v, np.ndarray):
        return _plain(v.tolist())
    if isinstance(v, dict):
        return {str(k): _plain(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_plain(x) for x in v]
    return str(v)


#: Types :func:`_scalar` keeps as they are (exactly these, not subclasses such as numpy's float64).
_AS_IS = frozenset({float, int, str, bool})


def _scalar(v):
    """GraphML-safe value: scalars stay, tuples/lists/arrays become JSON, geometry exact WKT, None ''."""
    t = type(v)
    if t in _AS_IS:  # most attributes: Python numbers
        return v
    if t is tuple and len(v) == 2 and type(v[0]) is float and type(v[1]) is float \
            and math.isfinite(v[0]) and math.isfinite(v[1]):  # p1, p2: json.dumps spells floats by repr
        return f"[{v[0]!r}, {v[1]!r}]"
    if v is None:
        return ""
    if isinstance(v, (bool, str)):
        return v
    if isinstance(v, (int, np.integer)) and not isinstance(v, np.bool_):
        return int(v)
    if isinstance(v, (float, np.floating)):
        return float(v)
    if isinstance(v, np.bool_):
        return bool(v)
    if _is_geom(v):
        return geometry_wkt(v)
    if isinstance(v, (list, tuple)):
        text = _json_as_is(v)
        if text is not None:
            return text
    return json.dumps(_plain(v))


def _json_as_is(v):
    """``json.dumps(v)`` when that is ``json.dumps(_plain(v))`` (lists and tuples of Python
    numbers, strings, bools and None, as ``door_distances``), else None."""
    try:
        text = json.dumps(v)
    except (TypeError, ValueError):  # numpy scalars, geometry, ...: through _plain
        return None
    # a dict inside: its keys are str() in _plain, json writes True / None keys as true / null
    return None if "{" in text else text


def _none(v):
    return v is None or (isinstance(v, str) and v.strip() in ("", "None", "null"))


def _json(v):
    return json.loads(v) if isinstance(v, str) else v


def _opt(f):
    def conv(v):
        return None if _none(v) else f(v)
    conv.__name__ = f"optional_{f.__name__}"
    return conv


def _float_tuple(v):
    return tuple(float(x) for x in _json(v))


def _whole(x) -> int:
    """``x`` as an int; ValueError for a fraction (1.5 is not read as 1), a bool or a non-number."""
    if isinstance(x, bool) or (isinstance(x, float) and not x.is_integer()):
        raise ValueError(f"{x!r} is not a whole number")
    return int(x)


def _int_tuple(v):
    return tuple(_whole(x) for x in _json(v))


_int_pair = _int_tuple


def _geometry(v):
    if _is_geom(v):
        return v
    if isinstance(v, dict):
        from shapely.geometry import shape

        return shape(v)
    from shapely import wkt

    return wkt.loads(v)


def _door_distances(v):
    return tuple((int(i), int(j), float(L)) for i, j, L in _json(v))


#: Types of the graph attributes (converter per attribute name).
GRAPH_TYPES = {"resolution": float, "origin": _float_tuple, "method": _opt(str), "threshold": _opt(float),
               "map": _opt(str), "shape": _int_tuple, "n_fragments": int, "fragment_area": float,
               "outside_area": float,
               "travel_distances": _opt(str)}
#: Types of the room (node) attributes.
NODE_TYPES = {"area": float, "cells": int, "x": float, "y": float, "row": float, "col": float,
              "interior_x": float, "interior_y": float, "interior_row": float, "interior_col": float,
              "polygon": _opt(_geometry), "door_distances": _door_distances,
              "room_kind": str, "width": float, "length": float}
#: Types of the door (edge) attributes.
EDGE_TYPES = {"door": int, "width": float, "x": float, "y": float, "x1": float, "y1": float, "x2": float,
              "y2": float, "p1": _float_tuple, "p2": _float_tuple, "rooms": _int_pair}


def _restore(d: dict, table: dict, where: str) -> dict:
    out = {}
    for k, v in d.items():
        f = table.get(k)
        if f is None:
            out[k] = v
            continue
        if v is None and f is float:  # a number JSON could not hold (NaN) was written as null
            out[k] = float("nan")
            continue
        try:
            out[k] = f(v)
        except Exception as exc:  # noqa: BLE001 - reported as a format error
            raise GraphFormatError(f"{where}: attribute {k!r} = {str(v)[:60]!r} is not valid: {exc}") from None
    return out


def _node_id(n):
    if isinstance(n, str):
        try:
            return int(n)
        except ValueError:
            return n
    return n


def restore_types(G: nx.Graph, name: str = "<graph>") -> nx.MultiGraph:
    """A room graph with attribute types restored after reading a file.

    Node IDs that look like integers become ``int``; every attribute listed in
    :data:`GRAPH_TYPES`, :data:`NODE_TYPES`, :data:`EDGE_TYPES` is converted
    (JSON strings to tuples, WKT to shapely geometry, ``""`` to ``None``);
    other attributes are kept as read. Edge keys become the door IDs.

    Raises
    ------
    GraphFormatError
        An attribute cannot be converted.
    """
    H = nx.MultiGraph()
    gattr = {k: v for k, v in G.graph.items() if k not in ("node_default", "edge_default")}  # GraphML reader's
    H.graph.update(_restore(gattr, GRAPH_TYPES, f"{name}: graph"))
    for n, d in G.nodes(data=True):
        H.add_node(_node_id(n), **_restore(d, NODE_TYPES, f"{name}: node {n}"))
    edges = G.edges(keys=True, data=True) if G.is_multigraph() else ((u, v, None, d) for u, v, d in G.edges(data=True))
    for u, v, k, d in edges:
        d = _restore(d, EDGE_TYPES, f"{name}: edge {u}-{v}")
        d.pop("id", None)
        key = d.get("door", _node_id(k) if k is not None else None)
        H.add_edge(_node_id(u), _node_id(v), key=key, **d)
    return H


# --------------------------------------------------------------------------
# GraphML and JSON
# --------------------------------------------------------------------------

def to_graphml_graph(G: nx.Graph) -> nx.Graph:
    """A copy of ``G`` whose attributes are all GraphML scalars (str, int, float, bool)."""
    H = G.__class__()
    H.graph.update({k: _scalar(v) for k, v in G.graph.items()})
    for n, d in G.nodes(data=True):
        H.add_node(n, **{k: _scalar(v) for k, v in d.items()})
    if G.is_multigraph():
        for u, v, k, d in G.edges(keys=True, data=True):
            H.add_edge(u, v, key=k, **{a: _scalar(b) for a, b in d.items()})
    else:
        for u, v, d in G.edges(data=True):
            H.add_edge(u, v, **{a: _scalar(b) for a, b in d.items()})
    return H


def save_graphml(G: nx.Graph, path) -> Path:
    """Write the room graph as GraphML (scalars only; geometry WKT, tuples JSON).

    Parameters
    ----------
    G : networkx.Graph
        Room–door graph.
    path : str, os.PathLike or binary file object
        Output file, written atomically (a file object: written as it is).

    Returns
    -------
    pathlib.Path
    """
    return _write(graphml_bytes(_scalars(G)), path)


#: Inside :func:`write_outputs`: ``[graph, to_graphml_graph(graph) or None until made]`` of the graph it
#: saves, so GraphML and JSON encode its attributes once.
_SCALAR_MEMO = contextvars.ContextVar("topomap_scalar_memo", default=None)


def _scalars(G: nx.Graph) -> nx.Graph:
    """:func:`to_graphml_graph` of ``G``; in :func:`write_outputs` made once, its rooms' outlines first
    all together (:func:`_memo_outlines`)."""
    memo = _SCALAR_MEMO.get()
    if memo is None or memo[0] is not G:
        return to_graphml_graph(G)
    if memo[1] is None:
        _memo_outlines([d.get("polygon") for _, d in G.nodes(data=True)])
        memo[1] = to_graphml_graph(G)
    return memo[1]


_XML_TYPES = {bool: "boolean", int: "long", float: "double", str: "string"}
_XML_HEAD = ("<?xml version='1.0' encoding='utf-8'?>\n<graphml xmlns=\"http://graphml.graphdrawing.org/xmlns\" "
             "xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" xsi:schemaLocation=\"http://graphml.graphdrawing"
             ".org/xmlns http://graphml.graphdrawing.org/xmlns/1.0/graphml.xsd\">")


#: Characters XML 1.0 cannot hold, not even as a character reference (lone surrogates: the bytes of a
#: file name that is not UTF-8, as Python decodes it).
_NOT_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ud800-\udfff\ufffe\uffff]")


def _escape_bad(m) -> str:
    c = ord(m.group())
    if 0xDC80 <= c <= 0xDCFF:  # a byte of a non-UTF-8 name (surrogateescape): written as \xNN
        return f"\\x{c - 0xDC00:02x}"
    return f"\\x{c:02x}" if c < 0x100 else f"\\u{c:04x}"


def _xml_text(v: str) -> str:
    if not (v.isascii() and v.isprintable()):
        v = _NOT_XML.sub(_escape_bad, v)
    return v.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def _xml_attr(v: str) -> str:
    return (_xml_text(v).replace("\"", "&quot;").replace("\r", "&#13;").replace("\n", "&#10;")
            .replace("\t", "&#09;"))


def graphml_bytes(G: nx.Graph) -> bytes:
    """GraphML document of ``G`` as ``networkx.write_graphml`` (its ElementTree writer) writes it.

    Written directly as text for graphs whose attributes are all str, int,
    float or bool (as :func:`to_graphml_graph` makes them): the same
    document, key ids, attribute types and layout, so ``networkx.read_graphml``
    reads back the same graph. Other graphs go through networkx.
    """
    gdata = {k: v for k, v in G.graph.items()}
    if any(k in gdata for k in ("id", "node_default", "edge_default")):
        return _nx_graphml_bytes(G)
    keys, key_lines = {}, []

    def data(items, scope, pad):
        out = []
        for k, v in items:
            t = type(v)
            xt = _XML_TYPES.get(t)
            if xt is None:
                raise TypeError(t)
            name = str(k)
            kid = keys.get((name, t, scope))
            if kid is None:
                kid = keys[(name, t, scope)] = f"d{len(keys)}"
                key_lines.append(f'  <key id="{kid}" for="{scope}" attr.name="{_xml_attr(name)}" '
                                 f'attr.type="{xt}" />')
            text = str(v)
            out.append(f'{pad}<data key="{kid}">{_xml_text(text)}</data>' if text else f'{pad}<data key="{kid}" />')
        return out

    try:
        graph_lines = data(gdata.items(), "graph", "    ")  # keys numbered graph first, as networkx does
        body = []
        for n, d in G.nodes(data=True):
            tag = f'    <node id="{_xml_attr(str(n))}"'
            lines = data(d.items(), "node", "      ")
            body += [tag + ">", *lines, "    </node>"] if lines else [tag + " />"]
        if G.is_multigraph():
            edges = ((u, v, f' id="{_xml_attr(str(k))}"', d) for u, v, k, d in G.edges(keys=True, data=True))
        else:
            edges = ((u, v, "", d) for u, v, d in G.edges(data=True))
        for u, v, eid, d in edges:
            tag = f'    <edge source="{_xml_attr(str(u))}" target="{_xml_attr(str(v))}"{eid}'
            lines = data(d.items(), "edge", "      ")
            body += [tag + ">", *lines, "    </edge>"] if lines else [tag + " />"]
    except TypeError:
        return _nx_graphml_bytes(G)
    body += graph_lines
    graph = f'  <graph edgedefault="{"directed" if G.is_directed() else "undirected"}"'
    parts = [_XML_HEAD, *key_lines[::-1]]  # networkx inserts every new key first
    parts += [graph + ">", *body, "  </graph>"] if body else [graph + " />"]
    parts.append("</graphml>\n")
    return "\n".join(parts).encode("utf-8", "xmlcharrefreplace")


def _nx_graphml_bytes(G) -> bytes:
    buf = io.BytesIO()
    nx.write_graphml_xml(G.copy(), buf)  # a copy: the writer takes "id" out of the graph's attributes
    return buf.getvalue()


def _bad(path, what, exc=None) -> GraphFormatError:
    msg = f"{path}: {what}"
    if exc is not None:
        msg += f": {first_line(exc)}"
    return GraphFormatError(msg)


def _check_file(path) -> Path:
    path = Path(path)
    if not path.is_file():
        raise MapFileNotFoundError(f"{path}: no such file" if not path.exists() else f"{path}: not a file")
    return path


def _read_json(path: Path):
    """The JSON value of ``path``; GraphFormatError (naming the file) when it is not JSON or nested too deeply."""
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (ValueError, UnicodeDecodeError) as exc:
        raise _bad(path, "not valid JSON", exc) from None
    except RecursionError:
        raise _bad(path, "not valid JSON: nested too deeply") from None
    except OSError as exc:
        raise _bad(path, "cannot read file", exc.strerror or exc) from None


def _check_frame(G: nx.MultiGraph, path) -> nx.MultiGraph:
    """``G`` if the map size its ``shape`` claims is within :func:`topomap.io.cell_limit`, else MapTooLargeError."""
    check_room_ids(G, path)
    # the map frame, checked here so that its errors name the file (not the '<array>' of a grid built from it)
    if G.graph.get("resolution") is not None:
        as_resolution(f"{path}: graph attribute", G.graph["resolution"])
    if G.graph.get("origin") is not None:
        as_origin(f"{path}: graph attribute", G.graph["origin"])
    shape = G.graph.get("shape")
    if shape is None:
        return G
    if len(shape) != 2 or not all(isinstance(v, numbers.Integral) and v >= 1 for v in shape):
        raise _bad(path, f"graph attribute 'shape' must be [rows, cols], two whole numbers >= 1, "
                         f"got {one_line(repr(list(shape)[:4]))[:60]}")
    rows, cols = (int(v) for v in shape)
    limit, why = cell_limit()
    if rows * cols > limit:
        raise MapTooLargeError(f"{path}: the graph claims a map of {cols:,} x {rows:,} cells = {rows * cols:,}, "
                               f"more than {why}")
    return G


def _check_door_ends(name, what, ends, rooms) -> None:
    """GraphFormatError naming ``name`` when a door (``what``) joins a room that is not among ``rooms`` (the
    rooms the file declares): graph readers would add it as a room without outline or position."""
    for r in ends:
        if r not in rooms:
            raise GraphFormatError(f"{name}: {what} joins room {one_line(repr(r))[:40]}, which is not a room "
                                   f"of the graph")


def _parse_graphml(data: bytes, name: str = "<graphml>") -> nx.MultiGraph:
    """The first graph of GraphML document ``data``, parsed by defusedxml with DTDs forbidden
    (a DOCTYPE, entity declaration or external reference anywhere in the document raises one of
    defusedxml's errors) and built by networkx's GraphML reader from that tree."""
    from defusedxml.ElementTree import fromstring

    reader = GraphMLReader(node_type=str, edge_key_type=int, force_multigraph=True)
    for attempt in (data, data.replace(b"<graphml>", b'<graphml xmlns="http://graphml.graphdrawing.org/xmlns">')):
        root = fromstring(attempt, forbid_dtd=True)
        reader.xml = root
        keys, defaults = reader.find_graphml_keys(root)
        for g in root.findall(f"{{{reader.NS_GRAPHML}}}graph"):
            rooms = {n.get("id") for n in g.findall(f"{{{reader.NS_GRAPHML}}}node")}
            for i, e in enumerate(g.findall(f"{{{reader.NS_GRAPHML}}}edge")):
                _check_door_ends(name, f"edge {i}", (e.get("source"), e.get("target")), rooms)
            return reader.make_graph(g, keys, defaults)
    raise nx.NetworkXError("file not successfully read as graphml")


def load_graphml(path) -> nx.MultiGraph:
    """Read a room graph written by :func:`save_graphml`, with types restored.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    networkx.MultiGraph
        Nodes are int room IDs, edges keyed by int door ID; attributes as in
        :func:`topomap.core.roomgraph.room_graph` (see :func:`restore_types`).

    Raises
    ------
    GraphFormatError
        The file is not GraphML or an attribute cannot be restored.
    """
    from defusedxml import DefusedXmlException

    path = _check_file(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise _bad(path, "cannot read file", exc.strerror or exc) from None
    try:
        G = _parse_graphml(data, str(path))
    except DefusedXmlException:  # DTDForbidden, EntitiesForbidden, ExternalReferenceForbidden
        # GraphML needs no document type; entity declarations can expand without bound
        raise _bad(path, "GraphML with a DOCTYPE or entity declarations is refused") from None
    except RecursionError:
        raise _bad(path, "not a valid GraphML file: nested too deeply") from None
    except GraphFormatError:
        raise
    except Exception as exc:  # noqa: BLE001 - ParseError, NetworkXError, ...
        raise _bad(path, "not a valid GraphML file", exc) from None
    return _check_frame(restore_types(G, str(path)), path)


def node_link(G: nx.Graph) -> dict:
    """JSON-ready node-link data of ``G`` (geometry as WKT, tuples as JSON strings)."""
    return nx.node_link_data(_scalars(G), edges="edges")


def save_json(G: nx.Graph, path) -> Path:
    """Write the room graph as node-link JSON (atomically; or into a binary file object); see :func:`node_link`."""
    data = node_link(G)
    try:  # compact: json's C encoder (indent or json.dump would use the Python one)
        text = _node_link_text(data, G)
    except ValueError:  # a NaN or infinity: written as null (valid JSON), read back as NaN
        text = json.dumps(_plain(data), allow_nan=False)
    return _write(text.encode("utf-8"), path)


#: Stands for an outline's WKT in :func:`_node_link_text`'s ``json.dumps`` (written ``"\u0000topomap WKT\u0000"``).
_MARK = "\0topomap WKT\0"


def _node_link_text(data: dict, G: nx.Graph) -> str:
    """``json.dumps(data, allow_nan=False)`` of the node-link data of ``G``'s scalars, the WKT of its
    rooms' geometry copied in whole: WKT is printable ASCII without quote or backslash, which JSON
    writes as it is, so json's escaping scan of it (most of the encoding time) is skipped.

    Each such text is replaced by :data:`_MARK` for the encoder and put back in its place; when the
    text does not hold exactly one mark per WKT (an attribute holds the mark itself), it is written
    the plain way.
    """
    nodes = G.nodes
    wkts = [(nd, k, v) for nd in data["nodes"] for k, v in nd.items()
            if type(v) is str and k != "id" and _is_geom(nodes[nd["id"]].get(k))]
    if not wkts:
        return json.dumps(data, allow_nan=False)
    for nd, k, _ in wkts:
        nd[k] = _MARK
    try:
        text = json.dumps(data, allow_nan=False)
    finally:
        for nd, k, v in wkts:
            nd[k] = v
    parts = text.split(json.dumps(_MARK))
    if len(parts) != len(wkts) + 1:
        return json.dumps(data, allow_nan=False)
    pieces = [parts[0]]
    for (_, _, v), p in zip(wkts, parts[1:]):
        pieces += ['"', v, '"', p]
    return "".join(pieces)


def load_json(path) -> nx.MultiGraph:
    """Read node-link JSON written by :func:`save_json`, with types restored.

    Returns a graph equal to the one saved: same nodes, edges (keys) and
    attributes (see :func:`restore_types`).

    Raises
    ------
    GraphFormatError
        Not JSON, or not node-link data of a graph.
    """
    path = _check_file(path)
    data = _read_json(path)
    if not isinstance(data, dict) or "nodes" not in data:
        raise _bad(path, "not node-link graph data (no 'nodes')")
    edges = "edges" if "edges" in data else "links"
    if isinstance(data["nodes"], list) and isinstance(data.get(edges), list):
        rooms = {n.get("id") for n in data["nodes"] if isinstance(n, dict) and isinstance(n.get("id"), Hashable)}
        for e in data[edges]:
            if isinstance(e, dict):
                _check_door_ends(path, f"edge {one_line(repr(e.get('door', e.get('key'))))[:20]}",
                                 (e.get("source"), e.get("target")), rooms)
    try:
        G = nx.node_link_graph(data, edges=edges)
    except Exception as exc:  # noqa: BLE001
        raise _bad(path, "not node-link graph data", exc) from None
    return _check_frame(restore_types(G, str(path)), path)


# --------------------------------------------------------------------------
# GeoJSON
# --------------------------------------------------------------------------

def to_geojson(G: nx.Graph) -> dict:
    """GeoJSON FeatureCollection of the rooms and doors, map-frame metres.

    Parameters
    ----------
    G : networkx.MultiGraph
        Room–door graph.

    Returns
    -------
    dict
        ``{"type": "FeatureCollection", "properties": {graph attributes},
        "features": [...]}``. A room is a Feature with its ``polygon`` as
        geometry (Polygon/MultiPolygon, ``null`` if it has none) and
        ``properties`` ``{"kind": "room", "room": id, "area": m², ...}``; a
        door is a LineString from ``(x1, y1)`` to ``(x2, y2)`` with
        ``{"kind": "door", "door": id, "rooms": [a, b], "width": m, ...}``.
        Coordinates are map-frame metres, not WGS 84: the collection's
        ``properties`` say so in ``"coordinate_system"``
        (:data:`GEOJSON_COORDINATES`).
    """
    props, feats = _geojson_parts(G)
    for f, geom in feats:
        if geom is not None:
            f["geometry"] = _geom_json(geom)
    return {"type": "FeatureCollection", "properties": props, "features": [f for f, _ in feats]}


def _geojson_parts(G, plain=_plain):
    """The collection's properties and ``(feature, room outline)`` pairs, geometry left None for rooms
    (``plain``: how node attributes are made plain JSON)."""
    feats = []
    for n, d in G.nodes(data=True):
        props = {"kind": "room", "room": _plain(n)}
        props.update({k: plain(v) for k, v in d.items() if k != "polygon"})
        feats.append(({"type": "Feature", "id": f"room-{n}", "geometry": None, "properties": props},
                      d.get("polygon")))
    edges = G.edges(keys=True, data=True) if G.is_multigraph() else ((u, v, None, d) for u, v, d in G.edges(data=True))
    for u, v, k, d in edges:
        did = d.get("door", k)
        props = {"kind": "door", "door": _plain(did), "rooms": [_plain(u), _plain(v)]}
        props.update({a: _plain(b) for a, b in d.items() if a not in ("door", "rooms")})
        line = [[float(d["x1"]), float(d["y1"])], [float(d["x2"]), float(d["y2"])]]
        feats.append(({"type": "Feature", "id": f"door-{did}",
                       "geometry": {"type": "LineString", "coordinates": line}, "properties": props}, None))
    props = {"coordinate_system": GEOJSON_COORDINATES}
    props.update({k: _plain(v) for k, v in G.graph.items()})
    return props, feats


def _geojson_text(G) -> str:
    """``json.dumps(to_geojson(G))``, the rooms' outlines from their coordinates texts (:func:`_coords_json`)."""
    props, feats = _geojson_parts(G, _plain_for_dumps)
    texts = []
    for f, geom in feats:
        text = json.dumps(f)
        if geom is not None:
            # inside a JSON string every quote is escaped: the first '"geometry": null' is the key's
            text = text.replace('"geometry": null', '"geometry": ' + _geom_json_text(geom), 1)
        texts.append(text)
    return ('{"type": "FeatureCollection", "properties": ' + json.dumps(props) + ', "features": ['
            + ", ".join(texts) + "]}")


def _plain_for_dumps(v):
    """What json.dumps writes as it writes :func:`_plain` of ``v``: lists and tuples of plain
    values as they are (``door_distances``: no copy as lists), anything else :func:`_plain`."""
    if isinstance(v, (list, tuple)) and _json_as_is(v) is not None:
        return v
    return _plain(v)


def _geom_json_text(geom) -> str:
    """``json.dumps(_geom_json(geom))``; 2-D polygons from their memoised coordinates texts."""
    t = geom.geom_type
    if t in ("Polygon", "MultiPolygon") and not geom.is_empty and not geom.has_z:
        return '{"type": "' + t + '", "coordinates": ' + _coords_json(geom) + "}"
    return json.dumps(_geom_json(geom))


def _geom_json(geom) -> dict:
    """GeoJSON geometry of a shapely geometry: plain lists of floats (exact values)."""
    t = geom.geom_type

    def rings(p):
        return [np.asarray(r.coords, float).tolist() for r in [p.exterior, *p.interiors]]

    if t == "Polygon" and not geom.is_empty:
        return {"type": "Polygon", "coordinates": rings(geom)}
    if t == "MultiPolygon" and not geom.is_empty:
        return {"type": "MultiPolygon", "coordinates": [rings(p) for p in geom.geoms]}
    from shapely.geometry import mapping

    return _plain_geom(mapping(geom))


def _plain_geom(m):
    if isinstance(m, dict):
        return {k: _plain_geom(v) for k, v in m.items()}
    if isinstance(m, (list, tuple)):
        return [_plain_geom(v) for v in m]
    return _plain(m)


def from_geojson(data: dict, name: str = "<geojson>") -> nx.MultiGraph:
    """Rebuild the room graph from :func:`to_geojson` data (types restored).

    Raises
    ------
    GraphFormatError
        Not a FeatureCollection of topomap rooms and doors.
    """
    if not isinstance(data, dict) or data.get("type") != "FeatureCollection" or \
            not isinstance(data.get("features"), list):
        raise GraphFormatError(f"{name}: not a GeoJSON FeatureCollection")
    G = nx.MultiGraph()
    if not isinstance(data.get("properties") or {}, dict) or \
            not all(isinstance(f, dict) and isinstance(f.get("properties") or {}, dict) for f in data["features"]):
        raise GraphFormatError(f"{name}: a feature or 'properties' is not a JSON object")
    gprops = dict(data.get("properties") or {})
    if gprops.get("coordinate_system") == GEOJSON_COORDINATES:
        del gprops["coordinate_system"]  # the note to_geojson adds, not a graph attribute
    G.graph.update(_restore(gprops, GRAPH_TYPES, f"{name}: collection"))
    doors = []
    for i, f in enumerate(data["features"]):
        props = dict((f or {}).get("properties") or {})
        kind = props.pop("kind", None)
        if kind == "room":
            if "room" not in props:
                raise GraphFormatError(f"{name}: feature {i}: a room needs its ID 'room'")
            n = _node_id(props.pop("room"))
            geom = f.get("geometry")
            if geom is not None:
                try:
                    props["polygon"] = _geometry(geom)
                except Exception as exc:  # noqa: BLE001
                    raise GraphFormatError(f"{name}: feature {i}: bad geometry: {exc}") from None
            else:
                props["polygon"] = None
            G.add_node(n, **_restore(props, NODE_TYPES, f"{name}: room {n}"))
        elif kind == "door":
            doors.append((i, props))
        # other features (annotations added by a GIS tool) are ignored
    for i, props in doors:
        try:
            a, b = (_node_id(r) for r in props.pop("rooms"))
        except Exception:  # noqa: BLE001
            raise GraphFormatError(f"{name}: feature {i}: a door needs 'rooms' [a, b]") from None
        d = _restore(props, EDGE_TYPES, f"{name}: door feature {i}")
        _check_door_ends(name, f"feature {i}", (a, b), G)
        G.add_edge(a, b, key=d.get("door"), **d)
    return G


def save_geojson(G: nx.Graph, path) -> Path:
    """Write :func:`to_geojson` of ``G`` to ``path`` (atomically; or into a binary file object)."""
    return _write(_geojson_text(G).encode("utf-8"), path)


def load_geojson(path) -> nx.MultiGraph:
    """Read a GeoJSON file written by :func:`save_geojson` back into a room graph."""
    path = _check_file(path)
    return _check_frame(from_geojson(_read_json(path), str(path)), path)


# --------------------------------------------------------------------------
# Any format by extension
# --------------------------------------------------------------------------

#: File extension -> format name.
FORMATS = {".graphml": "graphml", ".xml": "graphml", ".json": "json", ".geojson": "geojson"}


def graph_format(path) -> str:
    """The format of room graph file ``path`` by its extension (:data:`FORMATS`): ``"graphml"``,
    ``"json"`` or ``"geojson"``.

    Raises
    ------
    GraphFormatError
        Another extension, or none.
    """
    ext = Path(path).suffix.lower()
    if ext not in FORMATS:
        raise GraphFormatError(f"{path}: unknown graph format {ext or '(no extension)'!r}; "
                               f"use one of {', '.join(sorted(FORMATS))}")
    return FORMATS[ext]




def load_graph(path) -> nx.MultiGraph:
    """Load a room graph from ``.graphml``, ``.json`` (node-link) or ``.geojson``.

    Raises
    ------
    GraphFormatError
        Unknown extension, or the file is not a room graph (the message names the file).
    MapTooLargeError
        The graph's ``shape`` claims a map of more than :func:`topomap.io.cell_limit` cells.
    """
    try:
        return _load_graph(path)
    except (TopomapError, RecursionError, MemoryError):
        raise
    except Exception as exc:  # noqa: BLE001 - any other failure on odd content is a format error of the file
        raise _bad(path, "not a room graph topomap can read", f"{type(exc).__name__}: {exc}") from None


def _load_graph(path) -> nx.MultiGraph:
    fmt = graph_format(path)
    if fmt == "json":
        path = _check_file(path)
        head = _read_json(path)
        if isinstance(head, dict) and head.get("type") == "FeatureCollection":
            return _check_frame(from_geojson(head, str(path)), path)
    return {"graphml": load_graphml, "json": load_json, "geojson": load_geojson}[fmt](path)


def save_graph(G: nx.Graph, path) -> Path:
    """Save a room graph as ``.graphml``, ``.json`` (node-link) or ``.geojson`` by extension."""
    fmt = graph_format(path)
    return {"graphml": save_graphml, "json": save_json, "geojson": save_geojson}[fmt](G, path)


# --------------------------------------------------------------------------
# Label image as a ROS map pair
# --------------------------------------------------------------------------

def save_label_map(seg, stem, *, resolution=None, origin=None) -> Path:
    """Write the label image as a map_server PGM + YAML pair aligned with the map.

    The pair has the input map's size, ``resolution`` and ``origin``, so it
    overlays the map in RViz and other ROS tools. The PGM holds the labels
    as raw values (``0`` = not a room, ``1..n_rooms`` the rooms, higher
    values fragments, as in ``labels.png``) and the YAML says
    ``mode: raw``, so no threshold changes them:

    * an 8-bit PGM (maxval 255) when there are at most 255 labels;
    * a 16-bit PGM (maxval 65535, big-endian as Netpbm specifies) for more;
      :func:`load_label_map` reads both back exactly.

    Loaded by ``nav2_map_server`` (``map_server`` node, ``yaml_filename``
    the YAML), the ``nav_msgs/OccupancyGrid`` it publishes holds at each
    cell its label for labels ``0..100`` and ``-1`` for higher ones: Nav2's
    raw mode keeps pixel values ``0..100`` and makes everything else
    unknown (``nav2_map_server/src/map_io.cpp``, ``loadMapFromFile``), as
    :func:`topomap.io.load_map` does. ROS 1 ``map_server`` stores the pixel
    value as it is (int8: labels up to 127). For more labels, or exact IDs
    in every case, read the pair with :func:`load_label_map` or use the
    ``mono16`` image of :func:`topomap.io.ros.label_image`.

    Parameters
    ----------
    seg : Segmentation or (M, N) ndarray of int
        A segmentation (its labels and grid frame), or a label image with
        ``resolution``/``origin`` given.
    stem : str or os.PathLike
        Output path without suffix (``.yaml``/``.pgm`` suffixes are
        stripped): ``<stem>.pgm`` and ``<stem>.yaml`` are written, both
        renamed into place only after both were written.
    resolution : float, optional
        m/px; default the segmentation's grid's (0.05 for an array).
    origin : (x, y, yaw), optional
        Default the segmentation's grid's (``(0, 0, 0)`` for an array).

    Returns
    -------
    pathlib.Path
        The YAML file.
    """
    stem = Path(stem)
    if stem.suffix.lower() in (".yaml", ".yml", ".pgm"):
        stem = stem.with_suffix("")
    pgm, yml = stem.parent / (stem.name + ".pgm"), stem.parent / (stem.name + ".yaml")
    data, text = label_map_bytes(seg, pgm.name, resolution=resolution, origin=origin, name=str(stem))
    with ExitStack() as stack:
        fp = stack.enter_context(atomic_write(pgm))
        fy = stack.enter_context(atomic_write(yml))
        fp.write(data)
        fy.write(text)
    return yml


def label_map_bytes(seg, image_name: str, *, resolution=None, origin=None, name=None) -> tuple:
    """Contents of the :func:`save_label_map` pair: ``(pgm_bytes, yaml_bytes)``.

    ``image_name`` is the PGM's file name as the YAML names it; the other
    arguments are those of :func:`save_label_map` (``name`` for messages).
    """
    head, pixels, text = _label_map_parts(seg, image_name, resolution=resolution, origin=origin, name=name)
    return head + pixels.tobytes(), text


def _label_map_parts(seg, image_name: str, *, resolution=None, origin=None, name=None) -> tuple:
    """:func:`label_map_bytes` as ``(PGM header, PGM pixels as a C-contiguous array, yaml_bytes)``: the
    pixels written as they are by :func:`write_outputs`, not copied into one bytes object with the
    header (which would take fresh pages for a megabyte)."""
    name = image_name if name is None else name
    if hasattr(seg, "labels") and hasattr(seg, "grid"):
        resolution = seg.grid.resolution if resolution is None else resolution
        origin = seg.grid.origin if origin is None else origin
    labels = file_labels(seg, name, "PGM")
    top = labels.max(initial=0)
    res = float(0.05 if resolution is None else resolution)
    org = [float(v) for v in ((0.0, 0.0, 0.0) if origin is None else origin)]
    if len(org) == 2:
        org.append(0.0)
    wide = top > 255  # 16 bits, big-endian (Netpbm), for more than 255 labels
    pixels = np.ascontiguousarray(labels, dtype=">u2" if wide else np.uint8)
    meta = {"image": image_name, "mode": "raw", "resolution": res, "origin": org, "negate": 0,
            "occupied_thresh": OCCUPIED_THRESH, "free_thresh": FREE_THRESH}
    return pgm_header(labels.shape, 65535 if wide else 255), pixels, yaml_text(meta).encode()


def _pgm_tokens(buf: bytes, n: int, name):
    toks, i = [], 0
    while len(toks) < n:
        while i < len(buf) and (buf[i:i + 1].isspace() or buf[i:i + 1] == b"#"):
            if buf[i:i + 1] == b"#":
                j = buf.find(b"\n", i)
                i = len(buf) if j < 0 else j + 1
            else:
                i += 1
        j = i
        while j < len(buf) and not buf[j:j + 1].isspace() and buf[j:j + 1] != b"#":
            j += 1
        if j == i:
            raise GraphFormatError(f"{name}: truncated PGM header")
        toks.append(buf[i:j])
        i = j
    return toks, i + 1  # one whitespace byte after maxval


def load_label_map(path):
    """Read a label map pair written by :func:`save_label_map`.

    Parameters
    ----------
    path : str or os.PathLike
        The YAML file (or the PGM, or the stem).

    Returns
    -------
    labels : (M, N) ndarray of int32
    resolution : float
        m/px.
    origin : tuple of float
        ``(x, y, yaw)``.
    """
    import yaml

    path = Path(path)
    if path.suffix.lower() not in (".yaml", ".yml"):
        path = path.with_suffix(".yaml")
    path = _check_file(path)
    try:
        meta = yaml.safe_load(path.read_text(encoding="utf-8"))
        img = _check_file(path.parent / meta["image"])
        res = float(meta["resolution"])
        org = tuple(float(v) for v in meta["origin"])
    except GraphFormatError:
        raise
    except OSError:
        raise
    except Exception as exc:  # noqa: BLE001
        raise _bad(path, "not a label map YAML", exc) from None
    buf = img.read_bytes()
    if buf[:2] != b"P5":
        raise GraphFormatError(f"{img}: not a binary PGM (P5)")
    (w, h, maxval), off = _pgm_tokens(buf[2:], 3, img)
    w, h, maxval = int(w), int(h), int(maxval)
    dt = np.uint8 if maxval < 256 else np.dtype(">u2")
    n = w * h * np.dtype(dt).itemsize
    raw = buf[2 + off:2 + off + n]
    if len(raw) != n:
        raise GraphFormatError(f"{img}: PGM data truncated ({len(raw)} of {n} bytes)")
    return np.frombuffer(raw, dt).reshape(h, w).astype(np.int32), res, org


# --------------------------------------------------------------------------
# Label images of any Pillow mode (ground truths, label images of other tools)
# --------------------------------------------------------------------------

def _open_image(path: Path):
    """The Pillow image of ``path``, decoded, its size checked against :func:`topomap.io.cell_limit`."""
    from PIL import Image, UnidentifiedImageError

    if not path.exists():
        raise MapFileError(f"{path}: file does not exist")
    if path.is_dir():
        raise MapFileError(f"{path}: is a directory, not an image")
    try:
        with warnings.catch_warnings():  # the size is checked against MAX_CELLS below
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            img = Image.open(path)
        check_image_size(str(path), img.size[1], img.size[0])
        img.load()
    except Image.DecompressionBombError as exc:
        raise MapTooLargeError(f"{path}: image too large to decode ({first_line(exc)})") from None
    except UnidentifiedImageError as exc:
        raise MapError(f"{path}: not a readable image ({exc})") from None
    except OSError as exc:
        raise MapFileError(f"{path}: cannot be read ({exc})") from None
    return img


def read_gray(path) -> np.ndarray:
    """Read an image of any Pillow mode as 8-bit gray.

    Parameters
    ----------
    path : str or Path
        Any image Pillow reads.

    Returns
    -------
    (M, N) ndarray of uint8
        Pillow's ``convert("L")`` of the image; 16- and 32-bit gray values
        clipped to 0..255.

    Raises
    ------
    MapFileError
        No such file, a directory, or unreadable.
    MapError
        Not an image Pillow reads.
    MapTooLargeError
        More than :func:`topomap.io.cell_limit` cells.
    """
    path = Path(path)
    img = _open_image(path)
    if img.mode in ("I;16", "I;16B", "I;16L", "I"):
        arr = np.asarray(img)
        return np.clip(arr, 0, 255).astype(np.uint8)
    return np.asarray(img.convert("L"), dtype=np.uint8).copy()


def read_label_image(path) -> np.ndarray:
    """Read an integer room-label image.

    Parameters
    ----------
    path : str or Path
        A PNG (or other Pillow-readable image). Gray images (8-bit ``L``,
        16-bit ``I;16``, 32-bit ``I``) and palette images (``P``, the palette
        index is the label) give their values directly; ``LA`` uses the gray
        channel; colour images (``RGB``/``RGBA``) get one label per distinct
        colour, numbered 1.. in order of the packed colour value, with black
        (and fully transparent pixels) as 0.

    Returns
    -------
    (M, N) ndarray of int32
        0 = no room.
    """
    path = Path(path)
    img = _open_image(path)
    mode = img.mode
    if mode in ("L", "P", "I", "I;16", "I;16B", "I;16L", "1"):
        return np.asarray(img).astype(np.int32)
    if mode == "LA":
        return np.asarray(img)[..., 0].astype(np.int32)
    if mode in ("RGB", "RGBA"):
        arr = np.asarray(img)
        rgb = arr[..., :3].astype(np.int64)
        key = (rgb[..., 0] << 16) | (rgb[..., 1] << 8) | rgb[..., 2]
        if mode == "RGBA":
            key = np.where(arr[..., 3] == 0, 0, key)
        uniq, inv = np.unique(key, return_inverse=True)
        ids = np.arange(uniq.size, dtype=np.int32) + (0 if uniq[0] == 0 else 1)
        return ids[inv.reshape(key.shape)]
    raise MapError(f"{path}: unsupported image mode {mode!r} for a label image")


# --------------------------------------------------------------------------
# All outputs of a segmentation
# --------------------------------------------------------------------------

#: The files :func:`write_outputs` writes into a map's output folder, by kind.
OUTPUT_FILES = {"labels": "labels.png", "label_map_pgm": "labels.pgm", "label_map": "labels.yaml",
                "graphml": "rooms.graphml", "json": "rooms.json", "geojson": "rooms.geojson",
                "overlay": "overlay.png"}


def write_outputs(seg, outdir, graph, *, overlay_png: bytes | None = None, geojson: bool = True,
                  timings: dict | None = None, labels_png: bytes | None = None) -> dict:
    """Write ``labels.png``, ``labels.pgm`` + ``labels.yaml``, ``rooms.graphml``, ``rooms.json``,
    ``rooms.geojson`` and ``overlay.png``.

    Writes only: the graph and the picture are computed by the caller
    (:func:`topomap.cli.write_segmentation` does both, as ``topomap
    segment``).

    Parameters
    ----------
    seg : Segmentation
        Its ``labels`` are saved as ``labels.png`` and as the map_server
        pair ``labels.pgm`` + ``labels.yaml`` (:func:`save_label_map`).
    outdir : str or os.PathLike
        Created if missing.
    graph : networkx.Graph
        The graph saved as GraphML, JSON and GeoJSON (``topomap segment``
        saves :func:`topomap.planning.travel_graph`).
    overlay_png : bytes, optional
        PNG content of ``overlay.png`` (:func:`topomap.io.plot.overlay_png`);
        None writes no overlay.
    geojson : bool
        Also write ``rooms.geojson``.
    timings : dict, optional
        When given, the seconds each file took are stored in it as
        ``write_<name>`` (``write_labels``, ``write_graphml``, ...).
    labels_png : bytes, optional
        The content of ``labels.png`` when already made (:func:`save_labels`
        into a buffer); None makes it from ``seg.labels``.

    Returns
    -------
    dict
        ``{name: path}``. All files are first written to temporary names
        and renamed into place only once every one of them has been
        written, so a failure in any writer leaves no partial file and
        keeps every earlier output of ``outdir`` as it was.
    """
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    names = dict(OUTPUT_FILES)
    if not geojson:
        del names["geojson"]
    if overlay_png is None:
        del names["overlay"]
    label_map = {}

    def map_pair():  # labels.pgm (header, pixels) and labels.yaml, made once
        if not label_map:
            head, pixels, label_map["yaml"] = _label_map_parts(seg, names["label_map_pgm"],
                                                               name=str(outdir / names["label_map"]))
            label_map["pgm"] = (head, pixels)
        return label_map

    def write_pgm(fh):
        head, pixels = map_pair()["pgm"]
        fh.write(head)
        fh.write(pixels.data)

    writers = {"labels": lambda p: save_labels(seg, p) if labels_png is None else _write(labels_png, p),
               "label_map_pgm": write_pgm,
               "label_map": lambda p: save_bytes(map_pair()["yaml"], p),
               "graphml": lambda p: save_graphml(graph, p),
               "json": lambda p: save_json(graph, p), "geojson": lambda p: save_geojson(graph, p),
               "overlay": lambda p: save_bytes(overlay_png, p)}
    to_file = ("labels", "label_map_pgm", "graphml", "json", "geojson")  # writers given the open temporary file
    memo = _RING_MEMO.set({})  # outlines' floats encoded once, for the WKT and the GeoJSON
    scalars = _SCALAR_MEMO.set([graph, None])  # the GraphML scalars, encoded once for GraphML and JSON
    try:
        with ExitStack() as stack:  # on success renames every temporary file; on error removes them all
            tmp = {k: stack.enter_context(atomic_write(outdir / f, None)) for k, f in names.items()}
            for k in names:
                t = time.perf_counter()
                try:
                    if k in to_file:  # into the temporary file itself (renamed into place at the end)
                        with open(tmp[k], "wb") as fh:
                            writers[k](fh)
                    else:
                        writers[k](tmp[k])
                except OSError as exc:  # named after its own file (not the last temporary of the stack)
                    raise (renamed_error(exc, tmp[k], outdir / names[k]) or exc) from None
                if timings is not None:
                    timings[f"write_{k}"] = time.perf_counter() - t
    finally:
        _SCALAR_MEMO.reset(scalars)
        _RING_MEMO.reset(memo)
    return {k: outdir / f for k, f in names.items()}


def save_bytes(data: bytes, path) -> Path:
    """Write ``data`` to ``path`` (a file name or a binary file object) as it is."""
    if _is_file(path):
        path.write(data)
        return Path(_name(path))
    path = Path(path)
    path.write_bytes(data)
    return path
