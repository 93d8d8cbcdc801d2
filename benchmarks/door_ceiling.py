#!/usr/bin/env python
"""What finding every door would give: the simulated corpus cut at its true doors.

Run (not a test)::

    python benchmarks/door_ceiling.py CORPUS [--every 2] [--jobs 2]
        [--out benchmarks/sections/89b_door_ceiling.md]

``CORPUS`` is what ``topomap simulate`` writes (one folder per case; see
``benchmarks/simulated.py``). Each case, as its plan and as its simulated
scan, is loaded as ``topomap segment CASE/plan.yaml`` (``CASE/map.yaml``)
loads it and segmented three ways, each scored with the **original
protocol** against that variant's ground truth:

* **topomap**: the default method;
* **true doors**: the map's free space cut along the true doors between two
  rooms (``gt_doors*.json``) and nothing else, pieces under the default
  method's smallest room (``min_room_area``) joined to their neighbour as the
  default method joins them: what a method that found every door, and no
  other cut, would score;
* **topomap + true doors**: both sets of cuts: what the default method's
  own cuts cost when every door is found;
* **topomap + true gaps in walls**, **topomap + true open sides**: the
  default method's cuts and the true doors of one kind only (the kinds of the
  second table): what finding every door of that kind, and no other, would
  give.

A second table sorts the true doors between two rooms by what the map
shows of them, and how many of each the default method finds
(a door of its room graph within 0.5 m of the door's midpoint):

* **a gap in a wall**: the doorway is free (at least half of its line) and
  the map shows no free cell along the door's line for 0.5 m beyond each
  end (the wall the door is in goes on, or its unmapped inside);
* **an open side**: the doorway is free but the line runs on into free space
  beyond an end: the side of a room open onto the next, with no wall along
  it (an open-plan kitchen, the end of a hallway);
* **not free**: a closed door, or one the scan did not see through.

For the doors a gap in a wall that it misses, the status of the nearest
bottleneck it considered (within 0.5 m of the midpoint;
:data:`topomap.core.doors.STATUSES`), or none.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _section  # noqa: E402
from _section import _commit, _machine  # noqa: E402

WAYS = ("topomap", "true doors", "topomap + true doors", "topomap + true gaps in walls", "topomap + true open sides")
#: How far (m) the wall must go on beyond each end of a doorway, and how far a found door may be.
BEYOND, NEAR = 0.5, 0.5


def true_door_segments(bm, grid) -> list:
    """The true doors between two rooms (not to the outside) as pixel segments of ``grid``."""
    segs = []
    for d in bm.gt_doors or ():
        if 0 in tuple(d.get("rooms", ())):
            continue
        (x1, y1), (x2, y2) = d["p1"], d["p2"]
        a, b = grid.world_to_pixel(x1, y1), grid.world_to_pixel(x2, y2)
        segs.append(((float(a[0]), float(a[1])), (float(b[0]), float(b[1]))))
    return segs


def door_kind(free: np.ndarray, seg, resolution: float) -> str:
    """``"gap"``, ``"open"`` or ``"closed"``: what the map shows of one true door (module docstring)."""
    a, b = np.asarray(seg[0], float), np.asarray(seg[1], float)
    H, W = free.shape
    length = max(float(np.hypot(*(b - a))), 1e-9)

    def cells(p):
        p = np.rint(p).astype(int)
        inside = (p[:, 0] >= 0) & (p[:, 0] < H) & (p[:, 1] >= 0) & (p[:, 1] < W)
        return p[inside], inside

    on, _ = cells(a + (b - a) * np.linspace(0.15, 0.85, max(int(length), 2))[:, None])
    if on.size == 0 or free[on[:, 0], on[:, 1]].mean() < 0.5:
        return "closed"
    u = (b - a) / length
    steps = np.arange(2, int(BEYOND / resolution) + 1)[:, None]
    for p, sign in ((a, -1), (b, 1)):
        q, inside = cells(p + sign * u * steps)
        if not inside.all() or free[q[:, 0], q[:, 1]].any():
            return "open"
    return "gap"


def _segments_ways(grid, seg, truth, kinds):
    """The room labels of the ways (module docstring); ``kinds``: :func:`door_kind` of each true door."""
    from topomap.core.rooms import cut_rooms

    out = {"topomap": seg.room_labels}
    ours = [tuple(map(tuple, np.asarray(d.segment, float))) for d in seg.doors]
    min_cells = int(seg.options.min_room_area / grid.resolution ** 2)
    gaps = [s for s, k in zip(truth, kinds) if k == "gap"]
    sides = [s for s, k in zip(truth, kinds) if k == "open"]
    for way, cuts in (("true doors", truth), ("topomap + true doors", truth + ours),
                      ("topomap + true gaps in walls", gaps + ours), ("topomap + true open sides", sides + ours)):
        labels, _, n = cut_rooms(grid, cuts, min_room_cells=min_cells)
        out[way] = np.where(labels <= n, labels, 0)
    return out


def score_case(bm) -> dict:
    """One case and variant: P / R of the three ways, and every true door's kind, found or not."""
    from topomap.bench.evaluation import evaluate
    from topomap.core.segmentation import segment

    grid = bm.load()
    seg = segment(grid)
    res = grid.resolution
    truth = true_door_segments(bm, grid)
    row = {"map": bm.name, "variant": bm.variant, "doors": []}
    kinds = [door_kind(grid.free, s, res) for s in truth]
    for way, labels in _segments_ways(grid, seg, truth, kinds).items():
        ev = evaluate(labels, bm.map_gray, bm.gt_gray, resolution=res, scored=grid.free, gt_rooms=bm.gt_rooms)
        row[way] = (float(ev["precision"]), float(ev["recall"]), int(len(np.unique(labels[labels > 0]))))
    found = [np.mean(np.asarray(d.segment, float), 0) for d in seg.doors]
    cands = [((np.asarray(c.ip1) + np.asarray(c.ip2)) / 2 if c.ip1 is not None and c.ip2 is not None
              else np.asarray(c.centroid, float), c.status) for c in seg.candidates]
    for s, kind in zip(truth, kinds):
        mid = (np.asarray(s[0]) + np.asarray(s[1])) / 2
        near = min(((float(np.hypot(*(p - mid))) * res, st) for p, st in cands), default=(np.inf, "none"))
        row["doors"].append({"kind": kind,
                             "found": any(np.hypot(*(f - mid)) * res <= NEAR for f in found),
                             "nearest": near[1] if near[0] <= NEAR else "none"})
    return row


def tables(rows) -> str:
    """The section's two tables."""
    lines = ["| variant | cases | way | P (%) | R (%) | rooms found / true |", "| --- | ---: | --- | ---: | ---: | ---: |"]
    for variant in ("plan", "scan"):
        vr = [r for r in rows if r["variant"] == variant]
        if not vr:
            continue
        true_rooms = sum(r.get("true_rooms", 0) for r in vr)
        for way in WAYS:
            p = 100 * np.mean([r[way][0] for r in vr])
            rr = 100 * np.mean([r[way][1] for r in vr])
            lines.append(f"| {variant} | {len(vr)} | {way} | {p:.1f} | {rr:.1f} | {sum(r[way][2] for r in vr)} / {true_rooms} |")
    lines += ["", _summary(rows)]
    names = {"gap": "a gap in a wall", "open": "an open side", "closed": "not free"}
    lines += ["", "| variant | true door | doors | found by topomap (%) | nearest bottleneck of the missed ones |",
              "| --- | --- | ---: | ---: | --- |"]
    for variant in ("plan", "scan"):
        doors = [d for r in rows if r["variant"] == variant for d in r["doors"]]
        for kind in ("gap", "open", "closed"):
            sel = [d for d in doors if d["kind"] == kind]
            if not sel:
                continue
            missed = Counter(d["nearest"] for d in sel if not d["found"]).most_common(3)
            why = ", ".join(f"{k} {v}" for k, v in missed) or "–"
            lines.append(f"| {variant} | {names[kind]} | {len(sel)} | {100 * np.mean([d['found'] for d in sel]):.1f} | {why} |")
    return "\n".join(lines) + "\n"


def _summary(rows) -> str:
    """One sentence per variant: what the missed doors cost in precision, the extra cuts in recall."""
    out = []
    for variant in ("plan", "scan"):
        vr = [r for r in rows if r["variant"] == variant]
        if vr:
            m = {w: 100 * np.mean([r[w] for r in vr], axis=0)[:2] for w in WAYS}
            out.append(f"On the {variant}s, the doors the default method misses cost "
                       f"{m['true doors'][0] - m['topomap'][0]:.1f} points of precision (cut at the true doors only: "
                       f"{m['true doors'][0]:.1f} against {m['topomap'][0]:.1f}); its cuts where no true door is cost "
                       f"{m['true doors'][1] - m['topomap + true doors'][1]:.1f} points of recall once every door is found; "
                       f"every door that is a gap in a wall found as well would give {m['topomap + true gaps in walls'][0]:.1f}"
                       f" precision, every open side {m['topomap + true open sides'][0]:.1f}.")
    return " ".join(out)


def _true_rooms(bm) -> int:
    """The number of true rooms of a case (labels of its ground truth)."""
    gt = np.asarray(bm.gt_rooms)
    return int(len(np.unique(gt[gt > 0])))


def run(task) -> dict:
    row = score_case(task)
    row["true_rooms"] = _true_rooms(task)
    return row


def main(argv=None) -> int:
    from topomap.bench.datasets import load_simulated

    ap = _section.parser(__doc__, "the simulated corpus (topomap simulate's folder)", "89b_door_ceiling.md")
    ap.add_argument("--every", type=int, default=1, help="every n-th case (default every case)")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args(argv)
    corpus = _section.directory(a.directory, lambda: None, "CORPUS")
    t0 = time.time()
    cases = [bm for variant in ("plan", "scan") for bm in load_simulated(corpus, variant=variant)[::a.every]]
    with ProcessPoolExecutor(a.jobs) as ex:
        rows = list(ex.map(run, cases, chunksize=4))
    table = tables(rows)
    every = "" if a.every == 1 else f" --every {a.every}"
    text = (f"## What finding every door would give\n\n`python benchmarks/door_ceiling.py CORPUS{every} --jobs {a.jobs}` "
            f"(the folder `topomap simulate` wrote as `CORPUS`), {len(rows) // 2} cases, commit `{_commit()}`; {_machine()}.\n\n"
            + _PROSE + "\n" + table)
    _section.write(a.out, text, table, time.time() - t0)
    return 0


_PROSE = """\
Each simulated case (its drawn plan and its simulated scan) segmented five ways and scored with the
**original protocol** (true rooms whole; segments on the map's free cells): **topomap**, the default
method; **true doors**, the map's free space cut along the true doors between two rooms and nothing else
(pieces under the default method's smallest room joined to their neighbour): what a method that found
every door and made no other cut would score; **topomap + true doors**, both sets of cuts;
**topomap + true gaps in walls** and **topomap + true open sides**, the default method's cuts and the true
doors of that kind only (the kinds of the second table). Rooms: the
rooms of the result against the true rooms, summed over the cases (cutting at the true doors, the free
cells of no true room, such as laser fans beyond the facade, are rooms too). The second table sorts
the true doors between two rooms by what the map shows of them: *a gap in a wall* (the
doorway free, and no free cell along the door's line for 0.5 m beyond either end), *an open side* (the
line runs on into free space: a room open onto the next, with no wall along the line) or *not free* (a
closed door, or one the scan did not see through), and how many of each the default method finds (a door
of its room graph within 0.5 m of the door's midpoint); for the missed ones, the status of the nearest
bottleneck it considered within 0.5 m (`none`: no bottleneck there).
"""


if __name__ == "__main__":
    raise SystemExit(main())
