"""Simulated benchmark cases on disk: a floor plan, a robot's map of it and the ground truth.

What ``topomap simulate PLAN... -o OUT`` writes, one folder per plan (a
single plan: ``OUT`` itself; several: ``OUT/NAME``, named as
``topomap segment`` names its folders):

=====================  ====================================================
``map.pgm``,           the simulated robot map as ROS map_saver writes it
``map.yaml``           (0 occupied, 254 free, 205 unknown; trinary)
``plan.pgm``,          the drawn floor-plan map on the same grid (walls
``plan.yaml``          occupied, the home free, the outside unknown)
``gt_rooms.png``       16-bit room labels on that grid (0 = no room): the
                       ground truth of the plan
``gt_doors.json``      the plan's doors: end points in metres (map frame),
                       width, the two rooms (0 = outside)
``gt_rooms_scan.png``  the ground truth of the scan: the rooms of
                       ``gt_rooms.png`` the scan shows (at least
                       :data:`~topomap.bench.simulate.SHOWN_AREA` of a room free in
                       ``map.pgm``), each whole; the others 0
``gt_doors_scan.json`` the doors of the scan's ground truth: those of
                       ``gt_doors.json`` whose rooms are shown (or outside)
``gt_rooms.json``      each room's label kinds, area (m²), area the scan
                       shows free (m²) and whether the scan shows it
``simulation.json``    the plan, the seed, every scan option, the scale
=====================  ====================================================

Each case is written into a temporary folder beside its destination and
renamed into place when every file is written, so a case is whole or absent;
a case folder that holds a complete ``simulation.json`` for the same plan,
seed and options is kept (skipped) unless ``overwrite=True``.
:mod:`topomap.bench.datasets` reads such a folder of cases as the ``simulated``
benchmark layout.
"""

from __future__ import annotations

import concurrent.futures
import dataclasses
import json
import logging
import os
import shutil
import tempfile
import zlib
from pathlib import Path
from typing import Optional, Sequence

import numpy as np
from tqdm.auto import tqdm

from ..errors import MapFileError, OutputExistsError, ParameterError, first_line
from ..io.export import save_labels
from ..io.maps import save_map
from ..run.batch import FAILED, OK, SKIPPED, output_dirs, worker_count
from .floorplan import plan_grid, read_plan
from .simulate import ScanOptions, shown_doors, shown_rooms, simulate_scan

__all__ = ["CASE_FILES", "case_seed", "scan_options", "write_case", "simulate_case", "simulate_many"]

log = logging.getLogger("topomap.bench.corpus")

#: The files of a complete case folder.
CASE_FILES = ("map.pgm", "map.yaml", "plan.pgm", "plan.yaml", "gt_rooms.png", "gt_doors.json",
              "gt_rooms_scan.png", "gt_doors_scan.json", "gt_rooms.json", "simulation.json")
_RECORD = "simulation.json"


def case_seed(seed: int, name: str) -> int:
    """The scan seed of plan ``name`` in a corpus made with ``seed``: fixed per plan, independent of the order."""
    return (int(seed) * 1_000_003 + zlib.crc32(name.encode("utf-8", "surrogateescape"))) % (2 ** 32)


def scan_options(*, explore=None, glass_share=None, closed_doors=None, no_drift: bool = False,
                 no_furniture: bool = False, no_people: bool = False, extra: Sequence[str] = ()):
    """:class:`~topomap.bench.simulate.ScanOptions` from the ``topomap simulate`` options.

    ``extra`` holds ``NAME=VALUE`` texts for any other field; an unknown
    name or a value of the wrong kind is a :class:`~topomap.errors.ParameterError`
    naming it.
    """
    names = {f.name: f for f in dataclasses.fields(ScanOptions)}
    values = {}
    for text in extra:
        key, sep, val = str(text).partition("=")
        key = key.strip().replace("-", "_")
        if not sep or key not in names:
            raise ParameterError(f"--option {text!r}: expected NAME=VALUE with NAME one of {', '.join(names)}")
        default = names[key].default
        if isinstance(default, bool):
            low = val.strip().lower()
            if low not in ("true", "false", "1", "0", "yes", "no"):
                raise ParameterError(f"--option {text!r}: {key} takes true or false")
            values[key] = low in ("true", "1", "yes")
        else:
            try:
                values[key] = float(val)
            except ValueError:
                raise ParameterError(f"--option {text!r}: {key} takes a number, got {val!r}") from None
    for key, val in (("explore", explore), ("glass_share", glass_share), ("closed_doors", closed_doors)):
        if val is not None:
            values[key] = val
    if no_drift:
        values.update(drift_xy=0.0, drift_yaw=0.0)
    if no_furniture:
        values.update(plan_furniture=False, furniture_density=0.0)
    if no_people:
        values.update(people_per_metre=0.0)
    return ScanOptions(**values)


def _doors_json(plan, shown=None) -> dict:
    """The plan's doors (numbered from 1 in the plan's order); with ``shown`` (the scan's rooms) only
    the doors of :func:`topomap.bench.simulate.shown_doors`, with their plan numbers."""
    doors = list(enumerate(plan.doors, start=1))
    if shown is not None:
        keep = {id(d) for d in shown_doors(plan.doors, shown)}
        doors = [(i, d) for i, d in doors if id(d) in keep]
    return {"doors": [{"id": i, "p1": [float(v) for v in d.p1], "p2": [float(v) for v in d.p2],
                       "width": float(d.width), "rooms": [int(r) for r in d.rooms]} for i, d in doors]}


def _rooms_json(plan, free, shown) -> dict:
    labels = np.asarray(plan.rooms)
    n = int(labels.max(initial=0)) + 1
    cell = plan.resolution ** 2
    areas = np.bincount(labels.ravel(), minlength=n) * cell
    seen = np.bincount(labels[free].ravel(), minlength=n) * cell
    is_shown = np.zeros(n, bool)
    is_shown[np.unique(shown)] = True
    return {"rooms": [{"id": k, "kinds": list(plan.kinds.get(k, ())), "area": round(float(areas[k]), 4),
                       "scan_area": round(float(seen[k]), 4), "shown": bool(is_shown[k])}
                      for k in range(1, len(areas)) if areas[k] > 0]}


def _options_dict(options) -> dict:
    if options is None:
        return {}
    if dataclasses.is_dataclass(options):
        return {f.name: getattr(options, f.name) for f in dataclasses.fields(options)}
    return dict(options)


def _jsonable(v):
    if isinstance(v, (np.generic,)):
        return v.item()
    if isinstance(v, (tuple, list)):
        return [_jsonable(x) for x in v]
    if isinstance(v, dict):
        return {str(k): _jsonable(x) for k, x in v.items()}
    return v


def write_case(out_dir, plan, scan_grid, *, meta: Optional[dict] = None) -> Path:
    """Write one case folder (the files of :data:`CASE_FILES`), whole or not at all.

    Parameters
    ----------
    out_dir : str or os.PathLike
        The case folder; replaced as a whole if it exists.
    plan : topomap.bench.floorplan.FloorPlan
        The plan with its ground truth.
    scan_grid : topomap.io.OccupancyGrid
        The robot's map of the plan, on the plan's grid (same shape).
    meta : dict, optional
        What made the case (plan file, seed, options): ``simulation.json``.

    Returns
    -------
    pathlib.Path
        ``out_dir``.
    """
    out = Path(out_dir)
    if scan_grid.shape != plan.shape:
        raise ParameterError(f"{out}: the scan's grid {scan_grid.shape} is not the plan's {plan.shape}")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.case-p{os.getpid()}.", dir=out.parent))
    except OSError as exc:
        raise MapFileError(f"{out}: cannot write: {exc.strerror or exc}") from None
    try:
        save_map(scan_grid, tmp / "map")
        save_map(plan_grid(plan), tmp / "plan")
        save_labels(plan.rooms, tmp / "gt_rooms.png")
        shown = shown_rooms(plan.rooms, scan_grid.free, resolution=plan.resolution)
        save_labels(shown, tmp / "gt_rooms_scan.png")
        record = dict(meta or {}, name=plan.name, resolution=plan.resolution, scale=plan.scale, complete=True)
        for name, data in (("gt_doors.json", _doors_json(plan)), ("gt_doors_scan.json", _doors_json(plan, shown)),
                           ("gt_rooms.json", _rooms_json(plan, scan_grid.free, shown)),
                           (_RECORD, _jsonable(record))):
            (tmp / name).write_text(json.dumps(data, indent=1, allow_nan=False), encoding="utf-8")
        if out.is_dir():
            old = out.parent / f".{out.name}.old-p{os.getpid()}"
            os.replace(out, old)
            os.replace(tmp, out)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(tmp, out)
    except OSError as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        raise MapFileError(f"{out}: cannot write: {exc.strerror or exc}") from None
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return out


def _up_to_date(out: Path, meta: dict) -> bool:
    try:
        rec = json.loads((out / _RECORD).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    if not isinstance(rec, dict) or not rec.get("complete"):
        return False
    if any(rec.get(k) != v for k, v in _jsonable(meta).items()):
        return False
    return all((out / f).is_file() for f in CASE_FILES)


def simulate_case(plan_path, out_dir, *, seed: int = 0, options=None, resolution: float = 0.05,
                  overwrite: bool = False) -> dict:
    """Read one plan, scan it with a simulated robot and write its case folder.

    Parameters
    ----------
    plan_path : str or os.PathLike
        A vector plan (``NAME.txt`` of the R2V data set).
    out_dir : str or os.PathLike
        The case folder.
    seed : int
        The scan's seed (the same seed, plan and options give the same files).
    options : topomap.bench.simulate.ScanOptions, optional
        The simulated laser, path and faults; default ``ScanOptions()``.
    resolution : float
        Metres per cell of the plan's grid.
    overwrite : bool
        Write the case again even when its folder is up to date.

    Returns
    -------
    dict
        A summary row: ``plan``, ``output``, ``status`` (``"ok"`` or
        ``"skipped"``), ``rooms``, ``doors``, ``area`` (m² of the home),
        ``free_share`` (share of the home's cells the scan saw free),
        ``shown_rooms`` (the rooms of the scan's ground truth).
    """
    options = ScanOptions() if options is None else options
    out = Path(out_dir)
    meta = {"plan": os.path.abspath(plan_path), "seed": int(seed), "resolution": float(resolution),
            "options": _options_dict(options)}
    if not overwrite and _up_to_date(out, meta):
        rec = json.loads((out / _RECORD).read_text(encoding="utf-8"))
        return dict(rec.get("summary", {}), plan=str(plan_path), output=str(out), status=SKIPPED)
    plan = read_plan(plan_path, resolution=resolution)
    scan = simulate_scan(plan, options=options, seed=seed)
    inside = np.asarray(plan.inside)
    seen = float((scan.grid.free & inside).sum() / max(1, inside.sum()))
    shown = shown_rooms(plan.rooms, scan.grid.free, resolution=plan.resolution)
    summary = {"rooms": int(len(np.unique(plan.rooms[plan.rooms > 0]))), "doors": len(plan.doors),
               "area": round(float(inside.sum()) * plan.resolution ** 2, 2), "free_share": round(seen, 4),
               "shown_rooms": int(len(np.unique(shown[shown > 0])))}
    write_case(out, plan, scan.grid, meta=dict(meta, summary=summary))
    return dict(summary, plan=str(plan_path), output=str(out), status=OK)


def _case_task(args):
    path, out, seed, options, resolution, overwrite = args
    try:
        return simulate_case(path, out, seed=seed, options=options, resolution=resolution, overwrite=overwrite)
    except Exception as exc:  # noqa: BLE001 - one bad plan never stops the corpus; its row says why
        return {"plan": str(path), "output": str(out), "status": FAILED, "error": first_line(exc)}


def simulate_many(plan_paths: Sequence, out_dir, *, seed: int = 0, options=None, resolution: float = 0.05,
                  jobs: int = 1, overwrite: bool = False) -> list:
    """Simulate a case per plan; a single plan's case is ``out_dir`` itself, else ``out_dir/NAME``.

    Each plan's scan seed is :func:`case_seed` of ``seed`` and the plan's
    name, so a plan's case does not depend on the other plans or the order.
    A plan that cannot be read gets a row with ``status`` ``"failed"`` and
    its ``error``; the other plans still run.

    Returns
    -------
    list of dict
        One summary row per plan (see :func:`simulate_case`), in the order given.
    """
    paths = [Path(p) for p in plan_paths]
    if not paths:
        raise ParameterError("no plan given")
    if jobs < 1:
        raise ParameterError(f"jobs must be >= 1, got {jobs!r}")
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise OutputExistsError(f"-o {out}: exists and is not a folder")
    dirs = output_dirs(paths, out)
    tasks = [(p, d, case_seed(seed, p.stem) if len(paths) > 1 else int(seed), options, resolution, overwrite)
             for p, d in zip(paths, dirs)]
    jobs = worker_count(jobs, len(tasks))
    rows = []
    bar = tqdm(total=len(tasks), unit="plan", disable=len(tasks) < 2 or not log.isEnabledFor(logging.WARNING))
    if jobs == 1:
        for t in tasks:
            rows.append(_case_task(t))
            bar.update()
    else:
        with concurrent.futures.ProcessPoolExecutor(jobs) as pool:
            for row in pool.map(_case_task, tasks, chunksize=1):
                rows.append(row)
                bar.update()
    bar.close()
    failed = [r for r in rows if r["status"] == FAILED]
    if failed:
        log.info("%d of %d plans failed: %s", len(failed), len(rows), "; ".join(r["error"] for r in failed))
    return rows
