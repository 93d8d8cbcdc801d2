"""Room tours on the benchmark floor plans: optimum, heuristic, nearest neighbour, lower bound.

For every floor plan of ipa_room_segmentation (``NAME.png`` at 0.05 m/px, as
``topomap segment`` loads it): segment with the default method, take the travel
distances between the largest room's point and every room's point
(``topomap.planning.tour.stop_distances``, the distances ``plan_tour`` uses), and compare

* the full tour (every reachable room, open, from the largest room): the heuristic
  ``plan_tour`` uses above 12 rooms (nearest neighbour + 2-opt + Or-opt), plain
  nearest neighbour, and the minimum-spanning-tree lower bound (no tour is
  shorter); the optimum (Held–Karp) where the map has at most 12 rooms to visit;
* tours of 12 rooms (``--subsets`` random sets of 12 rooms per map, seed 0), open
  and back to the start, where the optimum is computed: how often the
  heuristic finds it and its worst excess.

    python benchmarks/tour.py [IPA_DIR] [--out benchmarks/sections/75_tour.md] [--subsets 10]
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _section  # noqa: E402
from _section import _commit, _machine  # noqa: E402



def run_map(bm, subsets, rng):
    from topomap.bench.benchmark import benchmark_grid
    from topomap.core.segmentation import segment
    from topomap.planning.tour import (EXACT_LIMIT, _nearest_neighbour, solve_order, stop_distances, tour_length,
                              tour_lower_bound)

    seg = segment(benchmark_grid(bm))
    G = seg.room_graph
    start = max(G.nodes, key=lambda r: (G.nodes[r]["area"], -r))
    t0 = time.perf_counter()
    sd = stop_distances(seg, start)
    t_dist = time.perf_counter() - t0
    D = sd["D"]
    idx = [0] + [k for k in range(1, D.shape[0]) if np.isfinite(D[0, k])]
    D = D[np.ix_(idx, idx)]
    n = len(idx) - 1
    t0 = time.perf_counter()
    heur, _ = solve_order(D, exact_limit=0)
    t_heur = time.perf_counter() - t0
    row = dict(map=bm.name, n=n, heur=tour_length(D, heur), nn=tour_length(D, _nearest_neighbour(D)),
               bound=tour_lower_bound(D), opt=np.nan, t_dist=t_dist, t_heur=t_heur)
    if n <= EXACT_LIMIT:
        row["opt"] = tour_length(D, solve_order(D)[0])
    sub = {False: [], True: []}
    t_exact = []
    if n >= EXACT_LIMIT:
        for _ in range(subsets):
            pick = [0] + sorted(rng.choice(np.arange(1, n + 1), EXACT_LIMIT, replace=False).tolist())
            S = D[np.ix_(pick, pick)]
            for closed in (False, True):
                t0 = time.perf_counter()
                opt = tour_length(S, solve_order(S, closed=closed)[0], closed=closed)
                t_exact.append(time.perf_counter() - t0)
                h = tour_length(S, solve_order(S, closed=closed, exact_limit=0)[0], closed=closed)
                sub[closed].append(100.0 * (h - opt) / opt if opt > 0 else 0.0)
    row["sub"] = sub
    row["t_exact"] = float(np.median(t_exact)) if t_exact else np.nan
    return row


def _f(v, fmt=".1f"):
    return "–" if v is None or (isinstance(v, float) and np.isnan(v)) else format(v, fmt)


def table(rows):
    out = ["| map | rooms to visit | optimum m | heuristic m | nearest neighbour m | MST bound m "
           "| heuristic / bound | 12-room tours: heuristic = optimum (open, closed) | worst excess % |",
           "| --- | ---: | ---: | ---: | ---: | ---: | ---: | --- | ---: |"]
    allsub = {False: [], True: []}
    for r in rows:
        eq = [sum(1 for g in r["sub"][c] if g < 1e-6) for c in (False, True)]
        ns = [len(r["sub"][c]) for c in (False, True)]
        worst = max(r["sub"][False] + r["sub"][True], default=np.nan)
        for c in (False, True):
            allsub[c] += r["sub"][c]
        out.append(f"| {r['map']} | {r['n']} | {_f(r['opt'])} | {_f(r['heur'])} | {_f(r['nn'])} | {_f(r['bound'])} "
                   f"| {_f(r['heur'] / r['bound'] if r['bound'] else np.nan, '.2f')} "
                   f"| {f'{eq[0]}/{ns[0]}, {eq[1]}/{ns[1]}' if ns[0] else '–'} | {_f(worst, '.2f')} |")
    h = sum(r["heur"] for r in rows)
    nn = sum(r["nn"] for r in rows)
    b = sum(r["bound"] for r in rows)
    eq = [sum(1 for g in allsub[c] if g < 1e-6) for c in (False, True)]
    worst = max(allsub[False] + allsub[True], default=np.nan)
    out.append(f"| **all** | {sum(r['n'] for r in rows)} | | {h:.1f} | {nn:.1f} | {b:.1f} | {h / b:.2f} "
               f"| {eq[0]}/{len(allsub[False])}, {eq[1]}/{len(allsub[True])} | {_f(worst, '.2f')} |")
    return "\n".join(out) + "\n", dict(h=h, nn=nn, b=b)


def main(argv=None):
    ap = _section.parser(__doc__, "ipa_room_segmentation maps", "75_tour.md")
    ap.add_argument("--subsets", type=int, default=10, help="random 12-room tours per map (default 10)")
    args = ap.parse_args(argv)
    from topomap.bench.datasets import benchmark_dir, load_benchmark

    directory = _section.directory(args.directory, benchmark_dir, "TOPOMAP_BENCHMARK_DIR")
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    rng = np.random.default_rng(0)
    rows = []
    for bm in load_benchmark(directory, variant="unfurnished"):
        rows.append(run_map(bm, args.subsets, rng))
        print(f"{bm.name}: {rows[-1]['n']} rooms", file=sys.stderr, flush=True)
    wall = time.perf_counter() - t0
    tab, tot = table(rows)
    from topomap.planning.tour import KICKS
    t_exact = np.nanmedian([r["t_exact"] for r in rows])
    t_heur = max(r["t_heur"] for r in rows)
    t_dist = np.median([r["t_dist"] for r in rows])
    text = f"""## Room tours

`python benchmarks/tour.py IPA_DIR --subsets {args.subsets}` (commit `{_commit()}`; {_machine()}; load average {load0:.1f} at the start;
{wall:.0f} s wall time).

The 14 unfurnished floor plans of ipa_room_segmentation, segmented with the default method; a tour
starts at the point of the largest room and visits every room reachable from it (the start room
counts as visited), on the travel distances `plan_tour` uses (shortest routes through doors, in-room
geodesic legs). *Heuristic*: nearest neighbour improved by 2-opt and Or-opt, then {KICKS} rounds of
iterated local search (seeded double-bridge kicks), what `plan_tour` uses above 12 rooms; *MST bound*: the weight of a minimum spanning tree of the stops, which no tour
undercuts; *optimum*: Held–Karp, for maps with at most 12 rooms to visit. On every map with at least
12 rooms, {args.subsets} random sets of 12 rooms (seed 0) were toured both open and back to the start,
where the optimum is computed: how often the heuristic found it, and its worst excess over it. Over
all maps the heuristic's full tours are {100 * (1 - tot['h'] / tot['nn']):.1f} % shorter than nearest
neighbour's and {100 * (tot['h'] / tot['b'] - 1):.1f} % above the lower bound. Times: the distances
{t_dist:.2f} s per map (median), the heuristic at most {t_heur * 1000:.0f} ms, Held–Karp on 12 rooms
{t_exact * 1000:.0f} ms (median).

{tab}"""
    _section.write(args.out, text, tab, wall)

if __name__ == "__main__":
    main()
