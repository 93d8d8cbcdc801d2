"""Quick scores of one method setting on both data sets, grouped as the issue tables are.

    python benchmarks/quick_eval.py                         # the default method, defaults
    python benchmarks/quick_eval.py '{"rise": 0.2}'         # options as JSON
    python benchmarks/quick_eval.py '{}' real --jobs 2      # only the real maps ("ipa": only the plans)
    python benchmarks/quick_eval.py '{}' --out rows.json    # per-map rows too
    python benchmarks/quick_eval.py '{}' plan,scan --corpus CORPUS --every 4   # a simulated corpus, every 4th case

Every map is loaded as ``topomap segment`` loads it (``BenchmarkMap.load``:
the real maps through their YAML, the plans as images at 0.05 m/px),
segmented with ``segment(grid, **options)`` and scored as
``topomap benchmark`` scores it (original protocol: true rooms whole, the
rooms a user gets; fragments are no room). Prints mean precision / recall
(%) per group — Freiburg 079 partial maps, Bremen partial maps, the two
full maps, ipa unfurnished and furnished — with rooms found / true rooms.
It is the tool for trying a change: the published page comes from
``benchmarks/report.py``.
"""

from __future__ import annotations

import argparse
import json
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from topomap.bench.datasets import benchmark_dir, load_benchmark, load_labelled, load_simulated, real_maps_dir
from topomap.bench.evaluation import evaluate
from topomap.core.segmentation import segment

GROUPS = [
    ("freiburg079_partial_*", lambda r: r["map"].startswith("freiburg079_partial")),
    ("bremen_cartesium_partial_*", lambda r: r["map"].startswith("bremen_cartesium_partial")),
    ("freiburg079_full", lambda r: r["map"] == "freiburg079_full"),
    ("bremen_cartesium_full", lambda r: r["map"] == "bremen_cartesium_full"),
    ("ipa unfurnished", lambda r: r["variant"] == "unfurnished"),
    ("ipa furnished", lambda r: r["variant"] == "furnished"),
    ("simulated plans", lambda r: r["variant"] == "plan"),
    ("simulated scans", lambda r: r["variant"] == "scan"),
]


def score(task):
    bm, options = task
    t0 = time.perf_counter()
    grid = bm.load()
    seg = segment(grid, **options)
    seconds = time.perf_counter() - t0
    ev = evaluate(seg.room_labels, bm.map_gray, bm.gt_gray, pred_doors=[d.segment for d in seg.doors],
                  resolution=grid.resolution, door_map_gray=bm.unfurnished_gray, scored=grid.free,
                  gt_rooms=bm.gt_rooms)
    return {"map": bm.name, "variant": bm.variant, "precision": float(ev["precision"]),
            "recall": float(ev["recall"]), "precision_free": float(ev["precision_free"]),
            "recall_free": float(ev["recall_free"]), "ceiling_recall": float(ev["ceiling_recall"]), "rooms": int(seg.n_rooms), "true_rooms": int(ev.get("n_true_rooms", 0)),
            "fragments": int(seg.n_fragments), "seconds": seconds}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("options", nargs="?", default="{}", help="options of segment() as JSON")
    ap.add_argument("which", nargs="?", default="real,ipa", help="real, ipa or real,ipa")
    ap.add_argument("--real", default=None, help="labelled real maps (default: real_maps_dir())")
    ap.add_argument("--ipa", default=None, help="ipa_room_segmentation maps (default: benchmark_dir())")
    ap.add_argument("--corpus", default=None, help="a simulated corpus (topomap simulate's output), for plan / scan")
    ap.add_argument("--every", type=int, default=1, help="of the corpus, every N-th case (sorted by name)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out", default=None, help="write the per-map rows to this JSON file")
    a = ap.parse_args(argv)
    options = json.loads(a.options)
    tasks = []
    if "real" in a.which:
        tasks += [(bm, options) for bm in load_labelled(a.real or real_maps_dir())]
    if "ipa" in a.which:
        for v in ("unfurnished", "furnished"):
            tasks += [(bm, options) for bm in load_benchmark(a.ipa or benchmark_dir(), variant=v)]
    for v in ("plan", "scan"):
        if v in a.which.split(","):
            cases = load_simulated(a.corpus, variant=v)
            tasks += [(bm, options) for bm in sorted(cases, key=lambda b: b.name)[::a.every]]
    with ProcessPoolExecutor(a.jobs) as ex:
        rows = list(ex.map(score, tasks))
    if a.out:
        with open(a.out, "w") as fh:
            json.dump(rows, fh, indent=1)
    print("| maps | P / R (original protocol) | ceiling R | P / R (free-cells) | rooms found / true |\n"
          "| --- | --- | ---: | --- | ---: |")
    for name, sel in GROUPS:
        r = [x for x in rows if sel(x)]
        if r:
            p, rec = 100 * np.mean([x["precision"] for x in r]), 100 * np.mean([x["recall"] for x in r])
            pf, rf = 100 * np.mean([x["precision_free"] for x in r]), 100 * np.mean([x["recall_free"] for x in r])
            cr = 100 * np.mean([x["ceiling_recall"] for x in r])
            print(f"| {name} | {p:.1f} / {rec:.1f} | {cr:.1f} | {pf:.1f} / {rf:.1f} | {sum(x['rooms'] for x in r)} / {sum(x['true_rooms'] for x in r)} |")
    print(f"median {np.median([x['seconds'] for x in rows]):.3f} s per map (load + segment, {a.jobs} processes)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
