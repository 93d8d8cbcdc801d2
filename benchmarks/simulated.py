#!/usr/bin/env python
"""The simulated corpus as a benchmark: every method on the drawn plans and on their simulated scans.

Run (not a test)::

    python benchmarks/simulated.py CORPUS [--jobs 2] [--maps 'a*,b*'] [--split dev]
        [--methods topomap,paper] [--csv rows.csv] [--rows rows.csv]
        [--out benchmarks/sections/89_simulated.md]

``CORPUS`` is what ``topomap simulate PLAN... -o CORPUS`` writes: one folder
per case with the simulated robot map (``map.yaml``), the floor plan drawn
on the same grid (``plan.yaml``), the room labels (``gt_rooms.png``) and the
doors (``gt_doors.json``). One :func:`topomap.bench.benchmark.run_benchmark` call
(``topomap benchmark CORPUS --variant both``) scores every method on both
variants:

* ``plan``: the drawn floor plan, as a user loads ``CASE/plan.yaml``;
* ``scan``: the simulated robot map, as a user loads ``CASE/map.yaml``,
  scored against its own ground truth (``gt_rooms_scan.png``,
  ``gt_doors_scan.json``: the rooms the scan shows, whole, and their doors).

The table is given per half of the plans (:func:`topomap.bench.datasets.plan_split`,
a fixed rule on the plan's name: ``dev`` to tune on, ``held-out`` to report
on); ``--split`` runs one half only.

Per method and variant the section gives the mean precision / recall of
Bormann et al. under the **original protocol** (true rooms whole; segments
on the free cells of the map as loaded), the rooms reported against the
true rooms (summed over the cases), and door precision / recall pooled
over the cases (detected doors within 0.5 m of a true door between two
rooms, matched one to one: the true positives of every case over all
detections, resp. over all true doors). ``--maps`` takes a fixed subset
(names or shell patterns), for a run that fits the time at hand. ``--rows``
writes the section again from the rows a run saved with ``--csv``.
"""

from __future__ import annotations

import logging
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _section  # noqa: E402
from _section import _commit, _machine  # noqa: E402

log = logging.getLogger("benchmarks.simulated")

#: topomap's methods and the baselines of topomap.core.segmentation.METHODS (voronoi about 1 s a map).
METHODS = "topomap,paper,voronoi,watershed,morphological,distance"


def _mean_pct(rows, key) -> str:
    v = np.array([float(r[key]) for r in rows], float)
    v = v[np.isfinite(v)]
    return f"{100 * v.mean():.1f}" if v.size else "–"


def _ratio(num, den) -> str:
    return f"{100 * num / den:.1f}" if den else "–"


def table(rows) -> str:
    """The section's table, one line per method, variant and half of the plans (:func:`plan_split`):
    the plan variant first, dev before held-out, methods in the order of the rows."""
    from topomap.bench.datasets import SPLITS, plan_split

    groups = {}
    for r in rows:
        groups.setdefault((r["method"], r["variant"], plan_split(r["map"])), []).append(r)
    methods = list(dict.fromkeys(r["method"] for r in rows))
    order = sorted(groups, key=lambda k: (k[1] != "plan", SPLITS.index(k[2]), methods.index(k[0])))
    out = ["| method | variant | plans | cases | P (%) | R (%) | ceiling P / R (%) | free-cells P / R (%) "
           "| rooms found / true | door P (%) | door R (%) | median s / case | failed |",
           "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for key in order:
        g = groups[key]
        ok = [r for r in g if not r.get("error")]
        tp = sum(int(r["door_tp"]) for r in ok)
        n_pred = sum(int(r["n_doors"]) for r in ok)
        n_true = sum(int(r["door_tp"]) + int(r["door_fn"]) for r in ok)
        doorless = n_pred == 0
        rooms = f"{sum(int(r['n_rooms']) for r in ok)} / {sum(int(r['n_true_rooms']) for r in ok)}" if ok else "–"
        secs = np.median([float(r["runtime_s"]) for r in g]) if g else float("nan")
        out.append(f"| {key[0]} | {key[1]} | {key[2]} | {len(ok)} | {_mean_pct(ok, 'precision')} | {_mean_pct(ok, 'recall')} "
                   f"| {_mean_pct(ok, 'ceiling_precision')} / {_mean_pct(ok, 'ceiling_recall')} "
                   f"| {_mean_pct(ok, 'precision_free')} / {_mean_pct(ok, 'recall_free')} "
                   f"| {rooms} | {'–' if doorless else _ratio(tp, n_pred)} | {_ratio(tp, n_true)} "
                   f"| {secs:.2f} | {len(g) - len(ok)} |")
    return "\n".join(out) + "\n"


def _command(a) -> str:
    """The command line of this run, as the section quotes it."""
    cmd = f"python benchmarks/simulated.py CORPUS --jobs {a.jobs}"
    if a.maps:
        cmd += f" --maps '{a.maps}'"
    if a.split:
        cmd += f" --split {a.split}"
    if a.methods != METHODS:
        cmd += f" --methods {a.methods}"
    return cmd


def _subset_text(a, rows, n_cases: int) -> str:
    """The sentence that says which cases a run on a subset scored ('' for the whole corpus)."""
    if not (a.maps or a.split):
        return ""
    from topomap.bench.datasets import _simulated_cases, plan_split

    n_all = len(_simulated_cases(Path(a.directory)))
    halves = [plan_split(m) for m in {r["map"] for r in rows}]
    return (f" A fixed subset, for the time at hand: the cases named by `--maps`"
            f"{' and `--split`' if a.split else ''}, {n_cases} of the corpus's {n_all} "
            f"({halves.count('dev')} dev, {halves.count('held-out')} held-out).")


def main(argv=None) -> int:
    from topomap.bench.benchmark import run_benchmark, write_rows

    ap = _section.parser(__doc__, "the simulated corpus (one folder per case)", "89_simulated.md")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--maps", default=None, help="comma-separated case names or shell patterns (default all)")
    ap.add_argument("--split", choices=("dev", "held-out"), default=None,
                    help="only the cases of this half of the plans (topomap.bench.datasets.plan_split; default both)")
    ap.add_argument("--methods", default=METHODS)
    ap.add_argument("--csv", type=Path, default=None, help="also save the per-case rows here")
    ap.add_argument("--rows", type=Path, default=None,
                    help="write the section from the rows a run saved with --csv (give that run's options)")
    a = ap.parse_args(argv)
    if a.directory is None or not Path(a.directory).is_dir():
        sys.exit(f"error: no corpus directory {a.directory or ''} (pass the folder topomap simulate wrote)")
    logging.basicConfig(level=logging.WARNING, format="%(message)s")
    log.setLevel(logging.INFO)
    t0 = time.perf_counter()

    def progress(done, total, row):
        if done % 20 == 0 or done == total or row.get("error"):
            log.info("%d / %d %s %s %s %s", done, total, row["method"], row["variant"], row["map"],
                         row.get("error", ""))

    maps = a.maps
    if a.split:
        from topomap.bench.datasets import _simulated_cases, plan_split, select_names

        found = _simulated_cases(Path(a.directory))
        maps = [n for n in select_names(found, a.maps, a.directory) if plan_split(n) == a.split]
        if not maps:
            sys.exit(f"error: no case of the {a.split} plans in {a.directory}")
    if a.rows is not None:
        import csv

        with open(a.rows, newline="", encoding="utf-8") as fh:
            rows = list(csv.DictReader(fh))
    else:
        rows = run_benchmark(a.directory, methods=a.methods, variants="both", jobs=a.jobs, maps=maps,
                             progress=progress)
    if a.csv is not None:
        write_rows(rows, a.csv)
    n_cases = len({r["map"] for r in rows})
    cmd = _command(a)
    tab = table(rows)
    subset = _subset_text(a, rows, n_cases)
    errors = sorted({f"{r['map']} ({r['variant']}): {r['error']}" for r in rows if r.get("error")})
    err_text = ("\nFailed runs:\n\n" + "\n".join(f"- {e}" for e in errors[:10]) + "\n") if errors else ""
    text = f"""## Simulated maps of home floor plans

`{cmd}` (the folder `topomap simulate` wrote as `CORPUS`), {n_cases} case{"" if n_cases == 1 else "s"}, commit `{_commit()}`; {_machine()}.

Each case is a home floor plan twice, on one grid: the plan as drawn
(**plan**: walls, free rooms, unknown outside) and the robot map a laser
SLAM run through it gives (**scan**). The plan's ground truth is its rooms
and doors; the scan's, the rooms it shows (at least 1 m² of a room free in
the map; a room behind a closed door or never reached is not drawn by a
person labelling the map), each whole, and the doors between them. Each
map is loaded as `topomap segment CASE/plan.yaml` (or `CASE/map.yaml`)
loads it. Plans: the half of the plans a case belongs to
(`topomap.bench.datasets.plan_split`, a fixed rule on the plan's name: tune on
**dev**, report on **held-out**; the default method's outside stage cuts laser
fans out of rooms by a rule chosen with the held-out scans' figures in view
too, so its scan figures on both halves are partly training figures). P / R: mean precision / recall of Bormann
et al. over the cases, **original protocol** (true rooms whole; segments on
the free cells of the map as loaded; segments and rooms of 100 cells or
fewer ignored); ceiling: the ground truth itself scored so (below 100 where
a true room has cells the map does not show free: furniture, corners the
laser did not reach); free-cells: the protocol that restricts the true rooms
to the map's free cells too. Rooms: reported (room-graph nodes) / true, summed over the
cases. Door P / R: detected doors within 0.5 m of a true door between two
rooms, matched one to one, pooled over the cases (–: the method reports
no doors). Runtimes with {a.jobs} parallel jobs.{subset}

{tab}{err_text}"""
    _section.write(a.out, text, tab, time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
