"""Files of Nav2 route graphs: writing a :func:`topomap.planning.nav2.route_graph` and reading the label
image it needs beside a saved room graph.

``topomap export OUT_DIR/rooms.graphml --nav2 graph.geojson`` reads the room graph and
:func:`labels_beside` it, makes the route graph and writes it with :func:`write_route_graph`.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import MapFileNotFoundError
from .export import load_label_map, read_label_image
from .files import atomic_write

__all__ = ["write_route_graph", "route_graph_bytes", "labels_beside"]


def write_route_graph(graph: dict, path) -> Path:
    """Write a :func:`~topomap.planning.nav2.route_graph` dict to ``path`` as JSON (atomically: a
    temporary renamed into place).

    Returns
    -------
    pathlib.Path
    """
    path = Path(path)
    with atomic_write(path) as f:
        f.write(route_graph_bytes(graph))
    return path


def route_graph_bytes(graph: dict) -> bytes:
    """The bytes :func:`write_route_graph` writes for ``graph``: indented JSON, no NaN."""
    return json.dumps(graph, indent=1, allow_nan=False).encode("utf-8")


def labels_beside(graph_path) -> np.ndarray:
    """The label image ``topomap segment`` wrote beside a room graph file.

    Parameters
    ----------
    graph_path : str or os.PathLike
        ``rooms.graphml`` (or ``.json``, ``.geojson``) in a segment output folder.

    Returns
    -------
    (M, N) ndarray of int
        From ``labels.yaml`` + ``labels.pgm`` (:func:`topomap.io.export.load_label_map`), else from
        ``labels.png``.

    Raises
    ------
    MapFileNotFoundError
        Neither file is in the folder.
    MapError
        ``labels.png`` cannot be read.
    """
    folder = Path(graph_path).parent
    if (folder / "labels.yaml").is_file():
        return load_label_map(folder / "labels.yaml")[0]
    png = folder / "labels.png"
    if not png.is_file():
        raise MapFileNotFoundError(f"{folder}: no labels.yaml + labels.pgm or labels.png beside the room graph "
                                   "(the folder topomap segment wrote)")
    return read_label_image(png).astype(np.int64)
