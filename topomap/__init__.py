"""topomap: rooms, doors and a room–door graph from occupancy grid maps.

The method follows Mora, Prados & Barber, "Segmenting Maps by Analyzing Free
and Occupied Regions with Voronoi Diagrams": skeletons (Voronoi diagrams) of
both free and occupied space; narrow passages of free space that meet
protruding wall parts are doors.

Quick start::

    import topomap
    grid = topomap.load_map("map.yaml")       # ROS map_server YAML, PGM/PNG or array
    seg = topomap.segment(grid)                # rooms, doors, skeleton graphs
    G = seg.room_graph                         # networkx: rooms = nodes, doors = edges

Heavy modules are imported on first use, so ``import topomap`` is fast.
"""

from __future__ import annotations

import importlib

from . import _moved

__version__ = "0.1.0"

_moved.install()  # the modules that moved keep their old import paths (topomap.export, ...)

_LAZY = {
    "load_map": "io.maps", "save_map": "io.maps", "from_array": "io.maps", "OccupancyGrid": "grid",
    "segment": "api", "Segmentation": "core.segmentation", "METHODS": "core.segmentation",
    "DEFAULT_METHOD": "core.segmentation",
    "room_graph": "core.roomgraph",
    "TopomapError": "errors", "MapError": "errors", "MapFileError": "errors", "ParameterError": "errors",
    "example_map_path": "io.example",
    "segment_many": "run.batch", "OutputExistsError": "errors",
}

__all__ = sorted(_LAZY) + ["__version__"]


def __getattr__(name):
    if name in _LAZY:
        mod = importlib.import_module(f".{_LAZY[name]}", __name__)
        return getattr(mod, name)
    raise AttributeError(f"module 'topomap' has no attribute {name!r}")


def __dir__():
    return __all__
