"""Map input and output: occupancy grids from ROS map files, images and arrays.

Cell states follow ROS ``nav_msgs/OccupancyGrid``: ``0`` free, ``100``
occupied, ``-1`` unknown. Pixel coordinates are ``(row, col)`` with row 0 at
the top of the image; world coordinates are ``(x, y)`` in metres in the map
frame, where ``origin`` is the pose of the *lower-left* corner of the image,
as ROS map_server defines it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from .errors import MapError, ParameterError

__all__ = ["FREE", "OCCUPIED", "UNKNOWN", "OccupancyGrid", "from_array"]

FREE = 0
OCCUPIED = 100
UNKNOWN = -1


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
        cells = np.asarray(self.cells)
        if cells.ndim != 2:
            raise MapError(f"{name}: grid must be 2-D, got ndim={cells.ndim}")
        if cells.shape[0] == 0 or cells.shape[1] == 0:
            raise MapError(f"{name}: grid is empty (shape {cells.shape})")
        try:
            res = float(self.resolution)
        except (TypeError, ValueError):
            raise ParameterError(f"{name}: resolution must be a number, got {self.resolution!r}") from None
        if not np.isfinite(res) or res <= 0:
            raise ParameterError(f"{name}: resolution must be > 0 m/px, got {self.resolution!r}")
        object.__setattr__(self, "resolution", res)
        origin = tuple(float(v) for v in self.origin)
        if len(origin) == 2:
            origin = origin + (0.0,)
        if len(origin) != 3:
            raise ParameterError(f"{name}: origin must be (x, y[, yaw]), got {self.origin!r}")
        object.__setattr__(self, "origin", origin)
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


def from_array(array, *, resolution: float = 0.05, origin=(0.0, 0.0, 0.0),
               source: Optional[str] = None) -> OccupancyGrid:
    """Build an :class:`OccupancyGrid` from a 2-D array.

    Parameters
    ----------
    array : (M, N) ndarray
        ``bool``: True = free, False = occupied. Signed integers: ROS values
        (0 free, 100 occupied, -1 unknown; 1..99 counted as occupied when
        >= 65, else free). ``uint8`` : a gray image, classified with
        map_server's trinary thresholds.
    resolution : float
        Metres per pixel.
    origin : (x, y[, yaw])
        Lower-left corner in map-frame metres.
    """
    name = source or "<array>"
    a = np.asarray(array)
    if a.ndim != 2:
        raise MapError(f"{name}: array must be 2-D, got ndim={a.ndim} (shape {a.shape})")
    if a.size == 0:
        raise MapError(f"{name}: array is empty (shape {a.shape})")
    if a.dtype == bool:
        cells = np.where(a, FREE, OCCUPIED).astype(np.int8)
        return OccupancyGrid(cells, resolution, origin, source)
    if a.dtype == np.uint8:
        from .io_images import classify_gray  # noqa: F401  (provided by the loader module)
        cells = classify_gray(a)
        return OccupancyGrid(cells, resolution, origin, source, gray=a)
    if np.issubdtype(a.dtype, np.signedinteger):
        cells = np.full(a.shape, UNKNOWN, np.int8)
        cells[(a >= 0) & (a < 65)] = FREE
        cells[a >= 65] = OCCUPIED
        return OccupancyGrid(cells, resolution, origin, source)
    raise MapError(f"{name}: unsupported array dtype {a.dtype} (use bool, uint8 gray or int8 ROS values)")
