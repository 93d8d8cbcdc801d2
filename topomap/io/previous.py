"""A previous result read from a file, for :func:`topomap.core.segmentation.segment`'s ``previous``."""

from __future__ import annotations

import os

from ..core.identity import DoorPrior
from .export import load_graph

__all__ = ["read_previous"]


def read_previous(path, *, within=None) -> DoorPrior:
    """The saved room graph at ``path`` (GraphML, JSON or GeoJSON) as the prior of a new segmentation.

    Parameters
    ----------
    path : str or os.PathLike
        A room graph ``topomap segment`` wrote (``rooms.graphml``, ...).
    within : OccupancyGrid, optional
        The map about to be segmented: the graph is rasterised only where it
        overlaps it (see :class:`~topomap.core.identity.DoorPrior`).

    Returns
    -------
    DoorPrior
        Pass it as ``previous`` to :func:`topomap.core.segmentation.segment`; messages about it name ``path``.

    Raises
    ------
    GraphFormatError, MapFileError
        The file cannot be loaded.
    ParameterError
        Its rooms or frame cannot be a previous result of this map.
    """
    return DoorPrior(load_graph(path), within=within, source=os.fspath(path))
