#!/usr/bin/env python
"""Door-to-door travel distances: the coarse grid against the map-grid geodesic.

Run (not a test)::

    python benchmarks/travel_accuracy.py [DATASET_DIR] [--variant both]

For every image of ipa_room_segmentation (``NAME.png`` loaded as ``topomap
segment NAME.png --resolution 0.05`` loads it, default method), every room
and every pair of its doors: the distance :func:`topomap.planning.travel_graph`
stores (coarse grid, short pairs refined; see the module notes of
:mod:`topomap.planning`) against ``room_distances(..., exact=True)`` (the
8-connected geodesic on the map's grid, one search per door). Reports per
map the pairs, the mean and largest relative difference and both times,
then over all pairs the mean, the 95th percentile and the largest
``|relative difference|``, the largest absolute one and the share of pairs
beyond 5 %. Writes ``benchmarks/sections/55_travel_accuracy.md``
(``--section``) and prints it.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from job_speed import _commit, _ipa_maps, _load, _machine  # noqa: E402

TOLERANCE = 0.05


def measure(path):
    from topomap import planning as P
    from topomap.io import load_map
    from topomap.core.segmentation import segment

    seg = segment(load_map(path, resolution=0.05))
    seg.room_graph
    t0 = time.perf_counter()
    G = P.travel_graph(seg)
    t_fast = time.perf_counter() - t0
    t0 = time.perf_counter()
    exact = {r: P.room_distances(seg, r, exact=True) for r in G.nodes}
    t_exact = time.perf_counter() - t0
    rel, ab, missing = [], [], 0
    for r, d in G.nodes(data=True):
        fast = {(i, j): L for i, j, L in d["door_distances"]}
        missing += len(set(fast) ^ set(exact[r]))
        for k, L in exact[r].items():
            if k in fast:
                rel.append((fast[k] - L) / L)
                ab.append(fast[k] - L)
    return np.array(rel), np.array(ab), missing, t_fast, t_exact


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("directory", nargs="?", default=None)
    ap.add_argument("--variant", choices=["unfurnished", "furnished", "both"], default="both")
    ap.add_argument("--section", default=str(HERE / "sections" / "55_travel_accuracy.md"))
    a = ap.parse_args(argv)
    from topomap.bench.datasets import benchmark_dir

    directory = a.directory or benchmark_dir()
    if directory is None:
        ap.error("no benchmark directory given and benchmark_dir() found none")
    maps = _ipa_maps(directory, a.variant)
    rows, R, A, miss, tf, te = [], [], [], 0, 0.0, 0.0
    for p in maps:
        rel, ab, m, t_fast, t_exact = measure(p)
        R.append(rel)
        A.append(ab)
        miss += m
        tf += t_fast
        te += t_exact
        worst = rel[np.argmax(np.abs(rel))] if len(rel) else 0.0
        rows.append(f"| {Path(p).stem} | {len(rel)} | {100 * rel.mean() if len(rel) else 0:+.2f} | "
                    f"{100 * worst:+.2f} | {t_fast * 1000:.0f} | {t_exact * 1000:.0f} |")
        print(rows[-1], file=sys.stderr, flush=True)
    rel, ab = np.concatenate(R), np.concatenate(A)
    cmd = "python benchmarks/travel_accuracy.py" + ("" if a.variant == "both" else f" --variant {a.variant}")
    lines = ["## Accuracy of the travel distances", "",
             f"`{cmd}` (the data set's directory as argument), commit `{_commit()}`; {_machine()}; {_load()}.", "",
             "Every pair of doors of every room of the default segmentation of each image (loaded as "
             "`topomap segment NAME.png --resolution 0.05` loads it): the distance `travel_graph` stores "
             "(coarse grid of 0.2 m blocks, open floor merged into 0.4 m nodes in rooms with at least 6 doors, pairs "
             "under 3.2 m measured again on the map's grid) against "
             "`room_distances(..., exact=True)`, the 8-connected geodesic on the map's grid. Relative "
             "difference = (coarse - exact) / exact.", "",
             f"**{len(rel)} door pairs: mean {100 * rel.mean():+.2f} %, 95 % of the pairs within "
             f"{100 * np.percentile(np.abs(rel), 95):.2f} %, largest {100 * np.abs(rel).max():.2f} % "
             f"({np.abs(ab).max():.2f} m); {100 * np.mean(np.abs(rel) > TOLERANCE):.2f} % of the pairs beyond "
             f"{100 * TOLERANCE:.0f} %; {miss} pairs reachable by one method only.** Time over all maps: "
             f"{tf:.2f} s coarse, {te:.2f} s exact ({te / tf:.0f} x).", "",
             "| map | door pairs | mean (%) | largest (%) | coarse (ms) | exact (ms) |",
             "| --- | ---: | ---: | ---: | ---: | ---: |", *rows, ""]
    text = "\n".join(lines) + "\n"
    Path(a.section).write_text(text, encoding="utf-8")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
