"""The functions ``import topomap`` offers that take a file where the core takes an object.

The core (:mod:`topomap.core`) never opens a file; :func:`segment` here is
:func:`topomap.core.segmentation.segment` with ``previous`` also accepted as
the path of a saved room graph, read with :func:`topomap.io.previous.read_previous`: the one
place that does (``topomap segment --previous`` goes through it too).
"""

from __future__ import annotations

import os
import time

from .core import segmentation
from .grid import OccupancyGrid
from .io.previous import read_previous

__all__ = ["segment"]


def segment(grid, *, method: str = None, previous=None, **params):
    """Segment an occupancy grid into rooms and doors.

    Parameters
    ----------
    grid : OccupancyGrid
        The map (see :func:`topomap.io.load_map`).
    method : str, optional
        One of :data:`topomap.core.segmentation.METHODS` (default
        ``"topomap"``).
    previous : Segmentation or networkx.MultiGraph or str or os.PathLike, optional
        An earlier result (or saved room graph file: GraphML, JSON or
        GeoJSON) of the same place: rooms keep its IDs
        (:func:`topomap.core.identity.match_rooms`; ``seg.changes``); with
        ``"topomap"`` its doors are a prior of the door stage
        (:class:`topomap.core.identity.DoorPrior`). Messages about a file
        name the file.
    **params
        Keyword options of the method, lengths in metres (for ``"topomap"``
        and ``"paper"`` the fields of :class:`~topomap.options.TopomapOptions`
        / :class:`~topomap.options.PaperOptions`, or ``options=`` an
        instance of it).

    Returns
    -------
    Segmentation

    Raises
    ------
    ParameterError
        Unknown method, not an OccupancyGrid, an unknown option of the
        method or an invalid value.
    GraphFormatError, MapFileError
        ``previous`` is a file that cannot be loaded.
    """
    if not isinstance(previous, (str, os.PathLike)) or not isinstance(grid, OccupancyGrid):
        return segmentation.segment(grid, method=method, previous=previous, **params)
    t0 = time.perf_counter()
    prior = read_previous(previous, within=grid)
    t_read = time.perf_counter() - t0
    seg = segmentation.segment(grid, method=method, previous=prior, **params)
    seg.timings["previous"] = seg.timings.get("previous", 0.0) + t_read
    seg.timings["total"] = seg.timings.get("total", 0.0) + t_read
    return seg
