#!/usr/bin/env python
"""Read every vector floor plan of a directory and check its ground truth.

Run (not a test)::

    python benchmarks/plans_check.py DATA_DIR [--names GLOB] [--max-gap 0.3] [--csv OUT.csv]

``DATA_DIR`` is the R2V / LIFULL plan directory (holding ``plans/NAME.txt``,
or the ``plans`` folder itself). Each plan goes through
:func:`topomap.bench.floorplan.read_plan` with its defaults and
:func:`topomap.bench.floorplan.ground_truth_problems`; printed (Markdown):

* the plans that fail, and why (the error's one line, or the broken
  invariants);
* distributions over the plans that read: area of the home (m²), rooms,
  doors, doors onto the outside, time to read and rasterise a plan;
* the mends of :func:`read_plan` (``FloorPlan.quirks``): how many plans
  needed each, and how many times in all;
* signs of rooms run together or lost: label boxes of a room kind whose
  centre is in no room, rooms holding two bedrooms, or a bedroom with a
  bathroom or toilet (these have walls between them in every home).
"""

from __future__ import annotations

import argparse
import csv
import logging
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from topomap.errors import TopomapError, first_line  # noqa: E402
from topomap.bench.floorplan import ground_truth_problems, read_plan  # noqa: E402

_PRIVATE = ("bathroom", "restroom")


def _suspect(kinds) -> bool:
    """A room whose kinds cannot share one space: two bedrooms, or a bedroom with a bath or toilet."""
    c = Counter(kinds)
    return c["bedroom"] >= 2 or (c["bedroom"] >= 1 and any(c[k] for k in _PRIVATE))


def _room_boxes(path: Path) -> int:
    from topomap.bench.floorplan import ROOM_KINDS

    n = 0
    for line in path.read_text(encoding="utf-8").splitlines():
        f = line.split()
        n += len(f) >= 5 and f[4] in ROOM_KINDS
    return n


def check(path: Path, **options) -> dict:
    row = {"name": path.stem}
    t = time.perf_counter()
    try:
        plan = read_plan(path, **options)
    except TopomapError as exc:
        row.update(error=first_line(exc))
        return row
    row["seconds"] = time.perf_counter() - t
    problems = ground_truth_problems(plan)
    row.update(problems="; ".join(problems), area=plan.area, rooms=plan.n_rooms, doors=len(plan.doors),
               outside_doors=sum(d.rooms[0] == 0 for d in plan.doors), cells=plan.walls.size,
               boxes_placed=sum(len(v) for v in plan.kinds.values()), boxes=_room_boxes(path),
               suspect_rooms=sum(_suspect(v) for v in plan.kinds.values()), **plan.quirks)
    return row


def _pct(values, qs=(0, 5, 25, 50, 75, 95, 100)) -> str:
    v = np.asarray(values, float)
    return " / ".join(f"{x:.3g}" for x in np.percentile(v, qs))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("data_dir", type=Path)
    ap.add_argument("--names", default="*", help="glob of plan names (default: all)")
    ap.add_argument("--max-gap", type=float, default=None, help="read_plan's max_gap (m)")
    ap.add_argument("--csv", type=Path, help="write one row per plan here")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    folder = args.data_dir / "plans" if (args.data_dir / "plans").is_dir() else args.data_dir
    paths = sorted(folder.glob(args.names + ".txt"))
    if not paths:
        print(f"{folder}: no plans ({args.names}.txt)", file=sys.stderr)
        return 1
    options = {} if args.max_gap is None else {"max_gap": args.max_gap}
    t0 = time.perf_counter()
    rows = [check(p, **options) for p in paths]
    total = time.perf_counter() - t0
    ok = [r for r in rows if "error" not in r]
    bad = [r for r in rows if "error" in r]
    broken = [r for r in ok if r["problems"]]
    print(f"# {len(paths)} plans of {folder.name}/ ({options or 'defaults'}): {len(ok)} read, {len(bad)} failed, "
          f"{len(broken)} with broken invariants; {total:.1f} s in all\n")
    for r in bad:
        print(f"- failed: `{r['name']}`: {r['error']}")
    for r in broken:
        print(f"- invariants: `{r['name']}`: {r['problems']}")
    if ok:
        print("\n| per plan | min / 5 % / 25 % / median / 75 % / 95 % / max |\n| --- | --- |")
        for key, label in (("area", "area of the home, m²"), ("rooms", "rooms"), ("doors", "doors"),
                           ("outside_doors", "doors onto the outside"), ("cells", "grid cells"),
                           ("seconds", "seconds to read (parse, rasterise, ground truth)")):
            print(f"| {label} | {_pct([r[key] for r in ok])} |")
        area = np.array([r["area"] for r in ok])
        print(f"\nHomes of 35-110 m²: {np.mean((area >= 35) & (area <= 110)) * 100:.1f} % "
              f"(under 35: {int((area < 35).sum())}, over 110: {int((area > 110).sum())}).\n")
        print("| mend / loss (FloorPlan.quirks) | plans | times |\n| --- | --- | --- |")
        for key in ("zero_walls", "duplicate_walls", "gaps_extended", "gaps_bridged", "doors_snapped", "doors_narrow",
                    "doors_floating", "doors_dropped", "closets_merged", "closed_spaces", "cells_unassigned"):
            v = np.array([r[key] for r in ok])
            print(f"| `{key}` | {int((v > 0).sum())} | {int(v.sum())} |")
        parts = np.array([r["parts"] for r in ok])
        print(f"| home in more than one piece (`parts` > 1) | {int((parts > 1).sum())} | {int(parts.sum())} |")
        placed = sum(r["boxes_placed"] for r in ok)
        boxes = sum(r["boxes"] for r in ok)
        lost = [r for r in ok if r["boxes_placed"] < r["boxes"]]
        sus = [r for r in ok if r["suspect_rooms"]]
        print(f"\nRoom label boxes placed in a room: {placed} of {boxes} ({placed / max(boxes, 1) * 100:.1f} %); "
              f"plans with a box in no room: {len(lost)}.")
        print(f"Plans with a room holding two bedrooms, or a bedroom with a bath or toilet: {len(sus)}"
              + (f" (e.g. {', '.join(r['name'] for r in sus[:5])})" if sus else "") + ".")
    if args.csv:
        keys = sorted({k for r in rows for k in r})
        with open(args.csv, "w", newline="", encoding="utf-8") as f:
            w = csv.DictWriter(f, keys)
            w.writeheader()
            w.writerows(rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
