#!/usr/bin/env python
"""Maps per second of a batch (``topomap.segment_many``): one process, two processes, a Dask cluster.

Run (not a test)::

    python benchmarks/batch_speed.py [DATASET_DIR] [--maps 12] [--rounds 3] [--section]

Takes the first ``--maps`` floor plans ``NAME.png`` of DATASET_DIR (default
:func:`topomap.bench.datasets.benchmark_dir`; every image that is not a
``*_furnitures`` or ``*_gt_segmentation`` one), loaded as ``topomap segment
NAME.png --resolution 0.05`` loads them, and segments the whole batch with
``jobs=1``, ``jobs=2`` and on a 2-worker ``distributed.LocalCluster`` (one
thread per worker process), every output written as the CLI writes it,
into a fresh temporary folder per run. The three set-ups alternate,
``--rounds`` times; the table gives the median wall time of a batch per
set-up, maps per second, and the speed-up over ``jobs=1``. ``jobs=2`` times
include starting its two processes; the cluster is started once before the
rounds (its start-up is printed apart), as a user's cluster already runs.
``--section`` also writes ``benchmarks/sections/60_batch.md`` for
``docs/benchmarks.md`` (``benchmarks/report.py`` includes it).
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from speed import _commit, _machine  # noqa: E402  (the machine and commit lines of the speed benchmark)

SECTION = Path(__file__).resolve().parent / "sections" / "60_batch.md"


def _maps(directory: Path, n: int) -> list:
    names = sorted(p for p in directory.glob("*.png")
                   if not p.stem.endswith(("_furnitures", "_gt_segmentation", "_gt")))
    if not names:
        sys.exit(f"error: {directory}: no floor plans NAME.png")
    return names[:n]


def _timed_batch(maps, **kw) -> float:
    from topomap import segment_many

    out = Path(tempfile.mkdtemp(prefix="batch_speed_"))
    try:
        t0 = time.perf_counter()
        rows = segment_many(maps, out, resolution=0.05, progress=False, **kw)
        dt = time.perf_counter() - t0
    finally:
        shutil.rmtree(out, ignore_errors=True)
    bad = [r for r in rows if r["status"] != "ok"]
    if bad:
        sys.exit(f"error: {bad[0]['map']}: {bad[0]['status']}: {bad[0].get('error')}")
    return dt


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dataset_dir", nargs="?", type=Path, default=None)
    ap.add_argument("--maps", type=int, default=12, help="number of maps in the batch (default 12)")
    ap.add_argument("--rounds", type=int, default=3, help="alternating rounds (default 3)")
    ap.add_argument("--section", action="store_true", help=f"write {SECTION.relative_to(SECTION.parents[2])}")
    args = ap.parse_args(argv)
    from distributed import Client, LocalCluster

    from topomap.bench.datasets import benchmark_dir

    directory = args.dataset_dir or benchmark_dir()
    if directory is None:
        sys.exit("error: no floor plans found; pass DATASET_DIR (or set TOPOMAP_BENCHMARK_DIR)")
    maps = _maps(Path(directory), args.maps)
    commit = _commit()  # of the code the run imports (now, not after it)
    load_before = os.getloadavg()
    t0 = time.perf_counter()
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                           silence_logs=40)
    client = Client(cluster)
    t_cluster = time.perf_counter() - t0
    setups = {"jobs=1": {"jobs": 1}, "jobs=2": {"jobs": 2}, "LocalCluster, 2 workers": {"scheduler": client}}
    times = {k: [] for k in setups}
    try:
        _timed_batch(maps[:2], jobs=1)  # warm-up: imports, first calls (here and on the workers)
        _timed_batch(maps[:2], scheduler=client)
        for r in range(args.rounds):
            for name, kw in setups.items():
                dt = _timed_batch(maps, **kw)
                times[name].append(dt)
                print(f"round {r + 1}: {name}: {dt:.2f} s ({len(maps) / dt:.2f} maps/s)", file=sys.stderr)
    finally:
        client.close()
        cluster.close()
    load_after = os.getloadavg()
    base = statistics.median(times["jobs=1"])
    lines = ["| set-up | median s / batch | maps / s | speed-up vs jobs=1 | all runs (s) |",
             "| --- | ---: | ---: | ---: | --- |"]
    for name, ts in times.items():
        med = statistics.median(ts)
        lines.append(f"| {name} | {med:.2f} | {len(maps) / med:.2f} | {base / med:.2f}x | "
                     f"{', '.join(f'{t:.2f}' for t in ts)} |")
    table = "\n".join(lines)
    cmd = "python benchmarks/batch_speed.py" + "".join(f" {a}" for a in (argv if argv is not None else sys.argv[1:])
                                                       if a != str(directory))
    text = f"""## Batches: maps per second

`{cmd.strip()}` at commit `{commit}`: a batch of the first {len(maps)} ipa floor plans
(`NAME.png --resolution 0.05`, every output written as `topomap segment` writes it), run
with `jobs=1`, `jobs=2` and on a 2-worker Dask `LocalCluster` (one thread per worker process,
started once beforehand in {t_cluster:.1f} s, then warmed up), alternating, {args.rounds} rounds; median wall time
per batch. Machine: {_machine()}; load average (1, 5, 15 min) {load_before[0]:.2f}, {load_before[1]:.2f},
{load_before[2]:.2f} before and {load_after[0]:.2f}, {load_after[1]:.2f}, {load_after[2]:.2f} after
the run. On a machine shared with other work the speed-up of two processes stays below 2x by
about the share of the CPUs the other work takes.

{table}
"""
    print(text)
    if args.section:
        SECTION.write_text(text, encoding="utf-8")
        print(f"-> {SECTION}", file=sys.stderr)


if __name__ == "__main__":
    main()
