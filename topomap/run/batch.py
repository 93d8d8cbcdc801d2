"""Batches of maps: :func:`segment_many` (what ``topomap segment MAP... -o OUT`` runs).

Rules (also on the docs page *Batches*):

Output folders
    One map: its files go straight into ``out``. Several maps: each map gets
    the folder of its path relative to the maps' common parent folder,
    without the extension (:func:`output_dirs`): ``ros/floor1/map.yaml`` and
    ``ros/floor2/map.yaml`` go to ``out/floor1/map/`` and ``out/floor2/map/``;
    ``maps/a.png`` to ``out/a/``. Two maps that differ only in their
    extension (``a.png``, ``a.yaml`` in one folder) keep it: ``out/a_png/``,
    ``out/a_yaml/``. The same map given twice is an error.
Run record
    Every output folder gets ``topomap_run.json``: the map it holds (absolute
    path), size and modification time of the input files (a YAML and the
    image it names), the options, the topomap version, size and
    modification time of every output file, and the map's summary row. It
    is written first as ``"status": "incomplete"`` and rewritten as
    ``"complete"`` after the last output file, always atomically; a map that
    fails puts the earlier record back (its earlier outputs are untouched).
    See :mod:`topomap.run.record`.
Refusal
    A folder that holds another map's results, or output files without a
    run record (results topomap did not write, or of unknown origin), is
    never written into: the whole batch stops before any map runs
    (:class:`~topomap.errors.OutputExistsError`) unless ``overwrite=True``.
One batch at a time
    A batch holds a lock on ``out`` (the file ``out/.topomap.lock``, locked
    with ``fcntl.flock``) from before it looks at the folders until its
    summary is written: a second batch into the same ``out`` meanwhile is
    refused at once (:class:`~topomap.errors.OutputExistsError`, nothing
    written). The lock goes with the process (a killed batch leaves no lock
    held); the file is removed when the batch ends.
Resume
    A map whose folder has a complete run record for the same input, the
    same options and version, unchanged input files and unchanged output
    files is skipped (status ``skipped``; its row comes from the record).
    ``overwrite=True`` runs every map again.
Crash safety
    Every output file is written to a temporary name and renamed into place
    once all of them are written (:func:`topomap.io.export.write_outputs`); a
    run killed in the middle leaves whole files only, with a record that
    says ``incomplete`` (so the map runs again); temporary files left by a
    killed run are removed when the map runs again.
Summary
    With several maps, ``out/summary.csv`` (:data:`SUMMARY_COLUMNS`, then
    ``t_<stage>`` seconds per stage, then ``error``), one row per map in the
    order given, written atomically every :data:`SUMMARY_EVERY` seconds and
    at the end (also when the batch is interrupted: maps not run yet are
    ``pending``).
Executors
    ``jobs=1``: in this process; ``jobs=N``: N local processes
    (:class:`concurrent.futures.ProcessPoolExecutor`); ``scheduler=``: an
    existing Dask distributed cluster (a scheduler address or a
    ``distributed.Client``; optional extra ``topomap[dask]``). Workers write
    the outputs themselves, so on a cluster ``out`` and the maps must be on
    a file system every worker sees, under the same paths (relative map
    paths are made absolute for the workers).
"""

from __future__ import annotations

import concurrent.futures
import csv
import io
import logging
import math
import numbers
import os
import signal
import sys
import time
import traceback
from collections import Counter
from contextlib import contextmanager, nullcontext
from pathlib import Path
from typing import Optional, Sequence

try:
    import fcntl
except ImportError:  # not a POSIX system: an O_EXCL lock file instead
    fcntl = None

from tqdm import tqdm
from tqdm.contrib.logging import logging_redirect_tqdm

from .. import __version__
from .._fast import keep_freed_memory, one_thread
from ..core.segmentation import METHODS, check_method_options
from ..errors import MapFileError, MissingDependencyError, OutputExistsError, ParameterError, TopomapError, \
    first_line, named
from ..grid import share_memory
from ..io.files import atomic_write, file_keys
from .job import STAGES, segment_file, summary_counts
from .record import COMPLETE, INCOMPLETE, OUTPUT_NAMES, RECORD, file_stamp, fingerprint, input_files, \
    nav2_exports, output_stamps, read_record, restore_record, up_to_date, write_record

__all__ = ["segment_many", "output_dirs", "read_summary", "RECORD", "SUMMARY", "SUMMARY_COLUMNS",
           "OUTPUT_NAMES", "STATUSES", "OK", "SKIPPED", "FAILED", "ERROR", "PENDING", "INCOMPLETE", "COMPLETE",
           "SUMMARY_EVERY"]

log = logging.getLogger("topomap.run.batch")

#: Name of the batch summary table in ``out``.
SUMMARY = "summary.csv"
#: Name of the lock file a running batch holds in ``out``.
LOCK = ".topomap.lock"
#: First columns of ``summary.csv`` (``t_<stage>`` columns and ``error`` follow).
SUMMARY_COLUMNS = ("map", "output", "status", "rooms", "doors", "fragments", "room_area_m2",
                   "fragment_area_m2", "outside_area_m2", "seconds")
#: Values of the ``status`` column: segmented now; up to date from an earlier
#: run; bad input or a failed write (exit code 1); an unexpected internal error
#: (exit code 3); not run because the batch was interrupted.
OK, SKIPPED, FAILED, ERROR, PENDING = "ok", "skipped", "failed", "error", "pending"
STATUSES = (OK, SKIPPED, FAILED, ERROR, PENDING)
#: Seconds between two rewrites of ``summary.csv`` while a batch runs.
SUMMARY_EVERY = 10.0


# --------------------------------------------------------------------------
# Output folders
# --------------------------------------------------------------------------

def _safe_part(name: str) -> str:
    """A folder name for one part of a map's path: a name that is empty or only dots (the stem of
    ``...png`` is ``..``) would leave ``out``; its dots become underscores (``..`` -> ``__``)."""
    return name if name.strip(".") else "_" * max(len(name), 1)


def output_dirs(paths: Sequence, out) -> list:
    """The output folder of every map of a batch (the rule of the module docstring).

    Parameters
    ----------
    paths : sequence of str or os.PathLike
        Map files.
    out : str or os.PathLike
        The batch's output folder.

    Returns
    -------
    list of pathlib.Path
        One folder per map, in the order of ``paths``; all different.

    Raises
    ------
    ParameterError
        A map given twice, or a map whose folder would be ``out/summary.csv``.
    """
    out = Path(out)
    paths = [Path(p) for p in paths]
    if len(paths) == 1:
        return [out]
    absolute = [Path(os.path.abspath(p)) for p in paths]
    seen = {}
    for p, a in zip(paths, absolute):
        if a in seen:
            raise ParameterError(f"{p}: map given twice (also as {seen[a]})")
        seen[a] = p
    base = Path(os.path.commonpath([str(a.parent) for a in absolute]))
    rel = [a.relative_to(base) for a in absolute]
    stems = [Path(*r.parent.parts, _safe_part(r.stem if r.suffix else r.name)) for r in rel]
    count = Counter(stems)
    dirs = [out / (s if count[s] == 1 else s.parent / f"{s.name}_{r.suffix[1:]}") for s, r in zip(stems, rel)]
    clash = Counter(dirs)
    for p, d in zip(paths, dirs):
        if d in (out / SUMMARY, out / LOCK) or clash[d] > 1:
            raise ParameterError(f"{p}: its output folder {d} is taken (rename the map)")
    return dirs


# --------------------------------------------------------------------------
# One batch at a time
# --------------------------------------------------------------------------

@contextmanager
def _output_lock(out: Path):
    """Hold the lock of the output folder ``out`` (created if missing) while the block runs.

    OutputExistsError at once when another process holds it. The lock is
    ``fcntl.flock`` on ``out/LOCK`` (released by the system when the process
    dies); the file is removed at the end, and ``out`` too when this created
    it and it is left empty.
    """
    created = not out.exists()
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise MapFileError(named(out, f"cannot create the output folder: {exc.strerror or exc}")) from None
    path = out / LOCK
    busy = OutputExistsError(f"{out}: another topomap run is writing into this folder (it holds {LOCK}); "
                             "nothing was written; wait for it to end, or use another output folder")
    while True:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | (0 if fcntl else os.O_EXCL), 0o644)
        except FileExistsError:  # no flock on this system: the file itself is the lock
            raise busy from None
        except OSError as exc:
            raise MapFileError(named(path, f"cannot create the lock file: {exc.strerror or exc}")) from None
        if fcntl is None:
            break
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            raise busy from None
        try:  # the file locked is still the one at the path (not one an ending batch just removed)
            st, now = os.fstat(fd), os.stat(path)
            if (st.st_dev, st.st_ino) == (now.st_dev, now.st_ino):
                break
        except FileNotFoundError:
            pass
        os.close(fd)
    try:
        os.write(fd, f"{os.getpid()}\n".encode())
        yield
    finally:
        try:
            os.unlink(path)
        except OSError:
            pass
        os.close(fd)
        if created:
            try:
                out.rmdir()  # only if empty
            except OSError:
                pass


# --------------------------------------------------------------------------
# Inputs that would be outputs, and the resume check
# --------------------------------------------------------------------------

def _refuse_inputs_as_outputs(paths, dirs, write_options):
    """ParameterError when an output file of the run (a map's files, changes.json, summary.csv, the
    --bag) would be one of its input files (a map, the image its YAML names, the --previous graph)."""
    inputs = [f for p in paths for f in input_files(Path(p))]
    if write_options.get("previous") is not None:
        inputs.append(Path(os.path.abspath(write_options["previous"])))
    outs = [(d / n, None) for d in dirs for n in (*OUTPUT_NAMES, RECORD, "changes.json")]
    if write_options.get("bag") is not None:
        outs.append((Path(write_options["bag"]), "--bag"))
    known = {}  # every input's keys (its resolved path, its device and inode): one look per file
    for i in inputs:
        for k in file_keys(i):
            if k is not None:
                known.setdefault(k, i)
    for o, what in outs:
        i = next((known[k] for k in file_keys(o) if k is not None and k in known), None)
        if i is not None:
            raise ParameterError(f"{what + ' ' if what else ''}{o}: is an input of this run ({i}); "
                                 "it would be replaced: choose another output")


def _plan(paths, dirs, settings, overwrite):
    """Per map ``"run"`` or ``"skip"`` (with the earlier row); raises on a folder this run must not write."""
    plan, refused = [], []
    for p, d in zip(paths, dirs):
        if os.path.lexists(d) and not d.is_dir():
            refused.append(f"{d} exists and is not a folder (the results of {p} go into a folder of that name)")
            plan.append(("run", None))
            continue
        rec = read_record(d)
        mine = str(Path(os.path.abspath(p)))
        if rec is None:
            theirs = [n for n in OUTPUT_NAMES if (d / n).exists()]
            if theirs and not overwrite:
                refused.append(f"{d} holds {theirs[0]} but no {RECORD} (results topomap did not write)")
            plan.append(("run", None))
        elif rec.get("input") != mine and not overwrite:
            other = rec.get("input") or "an unreadable run record"
            refused.append(f"{d} holds the results of {other}, not of {p}")
            plan.append(("run", None))
        elif not overwrite and rec.get("input") == mine and up_to_date(rec, settings, d):
            plan.append(("skip", rec.get("row") or {}))
        else:
            plan.append(("run", None))
    if refused:
        more = f" (and {len(refused) - 1} more)" if len(refused) > 1 else ""
        raise OutputExistsError(f"{refused[0]}{more}: nothing was written; use another output folder, "
                                "or --overwrite (overwrite=True) to replace them")
    return plan


# --------------------------------------------------------------------------
# One map (runs on a worker)
# --------------------------------------------------------------------------

def _new_record(task: dict) -> tuple:
    """``(run record, extra outputs)`` of a map about to run: the record (without its status) names the
    input files with their stamps (the --previous graph is one), the settings and the version; the extra
    outputs (the --bag) are absolute paths whose stamps go into the record's ``files``."""
    inputs = fingerprint(Path(task["path"]))
    extra_out = []
    for key in ("previous", "bag"):  # the --previous graph is an input, the --bag an output
        given = task["write_options"].get(key)
        if given is not None:
            if key == "previous":
                inputs[os.path.abspath(given)] = file_stamp(given)
            else:
                extra_out.append(os.path.abspath(given))
    record = {"topomap": __version__, "input": task["input"], "inputs": inputs, "settings": task["settings"]}
    return record, extra_out


def _run_one(task: dict) -> dict:
    """Segment one map into its folder; the summary row (never raises for a bad map)."""
    t0 = time.perf_counter()
    s = task["settings"]
    folder = Path(task["folder"])
    row = {"map": task["map"], "output": task["output"], "status": OK}
    existed = folder.exists()
    previous = claimed = None
    try:
        record, extra_out = _new_record(task)
        folder.mkdir(parents=True, exist_ok=True)
        # writing the record removes the temporaries a killed run left here (io.atomic_write)
        if (folder / RECORD).exists():
            previous = (folder / RECORD).read_text()
        # the Nav2 route graphs exported from the folder's room graph are made again with it
        nav2 = nav2_exports(read_record(folder) or {}) if previous is not None else []
        if nav2:
            record = dict(record, nav2=nav2)
        write_record(folder, dict(record, status=INCOMPLETE))  # a kill from here on: the map runs again
        claimed = True
        seg = segment_file(task["path"], folder, s["resolution"], s["method"], s["skeletons"],
                           nav2=nav2, options=s.get("options"), **task["write_options"])
        row.update(summary_counts(seg), outside_area_m2=float(seg.outside_area))
        row["seconds"] = time.perf_counter() - t0
        row.update({f"t_{k}": float(v) for k, v in seg.timings.items()})
        files = output_stamps(folder)
        files.update({f: file_stamp(f) for f in extra_out})
        write_record(folder, dict(record, status=COMPLETE, files=files, row=row))
        row["error"] = ""
        row["traceback"] = ""
    except Exception as exc:  # noqa: BLE001 - reported in the row, the batch goes on
        bad_input = isinstance(exc, (TopomapError, OSError, ValueError))
        row = {"map": task["map"], "output": task["output"], "status": FAILED if bad_input else ERROR,
               "seconds": time.perf_counter() - t0,
               "error": first_line(exc) if bad_input else f"{type(exc).__name__}: {first_line(exc)}",
               "traceback": "".join(traceback.format_exception(exc))}
        if claimed:  # the outputs are as they were (all files or none are replaced): so is the record
            restore_record(folder, previous, existed)
    return row


# --------------------------------------------------------------------------
# Executors
# --------------------------------------------------------------------------

def worker_count(jobs: int, tasks: int) -> int:
    """The local processes to start for ``tasks`` tasks asked to run on ``jobs``: at most one per task
    and one per CPU core (``--jobs 24`` for 3 maps starts 3 processes, on 2 cores 2)."""
    return max(1, min(int(jobs), int(tasks), os.cpu_count() or 1))


def _pool_init(jobs: int = 1):
    """Set up a local worker process: it ignores Ctrl-C (the parent stops it), and ``jobs`` maps share
    the memory."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    share_memory(jobs)  # the maps running at once share the memory the size limit is taken from
    keep_freed_memory()  # each worker runs many maps
    one_thread()  # one worker per core: a map's work on a second thread would compete with the others


def _crashed(task, exc) -> dict:
    return {"map": task["map"], "output": task["output"], "status": ERROR,
            "error": f"worker lost: {type(exc).__name__}: {first_line(exc)}",
            "traceback": "".join(traceback.format_exception(exc))}


def _client(scheduler):
    """``(client, whether this batch made it)`` of ``scheduler`` (an address or a distributed.Client)."""
    try:
        from distributed import Client  # the optional extra topomap[dask]
    except ImportError:
        raise MissingDependencyError("running on a Dask cluster needs dask.distributed: "
                                     "pip install 'topomap-rooms[dask]'") from None
    if isinstance(scheduler, Client):
        return scheduler, False
    if not isinstance(scheduler, str) or not scheduler.strip():
        raise ParameterError(f"scheduler must be an address like tcp://host:8786 or a distributed.Client, "
                             f"got {scheduler!r}")
    try:
        return Client(scheduler, timeout="20s"), True
    except (OSError, TimeoutError) as exc:
        raise ParameterError(f"scheduler {scheduler}: cannot reach it: {first_line(exc)}") from None


def _execute(tasks, jobs, scheduler):
    """Yield ``(index, row)`` as maps finish."""
    if scheduler is not None:
        yield from _execute_on_cluster(tasks, scheduler)
        return
    n = worker_count(jobs, len(tasks))
    if n < jobs:
        log.info("--jobs %d: %d local processes (%d maps to run, %d CPU cores)", jobs, n, len(tasks),
                 os.cpu_count() or 1)
    if n == 1:
        for i, t in enumerate(tasks):
            yield i, _run_one(t)
        return
    with concurrent.futures.ProcessPoolExecutor(max_workers=n, initializer=_pool_init, initargs=(n,)) as ex:
        futures = {ex.submit(_run_one, t): i for i, t in enumerate(tasks)}
        try:
            yield from _collect(concurrent.futures.as_completed(futures), futures.get, tasks)
        finally:
            for f in futures:
                f.cancel()


def _execute_on_cluster(tasks, scheduler):
    """Yield ``(index, row)`` as maps finish on the Dask cluster ``scheduler``."""
    client, own = _client(scheduler)
    try:
        from distributed import as_completed  # the optional extra topomap[dask]: only for a cluster

        futures = client.map(_run_one, tasks, pure=False)
        index = {f.key: i for i, f in enumerate(futures)}
        try:
            yield from _collect(as_completed(futures), lambda f: index[f.key], tasks)
        finally:
            client.cancel(futures)
    finally:
        if own:
            client.close()


def _collect(finished, index_of, tasks):
    """``(index, row)`` of every finished future (concurrent.futures or Dask)."""
    for fut in finished:
        i = index_of(fut)
        try:
            row = fut.result()
        except Exception as exc:  # noqa: BLE001 - a worker died
            row = _crashed(tasks[i], exc)
        yield i, row


# --------------------------------------------------------------------------
# Summary
# --------------------------------------------------------------------------

def _columns(rows) -> list:
    stages = []
    for r in rows:
        stages += [k for k in r if k.startswith("t_") and k not in stages]
    order = {f"t_{s}": i for i, s in enumerate(STAGES)}
    stages.sort(key=lambda k: order.get(k, len(order)))
    return [*SUMMARY_COLUMNS, *stages, "error"]


def _cell(v):
    """A summary cell: floats rounded to 12 significant digits (``154.395``, not the
    ``154.39500000000004`` a sum of cell areas gives), written as the repr of the rounded value."""
    if type(v) is float and math.isfinite(v):
        return repr(float(f"{v:.12g}"))
    return v


def _write_summary(rows, path: Path):
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=_columns(rows), restval="", extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    w.writerows([{k: _cell(v) for k, v in r.items()} for r in rows])
    with atomic_write(path, "w") as fh:
        fh.write(buf.getvalue())


def read_summary(path) -> list:
    """The rows of a ``summary.csv`` as dicts (numbers as float/int, empty cells as None)."""
    def value(k, v):
        if v == "":
            return None
        if k in ("rooms", "doors", "fragments"):
            return int(v)
        if k in ("room_area_m2", "fragment_area_m2", "outside_area_m2", "seconds") or k.startswith("t_"):
            return float(v)
        return v

    with open(path, newline="") as fh:
        return [{k: value(k, v) for k, v in r.items()} for r in csv.DictReader(fh)]


# --------------------------------------------------------------------------
# The batch
# --------------------------------------------------------------------------

def _line(done, total, row) -> str:
    st = row["status"]
    if st == OK:
        what = f"{row['rooms']} rooms, {row['doors']} doors, {row['seconds']:.1f} s -> {row['output']}"
    else:
        what = row.get("error", "")
    return f"[{done}/{total}] {row['map']}: {st}: {what}"


def segment_many(paths: Sequence, out, *, jobs: int = 1, scheduler=None, overwrite: bool = False,
                 resolution: Optional[float] = None, method: Optional[str] = None, skeletons: bool = False,
                 options: Optional[dict] = None, write_options: Optional[dict] = None,
                 progress: Optional[bool] = None) -> list:
    """Segment many maps and write each one's outputs, as ``topomap segment MAP... -o OUT``.

    Parameters
    ----------
    paths : sequence of str or os.PathLike
        Map files (ROS YAML, PGM, PNG).
    out : str or os.PathLike
        Output folder: one map's files go straight into it; several maps get
        a folder each (:func:`output_dirs`) and ``out/summary.csv``.
    jobs : int, optional
        Local worker processes (default 1: this process); at most one per
        map to run and one per CPU core are started (:func:`worker_count`).
    scheduler : str or distributed.Client, optional
        Run on this Dask distributed cluster instead (a scheduler address
        like ``"tcp://10.0.0.5:8786"``, or a client); ``jobs`` must then be 1.
        Needs ``pip install 'topomap-rooms[dask]'`` here and topomap on every
        worker; maps and ``out`` on a file system the workers share.
    overwrite : bool, optional
        Run every map again, and replace results this batch did not write.
    resolution : float, optional
        Metres per pixel for images without YAML (default 0.05).
    method : str, optional
        Segmentation method (default :data:`topomap.core.segmentation.DEFAULT_METHOD`).
    skeletons : bool, optional
        Draw both skeleton graphs in ``overlay.png``.
    options : dict, optional
        Keyword options of the method (:func:`topomap.segment`: lengths in metres, areas in m²), checked
        before any map runs (:func:`topomap.core.segmentation.check_method_options`) and kept in each
        folder's run record: a folder segmented with other options is not up to date.
    write_options : dict, optional
        More keyword options of the single-map writer
        (:func:`topomap.run.job.segment_file`).
    progress : bool, optional
        A progress bar on stderr (tqdm); default: when stderr is a terminal.
        Without the bar every finished map is logged at INFO level on the
        ``topomap.run.batch`` logger (with it, at DEBUG).

    Returns
    -------
    list of dict
        One row per map in the order of ``paths``: the columns of
        ``summary.csv`` (:data:`SUMMARY_COLUMNS`, ``t_<stage>`` seconds,
        ``error``; ``status`` one of :data:`STATUSES`) and ``traceback``
        (of a failed map, else empty; not in the CSV).

    Raises
    ------
    OutputExistsError
        An output folder holds results this run did not write (nothing is
        written then).
    ParameterError
        Bad options, a map given twice.
    MissingDependencyError
        ``scheduler`` without Dask installed.
    """
    paths = [Path(p) for p in paths]
    write_options = dict(write_options or {})
    jobs = _check_options(paths, jobs, scheduler, resolution, method, write_options.get("at"))
    options = check_method_options(method, options)
    for k, v in options.items():  # the run record is JSON, which has no NaN or infinity (nor does any option)
        if isinstance(v, numbers.Real) and not isinstance(v, bool) and not math.isfinite(v):
            raise ParameterError(f"option {k}={v!r}: not a finite number")
    out = Path(out)
    settings = {"resolution": None if resolution is None else float(resolution), "method": method,
                "skeletons": bool(skeletons), **{k: write_options[k] for k in sorted(write_options)}}
    if options:  # (no key without options: folders segmented before options could be given stay up to date)
        settings["options"] = {k: options[k] for k in sorted(options)}
    dirs = output_dirs(paths, out)
    _refuse_inputs_as_outputs(paths, dirs, write_options)
    with _output_lock(out):
        return _run_batch(paths, out, dirs, settings, overwrite, jobs, scheduler, write_options, progress)


def _check_options(paths, jobs, scheduler, resolution, method, at=None) -> int:
    """``jobs`` as an int; ParameterError for no maps, or options that are wrong or do not go together
    (``at``: the bag time of the write options; every setting goes into the run record's JSON, which has no
    NaN or infinity)."""
    if not paths:
        raise ParameterError("no maps given")
    if isinstance(jobs, bool) or not isinstance(jobs, numbers.Integral) or jobs < 1:
        raise ParameterError(f"jobs must be an integer >= 1, got {jobs!r}")
    jobs = int(jobs)
    if scheduler is not None and jobs != 1:
        raise ParameterError(f"jobs={jobs} and a scheduler: the cluster decides how many maps run at once")
    if resolution is not None and not (isinstance(resolution, (int, float)) and 0 < resolution < math.inf):
        raise ParameterError(f"resolution must be > 0 m/px, got {resolution!r}")
    if at is not None and not (isinstance(at, numbers.Real) and not isinstance(at, bool) and 0 <= at < math.inf):
        raise ParameterError(f"time must be seconds >= 0 after the start of the bag, got {at!r}")
    if method is not None and method not in METHODS:
        raise ParameterError(f"unknown method {method!r}; methods: {', '.join(METHODS)}")
    return jobs


def _run_batch(paths, out, dirs, settings, overwrite, jobs, scheduler, write_options, progress) -> list:
    """The batch of :func:`segment_many` once it holds the lock of ``out``: the rows of every map."""
    plan = _plan(paths, dirs, settings, overwrite)
    rows = [dict(earlier, map=str(p), output=str(d), status=SKIPPED) if what == "skip"
            else {"map": str(p), "output": str(d), "status": PENDING}
            for p, d, (what, earlier) in zip(paths, dirs, plan)]
    tasks, where = _tasks(paths, dirs, plan, settings, write_options, remote=scheduler is not None)
    skipped = len(paths) - len(tasks)
    if skipped:
        log.info("%d of %d maps up to date in %s, skipped (overwrite to run them again)", skipped, len(paths), out)
    many = len(paths) > 1
    if many:
        out.mkdir(parents=True, exist_ok=True)
    try:
        _run_tasks(tasks, where, rows, out, jobs, scheduler, progress)
    finally:
        if many:
            _write_summary(rows, out / SUMMARY)
    return rows


def _tasks(paths, dirs, plan, settings, write_options, remote: bool) -> tuple:
    """``(tasks, where)``: a task (the dict :func:`_run_one` takes) per map the plan runs, and the index of
    each one's map; on a cluster (``remote``) with absolute paths."""
    tasks, where = [], []
    for i, (p, d, (what, _)) in enumerate(zip(paths, dirs, plan)):
        if what == "run":
            where.append(i)
            tasks.append({"map": str(p), "output": str(d), "input": os.path.abspath(p),
                          "path": os.path.abspath(p) if remote else str(p),
                          "folder": os.path.abspath(d) if remote else str(d),
                          "settings": settings, "write_options": write_options})
    return tasks, where


def _run_tasks(tasks, where, rows, out, jobs, scheduler, progress) -> None:
    """Run ``tasks``, putting each finished map's row into ``rows`` (at its index of ``where``); with a
    progress bar or a log line per map, and ``summary.csv`` rewritten every :data:`SUMMARY_EVERY` seconds
    when the batch has several maps."""
    total = len(rows)
    many = total > 1
    show = (sys.stderr.isatty() if progress is None else bool(progress)) and many
    level = logging.DEBUG if show else logging.INFO
    last = time.monotonic()
    done = total - len(tasks)
    with tqdm(total=total, initial=done, desc="segmenting", unit="map", file=sys.stderr,
              disable=not show, dynamic_ncols=True) as bar, \
            (logging_redirect_tqdm() if show else nullcontext()):
        for k, row in _execute(tasks, jobs, scheduler):
            rows[where[k]] = row
            done += 1
            bar.set_postfix_str(Path(row["map"]).name, refresh=False)
            bar.update(1)
            log.log(level, "%s", _line(done, total, row))
            if many and time.monotonic() - last > SUMMARY_EVERY:
                _write_summary(rows, out / SUMMARY)
                last = time.monotonic()
