#!/usr/bin/env python
"""The whole job of ``topomap simulate``: one plan at a time as a command, and a corpus.

Run (not a test)::

    python benchmarks/simulate_job.py PLANS_DIR [--every 64] [--corpus-seconds S] [--out FILE]

``PLANS_DIR`` holds the R2V / LIFULL plans (``NAME.txt``, see
``../shared/datasets/r2v_floorplans`` in development). Every ``--every``-th
plan (sorted by name) is simulated by ``topomap simulate PLAN -o TMP`` in a
fresh process (start, imports, reading the plan, the scan, every file
written) with ``OMP_NUM_THREADS=1``; the section gives wall time and peak
memory (``ru_maxrss`` of the child) against the home's area, and the time
per 100 m² of home. ``--corpus-seconds`` adds the wall time measured for the
whole corpus (``topomap simulate PLANS_DIR/*.txt -o CORPUS --jobs 2``, timed
by the caller) to the section.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import _section
from _section import _commit, _machine


def _run(plan: Path) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
        t = time.perf_counter()
        r = subprocess.run([sys.executable, "-m", "topomap.cli", "simulate", str(plan), "-o", tmp],
                           capture_output=True, text=True,
                           env={**os.environ, "OMP_NUM_THREADS": "1", "OPENCV_FOR_THREADS_NUM": "1"})
        wall = time.perf_counter() - t
        peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
        if r.returncode != 0:
            return {"plan": plan.stem, "error": r.stderr.strip().splitlines()[-1]}
        rec = json.loads((Path(tmp) / "simulation.json").read_text())
    return {"plan": plan.stem, "seconds": wall, "peak_mb": max(peak, before) / 1024.0,
            "area": rec["summary"]["area"]}


def main(argv=None) -> int:
    ap = _section.parser(__doc__, "the folder of plans (NAME.txt)", "89_simulate_job.md")
    ap.add_argument("--every", type=int, default=64)
    ap.add_argument("--corpus-seconds", type=float, default=None)
    a = ap.parse_args(argv)
    d = Path(a.directory) if a.directory else None
    if d is None or not d.is_dir():
        sys.exit(f"error: no plans directory {a.directory or ''}")
    t0 = time.perf_counter()
    plans = sorted(d.glob("*.txt"))[::max(1, a.every)]
    rows = [_run(p) for p in plans]
    ok = [r for r in rows if "error" not in r]
    secs = np.array([r["seconds"] for r in ok])
    area = np.array([r["area"] for r in ok])
    peak = np.array([r["peak_mb"] for r in ok])
    per100 = secs / area * 100.0
    table = ("| plans | home area m² (median, max) | s per plan (median, max) | s per 100 m² (median) "
             "| peak MB (median, max) | failed |\n| ---: | --- | --- | ---: | --- | ---: |\n"
             f"| {len(ok)} | {np.median(area):.0f}, {area.max():.0f} | {np.median(secs):.2f}, {secs.max():.2f} "
             f"| {np.median(per100):.2f} | {np.median(peak):.0f}, {peak.max():.0f} | {len(rows) - len(ok)} |\n")
    corpus = ""
    if a.corpus_seconds is not None:
        corpus = (f"\nThe whole corpus, `topomap simulate PLANS_DIR/*.txt -o CORPUS --jobs 2` (every plan, "
                  f"every file written): {a.corpus_seconds:.0f} s wall.\n")
    text = f"""## The whole job of `topomap simulate`

`python benchmarks/simulate_job.py PLANS_DIR --every {a.every}`, commit `{_commit()}`; {_machine()}.

Every {a.every}th plan of the R2V / LIFULL set, each simulated by `topomap simulate PLAN -o OUT` in a fresh
process on one thread (start, imports, reading the plan, the scan with the default options, every file of
the case written): wall time and peak memory of the command, against the home's free area.

{table}{corpus}"""
    _section.write(a.out, text, table, time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    sys.exit(main())
