"""Running segmentation methods on a room-segmentation benchmark.

:func:`run_benchmark` segments every map of a benchmark directory -- either
layout of :mod:`topomap.bench.datasets`: the ipa_room_segmentation maps of Bormann
et al. 2016, or real maps with a YAML and a label image -- with every method
of :data:`topomap.core.segmentation.METHODS`, and scores the result with
:func:`topomap.bench.evaluation.evaluate`; :func:`format_table` turns the per-map
rows into a summary table and :func:`write_rows` saves them as CSV or JSON.

Conventions:

* **the user's path**: each map is loaded as a user loads it with the CLI --
  ``load_map(NAME.png, resolution=0.05)`` (``topomap segment NAME.png
  --resolution 0.05``) for the ipa maps, ``load_map(NAME.yaml)`` where the
  data set provides a YAML -- so the benchmark's labels are the CLI's;
* **scores** (Bormann et al.): the headline precision / recall is the
  *original* protocol (true rooms kept whole, furniture included; segments
  restricted to the cells the method was given, the free cells of the grid
  as loaded); beside it the *free-cells* protocol (true rooms restricted to
  those cells too) and the *ceiling* (the ground truth itself scored under
  each protocol); segments and rooms of <= 100 cells are ignored. See
  :mod:`topomap.bench.evaluation`;
* **rooms**: ``n_rooms`` is every room the method reports (the room
  graph's nodes, as the user sees them, however small), ``n_fragments``
  the free regions it set apart as too small to be a room (scored as no
  room: they are not in the room graph), ``n_true_rooms`` the ground
  truth's rooms;
* true doors (ipa layout) are extracted from the *unfurnished* map in both
  variants; a simulated case lists its doors (``gt_doors.json``, metres),
  drawn as lines of cells of the grid as loaded; only doors joining two
  true rooms are scored (as on the ipa maps);
* ``runtime_s`` is the wall time of the user's job up to the segmentation:
  ``load_map(...)`` plus ``segment(...)`` (``t_load`` is the loading part);
  scoring is excluded. Every method runs in the same process and the same
  run, map after map, after one untimed warm-up call per method on a small
  synthetic map (so that lazy imports and first-call costs are not charged
  to the first benchmark map). With ``jobs > 1`` the maps run in parallel
  worker processes that compete for the CPU and memory bandwidth, so their
  timings are less comparable.
"""

from __future__ import annotations

import concurrent.futures
import csv
import gc
import io
import json
import math
import signal
import time
from pathlib import Path
from typing import Callable, Iterable, Optional, Sequence

import numpy as np

from ..core import segmentation
from ..core.segmentation import METHODS
from ..errors import MapError, ParameterError
from ..grid import share_memory
from ..io.files import atomic_write
from ..io.maps import from_array
from ..run.batch import worker_count
from .datasets import LABELLED_VARIANT, SIMULATED_VARIANTS, VARIANTS, detect_layout, door_cells, load_benchmark, \
    load_labelled, load_simulated
from .evaluation import evaluate

__all__ = [
    "VARIANTS",
    "ROW_COLUMNS",
    "TABLE_CAPTION",
    "benchmark_grid",
    "segment_map",
    "run_benchmark",
    "run_map",
    "check_methods",
    "format_table",
    "write_rows",
]

#: Columns every row has, in this order (per-stage timings ``t_<stage>``
#: follow; their names depend on the method).
ROW_COLUMNS = (
    "method", "variant", "map", "precision", "recall", "f1",
    "precision_free", "recall_free", "f1_free",
    "ceiling_precision", "ceiling_recall", "ceiling_precision_free", "ceiling_recall_free",
    "precision_macro", "recall_macro", "precision_macro_free", "recall_macro_free",
    "door_precision", "door_recall", "door_f1", "door_tp", "door_fp", "door_fn",
    "adjacency_precision", "adjacency_recall", "adjacency_f1",
    "n_rooms", "n_fragments", "n_true_rooms", "n_segments", "room_count_error", "n_doors",
    "runtime_s", "t_load", "jobs", "error",
)

_SCORE_KEYS = ("precision", "recall", "f1", "precision_free", "recall_free", "f1_free",
               "ceiling_precision", "ceiling_recall", "ceiling_precision_free",
               "ceiling_recall_free", "precision_macro", "recall_macro",
               "precision_macro_free", "recall_macro_free",
               "door_precision", "door_recall", "door_f1", "door_tp", "door_fp", "door_fn",
               "adjacency_precision", "adjacency_recall", "adjacency_f1",
               "n_true_rooms", "n_segments", "room_count_error")


def benchmark_grid(bm):
    """The occupancy grid of a benchmark map, loaded as a user loads it.

    Parameters
    ----------
    bm : topomap.bench.datasets.BenchmarkMap

    Returns
    -------
    topomap.io.OccupancyGrid
        ``load_map(bm.load_path, **bm.load_kwargs)``: for an ipa map
        ``load_map(NAME.png, resolution=0.05)`` (a bare image: free where
        gray >= 250, see :func:`topomap.io.load_map`), for a labelled map
        ``load_map(NAME.yaml)``.
    """
    return bm.load()


def segment_map(bm, method: str):
    """Load ``bm`` as a user does and segment it, timed: ``(grid, seg, seconds)``.

    The same job as ``topomap segment`` up to writing the outputs; the
    seconds cover loading and segmentation (``seg.timings["load"]`` is set
    to the loading part).
    """
    gc.collect()
    t0 = time.perf_counter()
    grid = bm.load()
    t1 = time.perf_counter()
    seg = segmentation.segment(grid, method=method)
    t2 = time.perf_counter()
    seg.timings["load"] = t1 - t0
    return grid, seg, t2 - t0


def check_methods(methods) -> list:
    """The segmentation methods asked for, checked, in order and each once.

    Parameters
    ----------
    methods : sequence of str or str or None
        Method names, or one comma-separated string of them; None: every
        method of :data:`topomap.core.segmentation.METHODS`.

    Returns
    -------
    list of str

    Raises
    ------
    ParameterError
        An unknown method, or none given.
    """
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
    """The variants asked for, in order; ``"both"`` stays as given (each layout reads it its own way)."""
    if isinstance(variants, str):
        variants = [variants]
    out = []
    for v in variants:
        if v != "both" and v not in VARIANTS + SIMULATED_VARIANTS:
            raise ParameterError(f"variant must be 'unfurnished', 'furnished', 'plan', 'scan' or 'both', "
                                 f"got {v!r}")
        if v not in out:
            out.append(v)
    if not out:
        raise ParameterError("no variant given")
    return out


def _layout_variants(layout, variants, directory) -> list:
    """The variants of ``layout`` that ``variants`` (checked by :func:`_check_variants`) select."""
    own = VARIANTS if layout == "ipa" else SIMULATED_VARIANTS
    out = []
    for v in variants:
        for w in (own if v == "both" else (v,)):
            if w not in own:
                raise ParameterError(f"{directory}: variant {w!r} is not one of this {layout} data set's "
                                     f"({', '.join(own)} or both)")
            if w not in out:
                out.append(w)
    return out


_WARM = set()


def _warm_up(method: str) -> None:
    """Run ``method`` once, untimed, on a small drawn map (once per process)."""
    if method in _WARM:
        return
    _WARM.add(method)
    free = np.zeros((80, 120), bool)
    free[5:75, 5:58] = True
    free[5:75, 62:115] = True
    free[35:47, 58:62] = True
    try:
        segmentation.segment(from_array(free, resolution=0.05), method=method)
    except Exception:  # noqa: BLE001 - a failing method fails again, timed, on the real maps
        pass


def _error_row(row, exc, runtime, jobs):
    msg = " ".join(str(exc).split()) or type(exc).__name__
    row.update({k: math.nan for k in _SCORE_KEYS})
    row.update(n_rooms=math.nan, n_fragments=math.nan, n_doors=math.nan, runtime_s=runtime, t_load=math.nan,
               jobs=jobs, error=f"{type(exc).__name__}: {msg}"[:300])
    return row


def _score(bm, grid, seg) -> dict:
    """:func:`topomap.bench.evaluation.evaluate` of one segmentation of ``bm`` (the grid as loaded)."""
    if grid.shape != bm.gt_rooms.shape:
        raise MapError(f"{bm.load_path}: map is {grid.shape[1]} x {grid.shape[0]} cells, its ground truth "
                       f"{bm.gt_path.name} {bm.gt_rooms.shape[1]} x {bm.gt_rooms.shape[0]}")
    true_doors = true_edges = None
    if bm.gt_doors is not None:
        # doors joining two true rooms, as the door lines of the ipa ground truth (min_rooms=2)
        inner = [d for d in bm.gt_doors if len(d["rooms"]) == 2 and min(d["rooms"]) > 0
                 and d["rooms"][0] != d["rooms"][1]]
        true_doors = door_cells(inner, grid)
        true_edges = {tuple(sorted(d["rooms"])) for d in inner}
    # the rooms a user gets: fragments (not in the room graph) are no room
    return evaluate(seg.room_labels, bm.map_gray, bm.gt_gray, pred_doors=[d.segment for d in seg.doors],
                    resolution=grid.resolution, door_map_gray=bm.unfurnished_gray,
                    scored=grid.free, gt_rooms=bm.gt_rooms, true_doors=true_doors, true_edges=true_edges)


def run_map(bm, method: str, *, jobs: int = 1, warm_up: bool = True) -> dict:
    """Segment one benchmark map with one method, as a user would, and score it.

    Parameters
    ----------
    bm : topomap.bench.datasets.BenchmarkMap
    method : str
        A key of :data:`topomap.core.segmentation.METHODS`.
    jobs : int, optional
        Recorded in the row (the number of parallel workers of the run).
    warm_up : bool, optional
        Run the method once untimed on a small map first (once per process).

    Returns
    -------
    dict
        One row: see :data:`ROW_COLUMNS` and :func:`topomap.bench.evaluation.evaluate`
        (scores are scored on ``grid.free`` of the grid as loaded), plus
        ``t_<stage>`` per-stage seconds from ``Segmentation.timings``. If
        loading or the method raises, the row has ``error`` set to a
        one-line message and NaN scores.
    """
    row = {"method": method, "variant": bm.variant, "map": bm.name}
    if warm_up:
        _warm_up(method)
    t0 = time.perf_counter()
    try:
        grid, seg, runtime = segment_map(bm, method)
    except Exception as exc:  # noqa: BLE001 - one failing map does not stop the benchmark
        return _error_row(row, exc, time.perf_counter() - t0, jobs)
    try:
        ev = _score(bm, grid, seg)
    except Exception as exc:  # noqa: BLE001 - e.g. a YAML naming an image of another size than the truth
        return _error_row(row, exc, runtime, jobs)
    for k in _SCORE_KEYS:
        v = ev.get(k, math.nan)
        row[k] = int(v) if isinstance(v, (int, np.integer)) and not isinstance(v, bool) else float(v)
    row["n_rooms"] = int(seg.n_rooms)
    row["n_fragments"] = int(seg.n_fragments)
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


def _pool_init(jobs: int = 1):
    """Set up a worker process: it ignores Ctrl-C (the parent cancels it), and ``jobs`` maps share the
    memory."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    share_memory(jobs)  # the maps running at once share the memory the size limit is taken from


def _pool_task(bm, method, jobs):
    return run_map(bm, method, jobs=jobs)


def _load_maps(directory, variants, maps) -> dict:
    """``{variant: [BenchmarkMap]}`` for any layout (the labelled one has one variant)."""
    layout = detect_layout(directory)
    if layout == "labelled":
        return {LABELLED_VARIANT: load_labelled(directory, names=maps)}
    load = load_benchmark if layout == "ipa" else load_simulated
    return {v: load(directory, variant=v, names=maps) for v in _layout_variants(layout, variants, directory)}


def _execute(tasks, jobs, progress) -> dict:
    """Run ``(variant, map, method)`` tasks; ``{(method, variant, name): row}``."""
    results = {}
    total = len(tasks)
    jobs = worker_count(jobs, len(tasks))
    if jobs == 1:
        for m in dict.fromkeys(t[2] for t in tasks):
            _warm_up(m)
        for i, (v, bm, m) in enumerate(tasks):
            row = run_map(bm, m, jobs=1)
            results[(m, v, bm.name)] = row
            if progress is not None:
                progress(i + 1, total, row)
        return results
    with concurrent.futures.ProcessPoolExecutor(max_workers=jobs, initializer=_pool_init, initargs=(jobs,)) as ex:
        futs = {ex.submit(_pool_task, bm, m, jobs): (m, v, bm.name) for v, bm, m in tasks}
        try:
            for i, fut in enumerate(concurrent.futures.as_completed(futs)):
                row = fut.result()
                results[futs[fut]] = row
                if progress is not None:
                    progress(i + 1, total, row)
        except BaseException:
            for f in futs:
                f.cancel()
            raise
    return results


def run_benchmark(directory, *, methods: Optional[Sequence[str]] = None,
                  variants: Iterable[str] | str = "both", jobs: int = 1,
                  progress: Optional[Callable[[int, int, dict], None]] = None,
                  names: Optional[Iterable[str]] = None,
                  maps: Optional[Iterable[str] | str] = None) -> list:
    """Run methods on every map of a benchmark directory and score them.

    Parameters
    ----------
    directory : str or Path
        A folder in any layout of :mod:`topomap.bench.datasets`, picked by what
        it holds (:func:`topomap.bench.datasets.detect_layout`): ``NAME.png``,
        ``NAME_furnitures.png``, ``NAME_gt_segmentation.png`` (ipa),
        ``NAME.png`` + ``NAME.yaml`` + ``NAME_gt.png`` (labelled), or case
        folders ``CASE/`` with ``map.yaml``, ``plan.yaml``, ``gt_rooms.png``
        and ``gt_doors.json`` (simulated).
    methods : sequence of str or str, optional
        Method names (or one comma-separated string); default every method
        of :data:`topomap.core.segmentation.METHODS`.
    variants : iterable of str or str, optional
        ipa layout: ``"unfurnished"``, ``"furnished"`` or ``"both"``
        (default); simulated layout: ``"plan"`` (the drawn floor plan),
        ``"scan"`` (the simulated robot map) or ``"both"``. Ignored for the
        labelled layout, whose rows have the variant ``"map"``.
    jobs : int, optional
        Number of worker processes (:class:`concurrent.futures.ProcessPoolExecutor`);
        1 (default) runs everything in this process, the only setting whose
        timings are fully comparable.
    progress : callable, optional
        Called as ``progress(done, total, row)`` after every (map, method).
    maps : iterable of str or str, optional
        Only these maps: names or shell patterns (``freiburg079_*``), or one
        comma-separated string of them. A pattern that matches no map is an
        error.
    names : iterable of str, optional
        The same as ``maps`` (kept for older callers).

    Returns
    -------
    list of dict
        One row per (method, variant, map), ordered by method (in the order
        given), variant, map name. See :func:`run_map` for the columns.

    Raises
    ------
    ParameterError
        An unknown method or variant (or one of another layout), or ``jobs < 1``.
    topomap.bench.datasets.BenchmarkNotFoundError
        No benchmark maps in ``directory``, or a ``maps`` pattern matches none.
    """
    methods = check_methods(methods)
    variants = _check_variants(variants)
    try:
        jobs = int(jobs)
    except (TypeError, ValueError):
        raise ParameterError(f"jobs must be an integer >= 1, got {jobs!r}") from None
    if jobs < 1:
        raise ParameterError(f"jobs must be an integer >= 1, got {jobs!r}")
    if maps is None and names is not None:
        maps = list(names)

    loaded = _load_maps(directory, variants, maps)
    # map after map, every method on the map before the next one: all methods
    # see the same machine state over the run
    tasks = [(v, bm, m) for v in loaded for bm in loaded[v] for m in methods]
    results = _execute(tasks, jobs, progress)
    return [_ordered(results[(m, v, bm.name)]) for m in methods for v in loaded for bm in loaded[v]]


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


#: What the columns of :func:`format_table` mean (printed above the table).
TABLE_CAPTION = (
    "P / R: Bormann et al. precision / recall (%), mean ± sd over the maps, ORIGINAL protocol "
    "(ground-truth rooms whole, furniture included; segments restricted to the cells the method "
    "was given, the free cells of the map as loaded). free P / R: the free-cells protocol (rooms "
    "restricted to those cells too). ceiling: the ground truth itself scored under each protocol. "
    "Segments and rooms of <= 100 cells are ignored in every score. rooms: rooms reported (room-graph "
    "nodes; fragments not counted) / true rooms, summed over the maps. door F1: detected doors vs the ground truth's door "
    "lines (0.5 m). runtime: load_map + segment per map (s).")


def _group(rows) -> list:
    """``[((method, variant), rows)]``: variants in :data:`VARIANTS` order, methods as first seen."""
    groups = {}
    for r in rows:
        groups.setdefault((r["method"], r["variant"]), []).append(r)
    keys = list(groups)
    vorder = [v for v in VARIANTS + SIMULATED_VARIANTS if any(k[1] == v for k in keys)]
    vorder += [k[1] for k in keys if k[1] not in vorder]
    morder = list(dict.fromkeys(k[0] for k in keys))
    keys.sort(key=lambda k: (vorder.index(k[1]), morder.index(k[0])))
    return [(k, groups[k]) for k in keys]


def _pair(ok, kp, kr) -> str:
    p, r = _stats(ok, kp)[0], _stats(ok, kr)[0]
    return f"{_num(100 * p, '.1f')} / {_num(100 * r, '.1f')}"


def _sum(rows, key) -> str:
    vals = [float(r[key]) for r in rows if r.get(key) not in (None, "")]
    vals = [v for v in vals if np.isfinite(v)]
    return str(int(sum(vals))) if vals else "–"


def _table_line(key, g) -> tuple:
    """One summary line of :func:`format_table` and whether the method reports no doors."""
    ok = [r for r in g if not r.get("error")]
    p, psd, _, _ = _stats(ok, "precision")
    r_, rsd, _, _ = _stats(ok, "recall")
    f1 = 2 * p * r_ / (p + r_) if np.isfinite(p) and np.isfinite(r_) and p + r_ > 0 else math.nan
    df1 = _stats(ok, "door_f1")[0]
    doorless = bool(ok) and all(_is_zero(r.get("n_doors")) for r in ok)
    if doorless:
        df1 = math.nan  # the method reports no doors: no door score
    tm, _, tmed, _ = _stats(g, "runtime_s")
    line = (f"| {key[0]} | {key[1]} | {len(ok)} | {_pct(p, psd)} | {_pct(r_, rsd)} "
            f"| {_num(100 * f1, '.1f')} | {_pair(ok, 'ceiling_precision', 'ceiling_recall')} "
            f"| {_pair(ok, 'precision_free', 'recall_free')} "
            f"| {_pair(ok, 'ceiling_precision_free', 'ceiling_recall_free')} "
            f"| {_sum(ok, 'n_rooms')} / {_sum(ok, 'n_true_rooms')} | {_num(100 * df1, '.1f')} "
            f"| {_num(tm, '.3f')} | {_num(tmed, '.3f')} | {len(g) - len(ok)} |")
    return line, doorless


def format_table(rows: Sequence[dict], *, caption: bool = True) -> str:
    """A markdown table of the benchmark, one line per method and variant.

    Per method and variant: mean ± sample standard deviation over the maps
    of precision P and recall R (Bormann et al.'s micro figures, in %,
    original protocol), their F1 (harmonic mean of the mean P and mean R),
    the ceiling (the ground truth's own P / R), the free-cells protocol's
    P / R and its ceiling, the rooms reported against the true rooms
    (summed over the maps), the mean door F1 (%) and the runtime per map
    (load_map + segment) as mean and median seconds. Maps that failed are
    counted in the ``failed`` column and left out of the other columns.

    Parameters
    ----------
    rows : sequence of dict
        As :func:`run_benchmark` returns them (or read back from its CSV).
    caption : bool, optional
        Print :data:`TABLE_CAPTION` (the protocols, the 100-cell rule) above
        the table (default).

    Returns
    -------
    str
        Markdown, ending with a newline. A note line follows the table when
        the rows were measured with several parallel jobs.
    """
    head = ("| method | variant | maps | P ± sd (%) | R ± sd (%) | F1 (%) | ceiling P / R (%) "
            "| free P / R (%) | free ceiling P / R (%) | rooms found / true | door F1 (%) "
            "| runtime mean (s) | runtime median (s) | failed |")
    lines = [head, "| --- | --- " + "| ---: " * 12 + "|"]
    doorless = False
    for key, g in _group(rows):
        line, no_doors = _table_line(key, g)
        lines.append(line)
        doorless |= no_doors
    out = (TABLE_CAPTION + "\n\n" if caption else "") + "\n".join(lines) + "\n"
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

    The file is written atomically (:func:`topomap.io.atomic_write`).
    CSV columns are :data:`ROW_COLUMNS` then every other key in first-seen
    order (missing values empty); JSON is a list of objects with NaN as
    ``null``.

    Raises
    ------
    ParameterError
        Another file extension.
    """
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
        buf = io.StringIO()
        w = csv.DictWriter(buf, fieldnames=cols, restval="", lineterminator="\n")
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if isinstance(v, float) and not math.isfinite(v) else v)
                        for k, v in r.items()})
        text = buf.getvalue()
    with atomic_write(path, "w") as fh:
        fh.write(text)
    return path
