"""The occupancy grid: three cell states, a metric frame, and the largest map this machine takes.

Cell states follow ROS ``nav_msgs/OccupancyGrid``: ``0`` free, ``100``
occupied, ``-1`` unknown. Pixel coordinates are ``(row, col)`` with row 0 at
the top of the image; world coordinates are ``(x, y)`` in metres in the map
frame, where ``origin`` is the pose of the *lower-left* corner of the image,
as ROS map_server defines it.

This module is the bottom of the package: every stage takes an
:class:`OccupancyGrid`; reading one from a file is :mod:`topomap.io`'s job.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from .errors import MapError, MapTooLargeError, ParameterError, named, one_line

__all__ = ["FREE", "OCCUPIED", "UNKNOWN", "MAX_CELLS", "JOB_BYTES_PER_CELL", "JOB_BASE_BYTES",
           "FALLBACK_MAX_CELLS", "MIN_MAX_CELLS", "available_memory", "cells_for_memory", "cell_limit", "check_image_size",
           "share_memory", "MIN_RESOLUTION", "MAX_RESOLUTION", "USUAL_RESOLUTION", "MAX_ORIGIN",
           "check_resolution_range", "check_origin_range", "OccupancyGrid"]

FREE = 0
OCCUPIED = 100
UNKNOWN = -1

#: Largest map accepted, in cells (rows * cols), when set; None (the default)
#: bounds a map by the memory its job will take against the memory the
#: machine has available (:func:`max_cells`). Checked from the image header
#: before any pixel is decoded; larger maps raise
#: :class:`~topomap.errors.MapTooLargeError`. Read at call time, so it can be
#: changed (``topomap.io.MAX_CELLS = ...``); the environment variable
#: ``TOPOMAP_MAX_CELLS`` sets it too (for the command line).
MAX_CELLS = None
#: Memory the whole job of a map (``topomap segment``: loading, segmentation,
#: room graph, travel distances, overlay, every file) takes at most: this
#: many bytes per cell, plus :data:`JOB_BASE_BYTES` (measured on maps built
#: to break it, ``benchmarks/adversarial.py``; the worst shape, a corridor
#: three cells wide, takes 140 bytes per cell, most maps 33 to 62).
JOB_BYTES_PER_CELL = 150
#: The interpreter, the libraries and their caches (a 1-cell map's job peaks at about 125 MB).
JOB_BASE_BYTES = 250_000_000
#: The limit when the available memory cannot be read: (8 GiB - 250 MB) / 150 B.
FALLBACK_MAX_CELLS = 55_000_000
#: The limit is never below this many cells (a 1000 x 1000 map), however little memory is free.
MIN_MAX_CELLS = 1_000_000
#: How many maps share the machine's memory at once (the local workers of a batch set it).
MEMORY_SHARERS = 1


#: Smallest and largest cell size accepted, metres per cell (1 mm and 10 m).
#: The methods' options are lengths in metres, so their kernels grow as
#: ``1 / resolution**2``: below 1 mm a single kernel would outgrow any map.
#: A resolution outside :data:`USUAL_RESOLUTION` (what indoor maps use) is
#: accepted with a warning.
MIN_RESOLUTION = 0.001
MAX_RESOLUTION = 10.0
#: Resolutions indoor maps use (metres per cell); outside, :func:`load_map` warns.
USUAL_RESOLUTION = (0.005, 0.5)
#: Largest ``|x|`` or ``|y|`` of an origin, metres (10,000 km: UTM northings fit).
MAX_ORIGIN = 1e7


def available_memory() -> Optional[int]:
    """Bytes of memory this process can still take: ``MemAvailable`` of ``/proc/meminfo``, capped by
    the cgroup's (container's) ``memory.max`` less its use; else free physical pages
    (``os.sysconf``); None when neither can be read."""
    avail = None
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    avail = int(line.split()[1]) * 1024
                    break
    except (OSError, ValueError, IndexError):
        pass
    if avail is None:
        try:
            avail = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        except (AttributeError, ValueError, OSError):
            return None
    try:  # cgroup v2: a container's own limit
        with open("/sys/fs/cgroup/memory.max") as fh:
            top = fh.read().strip()
        if top != "max":
            with open("/sys/fs/cgroup/memory.current") as fh:
                used = int(fh.read().strip())
            avail = min(avail, max(int(top) - used, 0))
    except (OSError, ValueError):
        pass
    return avail


def cells_for_memory(nbytes: float) -> int:
    """The largest map (cells) whose job fits ``nbytes`` of memory: ``(nbytes - JOB_BASE_BYTES) /
    JOB_BYTES_PER_CELL``, at least :data:`MIN_MAX_CELLS`."""
    return max(int((nbytes - JOB_BASE_BYTES) // JOB_BYTES_PER_CELL), MIN_MAX_CELLS)


def share_memory(maps: int) -> None:
    """Say that ``maps`` maps run at once in this process's memory (the local workers of a batch):
    :func:`cell_limit` then gives each its share of the memory available."""
    global MEMORY_SHARERS
    MEMORY_SHARERS = max(int(maps), 1)


def cell_limit() -> tuple:
    """``(cells, why)``: the largest map accepted now, and the words an error gives for it.

    :data:`MAX_CELLS` when set, else the environment variable
    ``TOPOMAP_MAX_CELLS``, else the memory available (:func:`available_memory`,
    shared by the maps a batch runs at once) through :func:`cells_for_memory`
    (:data:`FALLBACK_MAX_CELLS` when it cannot be read).

    Raises
    ------
    ParameterError
        ``TOPOMAP_MAX_CELLS`` is not a whole number > 0.
    """
    if MAX_CELLS is not None:
        return int(MAX_CELLS), f"topomap.io.MAX_CELLS = {int(MAX_CELLS):,}"
    env = os.environ.get("TOPOMAP_MAX_CELLS", "").strip()
    if env:
        try:
            v = float(env.replace("_", "").replace(",", ""))
        except ValueError:
            v = float("nan")
        if not (v.is_integer() and v >= 1):
            raise ParameterError(f"TOPOMAP_MAX_CELLS must be a whole number of cells > 0, got {env!r}")
        return int(v), f"TOPOMAP_MAX_CELLS = {int(v):,}"
    avail = available_memory()
    if avail is None:
        return FALLBACK_MAX_CELLS, (f"the {FALLBACK_MAX_CELLS:,} cells topomap assumes when it cannot read the "
                                    f"free memory (set TOPOMAP_MAX_CELLS to change)")
    share = avail / max(int(MEMORY_SHARERS), 1)
    n = cells_for_memory(share)
    jobs = f" for each of {MEMORY_SHARERS} maps at once" if MEMORY_SHARERS > 1 else ""
    return n, (f"the {n:,} cells the free memory allows ({share / 1e9:.1f} GB{jobs}, at "
               f"{JOB_BYTES_PER_CELL} bytes per cell + {JOB_BASE_BYTES / 1e6:.0f} MB; set TOPOMAP_MAX_CELLS "
               f"to change)")


def check_resolution_range(name, v: float, key: str = "resolution"):
    """ParameterError (naming ``name`` and ``key``) unless ``MIN_RESOLUTION <= v <= MAX_RESOLUTION``."""
    if not MIN_RESOLUTION <= v <= MAX_RESOLUTION:
        hint = " (metres per cell, not cells per metre)" if v > MAX_RESOLUTION else ""
        text = f"{key} must be between {MIN_RESOLUTION:g} and {MAX_RESOLUTION:g} m per cell, got {v:g}{hint}"
        raise ParameterError(named(name, text) if name else one_line(text))


def check_origin_range(name, origin):
    """ParameterError naming ``name`` if the origin's x or y lies beyond :data:`MAX_ORIGIN`."""
    if any(abs(v) > MAX_ORIGIN for v in origin[:2]):
        raise ParameterError(named(name, f"origin x and y must be within +-{MAX_ORIGIN:g} m, got "
                                        f"[{', '.join(f'{v:g}' for v in origin)}]"))


def check_image_size(name, rows, cols):
    """MapTooLargeError naming ``name`` if an image of ``rows`` x ``cols`` pixels is over :func:`cell_limit`
    (checked from a header, before any pixel is decoded)."""
    limit, why = cell_limit()
    if int(rows) * int(cols) > limit:
        raise MapTooLargeError(named(name, f"image is {cols} x {rows} px = {rows * cols:,} cells, more than {why}"))


@dataclass(frozen=True, eq=False)
class OccupancyGrid:
    """A three-state occupancy grid with its metric frame.

    Parameters
    ----------
    cells : (M, N) ndarray of int8
        ``FREE`` (0), ``OCCUPIED`` (100) or ``UNKNOWN`` (-1) per cell.
    resolution : float
        Cell size in metres per pixel.
    origin : tuple of float
        ``(x, y, yaw)`` of the lower-left corner of the grid, metres and
        radians (ROS map_server convention).
    source : str, optional
        File the grid was read from, used in messages.
    gray : (M, N) ndarray of uint8, optional
        The gray image the grid was classified from, if any.
    """

    cells: np.ndarray
    resolution: float = 0.05
    origin: tuple = (0.0, 0.0, 0.0)
    source: Optional[str] = None
    gray: Optional[np.ndarray] = field(default=None, repr=False)

    def __post_init__(self):
        name = self.source or "<array>"
        try:
            cells = np.asarray(self.cells)
        except (TypeError, ValueError) as exc:
            raise MapError(named(name, f"cells are not an array: {exc}")) from None
        if cells.ndim != 2:
            raise MapError(f"{name}: grid must be 2-D, got ndim={cells.ndim}")
        if cells.shape[0] == 0 or cells.shape[1] == 0:
            raise MapError(f"{name}: grid is empty (shape {cells.shape})")
        limit, why = cell_limit()
        if cells.size > limit:
            raise MapTooLargeError(named(name, f"map is {cells.shape[1]} x {cells.shape[0]} cells = {cells.size:,}, "
                                              f"more than {why}"))
        try:
            res = float(self.resolution)
        except (TypeError, ValueError):
            raise ParameterError(named(name, f"resolution must be a number, got {self.resolution!r}")) from None
        if not np.isfinite(res) or res <= 0:
            raise ParameterError(f"{name}: resolution must be > 0 m/px, got {self.resolution!r}")
        check_resolution_range(name, res)
        object.__setattr__(self, "resolution", res)
        try:
            origin = tuple(float(v) for v in self.origin)
        except (TypeError, ValueError):
            raise ParameterError(named(name, f"origin must be (x, y[, yaw]) numbers, got {self.origin!r}")) from None
        if not all(math.isfinite(v) for v in origin):
            raise ParameterError(named(name, f"origin must be finite, got {self.origin!r}"))
        check_origin_range(name, origin)
        if len(origin) == 2:
            origin = origin + (0.0,)
        if len(origin) != 3:
            raise ParameterError(named(name, f"origin must be (x, y[, yaw]), got {self.origin!r}"))
        object.__setattr__(self, "origin", origin)
        if not (np.issubdtype(cells.dtype, np.integer) or cells.dtype == bool):
            raise MapError(named(name, f"cells must be integers (0, 100, -1), got dtype {cells.dtype}"))
        object.__setattr__(self, "cells", cells.astype(np.int8, copy=False))

    @property
    def name(self) -> str:
        """File name for messages, ``<array>`` when built from an array."""
        return self.source or "<array>"

    @property
    def shape(self) -> tuple:
        return self.cells.shape

    @property
    def free(self) -> np.ndarray:
        """(M, N) ndarray of bool: cells that are free."""
        return self.cells == FREE

    @property
    def occupied(self) -> np.ndarray:
        """(M, N) ndarray of bool: cells that are occupied."""
        return self.cells == OCCUPIED

    @property
    def unknown(self) -> np.ndarray:
        """(M, N) ndarray of bool: cells of unknown state."""
        return self.cells == UNKNOWN

    def pixel_to_world(self, row, col):
        """Centre of pixel ``(row, col)`` in map-frame metres ``(x, y)``.

        Accepts scalars or arrays (fractional pixels allowed). Yaw of the
        origin is applied as ROS does (rotation about the origin).
        """
        row = np.asarray(row, dtype=float)
        col = np.asarray(col, dtype=float)
        h = self.cells.shape[0]
        u = (col + 0.5) * self.resolution
        v = (h - row - 0.5) * self.resolution
        ox, oy, yaw = self.origin
        if yaw:
            c, s = np.cos(yaw), np.sin(yaw)
            u, v = c * u - s * v, s * u + c * v
        return ox + u, oy + v

    def world_to_pixel(self, x, y):
        """Fractional pixel ``(row, col)`` of map-frame point ``(x, y)`` in metres.

        Round the result to get the cell index; the inverse of
        :meth:`pixel_to_world`.
        """
        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        ox, oy, yaw = self.origin
        u, v = x - ox, y - oy
        if yaw:
            c, s = np.cos(yaw), np.sin(yaw)
            u, v = c * u + s * v, -s * u + c * v
        h = self.cells.shape[0]
        col = u / self.resolution - 0.5
        row = h - v / self.resolution - 0.5
        return row, col

