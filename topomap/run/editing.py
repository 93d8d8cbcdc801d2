"""Editing an output folder of ``topomap segment`` (what ``topomap edit OUT_DIR ...`` does).

The folder is read back as a segmentation with :func:`load_segmentation`, the
edits are made in memory by :func:`topomap.core.edit.apply_edits` (a bad one
raises before any file is touched), and :func:`save_edits` writes every
output again, all files or none — with the Nav2 route graphs exported from
the folder's room graph (``topomap export OUT_DIR/rooms.graphml --nav2
FILE``, noted in the run record) — and adds the edits to the run record
(:mod:`topomap.run.record`); :func:`edit_outputs` does all three.
"""

from __future__ import annotations

import logging
import time
from contextlib import ExitStack
from pathlib import Path

import numpy as np

from .. import __version__
from ..core.doors import Door
from ..core.edit import apply_edits, merged_ids
from ..core.identity import TrackedSegmentation
from ..errors import GraphFormatError, MapFileError, MapFileNotFoundError, first_line
from ..grid import FREE, OCCUPIED, OccupancyGrid
from ..io.export import NODE_TYPES, load_graph, load_label_map
from ..io.files import atomic_write
from ..io.maps import load_map
from .job import nav2_routes, summary_counts, write_segmentation
from .record import COMPLETE, INCOMPLETE, RECORD, fingerprint, nav2_exports, output_stamps, read_record, \
    restore_record, write_record

__all__ = ["load_segmentation", "save_edits", "edit_outputs"]

log = logging.getLogger("topomap")


def _grid_of(folder: Path, record: dict, labels: np.ndarray, res: float, origin, graph_map):
    """The map the folder's rooms were cut from, in the labels' frame (``res``, ``origin``): the file the run
    record names when it is unchanged since the run, else the file the room graph names (``graph_map``), when
    its free cells are the labelled cells; else a map of the labels' cells (free: the rooms and fragments),
    with a warning."""
    path, why = record.get("input"), "named neither in the run record nor in rooms.graphml"
    settings = record.get("settings") or {}
    if path and fingerprint(Path(path)) != (record.get("inputs") or {}):
        path, why = None, f"{record.get('input')} changed or is missing since the run"
    if not path and graph_map and Path(graph_map).exists():
        path, settings = graph_map, {}
    if path:
        try:
            grid = load_map(path, resolution=res, origin=origin, topic=settings.get("topic"), time=settings.get("at"))
            if grid.shape == labels.shape and np.array_equal(grid.free, labels > 0):
                return grid
            why = f"{path} is not the map of these labels"
        except Exception as exc:  # noqa: BLE001 - any reason the map cannot be used: the labels' map below
            why = f"{path} cannot be read ({first_line(exc)})"
    log.warning("%s: the map: %s; the rooms' cells are taken as the free space (overlay.png shows the rest as "
                "walls)", folder, why)
    cells = np.where(labels > 0, FREE, OCCUPIED).astype(np.int8)
    return OccupancyGrid(cells, res, origin, source=str(graph_map or folder))


def _check_folder(folder: Path) -> None:
    """MapFileNotFoundError / MapFileError unless ``folder`` is a folder with the files this module reads."""
    if not folder.exists():
        raise MapFileNotFoundError(f"{folder}: no such output folder")
    if not folder.is_dir():
        raise MapFileError(f"{folder}: is not a folder (give the output folder of topomap segment)")
    for name in ("rooms.graphml", "labels.yaml", "labels.pgm"):
        if not (folder / name).is_file():
            raise MapFileNotFoundError(f"{folder}: holds no {name}: not an output folder of topomap segment")


def _check_rooms(folder: Path, graph, labels: np.ndarray) -> list:
    """The room IDs (the graph's nodes, ascending); GraphFormatError unless the graph and the labels have
    the same size, the same rooms and the same cells per room."""
    where = f"{folder}: rooms.graphml and labels.pgm disagree"
    shape = tuple(graph.graph.get("shape") or ())
    if shape and shape != labels.shape:
        raise GraphFormatError(f"{where}: {shape[1]} x {shape[0]} and {labels.shape[1]} x {labels.shape[0]} cells")
    nodes = sorted(graph.nodes)
    if any(not isinstance(n, int) or n <= 0 for n in nodes):
        raise GraphFormatError(f"{folder / 'rooms.graphml'}: node {next(n for n in nodes if not isinstance(n, int) or n <= 0)!r} "
                               "is not a room ID")
    top = max(nodes, default=0)
    cnt = np.bincount(labels.ravel(), minlength=top + 1)
    in_labels = [int(i) for i in np.flatnonzero(cnt[:top + 1]) if i > 0]
    if in_labels != nodes:
        odd = sorted(set(in_labels) ^ set(nodes))
        raise GraphFormatError(f"{where}: room {odd[0]} is in one of them only")
    bad = [n for n in nodes if int(graph.nodes[n].get("cells", cnt[n])) != cnt[n]]
    if bad:
        raise GraphFormatError(f"{where}: room {bad[0]} has {graph.nodes[bad[0]]['cells']} cells in the graph and "
                               f"{cnt[bad[0]]} in the labels")
    return nodes


def _doors(folder: Path, graph) -> list:
    """The doors of the room graph (its edges), by ID; GraphFormatError for an edge that is no door."""
    doors = []
    for u, v, k, d in graph.edges(keys=True, data=True):
        try:
            doors.append(Door(id=int(d.get("door", k)), p1=tuple(float(t) for t in d["p1"]),
                              p2=tuple(float(t) for t in d["p2"]), xy1=(float(d["x1"]), float(d["y1"])),
                              xy2=(float(d["x2"]), float(d["y2"])), width=float(d["width"]),
                              rooms=(min(u, v), max(u, v))))
        except (KeyError, TypeError, ValueError) as exc:
            raise GraphFormatError(f"{folder / 'rooms.graphml'}: door {u}-{v} has no {exc} (not a graph topomap "
                                   "segment wrote)") from None
    return sorted(doors, key=lambda d: d.id)


def _user_attributes(graph) -> dict:
    """``{room ID: {name: value}}``: the node attributes topomap does not compute (``name``, ``no_go``,
    ``merged`` as a list of IDs, a user's own), of the rooms that have any."""
    computed = set(NODE_TYPES)
    attrs = {}
    for n, d in graph.nodes(data=True):
        extra = {k: v for k, v in d.items() if k not in computed}
        if "merged" in extra:
            extra["merged"] = merged_ids(extra["merged"])
        if extra:
            attrs[n] = extra
    return attrs


def load_segmentation(out_dir):
    """Read an output folder of ``topomap segment`` back as a segmentation.

    The rooms, fragments and their IDs come from ``labels.pgm`` +
    ``labels.yaml``; the doors, the room IDs, ``next_room_id`` and the
    rooms' user attributes (``name``, ``no_go``, ``merged``, ...) from
    ``rooms.graphml``; the map from the file the run record
    (``topomap_run.json``) names when that file is unchanged, else the
    labels' cells stand for the free space.

    Parameters
    ----------
    out_dir : str or os.PathLike

    Returns
    -------
    TrackedSegmentation
        No skeleton graphs, candidates or intermediate images (the folder
        does not hold them).

    Raises
    ------
    MapFileNotFoundError
        No such folder, or a file missing in it.
    MapFileError
        Not a folder.
    GraphFormatError
        A file cannot be read, or ``rooms.graphml`` and the labels
        disagree (different sizes, a room in one and not in the other).
    """
    folder = Path(out_dir)
    _check_folder(folder)
    graph = load_graph(folder / "rooms.graphml")
    labels, res, origin = load_label_map(folder / "labels.yaml")
    nodes = _check_rooms(folder, graph, labels)
    top = max(nodes, default=0)
    doors = _doors(folder, graph)
    record = read_record(folder) or {}
    grid = _grid_of(folder, record, labels, res, origin, graph.graph.get("map"))
    attrs = _user_attributes(graph)
    nxt = graph.graph.get("next_room_id")
    try:
        nxt = max(int(nxt), top + 1) if nxt not in (None, "") else top + 1
    except (TypeError, ValueError):
        raise GraphFormatError(f"{folder / 'rooms.graphml'}: next_room_id {nxt!r} is not an integer") from None
    threshold = graph.graph.get("threshold")
    return TrackedSegmentation(grid=grid, labels=labels.astype(np.int32), doors=doors,
                               method=str(graph.graph.get("method") or "loaded"), params={},
                               threshold=None if threshold is None else float(threshold), room_ids=tuple(nodes),
                               next_room_id=nxt, room_attributes=attrs)


def save_edits(seg, out_dir, records) -> dict:
    """Rewrite every output of ``out_dir`` from ``seg`` and add ``records`` to its run record.

    The files ``topomap segment`` wrote there (labels, room graph in each
    format, overlay; :func:`topomap.run.job.write_segmentation`) and the Nav2
    route graphs the run record notes (:func:`nav2_routes`) are all replaced
    or none is; the run record's ``edits`` list gets ``records``
    (each with the time, ``"at"``, UTC), its ``files`` and ``row`` are
    updated, so a later ``topomap segment`` of the same unchanged map into
    the same folder finds it up to date and keeps the edits. A failed write
    leaves the earlier files and record as they were.

    Returns
    -------
    dict
        ``{name: path}`` of the files written (a Nav2 route graph under ``"nav2:" + its path``).

    Raises
    ------
    PlanningError, ParameterError
        A noted Nav2 route graph cannot be made from the edited rooms (no file is changed).
    """
    folder = Path(out_dir)
    old = (folder / RECORD).read_text(encoding="utf-8") if (folder / RECORD).is_file() else None
    rec = dict(read_record(folder) or {})
    routes = nav2_routes(seg, folder, nav2_exports(rec))  # made before any file is touched: an error changes nothing
    rec.setdefault("topomap", __version__)
    at = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    rec["edits"] = list(rec.get("edits") or []) + [dict(r, at=at) for r in records]
    write_record(folder, dict(rec, status=INCOMPLETE))
    try:
        with ExitStack() as stack:  # the route graphs are renamed into place after the folder's files
            for path, data in routes.items():
                stack.enter_context(atomic_write(path)).write(data)
            written = write_segmentation(seg, folder, overlay=(folder / "overlay.png").exists(),
                                         geojson=(folder / "rooms.geojson").exists())
        written.update({f"nav2:{path}": path for path in routes})
        files = output_stamps(folder)
        row = dict(rec.get("row") or {}, **summary_counts(seg))
        write_record(folder, dict(rec, status=COMPLETE, files={**(rec.get("files") or {}), **files}, row=row))
    except BaseException:
        restore_record(folder, old, True)
        raise
    return written


def edit_outputs(out_dir, edits):
    """Apply ``edits`` (as :func:`topomap.core.edit.apply_edits`) to the output folder ``out_dir`` of
    ``topomap segment``.

    Reads the folder (:func:`load_segmentation`), makes every edit in
    memory — a bad one raises before any file is touched — then rewrites
    the outputs and the run record (:func:`save_edits`).

    Returns
    -------
    seg : TrackedSegmentation
        The edited result.
    records : list of dict
        The edits as recorded (see :func:`topomap.core.edit.apply_edits`).
    """
    seg = load_segmentation(out_dir)
    seg, records = apply_edits(seg, edits, source=str(out_dir))
    save_edits(seg, out_dir, records)
    return seg, records
