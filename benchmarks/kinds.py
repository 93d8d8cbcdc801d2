#!/usr/bin/env python
"""Room kinds against the kinds of the R2V floor plans: corridor precision and recall.

Run (not a test)::

    python benchmarks/kinds.py [CORPUS_DIR] [--per-half 150] [--rows rows.json] [--out benchmarks/sections/86_kinds.md]

``CORPUS_DIR`` is a simulated corpus (``topomap simulate`` of the R2V plans:
one folder per plan with ``plan.yaml``, ``map.yaml``, ``gt_rooms.png`` and
``gt_rooms.json``). The plans are split in two halves by name: a plan whose
name starts with two hex digits of even value is **training** (the kind
thresholds of :mod:`topomap.core.kinds` were chosen looking at these), every other
plan is **held out** (scored once, with the thresholds fixed). ``--per-half``
plans of each half (the first in name order) are segmented twice: the drawn
plan (``plan.yaml``) and the simulated scan (``map.yaml``), with
:func:`topomap.segment` at its defaults, which puts ``room_kind`` on every
room.

Protocol ("largest overlap, corridor vs the rest"): each found room is
matched to the true room (``gt_rooms.png``) that holds most of its cells;
found rooms with most cells outside every true room are left out. The true
kind is *corridor* when the true room's plan labels (``gt_rooms.json``)
include ``corridor`` and nothing but ``corridor``, ``entrance`` and storage
(``closet``, ``PS``); a found room is called a corridor when its
``room_kind`` is ``corridor``. Precision: share of the found rooms called
corridors whose true room is one; recall: share of the found rooms matched
to a true corridor that are called corridors. The same table is given for
every kind (``room_kind`` against the true kind), and with ``doorway``
counted as corridor.
"""

from __future__ import annotations

import json
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _section  # noqa: E402
from _section import _commit, _machine  # noqa: E402

SECTION = "86_kinds.md"
PASSAGE = {"corridor", "entrance", "stairs", "closet", "PS"}


def training(name: str) -> bool:
    """Whether plan ``name`` is in the training half (its first two characters, read as hex, are even)."""
    try:
        return int(name[:2], 16) % 2 == 0
    except ValueError:
        return False


def true_kind(kinds) -> str:
    """``corridor`` for a plan room labelled corridor and nothing but passage or storage, else ``other``."""
    kinds = set(kinds)
    return "corridor" if "corridor" in kinds and kinds <= PASSAGE else "other"


def rows_of_case(case: Path, variant: str) -> list:
    """One row per found room of ``case``'s ``variant`` (``plan`` or ``map``): measures, kind, true kind."""
    import topomap
    from PIL import Image

    grid = topomap.load_map(case / f"{variant}.yaml")
    seg = topomap.segment(grid)
    G = seg.room_graph
    gt = np.asarray(Image.open(case / "gt_rooms.png")).astype(np.int64)
    truth = {r["id"]: true_kind(r["kinds"]) for r in json.loads((case / "gt_rooms.json").read_text())["rooms"]}
    lab = seg.room_labels
    if gt.shape != lab.shape:
        return []
    out = []
    both = (lab > 0)
    pairs = np.bincount(lab[both] * (gt.max() + 1) + gt[both],
                        minlength=(lab.max() + 1) * (gt.max() + 1)).reshape(lab.max() + 1, gt.max() + 1)
    for n, d in G.nodes(data=True):
        row = pairs[n]
        t = int(np.argmax(row))
        if t == 0 or row[t] * 2 < row.sum():  # most of the room outside every true room
            continue
        out.append({"case": case.name, "variant": variant, "room": int(n), "kind": d["room_kind"],
                    "truth": truth.get(t, "other"), "area": d["area"], "width": d["width"],
                    "length": d["length"], "doors": int(G.degree(n))})
    return out


def rows_of_truth(case: Path) -> list:
    """One row per true room of ``case``: the kind :func:`topomap.core.kinds.room_kind` gives its own shape
    (``gt_rooms.png``) and doors (``gt_doors.json``, the outside's included): what the measure can do
    on rooms segmented exactly as the plan draws them."""
    from PIL import Image
    from scipy import ndimage as ndi

    from topomap.core.kinds import room_kind, room_shape

    gt = np.asarray(Image.open(case / "gt_rooms.png")).astype(np.int64)
    res = _resolution(case)
    doors = json.loads((case / "gt_doors.json").read_text())["doors"]
    boxes = ndi.find_objects(gt)
    out = []
    for r in json.loads((case / "gt_rooms.json").read_text())["rooms"]:
        k = r["id"]
        if k > len(boxes) or boxes[k - 1] is None:
            continue
        s = room_shape(gt[boxes[k - 1]] == k, res)
        nd = sum(k in d["rooms"] for d in doors)
        out.append({"case": case.name, "variant": "truth", "room": k, "truth": true_kind(r["kinds"]),
                    "kind": room_kind(s["area"], s["width"], s["length"], nd), "area": s["area"],
                    "width": s["width"], "length": s["length"], "doors": nd})
    return out


def _resolution(case: Path) -> float:
    import yaml

    return float(yaml.safe_load((case / "plan.yaml").read_text())["resolution"])


def score(rows, passage=("corridor",)) -> tuple:
    """(precision %, recall %, true corridors, called corridors) of the rows."""
    called = [r["kind"] in passage for r in rows]
    true = [r["truth"] == "corridor" for r in rows]
    tp = sum(c and t for c, t in zip(called, true))
    nc, nt = sum(called), sum(true)
    return (100.0 * tp / nc if nc else float("nan"), 100.0 * tp / nt if nt else float("nan"), nt, nc)


def main():
    ap = _section.parser(__doc__, "simulated corpus directory", SECTION)
    ap.add_argument("--per-half", type=int, default=150, help="plans of each half (default 150)")
    ap.add_argument("--rows", type=Path, default=None, help="also write the per-room rows as JSON here")
    args = ap.parse_args()
    corpus = _section.directory(args.directory, lambda: None, "CORPUS_DIR")
    cases = sorted(p for p in corpus.iterdir() if (p / "gt_rooms.json").is_file())
    halves = {"training": [c for c in cases if training(c.name)][:args.per_half],
              "held out": [c for c in cases if not training(c.name)][:args.per_half]}
    t0 = time.time()
    rows = []
    for half, cs in halves.items():
        for c in cs:
            for r in rows_of_case(c, "plan") + rows_of_case(c, "map") + rows_of_truth(c):
                r["half"] = half
                rows.append(r)
    wall = time.time() - t0
    if args.rows:
        args.rows.write_text(json.dumps(rows))
    table = ["| plans | variant | rooms | true corridors | called corridors | corridor P / R (%) | "
             "corridor + doorway P / R (%) |", "| --- | --- | --- | --- | --- | --- | --- |"]
    for half in halves:
        for v, vname in (("plan", "drawn plan"), ("map", "simulated scan"), ("truth", "the plan's own rooms")):
            rs = [r for r in rows if r["half"] == half and r["variant"] == v]
            p, rc, nt, nc = score(rs)
            p2, r2, _, _ = score(rs, ("corridor", "doorway"))
            table.append(f"| {half} ({len(halves[half])}) | {vname} | {len(rs)} | {nt} | {nc} | "
                         f"{p:.1f} / {rc:.1f} | {p2:.1f} / {r2:.1f} |")
    kinds = Counter((r["kind"], r["truth"]) for r in rows if r["variant"] != "truth")
    conf = ["| room_kind | true corridor | true other |", "| --- | --- | --- |"]
    for k in ("corridor", "doorway", "room", "hall"):
        conf.append(f"| {k} | {kinds[(k, 'corridor')]} | {kinds[(k, 'other')]} |")
    ho = score([r for r in rows if r["half"] == "held out" and r["variant"] == "plan"])
    verdict = ("meets" if min(ho[0], ho[1]) >= 85 else "does not meet") + \
        f" the target of 85 % corridor precision and recall on the held-out drawn plans ({ho[0]:.1f} / {ho[1]:.1f})"
    text = "\n".join([
        "## Room kinds against the floor plans",
        "",
        f"`python benchmarks/kinds.py CORPUS_DIR --per-half {args.per_half}` (the simulated R2V corpus), "
        f"commit `{_commit()}`; {_machine()}.",
        "",
        "Protocol **largest overlap, corridor vs the rest**: each found room is matched to the true room "
        "holding most of its cells; the true room is a corridor when its plan labels are `corridor` and "
        "nothing but `entrance` and storage besides. **Training** plans (name starting with an even hex "
        "byte) are the ones the thresholds of `topomap.core.kinds` were chosen on; the **held-out** plans were "
        f"scored once with them fixed. {args.per_half} plans of each half, each as the drawn plan and as "
        "the simulated scan, segmented at the defaults.",
        "",
        *table,
        "",
        "*The plan's own rooms*: the kind the same rules give each true room from its own cells "
        "(`gt_rooms.png`) and its doors in the plan (`gt_doors.json`, the doors to the outside "
        "included), without a segmentation: what the shape measure can tell on these plans. A found room "
        "is matched and scored as above; the true rooms are scored against their own labels.",
        "",
        "Every found room of both halves and both variants, by its `room_kind` and its true kind:",
        "",
        *conf,
        "",
        f"The shape measure {verdict}. The homes of these plans are small: most of their rooms "
        "(bathrooms, washrooms, closets, entrances) are as narrow as their corridors (about 1 to 1.5 m on "
        "the mean-width measure), and many of their corridors are short stubs with an entrance or stairs; "
        "even on the plan's own rooms the rules separate corridors from the rest only as the third row of "
        "each half shows. On found rooms it is lower still: a segmentation joins a short corridor to the "
        "room it opens into or cuts it at a door, and the scans see fewer doors.",
        "",
    ])
    _section.write(args.out, text, "\n".join(table) + "\n", wall)


if __name__ == "__main__":
    main()
