#!/usr/bin/env python
"""Speed of :func:`topomap.bench.simulate.simulate_scan` on synthetic homes.

Run (not a test)::

    python benchmarks/simulate_speed.py [--sizes 2x2,3x2,5x4] [--seed 0]

Each case is a grid of 4 m x 4 m rooms along corridors (``NXxNY`` rooms,
drawn by ``tests/_floorplans.big_home`` at 0.05 m per cell), scanned with
the default :class:`~topomap.bench.simulate.ScanOptions` but no door closed (every
room is scanned), in a fresh subprocess:
wall time of the ``simulate_scan`` call and peak memory (``ru_maxrss``
after the call minus the resident size before it). The bar: under 2 s for
a 100 m² home on one core.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def _one(nx: int, ny: int, seed: int) -> dict:
    sys.path.insert(0, os.path.join(ROOT, "tests"))
    sys.path.insert(0, ROOT)
    from _floorplans import big_home
    from topomap.bench.simulate import ScanOptions, simulate_scan

    plan = big_home(nx, ny)
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t = time.perf_counter()
    r = simulate_scan(plan, options=ScanOptions(closed_doors=0.0), seed=seed)  # every room scanned
    dt = time.perf_counter() - t
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return {"case": f"{nx}x{ny}", "area_m2": float(plan.inside.sum() * plan.resolution ** 2),
            "cells": int(plan.walls.size), "poses": len(r.poses), "rooms": f"{len(r.visited)}/{int(plan.rooms.max())}", "seconds": dt,
            "peak_mb": (peak - before) / 1024.0}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="2x2,3x2,5x4,8x6")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--one", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.one:
        nx, ny = (int(v) for v in a.one.split("x"))
        print(json.dumps(_one(nx, ny, a.seed)))
        return 0
    print(f"{'case':>6} {'m2':>7} {'cells':>9} {'poses':>6} {'rooms':>6} {'s':>7} {'MB':>7}")
    for size in a.sizes.split(","):
        out = subprocess.run([sys.executable, __file__, "--one", size, "--seed", str(a.seed)],
                             capture_output=True, text=True, check=True, cwd=ROOT,
                             env={**os.environ, "OMP_NUM_THREADS": "1", "OPENCV_FOR_THREADS_NUM": "1"})
        d = json.loads(out.stdout.strip().splitlines()[-1])
        print(f"{d['case']:>6} {d['area_m2']:7.0f} {d['cells']:9,d} {d['poses']:6d} {d['rooms']:>6} {d['seconds']:7.2f} "
              f"{d['peak_mb']:7.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
