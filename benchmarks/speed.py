#!/usr/bin/env python
"""Speed of topomap's default method against a plain watershed baseline.

Run (not a test)::

    python benchmarks/speed.py [DATASET_DIR] [--variant unfurnished|furnished]
    python benchmarks/speed.py [DATASET_DIR] --scaling [--maps a,b] [--max-cells N]

Default mode: in one process and one run, times ``segment(grid,
method=DEFAULT_METHOD)`` and ``segment(grid, method="watershed")`` (distance
transform, peaks, ``skimage.segmentation.watershed``: ``topomap.core.baselines.
watershed``) on every benchmark map, the two calls back to back per map, after
one untimed warm-up call per method. Timings are the ``segment(...)`` call
only (maps are read and classified before). Prints per-map times, the ratio of
the totals and of the medians (target: <= 1.0), and the default method's
per-stage breakdown summed over the maps.

``--scaling``: every map at 1x, 2x and 4x (``np.kron``, resolution halved /
quartered so every length in metres stays the same) and a synthetic building
of about 25 million cells (the example office map tiled 15 x 15), each case
in a fresh subprocess: wall time of the segmentation call and peak memory
(``ru_maxrss`` after the call minus the resident size just before it, i.e.
the memory the segmentation needed on top of the map) against the area;
prints a table and a least-squares exponent ``time ~ cells^k`` per method
(k <= 1: no worse than linear).

DATASET_DIR defaults to :func:`topomap.bench.datasets.benchmark_dir`.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import time

import numpy as np

BASELINE = "watershed"


# --------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------

def _grid_from_gray(gray, resolution, name):
    from topomap.io import FREE, OCCUPIED, OccupancyGrid

    cells = np.where(gray >= 250, FREE, OCCUPIED).astype(np.int8)
    return OccupancyGrid(cells, resolution, (0.0, 0.0, 0.0), name, gray=gray)


def _warm(method):
    from topomap.io import from_array
    from topomap.core.segmentation import segment

    free = np.zeros((80, 120), bool)
    free[5:75, 5:58] = True
    free[5:75, 62:115] = True
    free[35:47, 58:62] = True
    segment(from_array(free, resolution=0.05), method=method)


def _timed(grid, method):
    import gc

    from topomap.core.segmentation import segment

    gc.collect()
    t0 = time.perf_counter()
    seg = segment(grid, method=method)
    return time.perf_counter() - t0, seg


def _machine():
    cpu = "?"
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} CPUs, Python {platform.python_version()}"


def _commit():
    try:
        here = os.path.dirname(os.path.abspath(__file__))
        out = subprocess.run(["git", "-C", here, "rev-parse", "--short", "HEAD"], capture_output=True,
                             text=True, timeout=10)
        dirty = subprocess.run(["git", "-C", here, "status", "--porcelain", "--", "../topomap"],
                               capture_output=True, text=True, timeout=10)
        return out.stdout.strip() + (" (+ uncommitted changes in topomap/)" if dirty.stdout.strip() else "")
    except Exception:  # noqa: BLE001
        return "?"


# --------------------------------------------------------------------------
# default mode: default method vs watershed on the 14 maps
# --------------------------------------------------------------------------

def compare(directory, variant):
    from topomap.bench.benchmark import benchmark_grid
    from topomap.bench.datasets import load_benchmark
    from topomap.core.segmentation import DEFAULT_METHOD

    maps = load_benchmark(directory, variant=variant)
    grids = [(bm.name, benchmark_grid(bm)) for bm in maps]
    methods = [DEFAULT_METHOD, BASELINE]
    for m in methods:
        _warm(m)
    print(f"# topomap {DEFAULT_METHOD!r} (default method) vs {BASELINE!r} baseline, {variant} maps")
    print(f"# commit {_commit()}; {_machine()}")
    print()
    print(f"| map | cells (M) | {DEFAULT_METHOD} (s) | {BASELINE} (s) | ratio |")
    print("| --- | ---: | ---: | ---: | ---: |")
    times = {m: [] for m in methods}
    stages = {}
    for name, grid in grids:
        t_def, seg = _timed(grid, DEFAULT_METHOD)
        t_base, _ = _timed(grid, BASELINE)
        times[DEFAULT_METHOD].append(t_def)
        times[BASELINE].append(t_base)
        for k, v in seg.timings.items():
            if k != "total":
                stages[k] = stages.get(k, 0.0) + v
        print(f"| {name} | {grid.cells.size / 1e6:.2f} | {t_def:.3f} | {t_base:.3f} | {t_def / t_base:.2f} |",
              flush=True)
    td, tb = (np.array(times[m]) for m in methods)
    print(f"| **total** | {sum(g.cells.size for _, g in grids) / 1e6:.2f} | {td.sum():.3f} | {tb.sum():.3f} "
          f"| **{td.sum() / tb.sum():.2f}** |")
    print(f"| **median** | | {np.median(td):.3f} | {np.median(tb):.3f} "
          f"| **{np.median(td) / np.median(tb):.2f}** |")
    print()
    print(f"ratio of totals {DEFAULT_METHOD}/{BASELINE}: {td.sum() / tb.sum():.2f}; "
          f"ratio of medians: {np.median(td) / np.median(tb):.2f} (target <= 1.0)")
    print()
    tot = sum(stages.values())
    print(f"{DEFAULT_METHOD} per stage, summed over the {len(grids)} maps:")
    print()
    print("| stage | s | share |")
    print("| --- | ---: | ---: |")
    for k, v in sorted(stages.items(), key=lambda kv: -kv[1]):
        print(f"| {k} | {v:.3f} | {100 * v / tot:.0f} % |")


# --------------------------------------------------------------------------
# scaling mode
# --------------------------------------------------------------------------

SYNTH_TILES = (15, 15)  # 280 x 400 example office tiled: 4200 x 6000 = 25.2 M cells


def _case_gray(spec):
    """(gray, resolution, label) of a scaling case."""
    if spec["map"] == "synthetic":
        from topomap.io.example import make_example_office

        ex = make_example_office()
        gray = np.tile(ex.gray, SYNTH_TILES)
        return gray, 0.05, f"synthetic office x{SYNTH_TILES[0]}x{SYNTH_TILES[1]}"
    from topomap.bench.datasets import load_benchmark

    (bm,) = load_benchmark(spec["dir"], variant=spec["variant"], names=[spec["map"]])
    k = int(spec["scale"])
    gray = bm.map_gray if k == 1 else np.kron(bm.map_gray, np.ones((k, k), np.uint8))
    return gray, bm.resolution / k, f"{bm.name} x{k}"


def _rss_now():
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def run_case(spec):
    """Child process: one (map, scale, method) case; prints one JSON line."""
    gray, res, label = _case_gray(spec)
    grid = _grid_from_gray(gray, res, label)
    del gray
    _warm(spec["method"])
    import gc

    gc.collect()
    before = _rss_now()
    t, seg = _timed(grid, spec["method"])
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # kB on Linux
    print(json.dumps({"case": label, "method": spec["method"], "cells": int(grid.cells.size),
                      "time_s": t, "peak_mb": max(peak - before, 0) / 2**20,
                      "rooms": seg.n_rooms}))


def scaling(directory, variant, names, max_cells, methods, scales):
    from topomap.bench.datasets import load_benchmark

    maps = load_benchmark(directory, variant=variant, names=names)
    specs = []
    for bm in maps:
        for k in scales:
            specs.append(dict(map=bm.name, scale=k, dir=str(directory), variant=variant,
                              cells=bm.map_gray.size * k * k))
    specs.append(dict(map="synthetic", scale=1, cells=280 * 400 * SYNTH_TILES[0] * SYNTH_TILES[1]))
    print(f"# scaling: {', '.join(methods)}; {variant} maps x{', x'.join(map(str, scales))} and a synthetic "
          f"building; one subprocess per case; cases over {max_cells / 1e6:.0f} M cells skipped")
    print(f"# commit {_commit()}; {_machine()}")
    print()
    print("| case | cells (M) | method | time (s) | s / M cells | peak extra memory (MB) | MB / M cells | rooms |")
    print("| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: |")
    results = []
    for spec in specs:
        label = "synthetic" if spec["map"] == "synthetic" else f"{spec['map']} x{spec['scale']}"
        if spec["cells"] > max_cells:
            print(f"| {label} | {spec['cells'] / 1e6:.1f} | (skipped: over --max-cells) | | | | | |", flush=True)
            continue
        for m in methods:
            s = dict(spec, method=m)
            s.pop("cells")
            proc = subprocess.run([sys.executable, os.path.abspath(__file__), "--_case", json.dumps(s)],
                                  capture_output=True, text=True)
            if proc.returncode != 0:
                err = (proc.stderr.strip().splitlines() or ["?"])[-1]
                print(f"| {label} | {spec['cells'] / 1e6:.1f} | {m} | failed: {err} | | | | |", flush=True)
                continue
            r = json.loads(proc.stdout.strip().splitlines()[-1])
            results.append(r)
            mc = r["cells"] / 1e6
            print(f"| {r['case']} | {mc:.1f} | {m} | {r['time_s']:.2f} | {r['time_s'] / mc:.3f} "
                  f"| {r['peak_mb']:.0f} | {r['peak_mb'] / mc:.0f} | {r['rooms']} |", flush=True)
    print()
    for m in methods:
        rs = [r for r in results if r["method"] == m]
        if len(rs) < 3:
            continue
        x = np.log([r["cells"] for r in rs])
        kt = np.polyfit(x, np.log([r["time_s"] for r in rs]), 1)[0]
        mem = [(c, p) for c, p in zip(x, [r["peak_mb"] for r in rs]) if p > 0]
        km = np.polyfit([c for c, _ in mem], np.log([p for _, p in mem]), 1)[0] if len(mem) >= 3 else float("nan")
        # per-map growth from x1 to the largest scale run
        print(f"{m}: time ~ cells^{kt:.2f}, peak memory ~ cells^{km:.2f} (least squares over {len(rs)} cases)")
        for base in sorted({r["case"].rsplit(" x", 1)[0] for r in rs if r["case"].endswith(" x1")}):
            one = [r for r in rs if r["case"] == f"{base} x1"]
            big = [r for r in rs if r["case"].startswith(base + " x") and r["case"] != f"{base} x1"]
            if one and big:
                b = max(big, key=lambda r: r["cells"])
                a = b["cells"] / one[0]["cells"]
                print(f"  {base}: area x{a:.0f} -> time x{b['time_s'] / one[0]['time_s']:.1f}, "
                      f"memory x{b['peak_mb'] / max(one[0]['peak_mb'], 1e-9):.1f}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("directory", nargs="?", default=None, help="benchmark directory (default: benchmark_dir())")
    ap.add_argument("--variant", choices=["unfurnished", "furnished"], default="unfurnished")
    ap.add_argument("--scaling", action="store_true", help="time and memory against map area")
    ap.add_argument("--maps", default=None, help="comma-separated map names (default: all)")
    ap.add_argument("--scales", default="1,2,4", help="upsampling factors for --scaling (default 1,2,4)")
    ap.add_argument("--methods", default=None,
                    help="methods for --scaling (default: the default method and watershed)")
    ap.add_argument("--max-cells", type=float, default=30e6,
                    help="skip --scaling cases larger than this many cells (default 30e6)")
    ap.add_argument("--_case", default=None, help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a._case:
        run_case(json.loads(a._case))
        return 0
    from topomap.bench.datasets import benchmark_dir
    from topomap.core.segmentation import DEFAULT_METHOD

    directory = a.directory or benchmark_dir()
    if directory is None:
        ap.error("no benchmark directory given and benchmark_dir() found none")
    names = a.maps.split(",") if a.maps else None
    if a.scaling:
        methods = a.methods.split(",") if a.methods else [DEFAULT_METHOD, BASELINE]
        scaling(directory, a.variant, names, a.max_cells, list(dict.fromkeys(methods)),
                [int(s) for s in a.scales.split(",")])
    else:
        compare(directory, a.variant)
    return 0


if __name__ == "__main__":
    sys.exit(main())
