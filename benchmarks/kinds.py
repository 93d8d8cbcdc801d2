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
kind (:func:`true_kind`, from the true room's plan labels in
``gt_rooms.json``) is *corridor* when the labels include ``corridor`` and
nothing but passage (``corridor``, ``entrance``, ``stairs``) and storage
(``closet``, ``PS``); *mixed* when they join a passage label to a room's
(``entrance`` + ``kitchen``, ``corridor`` + ``living_room``: a hallway that is
also a kitchen, or a living room the plan draws with its hallway); else
*other*. A mixed room is both a passage and a room, so neither kind is wrong
for it: mixed rooms are left out of the precision and recall (and, for
comparison with the tables before, also scored as *other*). An ``entrance``
with no ``corridor`` label is *other*: on these plans it is the small
vestibule inside the front door (1 to 2 m², a door on each side), a doorway
rather than a corridor. A found room is called a corridor when its
``room_kind`` is ``corridor``. Precision: share of the found rooms called
corridors whose true room is one; recall: share of the found rooms matched
to a true corridor that are called corridors. The same table is given with
``doorway`` counted as corridor, and every kind against the true kind.

``--jobs N`` segments the plans in N processes.
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
PASSAGE = {"corridor", "entrance", "stairs"}
STORAGE = {"closet", "PS"}


def training(name: str) -> bool:
    """Whether plan ``name`` is in the training half (its first two characters, read as hex, are even)."""
    try:
        return int(name[:2], 16) % 2 == 0
    except ValueError:
        return False


def true_kind(kinds) -> str:
    """``corridor`` for a plan room labelled corridor and nothing but passage or storage, ``mixed`` for one
    whose labels join a passage label to a room's, else ``other``."""
    kinds = set(kinds)
    if kinds <= PASSAGE | STORAGE:
        return "corridor" if "corridor" in kinds else "other"
    return "mixed" if kinds & PASSAGE else "other"


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
    place = _place(G)
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
                    "length": d["length"], "doors": int(G.degree(n)), **place[n]})
    return out


def _place(G) -> dict:
    """Per room of the room graph ``G``: the measures of its place in the graph that the rules use (whether it
    is a cut vertex, how many of its neighbours are dead ends, its widest door), for scoring other rules from
    the rows."""
    from topomap.core.kinds import graph_place

    cut, dead = graph_place(G)
    widest = {n: 0.0 for n in G}
    for a, b, w in G.edges(data="width", default=0.0):
        widest[a] = max(widest[a], w)
        widest[b] = max(widest[b], w)
    return {n: {"cut": n in cut, "dead_ends": int(dead[n]), "widest_door": float(widest[n])} for n in G}


def rows_of_truth(case: Path) -> list:
    """One row per true room of ``case``: the kind :func:`topomap.core.kinds.annotate_kinds` gives it from its
    own cells (``gt_rooms.png``) and the room graph of the plan's doors (``gt_doors.json``; the doors to the
    outside are left out, as the room graph of a map has none): what the rules can do on rooms segmented
    exactly as the plan draws them."""
    import networkx as nx
    from PIL import Image

    from topomap.core.kinds import annotate_kinds

    gt = np.asarray(Image.open(case / "gt_rooms.png")).astype(np.int64)
    res = _resolution(case)
    rooms = json.loads((case / "gt_rooms.json").read_text())["rooms"]
    present = set(np.unique(gt).tolist())
    G = nx.MultiGraph()
    G.add_nodes_from(r["id"] for r in rooms if r["id"] in present and r["id"] > 0)
    front = Counter()  # doors to the outside, per room
    for k, d in enumerate(json.loads((case / "gt_doors.json").read_text())["doors"]):
        a, b = d["rooms"]
        if a != b and a in G and b in G:
            G.add_edge(a, b, key=k, width=float(d["width"]))
        elif 0 in (a, b):
            front[a or b] += 1
    annotate_kinds(G, gt, res)
    place = _place(G)
    out = []
    for r in rooms:
        k = r["id"]
        if k not in G or "room_kind" not in G.nodes[k]:
            continue
        d = G.nodes[k]
        area = float(np.count_nonzero(gt == k)) * res ** 2
        out.append({"case": case.name, "variant": "truth", "room": k, "truth": true_kind(r["kinds"]),
                    "kind": d["room_kind"], "area": area, "width": d["width"], "length": d["length"],
                    "doors": int(G.degree(k)), **place[k], "outside_doors": front[k]})
    return out


def rows_of_plan(case: Path) -> list:
    """The rows of one case: its drawn plan, its simulated scan and its own true rooms."""
    return rows_of_case(case, "plan") + rows_of_case(case, "map") + rows_of_truth(case)


def _resolution(case: Path) -> float:
    import yaml

    return float(yaml.safe_load((case / "plan.yaml").read_text())["resolution"])


def score(rows, passage=("corridor",), mixed="left out") -> tuple:
    """(precision %, recall %, true corridors, called corridors) of the rows; rooms of true kind ``mixed``
    left out (``mixed="left out"``) or scored as ``other`` (``mixed="other"``)."""
    if mixed == "left out":
        rows = [r for r in rows if r["truth"] != "mixed"]
    called = [r["kind"] in passage for r in rows]
    true = [r["truth"] == "corridor" for r in rows]
    tp = sum(c and t for c, t in zip(called, true))
    nc, nt = sum(called), sum(true)
    return (100.0 * tp / nc if nc else float("nan"), 100.0 * tp / nt if nt else float("nan"), nt, nc)


def _rows(halves: dict, jobs: int) -> list:
    """Every row of every case of ``halves`` (``{half: [case, ...]}``), each with its ``half``."""
    todo = [(half, c) for half, cs in halves.items() for c in cs]
    if jobs > 1:
        from multiprocessing import Pool

        with Pool(jobs) as pool:
            per_case = pool.map(rows_of_plan, [c for _, c in todo], chunksize=1)
    else:
        per_case = [rows_of_plan(c) for _, c in todo]
    rows = []
    for (half, _), rs in zip(todo, per_case):
        for r in rs:
            r["half"] = half
            rows.append(r)
    return rows


#: The measures of a room the separability check (:func:`tree_ceiling`) may split on: those the rules use ...
MEASURES = ("area", "width", "length", "elongation", "doors", "cut", "dead_ends", "widest_door")
#: ... and, in its second run, the number of the room's doors to the outside, which no map's room graph holds
#: (the front door: most of these homes' corridors are their entrance hall).
FRONT = "outside_doors"


def _features(rows, names) -> np.ndarray:
    """The measures ``names`` of the rows as a float array ``(rows, measures)``."""
    def value(r, n):
        return r["length"] / r["width"] if n == "elongation" else float(r[n])

    return np.array([[value(r, n) for n in names] for r in rows], float).reshape(len(rows), len(names))


def _grow(X, y, idx, depth, min_leaf=20):
    """A classification tree (Gini splits, at most ``depth`` levels, leaves of ``min_leaf`` rooms or more):
    ``(measure, threshold, left, right)`` or a leaf's share of corridors."""
    yy = y[idx]
    if depth == 0 or len(idx) < 2 * min_leaf or yy.all() or not yy.any():
        return float(yy.mean()) if len(idx) else 0.0
    best = None
    for j in range(X.shape[1]):
        xs = X[idx, j]
        for v in np.unique(np.percentile(xs, np.linspace(2, 98, 49))):
            left = xs <= v
            nl = int(left.sum())
            if nl < min_leaf or len(idx) - nl < min_leaf:
                continue
            pl, pr = yy[left].mean(), yy[~left].mean()
            g = nl * pl * (1 - pl) + (len(idx) - nl) * pr * (1 - pr)
            if best is None or g < best[0]:
                best = (g, j, v)
    if best is None:
        return float(yy.mean())
    _, j, v = best
    left = X[idx, j] <= v
    return (j, v, _grow(X, y, idx[left], depth - 1, min_leaf), _grow(X, y, idx[~left], depth - 1, min_leaf))


def _predict(tree, x) -> bool:
    while isinstance(tree, tuple):
        tree = tree[2] if x[tree[0]] <= tree[1] else tree[3]
    return tree >= 0.5


def tree_ceiling(rows, names, depth) -> tuple:
    """How well the measures ``names`` of the plans' own rooms can tell a corridor at all: a tree of ``depth``
    levels fit to the training half's own rooms (``variant`` ``truth``, mixed rooms left out), scored on both
    halves. ``((P, R) training, (P, R) held out)``, %."""
    rows = [r for r in rows if r["variant"] == "truth" and r["truth"] != "mixed"]
    out = []
    fit = None
    for half in ("training", "held out"):
        rs = [r for r in rows if r["half"] == half]
        X, y = _features(rs, names), np.array([r["truth"] == "corridor" for r in rs])
        if fit is None:
            fit = _grow(X, y, np.arange(len(rs)), depth)
        called = np.array([_predict(fit, x) for x in X], bool)
        tp = int((called & y).sum())
        out.append((100.0 * tp / max(int(called.sum()), 1), 100.0 * tp / max(int(y.sum()), 1)))
    return tuple(out)


def _ceiling_table(rows) -> list:
    """The separability table: trees of 3 to 6 levels on the rules' measures, without and with the front door."""
    table = ["| measures | tree levels | training P / R (%) | held out P / R (%) |", "| --- | ---: | --- | --- |"]
    for names, label in ((MEASURES, "the rules' measures"), (MEASURES + (FRONT,), "the rules' measures + doors to the outside")):
        for depth in (3, 4, 5, 6):
            (p1, r1), (p2, r2) = tree_ceiling(rows, names, depth)
            table.append(f"| {label} | {depth} | {p1:.1f} / {r1:.1f} | {p2:.1f} / {r2:.1f} |")
    return table


def _tables(rows, halves) -> tuple:
    """The score table and the table of kinds against true kinds."""
    table = ["| plans | variant | rooms (mixed) | true corridors | called corridors | corridor P / R (%) | "
             "corridor + doorway P / R (%) | mixed as other: corridor P / R (%) |",
             "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for half in halves:
        for v, vname in (("plan", "drawn plan"), ("map", "simulated scan"), ("truth", "the plan's own rooms")):
            rs = [r for r in rows if r["half"] == half and r["variant"] == v]
            p, rc, nt, nc = score(rs)
            p2, r2, _, _ = score(rs, ("corridor", "doorway"))
            p3, r3, _, _ = score(rs, mixed="other")
            nm = sum(r["truth"] == "mixed" for r in rs)
            table.append(f"| {half} ({len(halves[half])}) | {vname} | {len(rs)} ({nm}) | {nt} | {nc} | "
                         f"{p:.1f} / {rc:.1f} | {p2:.1f} / {r2:.1f} | {p3:.1f} / {r3:.1f} |")
    kinds = Counter((r["kind"], r["truth"]) for r in rows if r["variant"] != "truth")
    conf = ["| room_kind | true corridor | true mixed | true other |", "| --- | --- | --- | --- |"]
    for k in ("corridor", "doorway", "room", "hall"):
        conf.append(f"| {k} | {kinds[(k, 'corridor')]} | {kinds[(k, 'mixed')]} | {kinds[(k, 'other')]} |")
    return table, conf


def main():
    ap = _section.parser(__doc__, "simulated corpus directory", SECTION)
    ap.add_argument("--per-half", type=int, default=150, help="plans of each half (default 150)")
    ap.add_argument("--half", choices=("both", "training"), default="both",
                    help="score both halves (default) or the training half alone (while choosing rules)")
    ap.add_argument("--jobs", type=int, default=1, help="plans in this many processes (default 1)")
    ap.add_argument("--rows", type=Path, default=None, help="also write the per-room rows as JSON here")
    args = ap.parse_args()
    corpus = _section.directory(args.directory, lambda: None, "CORPUS_DIR")
    cases = sorted(p for p in corpus.iterdir() if (p / "gt_rooms.json").is_file())
    halves = {"training": [c for c in cases if training(c.name)][:args.per_half],
              "held out": [c for c in cases if not training(c.name)][:args.per_half]}
    if args.half == "training":
        del halves["held out"]
    t0 = time.time()
    rows = _rows(halves, args.jobs)
    wall = time.time() - t0
    if args.rows:
        args.rows.write_text(json.dumps(rows))
    table, conf = _tables(rows, halves)
    ho = [r for r in rows if r["half"] == "held out" and r["variant"] == "plan"]
    if not ho:
        sys.stdout.write("\n".join(table + [""] + conf) + "\n")
        print(f"training half only: no section written ({wall:.0f} s)")
        return
    own = _own_rooms({"training": [c for c in cases if training(c.name)],
                      "held out": [c for c in cases if not training(c.name)]})
    corridors = [r for r in own if r["truth"] == "corridor"]
    few = 100.0 * sum(r["doors"] <= 1 for r in corridors) / max(len(corridors), 1)
    _section.write(args.out, _text(args, table, conf, score(ho), score(ho, mixed="other"), _ceiling_table(own),
                                   {h: len({r["case"] for r in own if r["half"] == h}) for h in ("training", "held out")},
                                   few),
                   "\n".join(table) + "\n", wall)


def _own_rooms(halves: dict) -> list:
    """The rows of the own rooms (:func:`rows_of_truth`) of every plan of ``halves``, each with its ``half``
    (no segmentation: a few seconds for the whole corpus)."""
    rows = []
    for half, cs in halves.items():
        for c in cs:
            for r in rows_of_truth(c):
                r["half"] = half
                rows.append(r)
    return rows


def _text(args, table, conf, ho, ho_old, ceiling, plans, few) -> str:
    """The section's text."""
    verdict = ("meet" if min(ho[0], ho[1]) >= 85 else "do not meet") + \
        f" the target of 85 % corridor precision and recall on the held-out drawn plans ({ho[0]:.1f} / {ho[1]:.1f}; " \
        f"{ho_old[0]:.1f} / {ho_old[1]:.1f} with the mixed rooms scored as other)"
    return "\n".join([
        "## Room kinds against the floor plans",
        "",
        f"`python benchmarks/kinds.py CORPUS_DIR --per-half {args.per_half}` (the simulated R2V corpus), "
        f"commit `{_commit()}`; {_machine()}.",
        "",
        "Protocol **largest overlap, corridor vs the rest**: each found room is matched to the true room "
        "holding most of its cells; the true room is a *corridor* when its plan labels are `corridor` and "
        "nothing but `entrance`, `stairs` and storage besides, *mixed* when they join a passage label "
        "(`corridor`, `entrance`, `stairs`) to a room's (a hallway that is also the kitchen, a living room "
        "drawn with its hallway), else *other*. Neither kind is wrong for a mixed room: mixed rooms are left "
        "out of the precision and recall (the last column scores them as other, as the tables before did). "
        "**Training** plans (name starting with an even hex byte; this script's own split, not "
        "`plan_split`'s) are the ones the rules and thresholds of `topomap.core.kinds` were chosen on; the "
        "**held-out** plans were scored once with them fixed. "
        f"{args.per_half} plans of each half, each as the drawn plan and as the simulated scan, segmented at "
        "the defaults.",
        "",
        *table,
        "",
        "*The plan's own rooms*: the kind the same rules give each true room from its own cells "
        "(`gt_rooms.png`) and the room graph of the plan's doors (`gt_doors.json`, without the doors to the "
        "outside, which a map's room graph never has), without a segmentation: what the rules can tell on "
        "these plans.",
        "",
        "Every found room of both halves and both variants, by its `room_kind` and its true kind:",
        "",
        *conf,
        "",
        f"The rules {verdict}. The shape alone cannot tell the corridors of these homes: their washrooms, "
        "toilets and balconies are as narrow (about 0.8 to 1.3 m on the mean-width measure) and as long. "
        "The room's place in the room graph separates most of them: a narrow room three or more rooms open "
        "onto is a hallway; one with two doors is a corridor when every route between its two neighbours "
        "passes through it and neither is a dead end (a washroom is the anteroom of its bath), and not when "
        "it opens through doors much wider than itself onto rooms joined otherwise as well (a balcony). What "
        "stays wrong is mostly the segmentation's: a short hallway joined to the room it opens into, or cut "
        "at its entrance into a stub whose front door the room graph does not hold (a corridor with one "
        "door: most of the corridors missed), and washrooms with a third door (most of the rooms wrongly "
        "called corridors have three doors). The scans see fewer doors still. The held-out plans are "
        "harder for the rules before this change as well (corridor precision and recall 43.2 / 43.2 on the "
        "training drawn plans, 28.4 / 33.3 on the held-out ones, under this protocol).",
        "",
        "**How far these measures can go.** The measures of the plans' own rooms (true rooms, the room graph of "
        "the plan's doors, no segmentation), given to a classification tree (Gini splits, leaves of 20 rooms or "
        f"more) fit to the own rooms of all {plans['training']} training plans and scored on those of all "
        f"{plans['held out']} held-out plans; the second run also gives it each room's number of doors to the "
        "outside, which no map's room graph holds:",
        "",
        *ceiling,
        "",
        "Even on the true rooms and doors, no tree on these measures reaches 85 % corridor precision and recall "
        "on the held-out plans. The front door is the strongest clue on these homes (most of their corridors "
        "are the entrance hall), and a map does not show it; with it, recall still stays low: "
        f"{few:.0f} % of the plans' corridors have one door or none in the plan's room graph (the plan draws "
        "their other openings as open boundaries, not doors), so their place in the graph tells nothing. On a "
        "segmentation the rooms and doors are the ones found, and the figures fall further (the tables above).",
        "",
    ])


if __name__ == "__main__":
    main()
