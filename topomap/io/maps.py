"""Map input and output: occupancy grids from ROS map files, images and arrays.

Cell states follow ROS ``nav_msgs/OccupancyGrid``: ``0`` free, ``100``
occupied, ``-1`` unknown. Pixel coordinates are ``(row, col)`` with row 0 at
the top of the image; world coordinates are ``(x, y)`` in metres in the map
frame, where ``origin`` is the pose of the *lower-left* corner of the image,
as ROS map_server defines it.
"""

from __future__ import annotations

import logging
import os
import re
import threading
import warnings
from pathlib import Path
from typing import NamedTuple, Optional

import numpy as np

from .._fast import lookup
from ..errors import (MapError, MapFileError, MapFileNotFoundError, MapTooLargeError, ParameterError, TopomapError,
                      named, one_line)
from ..grid import FREE, OCCUPIED, UNKNOWN, USUAL_RESOLUTION, OccupancyGrid, cell_limit, check_image_size
from .files import write_bytes
from .metadata import (MAX_YAML_BYTES, YAML_KEYS, YAML_SUFFIXES, as_bool, as_mode, as_origin, as_resolution,
                       check_file, check_resolution, check_thresholds, exists, read_yaml)
from .ros import BAG_SUFFIXES, is_bag, read_map

__all__ = [
    "USUAL_FREE_AREA",
    "check_resolution",
    "MAX_YAML_BYTES",
    "YAML_KEYS",
    "DEFAULT_RESOLUTION",
    "OCCUPIED_THRESH",
    "FREE_THRESH",
    "FREE_GRAY",
    "GRAY_FREE",
    "GRAY_OCCUPIED",
    "GRAY_UNKNOWN",
    "classify_gray",
    "classify_plan",
    "from_array",
    "load_map",
    "yaml_beside",
    "save_map",
]

log = logging.getLogger(__name__)

#: Cell size in metres per pixel used for bare images when none is given.
DEFAULT_RESOLUTION = 0.05
#: map_server default thresholds on the occupancy probability ``p``.
OCCUPIED_THRESH = 0.65
FREE_THRESH = 0.196

#: A bare image (no YAML) is read as a floor plan: a pixel is free from this
#: gray level up (map_saver writes free cells as 254), unknown where it is
#: map_saver's unknown gray 205, occupied everywhere else (:func:`classify_plan`).
#: The same level defines the free cells of the ipa_room_segmentation benchmark
#: and the white of its ground-truth drawings.
FREE_GRAY = 250

#: Gray values map_saver writes (and :func:`save_map` writes) per state.
GRAY_FREE = 254
GRAY_OCCUPIED = 0
GRAY_UNKNOWN = 205


def classify_gray(gray, *, negate: bool = False, occupied_thresh: float = OCCUPIED_THRESH,
                  free_thresh: float = FREE_THRESH, mode: str = "trinary",
                  transparent=None) -> np.ndarray:
    """Classify an 8-bit gray image into ROS cell values, as map_server does.

    With ``p = (255 - v) / 255`` (``v / 255`` when ``negate``), a pixel is
    ``OCCUPIED`` if ``p > occupied_thresh``, ``FREE`` if ``p < free_thresh``
    and ``UNKNOWN`` otherwise (``trinary``). ``scale`` mode is classified
    the same way (topomap only needs three states; map_server would give the
    in-between pixels graded values). In ``raw`` mode the pixel value
    (after ``negate``: ``255 - v``) *is* the ROS value: ``0..100`` kept,
    anything above is ``UNKNOWN``.

    Parameters
    ----------
    gray : (M, N) ndarray of uint8
        Gray image, 0 = black.
    negate : bool
        Invert the meaning of gray (white = occupied).
    occupied_thresh, free_thresh : float
        Thresholds on ``p`` in ``[0, 1]``, ``free_thresh < occupied_thresh``.
    mode : {'trinary', 'scale', 'raw'}
        map_server interpretation mode.
    transparent : (M, N) ndarray of bool, optional
        Pixels to mark ``UNKNOWN`` regardless of value (fully transparent).

    Returns
    -------
    (M, N) ndarray of int8
        ``FREE`` (0), ``OCCUPIED`` (100), ``UNKNOWN`` (-1); in raw mode any
        value in ``0..100``.
    """
    mode = as_mode("<array>", mode)
    occ, free = check_thresholds("<array>", occupied_thresh, free_thresh)
    v = np.arange(256)
    if negate:
        v = 255 - v
    if mode == "raw":
        lut = np.where(v <= 100, v, UNKNOWN).astype(np.int8)
    else:
        p = (255 - v) / 255.0
        lut = np.full(256, UNKNOWN, np.int8)
        lut[p > occ] = OCCUPIED
        lut[p < free] = FREE
    cells = lut[np.asarray(gray, dtype=np.uint8)]
    if transparent is not None:
        cells[np.asarray(transparent, bool)] = UNKNOWN
    return cells


def classify_plan(gray, *, negate: bool = False, transparent=None) -> np.ndarray:
    """Classify an 8-bit gray floor plan or map_saver image (the bare-image rule).

    ``FREE`` where gray >= :data:`FREE_GRAY` (250), ``UNKNOWN`` where gray is
    exactly :data:`GRAY_UNKNOWN` (205, map_saver's unknown), ``OCCUPIED``
    everywhere else. This is the rule :func:`load_map` applies to a bare
    image (no YAML): a drawn floor plan's walls, anti-aliased fringes and
    gray areas are obstacles, and an image map_saver wrote (0 / 205 / 254)
    reads exactly as map_server reads it with its default thresholds.

    Parameters
    ----------
    gray : (M, N) ndarray of uint8
        Gray image, 0 = black.
    negate : bool
        Invert the gray values first (white = occupied).
    transparent : (M, N) ndarray of bool, optional
        Pixels to mark ``UNKNOWN`` (fully transparent).

    Returns
    -------
    (M, N) ndarray of int8
        ``FREE`` (0), ``OCCUPIED`` (100) or ``UNKNOWN`` (-1).
    """
    v = np.asarray(gray, dtype=np.uint8)
    lut = np.where(np.arange(256) >= FREE_GRAY, FREE, OCCUPIED).astype(np.int8)
    lut[GRAY_UNKNOWN] = UNKNOWN
    if negate:
        lut = lut[::-1].copy()  # the class of 255 - v
    cells = lookup(lut, v) if v.ndim == 2 else lut[v]
    if transparent is not None:
        cells[np.asarray(transparent, bool)] = UNKNOWN
    return cells


def from_array(array, *, resolution: float = DEFAULT_RESOLUTION, origin=(0.0, 0.0, 0.0),
               source: Optional[str] = None, negate: bool = False,
               occupied_thresh: float = OCCUPIED_THRESH,
               free_thresh: float = FREE_THRESH) -> OccupancyGrid:
    """Build an :class:`OccupancyGrid` from a 2-D array.

    Parameters
    ----------
    array : (M, N) ndarray
        ``bool``: True = free, False = occupied. Signed integers: ROS values
        (0 free, 100 occupied, negative unknown; 1..99 counted as occupied
        when >= 65, else free). ``uint8``: a gray image, classified with
        map_server's trinary rule (see :func:`classify_gray`) and kept as
        ``grid.gray``.
    resolution : float
        Metres per pixel, > 0.
    origin : (x, y[, yaw])
        Lower-left corner in map-frame metres (yaw in radians).
    source : str, optional
        Name used in messages.
    negate, occupied_thresh, free_thresh
        Gray classification options, used for ``uint8`` input only.

    Returns
    -------
    OccupancyGrid

    Raises
    ------
    MapError
        Not 2-D, empty, or an unsupported dtype.
    ParameterError
        Bad resolution, origin or thresholds.
    """
    name = source or "<array>"
    try:
        a = np.asarray(array)
    except (TypeError, ValueError) as exc:
        raise MapError(named(name, f"cannot convert {type(array).__name__} to an array: {exc}")) from None
    if a.ndim != 2:
        raise MapError(named(name, f"array must be 2-D, got ndim={a.ndim} (shape {a.shape})"))
    if a.size == 0:
        raise MapError(named(name, f"array is empty (shape {a.shape})"))
    if a.dtype == bool:
        cells = np.where(a, FREE, OCCUPIED).astype(np.int8)
        return OccupancyGrid(cells, resolution, origin, source)
    if a.dtype == np.uint8:
        occ, free = check_thresholds(name, occupied_thresh, free_thresh)
        cells = classify_gray(a, negate=as_bool(name, "negate", negate),
                              occupied_thresh=occ, free_thresh=free)
        return OccupancyGrid(cells, resolution, origin, source, gray=a)
    if np.issubdtype(a.dtype, np.signedinteger):
        cells = np.full(a.shape, UNKNOWN, np.int8)
        cells[(a >= 0) & (a < 65)] = FREE
        cells[a >= 65] = OCCUPIED
        return OccupancyGrid(cells, resolution, origin, source)
    raise MapError(named(name, f"unsupported array dtype {a.dtype} (use bool, uint8 gray or int8 ROS values)"))


# --------------------------------------------------------------------------
# Reading images
# --------------------------------------------------------------------------

def _to_gray(name, img):
    """Decode a Pillow image into ``(gray uint8, transparent bool or None)``."""
    mode = img.mode
    transparent = None
    if mode == "P" or (mode in ("L", "RGB", "1") and "transparency" in img.info):
        img = img.convert("RGBA")
        mode = "RGBA"
    elif mode in ("PA", "La"):
        img = img.convert("LA")
        mode = "LA"
    elif mode in ("RGBa",):
        img = img.convert("RGBA")
        mode = "RGBA"
    if mode == "1":
        gray = np.asarray(img.convert("L"), dtype=np.uint8)
    elif mode == "L":
        gray = np.asarray(img, dtype=np.uint8)
    elif mode == "LA":
        a = np.asarray(img, dtype=np.uint8)
        gray, transparent = a[..., 0], a[..., 1] == 0
    elif mode.startswith("I;16"):
        a = np.asarray(img).astype(np.uint32)
        gray = (a >> 8).astype(np.uint8)
    elif mode == "I":
        a = np.asarray(img).astype(np.int64)
        gray = (np.clip(a, 0, 65535) >> 8).astype(np.uint8)
    elif mode == "F":
        a = np.nan_to_num(np.asarray(img, dtype=np.float64), nan=0.0, posinf=255.0, neginf=0.0)
        gray = np.clip(np.rint(a), 0, 255).astype(np.uint8)
    else:
        if mode not in ("RGB", "RGBA"):
            img = img.convert("RGBA" if "A" in img.getbands() else "RGB")
            mode = img.mode
        a = np.asarray(img, dtype=np.uint8)
        # map_server averages the colour channels, rounded to the nearest (a third is never a half:
        # rint((r + g + b) / 3) is (r + g + b + 1) // 3)
        gray = ((a[..., 0].astype(np.uint16) + a[..., 1] + a[..., 2] + 1) // 3).astype(np.uint8)
        if mode == "RGBA":
            transparent = a[..., 3] == 0
    if gray.ndim != 2:
        raise MapError(named(name, f"image mode {img.mode} decoded to shape {gray.shape}, not 2-D"))
    gray = np.ascontiguousarray(gray)
    if transparent is not None and not transparent.any():
        transparent = None
    return gray, transparent


_PIL_LIMIT_LOCK = threading.Lock()


def _open_decode(path: Path, name: str, lift_pillow_limit: bool = False):
    from PIL import Image

    if lift_pillow_limit:
        with _PIL_LIMIT_LOCK:
            saved = Image.MAX_IMAGE_PIXELS
            Image.MAX_IMAGE_PIXELS = None
            try:
                img = Image.open(path)
            finally:
                Image.MAX_IMAGE_PIXELS = saved
    else:
        img = Image.open(path)
    with img:
        cols, rows = img.size
        check_image_size(name, rows, cols)
        if rows == 0 or cols == 0:
            raise MapError(named(name, f"image has zero size ({cols} x {rows} px)"))
        img.load()
        return _to_gray(name, img)


def _read_image(path: Path, name: str):
    """Read any Pillow image as ``(gray uint8 (M, N), transparent or None)``.

    The size limit is :func:`cell_limit`, checked from the header. Pillow's
    own decompression-bomb check is silenced (warning) or turned into
    :class:`MapTooLargeError` (error) when the image also exceeds the
    limit; an image within it is decoded regardless.
    """
    from PIL import Image, UnidentifiedImageError

    check_file(name, path, "image file")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", Image.DecompressionBombWarning)
        try:
            try:
                return _open_decode(path, name)
            except Image.DecompressionBombError as exc:
                m = re.search(r"\((\d+) pixels\)", str(exc))
                count = int(m.group(1)) if m else None
                limit, why = cell_limit()
                if count is None or count > limit:
                    size = f"{count:,} cells" if count is not None else "too many cells"
                    raise MapTooLargeError(named(name, f"image is {size}, more than {why}")) from None
                return _open_decode(path, name, lift_pillow_limit=True)
        except (MapError, MapFileError):
            raise
        except UnidentifiedImageError:
            raise MapError(named(name, "not an image file Pillow can read (unknown or corrupt format)")) from None
        except MemoryError:
            raise MapTooLargeError(named(name, "out of memory while decoding the image")) from None
        except PermissionError as exc:
            raise MapFileError(named(name, f"cannot read image: {exc.strerror or exc}")) from None
        except Exception as exc:  # Pillow raises OSError, ValueError, SyntaxError, struct.error, ...
            detail = one_line(exc) or type(exc).__name__
            if "truncated" in detail.lower():
                raise MapError(named(name, f"image file is truncated or corrupt ({detail})")) from None
            raise MapError(named(name, f"cannot decode image: {detail}")) from None


# --------------------------------------------------------------------------
# Loading
# --------------------------------------------------------------------------

def yaml_beside(path) -> tuple:
    """The map_server YAML of the same stem beside image ``path`` (``map.pgm`` -> ``map.yaml``), for
    ``topomap segment map.pgm`` without ``--resolution``.

    Returns
    -------
    (pathlib.Path or None, str or None)
        ``(yaml, None)`` when ``map.yaml`` (or ``.yml``) names this very image: read the map through
        it; ``(None, why)`` when such a YAML exists but names another image or cannot be read (the
        image is read alone; ``why`` says so); ``(None, None)`` when there is none (or ``path`` is a
        YAML or a bag).
    """
    p = Path(os.fspath(path))
    if p.suffix.lower() in YAML_SUFFIXES or p.suffix.lower() in BAG_SUFFIXES or not p.is_file():
        return None, None
    for suffix in YAML_SUFFIXES:
        y = p.with_suffix(suffix)
        if y == p or not y.is_file():
            continue
        try:
            image = read_yaml(y, str(y)).get("image")
        except (TopomapError, OSError) as exc:
            return None, f"{y.name} beside it cannot be read ({one_line(exc)}); the image is read alone"
        if isinstance(image, str) and image.strip() and "\x00" not in image:
            target = Path(image) if Path(image).is_absolute() else y.parent / image
            try:
                if target.exists() and os.path.samefile(target, p):
                    return y, None
            except OSError:
                pass
        return None, f"{y.name} beside it names another image ({one_line(repr(image))[:60]}); the image is read alone"
    return None, None


def load_map(path, *, resolution=None, origin=None, negate=None, occupied_thresh=None,
             free_thresh=None, mode=None, topic=None, time=None) -> OccupancyGrid:
    """Load an occupancy grid from a ROS map_server YAML, an image file or a ROS bag.

    Parameters
    ----------
    path : str or os.PathLike
        A ``.yaml``/``.yml`` map_server description (keys ``image``,
        ``resolution``, ``origin`` required; ``negate``, ``occupied_thresh``,
        ``free_thresh``, ``mode`` optional; ``image`` relative to the YAML
        file), any image Pillow reads (PGM, PNG, ...), or a ROS bag (``.bag``,
        ``.mcap``, ``.db3`` or a ROS 2 bag directory), read by
        :func:`topomap.io.ros.read_map` (needs ``pip install 'topomap-rooms[ros]'``).
    resolution : float, optional
        Metres per pixel; overrides the YAML. Images default to
        :data:`DEFAULT_RESOLUTION` (0.05 m/px).
    origin : (x, y[, yaw]), optional
        Map-frame pose of the lower-left image corner, metres and radians;
        overrides the YAML. Images default to ``(0, 0, 0)``.
    negate : bool, optional
        White means occupied. Default ``False``.
    occupied_thresh, free_thresh : float, optional
        Thresholds on ``p = (255 - v) / 255`` (override the YAML); defaults
        0.65 and 0.196 (map_server's). Giving either for a bare image reads
        it with map_server's rule instead of the floor-plan rule (Notes).
    mode : {'trinary', 'scale', 'raw'}, optional
        map_server mode. ``scale`` is classified like ``trinary``; ``raw``
        takes pixel values ``0..100`` as ROS values (others unknown). Giving
        it for a bare image reads it with map_server's rule.
    topic : str, optional
        Bag only: the ``nav_msgs/OccupancyGrid`` topic (default the bag's
        only one).
    time : float, optional
        Bag only: seconds after the start of the bag; the last map message
        at or before it is read (default the last message).

    Returns
    -------
    OccupancyGrid
        ``cells`` (M, N) int8, ``gray`` the (M, N) uint8 image as read
        (any mode converted to 8-bit gray: colour channels averaged,
        16-bit values ``>> 8``; fully transparent pixels are ``UNKNOWN``).

    Raises
    ------
    MapFileNotFoundError
        The file, or the image a YAML names, does not exist.
    MapFileError
        A directory or unreadable file.
    MapTooLargeError
        More than :func:`cell_limit` cells (checked from the image header).
    MapError
        Empty, corrupt, truncated or unreadable content; bad YAML.
    ParameterError
        Invalid resolution, origin, thresholds, negate or mode (from the
        YAML or the arguments).

    Notes
    -----
    **A YAML** is read with map_server's exact semantics: its own
    ``occupied_thresh``, ``free_thresh``, ``negate`` and ``mode``.

    **A bare image** (no YAML, no threshold or mode argument) is read as a
    floor plan or an image map_saver wrote (:func:`classify_plan`): a pixel
    is free where its gray value is at least :data:`FREE_GRAY` (250; map_saver
    writes free space as 254), unknown where it is exactly 205 (map_saver's
    unknown) and occupied everywhere else. A map_saver image thus reads as
    map_server reads it with its default thresholds. A drawn floor plan,
    though, would not: map_server's defaults call every gray from 206 up
    free (the anti-aliased fringe of a wall) and every gray from 90 to 204
    unknown, and many floor plans draw walls and the outside in such grays;
    a method that builds on occupied space then loses the walls. To read an
    image with map_server's rule, write a YAML for it or pass
    ``free_thresh`` / ``occupied_thresh`` / ``mode``.

    **A bag** gives a :class:`topomap.io.ros.RosMap` (an ``OccupancyGrid``
    that also keeps the message's ``frame_id`` and stamp): cell values as
    map_saver + map_server turn them into three states (``0..25`` free,
    ``65..100`` occupied, the rest unknown; ``free_thresh`` /
    ``occupied_thresh`` change the 0.25 / 0.65 of map_saver), resolution
    and origin (with yaw) from the message. See :func:`topomap.io.ros.read_map`
    for its errors (:class:`~topomap.errors.BagError`).
    """
    p, name = _map_path(path)
    if is_bag(p):
        if negate is not None or mode is not None:
            raise ParameterError(named(name, "negate and mode apply to images; a bag holds ROS cell values"))
        return read_map(p, topic=topic, time=time, free_thresh=free_thresh, occupied_thresh=occupied_thresh,
                        resolution=resolution, origin=origin)
    if topic is not None or time is not None:
        raise ParameterError(named(name, "topic and time apply to ROS bags (.bag, .mcap, .db3, a bag directory)"))
    is_yaml = p.suffix.lower() in YAML_SUFFIXES
    meta, image_path = _map_yaml(p, name, resolution is None, origin is None) if is_yaml else ({}, p)
    how = _how_to_read(name, meta, resolution=resolution, origin=origin, negate=negate, mode=mode,
                       occupied_thresh=occupied_thresh, free_thresh=free_thresh)
    gray, transparent = _read_map_image(p, name, image_path)
    if is_yaml or any(v is not None for v in (occupied_thresh, free_thresh, mode)):
        cells = classify_gray(gray, negate=how.negate, occupied_thresh=how.occupied_thresh,
                              free_thresh=how.free_thresh, mode=how.mode, transparent=transparent)
        _warn_unknown_read_free(name, gray, cells, how.free_thresh, how.free_thresh_from, how.negate)
    else:
        cells = classify_plan(gray, negate=how.negate, transparent=transparent)
    grid = OccupancyGrid(cells, how.resolution, how.origin, name, gray=gray)
    _warn_free_area(name, np.count_nonzero(cells == FREE) * how.resolution * how.resolution)
    return grid


def _map_path(path) -> tuple:
    """``(pathlib.Path, name)`` of the ``path`` argument of :func:`load_map`."""
    try:
        p = Path(os.fspath(path))
    except TypeError:
        raise MapFileError(named(repr(path), "map path must be a str or os.PathLike")) from None
    name = str(p)
    if "\x00" in name:
        raise MapFileError(named(repr(name), "map path contains a NUL byte"))
    return p, name


def _map_yaml(p: Path, name: str, needs_resolution: bool, needs_origin: bool) -> tuple:
    """``(meta, image path)`` of the map YAML ``p``: its keys, checked for the required ones
    (``resolution`` and ``origin`` only when no argument gives them), and the image it names
    (relative to the YAML's folder), which must exist."""
    meta = read_yaml(p, name)
    required = ("image",) + (("resolution",) if needs_resolution else ()) + (("origin",) if needs_origin else ())
    for key in required:
        if key not in meta or meta[key] is None:
            raise MapError(named(name, f"map YAML lacks the required key '{key}'"))
    img = meta["image"]
    if not isinstance(img, str) or not img.strip() or "\x00" in img:
        raise MapError(named(name, f"'image' must be a file name, got {img!r}"))
    image_path = Path(img)
    if not image_path.is_absolute():
        image_path = p.parent / image_path
    if not exists(image_path):
        raise MapFileNotFoundError(named(name, f"image '{img}' not found (looked for {image_path})"))
    return meta, image_path


class _HowToRead(NamedTuple):
    """The checked values :func:`load_map` reads a map image with (from the arguments, else the YAML,
    else the defaults)."""

    resolution: float
    origin: tuple
    negate: bool
    mode: str
    occupied_thresh: float
    free_thresh: float
    free_thresh_from: str  # the file, or "<argument>": named when free_thresh makes unknown cells free


def _pick(name: str, meta: dict, key: str, value, default) -> tuple:
    """``(value, where it came from)``: the argument if given, else the YAML's value, else ``default``."""
    if value is not None:
        return value, "<argument>"
    if key in meta and meta[key] is not None:
        return meta[key], name
    return default, name


def _how_to_read(name: str, meta: dict, *, resolution, origin, negate, mode, occupied_thresh,
                 free_thresh) -> _HowToRead:
    """The :class:`_HowToRead` of a map: each value checked, its error naming where it came from; a
    warning when the resolution is outside what indoor maps use."""
    val, where = _pick(name, meta, "resolution", resolution, DEFAULT_RESOLUTION)
    res = as_resolution(where, val)
    if not USUAL_RESOLUTION[0] <= res <= USUAL_RESOLUTION[1]:
        log.warning("%s", named(name, f"resolution {res:g} m per cell is outside what indoor maps use "
                                     f"({USUAL_RESOLUTION[0]:g}-{USUAL_RESOLUTION[1]:g}); rooms and doors "
                                     f"may be meaningless"))
    val, where = _pick(name, meta, "origin", origin, (0.0, 0.0, 0.0))
    org = as_origin(where, val)
    val, where = _pick(name, meta, "negate", negate, False)
    neg = as_bool(where, "negate", val)
    val, where = _pick(name, meta, "mode", mode, "trinary")
    mod = as_mode(where, val)
    occ_v, where_o = _pick(name, meta, "occupied_thresh", occupied_thresh, OCCUPIED_THRESH)
    free_v, where_f = _pick(name, meta, "free_thresh", free_thresh, FREE_THRESH)
    where = where_o if where_o == where_f else f"{name} (with arguments)"
    occ, free = check_thresholds(where, occ_v, free_v)
    return _HowToRead(res, org, neg, mod, occ, free, where_f)


def _read_map_image(p: Path, name: str, image_path: Path) -> tuple:
    """``(gray, transparent)`` of the map's image (:func:`_read_image`); an error about the image a
    YAML names names the YAML too."""
    try:
        return _read_image(image_path, str(image_path))
    except (MapError, MapFileError) as exc:
        if image_path is p:
            raise
        raise type(exc)(named(name, f"image {exc}")) from None


#: :func:`load_map` warns when at least this share of the free cells (and :data:`UNKNOWN_FREE_MIN_CELLS`
#: cells) have exactly map_saver's unknown gray (205) and the thresholds read them as free.
UNKNOWN_FREE_SHARE = 0.01
UNKNOWN_FREE_MIN_CELLS = 100


def _warn_unknown_read_free(name, gray, cells, free_thresh, where, negate=False):
    """One warning when the thresholds make map_saver's unknown gray 205 free and many cells have it
    (Nav2's ``free_thresh: 0.25`` reads 205, p = 0.196, as free: the unknown outside becomes rooms)."""
    g = GRAY_UNKNOWN
    at = np.flatnonzero(gray.ravel() == g)
    if at.size < UNKNOWN_FREE_MIN_CELLS:
        return
    n = int(np.count_nonzero(cells.ravel()[at] == FREE))
    n_free = int(np.count_nonzero(cells == FREE))
    if n < max(UNKNOWN_FREE_MIN_CELLS, UNKNOWN_FREE_SHARE * n_free):
        return
    pv = (255 - (255 - g if negate else g)) / 255
    src = "" if where == name else f" (from {where})"
    log.warning("%s", named(name, f"{n:,} cells ({100 * n / n_free:.0f} % of the free space) have gray {g}, "
                                 f"map_saver's unknown, and free_thresh {free_thresh:g}{src} reads them as free "
                                 f"(p = {pv:.3f}); if they are unknown, set free_thresh to at most "
                                 f"{pv - 0.001:.3f} (map_server's default is {FREE_THRESH})"))


#: Free area (m²) outside which :func:`load_map` warns: less than a small room, more than any building.
USUAL_FREE_AREA = (1.0, 1e6)


def _warn_free_area(name, area: float):
    lo, hi = USUAL_FREE_AREA
    if 0 < area < lo:
        log.warning("%s", named(name, f"free space is only {area:.3g} m², less than a small room; "
                                     f"is the resolution right?"))
    elif area > hi:
        log.warning("%s", named(name, f"free space is {area:.3g} m², more than any building; "
                                     f"is the resolution right (metres per cell)?"))


# --------------------------------------------------------------------------
# Saving
# --------------------------------------------------------------------------

def pgm_bytes(gray) -> bytes:
    """Binary (P5) PGM encoding of an (M, N) uint8 image, no comment line."""
    g = np.ascontiguousarray(gray, dtype=np.uint8)
    return pgm_header(g.shape, 255) + g.tobytes()


def pgm_header(shape, maxval: int) -> bytes:
    """The header of a binary (P5) PGM of an image of ``shape`` (M, N) whose largest value is
    ``maxval`` (255: 8-bit pixels; up to 65535: 16-bit, big-endian), no comment line."""
    return b"P5\n%d %d\n%d\n" % (shape[1], shape[0], maxval)


def _fmt_float(v: float) -> str:
    return repr(float(v))


def yaml_text(meta: dict) -> str:
    """map_server YAML text for ``meta`` in a fixed key order (deterministic)."""
    lines = [f"image: {meta['image']}"]
    if "mode" in meta:
        lines.append(f"mode: {meta['mode']}")
    lines.append(f"resolution: {_fmt_float(meta['resolution'])}")
    lines.append("origin: [" + ", ".join(_fmt_float(v) for v in meta["origin"]) + "]")
    lines.append(f"negate: {int(meta.get('negate', 0))}")
    lines.append(f"occupied_thresh: {_fmt_float(meta.get('occupied_thresh', OCCUPIED_THRESH))}")
    lines.append(f"free_thresh: {_fmt_float(meta.get('free_thresh', FREE_THRESH))}")
    return "\n".join(lines) + "\n"


def save_map(grid_or_cells, path_stem, *, resolution=None, origin=None, mode: str = "trinary"):
    """Write a map_server PGM + YAML pair, atomically.

    Parameters
    ----------
    grid_or_cells : OccupancyGrid or (M, N) ndarray
        A grid, ROS cell values (signed integers), a bool free mask, or a
        ``uint8`` image that is written verbatim (e.g. a label image to be
        read back with ``mode='raw'``).
    path_stem : str or os.PathLike
        Output path without suffix; ``<stem>.pgm`` and ``<stem>.yaml`` are
        written (a ``.yaml``/``.yml``/``.pgm`` suffix is stripped).
    resolution : float, optional
        Metres per pixel; default the grid's, or 0.05.
    origin : (x, y[, yaw]), optional
        Lower-left corner pose; default the grid's, or ``(0, 0, 0)``.
    mode : {'trinary', 'raw'}
        ``trinary``: cells written as 254 free, 0 occupied, 205 unknown.
        ``raw``: cell values ``0..100`` written as is, unknown as 255.
        (``uint8`` input is always written verbatim.)

    Returns
    -------
    pathlib.Path
        The YAML file, loadable with :func:`load_map`.

    Raises
    ------
    MapFileError
        The directory does not exist or cannot be written. Each file is
        written to a temporary file in the same directory and renamed into
        place, so no half-written file is ever left.
    """
    stem = Path(os.fspath(path_stem))
    if stem.suffix.lower() in YAML_SUFFIXES + (".pgm",):
        stem = stem.with_suffix("")
    name = str(stem)
    mode = as_mode(name, mode)
    if mode == "scale":
        raise ParameterError(named(name, "save_map supports mode 'trinary' or 'raw', got 'scale'"))
    if isinstance(grid_or_cells, OccupancyGrid):
        grid = grid_or_cells
        gray = None
        cells = grid.cells
        resolution = grid.resolution if resolution is None else resolution
        origin = grid.origin if origin is None else origin
    else:
        try:
            a = np.asarray(grid_or_cells)
        except (TypeError, ValueError) as exc:
            raise MapError(named(name, f"cannot convert {type(grid_or_cells).__name__} to an array: {exc}")) from None
        if a.dtype == np.uint8 and a.ndim == 2 and a.size:
            gray, cells = a, None
        else:
            gray, cells = None, from_array(a, source=name).cells
    res = as_resolution(name, DEFAULT_RESOLUTION if resolution is None else resolution)
    org = as_origin(name, (0.0, 0.0, 0.0) if origin is None else origin)
    if gray is None:
        if mode == "raw":
            gray = np.where((cells >= 0) & (cells <= 100), cells, 255).astype(np.uint8)
        else:
            gray = np.full(cells.shape, GRAY_UNKNOWN, np.uint8)
            gray[cells == FREE] = GRAY_FREE
            gray[cells == OCCUPIED] = GRAY_OCCUPIED
    pgm = stem.parent / (stem.name + ".pgm")
    yml = stem.parent / (stem.name + ".yaml")
    meta = {"image": pgm.name, "resolution": res, "origin": list(org), "negate": 0,
            "occupied_thresh": OCCUPIED_THRESH, "free_thresh": FREE_THRESH}
    if mode != "trinary":
        meta["mode"] = mode
    if not stem.parent.is_dir():
        raise MapFileNotFoundError(named(name, f"output directory {str(stem.parent)!r} does not exist"))
    try:
        write_bytes(pgm, pgm_bytes(gray))
        write_bytes(yml, yaml_text(meta).encode())
    except OSError as exc:
        raise MapFileError(named(name, f"cannot write map: {exc.strerror or exc}")) from None
    return yml
