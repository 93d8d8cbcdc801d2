"""The map_server YAML of a map and the values in it, read and checked.

:func:`read_yaml` reads a map YAML safely (size bound, no aliases, unknown
keys warned about, near-misses of known keys refused); the ``as_*``
functions turn one value of it (or of an argument that overrides it) into
the type :func:`topomap.io.maps.load_map` uses, raising
:class:`~topomap.errors.ParameterError` naming where the value came from;
:func:`check_file` refuses a missing, empty, unreadable file or a directory
with a one-line message. Shared by :mod:`topomap.io.maps` (map files) and
:mod:`topomap.io.ros` (bag metadata, map_saver thresholds).
"""

from __future__ import annotations

import difflib
import logging
import math
import os
import stat
from pathlib import Path

import numpy as np

from ..errors import MapError, MapFileError, MapFileNotFoundError, ParameterError, named, one_line
from ..grid import check_origin_range, check_resolution_range

__all__ = [
    "MAX_YAML_BYTES",
    "YAML_KEYS",
    "YAML_SUFFIXES",
    "MODES",
    "as_float",
    "as_bool",
    "as_mode",
    "as_resolution",
    "as_origin",
    "check_resolution",
    "check_thresholds",
    "exists",
    "check_file",
    "yaml_loader",
    "check_yaml_keys",
    "read_yaml",
    "image_named",
]

#: Largest map YAML read, bytes (a map_server YAML is a few hundred bytes).
MAX_YAML_BYTES = 1 << 20
#: The keys of a map_server YAML (anything else is a warning, a near-miss of one of these an error).
YAML_KEYS = ("image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh", "mode")
#: File suffixes read as a map YAML.
YAML_SUFFIXES = (".yaml", ".yml")
#: map_server's interpretation modes of the image.
MODES = ("trinary", "scale", "raw")

#: The logger of every warning :func:`~topomap.io.maps.load_map` gives (its name shows in the CLI's messages).
log = logging.getLogger("topomap.io.maps")


def as_float(name, key, val) -> float:
    """``val`` as a finite float (a number or a numeric string).

    Parameters
    ----------
    name : str or None
        Where the value came from (the file, ``<argument>``), leading the message.
    key : str
        The value's name in the message.
    val
        The value.

    Raises
    ------
    ParameterError
        A bool, None, not a number, or not finite.
    """
    if isinstance(val, (bool, np.bool_)) or val is None:
        raise ParameterError(named(name, f"{key} must be a number, got {val!r}"))
    try:
        v = float(val)
    except (TypeError, ValueError, OverflowError):
        raise ParameterError(named(name, f"{key} must be a number, got {val!r}")) from None
    if not math.isfinite(v):
        raise ParameterError(named(name, f"{key} must be finite, got {val!r}"))
    return v


def as_bool(name, key, val) -> bool:
    """``val`` as a bool: True/False, 0/1 or the strings "0", "1", "true", "false" (any case).

    Raises
    ------
    ParameterError
        Anything else; the message names ``name`` and ``key``.
    """
    if isinstance(val, (bool, np.bool_)):
        return bool(val)
    if isinstance(val, (int, np.integer)) and val in (0, 1):
        return bool(val)
    if isinstance(val, str) and val.strip().lower() in ("0", "1", "true", "false"):
        return val.strip().lower() in ("1", "true")
    raise ParameterError(named(name, f"{key} must be 0 or 1, got {val!r}"))


def as_mode(name, val) -> str:
    """``val`` as one of :data:`MODES` (lower case, stripped).

    Raises
    ------
    ParameterError
        Not a string, or not a map_server mode.
    """
    if not isinstance(val, str) or val.strip().lower() not in MODES:
        raise ParameterError(named(name, f"mode must be one of {', '.join(MODES)}, got {val!r}"))
    return val.strip().lower()


def as_resolution(name, val, key: str = "resolution") -> float:
    """``val`` as a resolution in metres per cell.

    Raises
    ------
    ParameterError
        Not a finite number > 0, or outside [:data:`~topomap.grid.MIN_RESOLUTION`,
        :data:`~topomap.grid.MAX_RESOLUTION`]; the message names ``key``.
    """
    v = as_float(name, key, val)
    if v <= 0:
        raise ParameterError(named(name, f"{key} must be > 0 m/px, got {val!r}"))
    check_resolution_range(name, v, key)
    return v


def check_resolution(value, *, name: str = "--resolution") -> float:
    """``value`` as a resolution (m per cell) in the accepted range.

    Raises
    ------
    ParameterError
        Not a number, not > 0, or outside [:data:`MIN_RESOLUTION`,
        :data:`MAX_RESOLUTION`]; the message begins with ``name``.
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)) \
            or not value > 0 or not math.isfinite(value):
        raise ParameterError(one_line(f"{name} must be > 0 m/px (a number), got {value!r}"))
    check_resolution_range(None, float(value), name)
    return float(value)


def as_origin(name, val) -> tuple:
    """``val`` (``[x, y]`` or ``[x, y, yaw]``) as the float triple ``(x, y, yaw)``, yaw 0 when not given.

    Raises
    ------
    ParameterError
        Not two or three finite numbers, or beyond :data:`~topomap.grid.MAX_ORIGIN`.
    """
    if isinstance(val, (str, bytes)) or not hasattr(val, "__len__") or len(val) not in (2, 3):
        raise ParameterError(named(name, f"origin must be [x, y, yaw] in metres/radians, got {val!r}"))
    org = tuple(as_float(name, "origin", v) for v in val) + ((0.0,) if len(val) == 2 else ())
    check_origin_range(name, org)
    return org


def check_thresholds(name, occupied_thresh, free_thresh) -> tuple:
    """map_server's thresholds as floats ``(occupied_thresh, free_thresh)``.

    Raises
    ------
    ParameterError
        Either is not a number in ``[0, 1]``, or ``free_thresh >= occupied_thresh``.
    """
    vals = []
    for key, val in (("occupied_thresh", occupied_thresh), ("free_thresh", free_thresh)):
        v = as_float(name, key, val)
        if not 0.0 <= v <= 1.0:
            raise ParameterError(named(name, f"{key} must be in [0, 1], got {val!r}"))
        vals.append(v)
    occ, free = vals
    if free >= occ:
        raise ParameterError(named(name, f"free_thresh ({free!r}) must be < occupied_thresh ({occ!r})"))
    return occ, free


def exists(path: Path) -> bool:
    """Whether ``path`` exists; False for a name the system refuses (too long, a NUL byte)."""
    try:
        return os.path.exists(path)
    except (OSError, ValueError):
        return False


def check_file(name, path: Path, what="map file") -> None:
    """Refuse a file that cannot be read whole; ``what`` names it in the message.

    Raises
    ------
    MapFileNotFoundError
        No such file.
    MapFileError
        A directory, not a regular file (a FIFO, socket or device), or not readable.
    MapError
        Empty (0 bytes).
    """
    if not exists(path):
        raise MapFileNotFoundError(named(name, f"{what} not found"))
    if path.is_dir():
        raise MapFileError(named(name, f"{what} is a directory, not a file"))
    try:
        st = path.stat()
    except OSError as exc:
        raise MapFileError(named(name, f"cannot stat {what}: {exc.strerror or exc}")) from None
    if not stat.S_ISREG(st.st_mode):  # never opened: reading a FIFO waits for a writer, a device never ends
        raise MapFileError(named(name, f"{what} is not a regular file (a FIFO, socket or device)"))
    size = st.st_size
    if size == 0:
        raise MapError(named(name, f"{what} is empty (0 bytes)"))
    if not os.access(path, os.R_OK):
        raise MapFileError(named(name, f"{what} is not readable (permission denied)"))


def yaml_loader():
    """A safe YAML loader that refuses aliases (``*name``): nothing expands (no "billion laughs"); and a
    key given twice in the document's mapping (PyYAML would keep the last value, map_server's yaml-cpp
    the first: the two would read different maps)."""
    import yaml

    class NoAliasLoader(yaml.SafeLoader):
        def compose_node(self, parent, index):
            if self.check_event(yaml.AliasEvent):
                mark = self.peek_event().start_mark
                raise yaml.composer.ComposerError(None, None, "aliases (*name) are not allowed in a map YAML",
                                                  mark)
            return super().compose_node(parent, index)

        def construct_document(self, node):
            self.top = node
            return super().construct_document(node)

        def construct_mapping(self, node, deep=False):
            seen = {}
            for key_node, _ in node.value if node is getattr(self, "top", None) else ():
                if not isinstance(key_node, yaml.ScalarNode) or key_node.tag == "tag:yaml.org,2002:merge":
                    continue
                key, mark = self.construct_object(key_node), key_node.start_mark
                try:
                    first = seen.setdefault(key, mark)
                except TypeError:  # unhashable: the constructor says so
                    continue
                if first is not mark:
                    lines = f"line {mark.line + 1}" if first.line == mark.line else \
                        f"lines {first.line + 1} and {mark.line + 1}"
                    raise yaml.constructor.ConstructorError(
                        None, None, f"key {one_line(repr(key))[:60]} given twice ({lines})", mark)
            return super().construct_mapping(node, deep=deep)

    return NoAliasLoader


def check_yaml_keys(name, meta: dict):
    """ParameterError for a near-miss of a known key (a typo); a warning for any other unknown key."""
    for key in meta:
        if key in YAML_KEYS:
            continue
        shown = one_line(repr(key))[:60]
        close = difflib.get_close_matches(str(key), YAML_KEYS, n=1, cutoff=0.75) if isinstance(key, str) else []
        if close:
            raise ParameterError(named(name, f"unknown key {shown} (did you mean '{close[0]}'?); a map YAML has "
                                            f"{', '.join(YAML_KEYS)}"))
        log.warning("%s", named(name, f"unknown key {shown} ignored (a map YAML has {', '.join(YAML_KEYS)})"))


def read_yaml(path: Path, name: str) -> dict:
    """The mapping of the map YAML ``path`` (``name`` leads the messages).

    At most :data:`MAX_YAML_BYTES`, read without aliases (:func:`yaml_loader`),
    its keys checked by :func:`check_yaml_keys`.

    Raises
    ------
    MapFileNotFoundError, MapFileError
        As :func:`check_file`, or the file cannot be read.
    MapError
        Empty, too large, not valid YAML, or not a mapping.
    ParameterError
        A near-miss of a known key.
    """
    meta = _parse_yaml(path, name)
    check_yaml_keys(name, meta)
    return meta


def image_named(path: Path):
    """The image file the map YAML ``path`` names (absolute; relative names are relative to the YAML's
    folder), or None when the YAML cannot be read or names no usable file name.

    Read as :func:`read_yaml` reads it (bounded by :data:`MAX_YAML_BYTES`, no aliases, a FIFO or device
    never opened), without its warnings and errors: for callers that only want to know the files a map
    is made of (the run record), leaving the messages to :func:`~topomap.io.maps.load_map`.
    """
    path = Path(path)
    try:
        image = _parse_yaml(path, str(path)).get("image")
    except (MapError, MapFileError, ParameterError):
        return None
    if not isinstance(image, str) or not image.strip() or "\x00" in image:
        return None
    return Path(os.path.abspath(path.parent / image))


def _parse_yaml(path: Path, name: str) -> dict:
    """The mapping of the map YAML ``path``, as :func:`read_yaml` reads it, its keys not checked."""
    import yaml

    check_file(name, path, "map YAML")
    try:
        size = path.stat().st_size
    except OSError as exc:
        raise MapFileError(named(name, f"cannot read map YAML: {exc.strerror or exc}")) from None
    if size > MAX_YAML_BYTES:
        raise MapError(named(name, f"map YAML is {size:,} bytes, more than {MAX_YAML_BYTES:,} (a map_server YAML "
                                  f"is a few lines; is this the image?)"))
    try:
        text = path.read_bytes()
    except OSError as exc:
        raise MapFileError(named(name, f"cannot read map YAML: {exc.strerror or exc}")) from None
    try:
        meta = yaml.load(text, Loader=yaml_loader())  # noqa: S506 - a SafeLoader without aliases
    except yaml.reader.ReaderError as exc:
        raise MapError(named(name, f"not valid YAML: {_reader_problem(exc)}")) from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        problem = getattr(exc, "problem", None) or type(exc).__name__
        raise MapError(named(name, f"not valid YAML{where}: {problem}")) from None
    except (RecursionError, MemoryError):
        raise MapError(named(name, "not valid YAML: nested too deeply")) from None
    except Exception as exc:
        raise MapError(named(name, f"not valid YAML: {one_line(exc) or type(exc).__name__}")) from None
    if not isinstance(meta, dict):
        raise MapError(named(name, f"map YAML must be a mapping (key: value), got {type(meta).__name__}"))
    return meta


def _reader_problem(exc) -> str:
    """What PyYAML's ReaderError ``exc`` found, in words: a byte that is not UTF-8 (UTF-16 with its BOM is
    read too), or a control character YAML does not allow; with its offset in the file."""
    if exc.encoding != "unicode" and isinstance(exc.character, int):
        return (f"byte 0x{exc.character:02x} at offset {exc.position} is not {exc.encoding.upper()} "
                f"({exc.reason}; a map YAML is UTF-8 text)")
    return f"character U+{exc.character:04X} at offset {exc.position} is not allowed in YAML text ({exc.reason})"
