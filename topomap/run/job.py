"""The job of one map: read it, segment it, write its output files (what ``topomap segment MAP -o OUT`` does).

:func:`segment_file` runs the whole job of one map file; :func:`write_segmentation`
writes the files of a segmentation made in Python. :data:`STAGES` names the
timed stages of the job (``Segmentation.timings``, the ``t_<stage>`` columns
of ``summary.csv``, ``topomap segment --profile``); :func:`preload` and
:func:`warm_up` pay the one-off costs of a process before its first map, so
they are stages of their own.
"""

from __future__ import annotations

import importlib
import io
import json
import logging
import time
from contextlib import ExitStack
from pathlib import Path

import numpy as np

from .._fast import BackgroundCall
from ..errors import first_line
# modules, not their functions: a function replaced in its module (a test's stand-in) is the one called
from .. import api
from ..core import segmentation
from ..io import export, plot
from ..io.files import atomic_write
from ..io.nav2 import route_graph_bytes
from ..io.maps import DEFAULT_RESOLUTION, from_array, load_map, yaml_beside
from ..io.ros import staged_bag
from ..planning.nav2 import DEFAULT_CLEARANCE, route_graph
from ..planning.paths import travel_graph

__all__ = ["segment_file", "write_segmentation", "summary_counts", "preload", "warm_up", "STAGES", "PRELOAD"]

log = logging.getLogger("topomap")

#: Stages of a map's job in their order (``t_<stage>`` columns, ``--profile``): ``total`` is the
#: segmentation call (its stages before it); ``write`` is travel distances, overlay and every
#: ``write_<file>``; ``job`` is the map from loading to the last file; ``start``, ``import`` and
#: ``warmup`` are the command's own, before the first map.
STAGES = ("start", "import", "warmup", "load", "previous", "preprocess", "walls", "furniture", "skeletons",
          "graphs", "doors", "openings", "gaps", "prior doors", "rooms", "outside", "match", "segment", "total", "room_graph", "travel",
          "overlay", "write_labels", "write_label_map_pgm", "write_label_map", "write_graphml", "write_json",
          "write_geojson", "write_overlay", "write", "job")

#: Modules the segment command uses, imported up front (their import time is the
#: ``import`` stage of ``--profile``, not hidden in the first map's stages).
PRELOAD = ("numpy", "scipy.ndimage", "scipy.sparse.csgraph", "scipy.spatial", "cv2", "PIL.Image",
           "PIL.PngImagePlugin", "networkx", "shapely", "shapely.geometry", "skimage.draw",
           "skimage.graph", "skimage.morphology", "skimage.segmentation", "topomap.io", "topomap.core.segmentation",
           "topomap.core.roomgraph", "topomap.planning", "topomap.io.export", "topomap.io.plot")


def write_segmentation(seg, outdir, *, overlay: bool = True, skeletons: bool = False, geojson: bool = True,
                       timings: dict | None = None) -> dict:
    """The files ``topomap segment`` writes for ``seg`` into ``outdir``.

    Computes what is saved — the travel graph
    (:func:`topomap.planning.travel_graph`: the room–door graph with
    in-room door-to-door distances, so ``topomap plan`` works from
    ``rooms.graphml`` or ``rooms.json`` alone) and, unless ``overlay`` is
    False, the overlay picture (:func:`topomap.io.plot.overlay_png`) — then
    writes everything with :func:`topomap.io.export.write_outputs` (all files
    or none; ``rooms.geojson`` only when ``geojson``).

    ``timings``, when given, receives the seconds of each step: ``travel``,
    ``overlay`` and ``write_<file>`` per file. The overlay and the
    ``labels.png`` image are made on a second thread while the travel
    distances are measured: ``overlay`` is the time still waited for them
    after the travel distances, ``write_labels`` the writing of the file.

    Returns
    -------
    dict
        ``{name: path}`` of the files written.
    """
    t = {} if timings is None else timings
    seg.room_graph  # made here, before the thread below reads it
    # the pictures (OpenCV's drawing, zlib: mostly without Python's lock) on a second core while the
    # travel distances are measured; ``overlay`` is the time the job then still waits for them
    pictures = BackgroundCall(_pictures, seg, overlay, skeletons)
    t0 = time.perf_counter()
    graph = travel_graph(seg)
    t["travel"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    png, labels_png = pictures.result()
    if overlay:
        t["overlay"] = time.perf_counter() - t0
    return export.write_outputs(seg, outdir, graph, overlay_png=png, geojson=geojson, timings=t, labels_png=labels_png)


def _pictures(seg, overlay, skeletons):
    """``(overlay.png bytes or None, labels.png bytes)`` of ``seg``."""
    png = plot.overlay_png(seg, skeletons=skeletons) if overlay else None
    buf = io.BytesIO()
    export.save_labels(seg, buf)
    return png, buf.getvalue()


def _read_map(path, resolution, topic, at):
    """The grid of the map file ``path``; an image with ``resolution`` None is read through the YAML beside
    it that names it (its resolution, origin and thresholds), when there is one."""
    source = path
    if resolution is None:
        beside, why = yaml_beside(path)
        if beside is not None:
            log.info("%s: read through %s beside it (its resolution, origin and thresholds); give --resolution "
                     "to read the image alone", path, beside.name)
            source = beside
        elif why is not None:
            log.warning("%s: %s at %g m per cell", path, why, DEFAULT_RESOLUTION)
    return load_map(source, resolution=resolution, topic=topic, time=at)


def segment_file(path, outdir, resolution=None, method=None, skeletons=False, *, topic=None, at=None, bag=None,
                 previous=None, overlay=True, geojson=True, nav2=(), options=None):
    """Segment the map file ``path`` and write its outputs into ``outdir``: one map of ``topomap segment``.

    Parameters
    ----------
    path : str or os.PathLike
        A map file (ROS YAML, PGM, PNG or a ROS bag). An image without
        ``resolution`` is read through the YAML beside it that names it.
    outdir : str or os.PathLike
        Output folder (:func:`write_segmentation`).
    resolution : float, optional
        Metres per pixel of an image map (default: its YAML's, else 0.05).
    method : str, optional
        Segmentation method (default the library's).
    skeletons : bool, optional
        Draw both skeleton graphs in ``overlay.png``.
    topic, at : optional
        Bag maps: the topic and the time (seconds after the bag's start).
    bag : str or os.PathLike, optional
        Also write the map, rooms and labels into this new bag.
    previous : str or os.PathLike, optional
        Room graph of an earlier map of the same place: room IDs follow it,
        and ``changes.json`` is written beside the graph.
    overlay, geojson : bool, optional
        Write ``overlay.png``, ``rooms.geojson``.
    nav2 : sequence of dict, optional
        The Nav2 route graphs exported from the folder's previous room graph
        (:func:`topomap.run.record.nav2_exports` of its run record): each is
        made again from the new rooms (:func:`nav2_routes`).
    options : dict, optional
        Keyword options of the method (:func:`topomap.segment`).

    Returns
    -------
    Segmentation
        Its ``timings`` also hold ``load``, ``write`` and ``job`` (seconds).
        The outputs (with the bag, ``changes.json`` and the Nav2 route graphs)
        are written all or none; an error leaves the earlier outputs as they
        were.
    """
    t0 = time.perf_counter()
    grid = _read_map(path, resolution, topic, at)
    t1 = time.perf_counter()
    seg = api.segment(grid, method=method, previous=previous, **(options or {}))  # a previous graph file: its messages name it
    # the label files hold 16-bit room IDs: more rooms than that are refused now, not after the room graph,
    # travel distances and pictures of every room (a noise image at 1 m per cell: 500,000 rooms, 7 GB, 5 min)
    export.file_labels(seg, export.OUTPUT_FILES["labels"], "PNG")
    seg.room_graph  # built here so its time is its own stage (timings["room_graph"])
    t2 = time.perf_counter()
    # the map's outputs land together or not at all: the bag and changes.json are written to temporaries
    # first and renamed into place only after write_segmentation renamed its files (an error anywhere
    # removes every temporary; the earlier outputs stay as they were)
    with ExitStack() as stack:
        if bag is not None:
            stack.enter_context(staged_bag(seg, bag))
        if previous is not None:  # the change record beside the graph (room IDs follow the previous graph)
            fh = stack.enter_context(atomic_write(Path(outdir) / "changes.json", "w"))
            json.dump(seg.changes.as_dict(), fh, indent=1)
        for route_path, data in nav2_routes(seg, outdir, nav2).items():  # Nav2 exports of the folder
            stack.enter_context(atomic_write(route_path)).write(data)
        write_segmentation(seg, outdir, skeletons=skeletons, overlay=overlay, geojson=geojson,
                           timings=seg.timings)
    seg.timings["load"] = t1 - t0
    seg.timings["write"] = time.perf_counter() - t2
    seg.timings["job"] = time.perf_counter() - t0
    return seg


def nav2_routes(seg, folder, notes) -> dict:
    """``{path: GeoJSON bytes}``: the Nav2 route graph of ``seg`` for every export ``notes`` names (what the run
    record of the output folder ``folder`` notes: :func:`topomap.run.record.nav2_exports`), with the clearance
    it was exported with; a relative path is taken in ``folder``.

    Raises
    ------
    PlanningError, ParameterError
        A route graph cannot be made (the message names its file).
    """
    out = {}
    for note in notes:
        path = Path(folder) / note["path"]  # an absolute path stays itself
        clearance = DEFAULT_CLEARANCE if note["clearance"] is None else note["clearance"]
        try:
            route = route_graph(seg, clearance=clearance)
        except Exception as exc:
            raise type(exc)(f"{path}: the Nav2 route graph of the edited rooms: {first_line(exc)}") from None
        out[path] = route_graph_bytes(route)
    return out


def summary_counts(seg) -> dict:
    """``rooms``, ``doors``, ``fragments``, ``room_area_m2`` and ``fragment_area_m2`` of ``seg``: the counts of
    a map's summary row (``summary.csv``, the run record)."""
    return {"rooms": seg.n_rooms, "doors": len(seg.doors), "fragments": seg.n_fragments,
            "room_area_m2": float((seg.room_labels > 0).sum()) * seg.grid.resolution ** 2,
            "fragment_area_m2": float(seg.fragment_area)}


def preload(maps=()) -> float:
    """Import :data:`PRELOAD` (and the YAML reader when a map of ``maps`` is a YAML file); returns the
    seconds it took."""
    t0 = time.perf_counter()
    yaml = any(str(m).lower().endswith((".yaml", ".yml")) for m in maps)
    for name in PRELOAD + (("yaml",) if yaml else ()):
        importlib.import_module(name)
    return time.perf_counter() - t0


def warm_up(method) -> float:
    """Run the whole job once on a tiny map in memory (nothing written); returns the seconds.

    First calls pay one-off costs (lazy imports inside libraries, caches,
    font set-up); paid here they are the ``warmup`` stage of ``--profile``
    instead of hiding in the first map's stages.
    """
    t0 = time.perf_counter()
    free = np.zeros((60, 100), bool)
    free[4:56, 4:48] = True
    free[4:56, 52:96] = True
    free[24:36, 48:52] = True
    seg = segmentation.segment(from_array(free, resolution=0.05), method=method)
    seg.room_graph
    travel_graph(seg)
    plot.overlay_png(seg)
    return time.perf_counter() - t0
