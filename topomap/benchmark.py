"""Running every segmentation method on a room-segmentation benchmark.

:func:`run_benchmark` segments every map of a benchmark directory (the
layout of Bormann et al. 2016, see :mod:`topomap.datasets`) with every
method of :data:`topomap.segmentation.METHODS` and scores the result with
:func:`topomap.evaluation.evaluate`; :func:`format_table` turns the per-map
rows into a table like Tables 1 and 2 of the paper, and :func:`write_rows`
saves them as CSV or JSON.

Conventions (those of the data set's README):

* the map is classified as the peers were given it: a cell is free where the
  map's gray value is >= 250 and occupied everywhere else
  (:func:`benchmark_grid`); no cell is unknown;
* true doors are extracted from the *unfurnished* map in both variants;
* ``runtime_s`` is the wall time of the ``segment(...)`` call only: file
  reading, building the grid and scoring are excluded. Every method runs in
  the same process and the same run, map after map, after one untimed
  warm-up call per method on a small synthetic map (so that lazy imports
  and first-call costs are not charged to the first benchmark map). With
  ``jobs > 1`` the maps run in parallel worker processes that compete for
  the CPU and memory bandwidth, so their timings are less comparable.
"""

from __future__ import annotations

import csv
import gc
import io as _io
import json
import math
import time
from pathlib import Path
from typing import Callable, Iterable, Optional, Sequence

import numpy as np

from .errors import ParameterError

__all__ = [
    "VARIANTS",
    "ROW_COLUMNS",
    "benchmark_grid",
    "run_benchmark",
    "run_map",
    "format_table",
    "write_rows",
]

#: The two map variants of the benchmark.
VARIANTS = ("unfurnished", "furnished")

#: Columns every row has, in this order (per-stage timings ``t_<stage>``
#: follow; their names depend on the method).
ROW_COLUMNS = (
    "method", "variant", "map", "precision", "recall", "precision_macro", "recall_macro", "f1",
    "door_precision", "door_recall", "door_f1", "door_tp", "door_fp", "door_fn",
    "adjacency_precision", "adjacency_recall", "adjacency_f1",
    "n_rooms", "n_segments", "n_true_rooms", "room_count_error", "n_doors",
    "runtime_s", "jobs", "error",
)

_SCORE_KEYS = ("precision", "recall", "precision_macro", "recall_macro", "f1",
               "door_precision", "door_recall", "door_f1", "door_tp", "door_fp", "door_fn",
               "adjacency_precision", "adjacency_recall", "adjacency_f1",
               "n_segments", "room_count_error")


def benchmark_grid(bm):
    """The occupancy grid of a benchmark map, with the data set's convention.

    Parameters
    ----------
    bm : topomap.datasets.BenchmarkMap

    Returns
    -------
    topomap.io.OccupancyGrid
        ``cells`` int8: 0 (free) where ``bm.map_gray >= 250``, 100
        (occupied) everywhere else; ``gray`` is ``bm.map_gray``; resolution
        ``bm.resolution``; source the map file.
    """
    from .io import FREE, OCCUPIED, OccupancyGrid

    gray = np.asarray(bm.map_gray)
    cells = np.where(gray >= 250, FREE, OCCUPIED).astype(np.int8)
    return OccupancyGrid(cells, bm.resolution, (0.0, 0.0, 0.0), str(bm.map_path), gray=gray)


def _check_methods(methods) -> list:
    from .segmentation import METHODS

    if methods is None:
        return list(METHODS)
    if isinstance(methods, str):
        methods = [m for m in methods.split(",")]
    out = []
    for m in methods:
        m = str(m).strip()
        if not m:
            continue
        if m not in METHODS:
            raise ParameterError(f"unknown method {m!r}; choose from {', '.join(sorted(METHODS))}")
        if m not in out:
            out.append(m)
    if not out:
        raise ParameterError("no method given")
    return out


def _check_variants(variants) -> list:
    if isinstance(variants, str):
        variants = list(VARIANTS) if variants == "both" else [variants]
    out = []
    for v in variants:
        if v not in VARIANTS:
            raise ParameterError(f"variant must be 'unfurnished', 'furnished' or 'both', got {v!r}")
        if v not in out:
            out.append(v)
    if not out:
        raise ParameterError("no variant given")
    return out


_WARM = set()


def _warm_up(method: str) -> None:
    """Run ``method`` once, untimed, on a small drawn map (once per process)."""
    if method in _WARM:
        return
    _WARM.add(method)
    from .io import from_array
    from .segmentation import segment

    free = np.zeros((80, 120), bool)
    free[5:75, 5:58] = True
    free[5:75, 62:115] = True
    free[35:47, 58:62] = True
    try:
        segment(from_array(free, resolution=0.05), method=method)
    except Exception:  # noqa: BLE001 - a failing method fails again, timed, on the real maps
        pass


def run_map(bm, method: str, *, jobs: int = 1, warm_up: bool = True) -> dict:
    """Segment one benchmark map with one method and score it.

    Parameters
    ----------
    bm : topomap.datasets.BenchmarkMap
    method : str
        A key of :data:`topomap.segmentation.METHODS`.
    jobs : int, optional
        Recorded in the row (the number of parallel workers of the run).
    warm_up : bool, optional
        Run the method once untimed on a small map first (once per process).

    Returns
    -------
    dict
        One row: see :data:`ROW_COLUMNS`, plus ``t_<stage>`` per-stage
        seconds from ``Segmentation.timings``. If the method raises, the row
        has ``error`` set to a one-line message and NaN scores.
    """
    from .evaluation import evaluate
    from .segmentation import segment

    row = {"method": method, "variant": bm.variant, "map": bm.name}
    if warm_up:
        _warm_up(method)
    grid = benchmark_grid(bm)
    gc.collect()
    t0 = time.perf_counter()
    try:
        seg = segment(grid, method=method)
    except Exception as exc:  # noqa: BLE001 - one failing map does not stop the benchmark
        runtime = time.perf_counter() - t0
        msg = " ".join(str(exc).split()) or type(exc).__name__
        row.update({k: math.nan for k in _SCORE_KEYS})
        row.update(n_rooms=math.nan, n_true_rooms=math.nan, n_doors=math.nan,
                   runtime_s=runtime, jobs=jobs, error=f"{type(exc).__name__}: {msg}"[:300])
        return row
    runtime = time.perf_counter() - t0
    doors = [d.segment for d in seg.doors]
    ev = evaluate(seg.labels, bm.map_gray, bm.gt_gray, pred_doors=doors,
                  resolution=bm.resolution, door_map_gray=bm.unfurnished_gray)
    for k in _SCORE_KEYS:
        v = ev.get(k, math.nan)
        row[k] = int(v) if isinstance(v, (int, np.integer)) and not isinstance(v, bool) else float(v)
    row["n_rooms"] = int(seg.n_rooms)
    row["n_true_rooms"] = int(ev["n_rooms"])
    row["n_doors"] = len(seg.doors)
    row["runtime_s"] = runtime
    row["jobs"] = int(jobs)
    row["error"] = ""
    for stage, secs in seg.timings.items():
        row[f"t_{stage}"] = float(secs)
    return row


def _ordered(row: dict) -> dict:
    head = {k: row[k] for k in ROW_COLUMNS if k in row}
    head.update({k: v for k, v in row.items() if k not in head})
    return head


def _pool_init():
    # workers ignore Ctrl-C; the parent cancels them
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _pool_task(bm, method, jobs):
    return run_map(bm, method, jobs=jobs)


def run_benchmark(directory, *, methods: Optional[Sequence[str]] = None,
                  variants: Iterable[str] | str = VARIANTS, jobs: int = 1,
                  progress: Optional[Callable[[int, int, dict], None]] = None,
                  names: Optional[Iterable[str]] = None) -> list:
    """Run methods on every map of a benchmark directory and score them.

    Parameters
    ----------
    directory : str or Path
        Folder in the data set's layout (``NAME.png``,
        ``NAME_furnitures.png``, ``NAME_gt_segmentation.png``).
    methods : sequence of str or str, optional
        Method names (or one comma-separated string); default every method
        of :data:`topomap.segmentation.METHODS`.
    variants : iterable of str or str, optional
        ``"unfurnished"``, ``"furnished"`` or both (default; the string
        ``"both"`` is accepted too).
    jobs : int, optional
        Number of worker processes (:class:`concurrent.futures.ProcessPoolExecutor`);
        1 (default) runs everything in this process, the only setting whose
        timings are fully comparable.
    progress : callable, optional
        Called as ``progress(done, total, row)`` after every (map, method).
    names : iterable of str, optional
        Only these maps.

    Returns
    -------
    list of dict
        One row per (method, variant, map), ordered by method (in the order
        given), variant, map name. See :func:`run_map` for the columns.

    Raises
    ------
    ParameterError
        An unknown method or variant, or ``jobs < 1``.
    topomap.datasets.BenchmarkNotFoundError
        No benchmark maps in ``directory``.
    """
    from .datasets import load_benchmark

    methods = _check_methods(methods)
    variants = _check_variants(variants)
    try:
        jobs = int(jobs)
    except (TypeError, ValueError):
        raise ParameterError(f"jobs must be an integer >= 1, got {jobs!r}") from None
    if jobs < 1:
        raise ParameterError(f"jobs must be an integer >= 1, got {jobs!r}")
    names = None if names is None else list(names)

    maps = {v: load_benchmark(directory, variant=v, names=names) for v in variants}
    # map after map, every method on the map before the next one: all methods
    # see the same machine state over the run
    tasks = [(v, bm, m) for v in variants for bm in maps[v] for m in methods]
    total = len(tasks)
    results = {}
    if jobs == 1:
        for m in methods:
            _warm_up(m)
        for i, (v, bm, m) in enumerate(tasks):
            row = run_map(bm, m, jobs=1)
            results[(m, v, bm.name)] = row
            if progress is not None:
                progress(i + 1, total, row)
    else:
        from concurrent.futures import ProcessPoolExecutor, as_completed

        with ProcessPoolExecutor(max_workers=jobs, initializer=_pool_init) as ex:
            futs = {ex.submit(_pool_task, bm, m, jobs): (m, v, bm.name) for v, bm, m in tasks}
            try:
                for i, fut in enumerate(as_completed(futs)):
                    row = fut.result()
                    results[futs[fut]] = row
                    if progress is not None:
                        progress(i + 1, total, row)
            except BaseException:
                for f in futs:
                    f.cancel()
                raise
    rows = []
    for m in methods:
        for v in variants:
            for bm in maps[v]:
                rows.append(_ordered(results[(m, v, bm.name)]))
    return rows


def _stats(rows, key):
    vals = np.array([float(r[key]) for r in rows if key in r and r[key] is not None
                     and r[key] != "" and np.isfinite(float(r[key]))], float)
    if vals.size == 0:
        return math.nan, math.nan, math.nan, 0
    sd = float(vals.std(ddof=1)) if vals.size > 1 else math.nan
    return float(vals.mean()), sd, float(np.median(vals)), int(vals.size)


def _is_zero(v):
    try:
        return float(v) == 0
    except (TypeError, ValueError):
        return False


def _pct(mean, sd):
    if not np.isfinite(mean):
        return "–"
    if not np.isfinite(sd):
        return f"{100 * mean:.1f}"
    return f"{100 * mean:.1f} ± {100 * sd:.1f}"


def _num(v, fmt):
    return format(v, fmt) if np.isfinite(v) else "–"


def format_table(rows: Sequence[dict]) -> str:
    """A markdown table of the benchmark, one line per method and variant.

    Like Tables 1 and 2 of the paper: mean ± sample standard deviation over
    the maps of precision P and recall R (Bormann et al.'s micro figures, in
    %), their F1 (harmonic mean of the mean P and mean R), the mean door F1
    (%) and the runtime per map (segmentation call only) as mean and median
    seconds. Methods keep the order of their first row; maps that failed are
    counted in the ``failed`` column and left out of the means.

    Parameters
    ----------
    rows : sequence of dict
        As :func:`run_benchmark` returns them (or read back from its CSV).

    Returns
    -------
    str
        Markdown, ending with a newline. A note line follows the table when
        the rows were measured with several parallel jobs.
    """
    order = []
    groups = {}
    for r in rows:
        key = (r["method"], r["variant"])
        if key not in groups:
            groups[key] = []
            order.append(key)
        groups[key].append(r)
    vorder = [v for v in VARIANTS if any(k[1] == v for k in order)]
    vorder += [v for k in order for v in [k[1]] if v not in vorder]
    morder = list(dict.fromkeys(k[0] for k in order))
    order.sort(key=lambda k: (vorder.index(k[1]), morder.index(k[0])))
    head = ("| method | variant | maps | P ± sd (%) | R ± sd (%) | F1 (%) | door F1 (%) "
            "| runtime mean (s) | runtime median (s) | failed |")
    lines = [head, "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    doorless = False
    for key in order:
        g = groups[key]
        ok = [r for r in g if not r.get("error")]
        p, psd, _, _ = _stats(ok, "precision")
        r_, rsd, _, _ = _stats(ok, "recall")
        f1 = 2 * p * r_ / (p + r_) if np.isfinite(p) and np.isfinite(r_) and p + r_ > 0 else math.nan
        df1, _, _, _ = _stats(ok, "door_f1")
        if ok and all(_is_zero(r.get("n_doors")) for r in ok):
            df1 = math.nan  # the method reports no doors: no door score
            doorless = True
        tm, _, tmed, _ = _stats(g, "runtime_s")
        lines.append(f"| {key[0]} | {key[1]} | {len(ok)} | {_pct(p, psd)} | {_pct(r_, rsd)} "
                     f"| {_num(100 * f1, '.1f')} | {_num(100 * df1, '.1f')} "
                     f"| {_num(tm, '.3f')} | {_num(tmed, '.3f')} | {len(g) - len(ok)} |")
    out = "\n".join(lines) + "\n"
    if doorless:
        out += "\n(–: the method reports no doors, so it has no door score.)\n"
    jobs = {int(float(r["jobs"])) for r in rows if r.get("jobs") not in (None, "")}
    if any(j > 1 for j in jobs):
        out += (f"\nNote: measured with {max(jobs)} parallel jobs; the runtimes are less "
                "comparable than with --jobs 1.\n")
    return out


def _jsonable(v):
    if isinstance(v, (np.integer,)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        v = float(v)
        return v if math.isfinite(v) else None
    if isinstance(v, np.bool_):
        return bool(v)
    return v


def write_rows(rows: Sequence[dict], path) -> Path:
    """Write per-map rows to ``path``: CSV (``.csv``) or JSON (``.json``).

    The file is written atomically (:func:`topomap.export.atomic_write`).
    CSV columns are :data:`ROW_COLUMNS` then every other key in first-seen
    order (missing values empty); JSON is a list of objects with NaN as
    ``null``.

    Raises
    ------
    ParameterError
        Another file extension.
    """
    from .export import atomic_write

    path = Path(path)
    ext = path.suffix.lower()
    if ext not in (".csv", ".json"):
        raise ParameterError(f"{path}: output must end in .csv or .json, got {ext or 'no extension'!r}")
    rows = list(rows)
    if ext == ".json":
        text = json.dumps([{k: _jsonable(v) for k, v in r.items()} for r in rows], indent=1,
                          allow_nan=False) + "\n"
    else:
        cols = [c for c in ROW_COLUMNS if any(c in r for r in rows)]
        for r in rows:
            cols += [k for k in r if k not in cols]
        buf = _io.StringIO()
        w = csv.DictWriter(buf, fieldnames=cols, restval="", lineterminator="\n")
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if isinstance(v, float) and not math.isfinite(v) else v)
                        for k, v in r.items()})
        text = buf.getvalue()
    with atomic_write(path, "w") as fh:
        fh.write(text)
    return path
