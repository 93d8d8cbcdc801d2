"""Reading and writing: maps (ROS map_server YAML + PGM/PNG, images, arrays, bags), room graphs
(GraphML, JSON, GeoJSON), label images, pictures and ROS messages.

I/O converts types and never runs an algorithm. The names below are the
ones ``topomap.io`` has always offered (``topomap.io.load_map``,
``topomap.io.MAX_CELLS``, ...); each lives in the module of its concern:
:mod:`topomap.grid` (the grid and the size limit), :mod:`topomap.io.maps`
(map files), :mod:`topomap.io.metadata` (the map YAML and its values),
:mod:`topomap.io.files` (atomic writes).
"""

from __future__ import annotations

import sys
import types

from .. import grid as _grid
from ..grid import (
    FALLBACK_MAX_CELLS,
    FREE,
    JOB_BASE_BYTES,
    JOB_BYTES_PER_CELL,
    MAX_ORIGIN,
    MAX_RESOLUTION,
    MIN_MAX_CELLS,
    MIN_RESOLUTION,
    OCCUPIED,
    UNKNOWN,
    USUAL_RESOLUTION,
    OccupancyGrid,
    available_memory,
    cell_limit,
    cells_for_memory,
)
from .files import atomic_write, remove_stale_temporaries
from .maps import (
    DEFAULT_RESOLUTION,
    FREE_GRAY,
    FREE_THRESH,
    GRAY_FREE,
    GRAY_OCCUPIED,
    GRAY_UNKNOWN,
    OCCUPIED_THRESH,
    UNKNOWN_FREE_MIN_CELLS,
    UNKNOWN_FREE_SHARE,
    USUAL_FREE_AREA,
    classify_gray,
    classify_plan,
    from_array,
    load_map,
    pgm_bytes,
    pgm_header,
    save_map,
    yaml_beside,
    yaml_text,
)
from .metadata import MAX_YAML_BYTES, YAML_KEYS, check_resolution

__all__ = [
    "FREE", "OCCUPIED", "UNKNOWN", "MAX_CELLS", "JOB_BYTES_PER_CELL", "JOB_BASE_BYTES", "FALLBACK_MAX_CELLS",
    "MIN_MAX_CELLS", "MIN_RESOLUTION", "MAX_RESOLUTION", "USUAL_RESOLUTION", "MAX_ORIGIN", "USUAL_FREE_AREA",
    "UNKNOWN_FREE_SHARE", "UNKNOWN_FREE_MIN_CELLS", "MAX_YAML_BYTES", "YAML_KEYS", "DEFAULT_RESOLUTION",
    "OCCUPIED_THRESH", "FREE_THRESH", "FREE_GRAY", "GRAY_FREE", "GRAY_OCCUPIED", "GRAY_UNKNOWN",
    "OccupancyGrid", "available_memory", "cell_limit", "cells_for_memory", "check_resolution", "classify_gray",
    "classify_plan", "from_array", "load_map", "save_map", "yaml_beside", "yaml_text", "pgm_bytes",
    "pgm_header", "atomic_write", "remove_stale_temporaries",
]


class _IoModule(types.ModuleType):
    """``topomap.io.MAX_CELLS`` reads and sets :data:`topomap.grid.MAX_CELLS` (the limit every grid checks)."""

    @property
    def MAX_CELLS(self):
        return _grid.MAX_CELLS

    @MAX_CELLS.setter
    def MAX_CELLS(self, value):
        _grid.MAX_CELLS = value


sys.modules[__name__].__class__ = _IoModule
