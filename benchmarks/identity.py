"""Room identities along exploration runs: do rooms keep their IDs as the map grows?

On each exploration sequence of the real maps (ROSE² data: freiburg079_partial_02..15,
bremen_cartesium_partial_03..17, each map a later state of the same run), every map
is segmented three ways: ``topomap.segment(grid, previous=...)`` with the previous
map's result (its doors are a prior of the door stage, ``topomap.core.identity.DoorPrior``,
then its rooms' IDs are given by ``topomap.core.identity.match_rooms``); a fresh
``topomap.segment(grid)`` whose rooms are matched to the previous map's
(``match_rooms`` only); and fresh numbering. A ground-truth room present in two
consecutive maps (the same true room: one-to-one, overlapping by at least half of
the smaller in the map frame, both over 100 cells) *keeps its ID* when the topomap
room covering most of it carries the same ID in both maps; an ID change is
*explained* when the change record links the two IDs (a split or a merge); an ID
change *between two kept rooms* is one where both rooms are in both maps (a
boundary moved and the true room's larger share with it). The
room F1 (harmonic mean of the mean precision and recall over the maps, free cells
scored, :func:`topomap.bench.evaluation.score_segmentation`) shows what the segmentation
gives up for steadier doors.

The data set's YAML files give every map the origin (0, 0), although the Bremen
images were cropped anew as the map grew (the building shifts by up to 248 cells
between two maps). The script recovers each map's origin the way a SLAM map's
own origin would give it: the whole-cell shift that best aligns its free cells
with the previous map's (FFT cross-correlation), chained along the sequence.

    python benchmarks/identity.py [REAL_DIR] [--out benchmarks/sections/70_identity.md]
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

SEQUENCES = {"freiburg079": ("freiburg079_partial_%02d", range(2, 16)),
             "bremen_cartesium": ("bremen_cartesium_partial_%02d", range(3, 18))}
MIN_GT_CELLS = 100


def shift(prev_free, free):
    """``(dr, dc)``: ``free[r + dr, c + dc]`` best matches ``prev_free[r, c]`` (whole cells)."""
    from scipy.signal import fftconvolve

    c = fftconvolve(free.astype(np.float32), prev_free[::-1, ::-1].astype(np.float32), mode="full")
    r, k = np.unravel_index(int(np.argmax(c)), c.shape)
    return int(r - (prev_free.shape[0] - 1)), int(k - (prev_free.shape[1] - 1))


def aligned(grid, prev_grid, prev_free):
    """``grid`` with its origin moved so that its free cells fall on ``prev_grid``'s."""
    from topomap.io import OccupancyGrid

    dr, dc = shift(prev_free, grid.free)
    x0, y0 = prev_grid.pixel_to_world(0, 0)   # prev cell (0, 0) ...
    x1, y1 = grid.pixel_to_world(dr, dc)      # ... is this cell of the new map
    ox, oy, yaw = grid.origin
    return OccupancyGrid(grid.cells, grid.resolution, (ox + x0 - x1, oy + y0 - y1, yaw), grid.source, grid.gray)


def gt_pairs(gt0, grid0, gt1, grid1):
    """``[(g0, g1)]``: true rooms of two maps that are the same room (one-to-one)."""
    from scipy.optimize import linear_sum_assignment

    rr, cc = np.nonzero(gt1)
    x, y = grid1.pixel_to_world(rr, cc)
    r0, c0 = grid0.world_to_pixel(x, y)
    r0, c0 = np.rint(r0).astype(int), np.rint(c0).astype(int)
    ok = (r0 >= 0) & (r0 < gt0.shape[0]) & (c0 >= 0) & (c0 < gt0.shape[1])
    a = np.zeros(rr.shape, np.int64)
    a[ok] = gt0[r0[ok], c0[ok]]
    b = gt1[rr, cc].astype(np.int64)
    n0, n1 = np.bincount(gt0.ravel()), np.bincount(gt1.ravel())
    ids0 = [i for i in range(1, n0.size) if n0[i] > MIN_GT_CELLS]
    ids1 = [i for i in range(1, n1.size) if n1[i] > MIN_GT_CELLS]
    O = np.zeros((len(ids0), len(ids1)))
    i0, i1 = {g: k for k, g in enumerate(ids0)}, {g: k for k, g in enumerate(ids1)}
    m = a > 0
    pairs, cnt = np.unique(np.stack([a[m], b[m]]), axis=1, return_counts=True)
    for (g, h), k in zip(pairs.T, cnt):
        if g in i0 and h in i1 and k >= 0.5 * min(n0[g], n1[h]):
            O[i0[g], i1[h]] = k
    rows, cols = linear_sum_assignment(O, maximize=True)
    return [(ids0[r], ids1[c]) for r, c in zip(rows, cols) if O[r, c] > 0]


def room_of(labels, top, gt, g):
    """The room label (<= ``top``) covering most of true room ``g`` (0: none)."""
    v = labels[gt == g]
    v = v[(v > 0) & (v <= top)]
    return int(np.bincount(v).argmax()) if v.size else 0


def _score(seg, gt, grid):
    """``(precision, recall)`` of ``seg``'s rooms against the ground truth (free cells scored)."""
    from topomap.bench.evaluation import score_segmentation

    sc = score_segmentation(seg.room_labels, gt, scored=grid.free)
    return sc["precision"], sc["recall"]


def _chain_step(st, pre, prev, seg, ch, prev_gt, prev_grid, gt, grid):
    """Add one map pair of one chain (``pre``: its key prefix) to the counts ``st``."""
    st[pre + "pairs"] += 1
    for k in ("new", "vanished", "split", "merged"):
        st[pre + k] += len(getattr(ch, k))
    ids0, ids1 = set(np.unique(prev.room_labels)) - {0}, set(np.unique(seg.room_labels)) - {0}
    for g0, g1 in gt_pairs(prev_gt, prev_grid, gt, grid):
        a = room_of(prev.labels, prev.top_room_id, prev_gt, g0)
        b = room_of(seg.labels, seg.top_room_id, gt, g1)
        st[pre + "gt"] += 1
        if not a or not b:
            st[pre + "uncovered"] += 1
        elif a == b:
            st[pre + "kept"] += 1
        else:
            st[pre + "changed"] += 1
            st[pre + "explained"] += int(ch.explains(a, b))
            # the true room moved from one room to another and both rooms are
            # in both maps (a boundary moved: no room changed its ID)
            st[pre + "moved"] += int(a in ids1 and b in ids0)


CHAIN_KEYS = ("pairs", "gt", "kept", "changed", "explained", "moved", "uncovered", "new", "vanished", "split",
              "merged",
              "precision", "recall")


def run_sequence(directory, name):
    """Counts of one sequence for three numberings: ``prior_`` (``segment(grid,
    previous=...)``: the previous doors are a prior of the door stage, then the
    rooms are matched), ``match_`` (each map segmented afresh, its rooms matched
    to the previous map's: ``match_rooms``) and fresh numbering."""
    import topomap
    from PIL import Image
    from topomap.core.identity import match_rooms

    pattern, rng = SEQUENCES[name]
    st = dict(sequence=name, maps=0, fresh_kept=0, fresh_n=0, t_segment=0.0, t_prior=0.0, t_match=0.0,
              fresh_precision=0.0, fresh_recall=0.0)
    for pre in ("prior_", "match_"):
        st.update({pre + k: 0 for k in CHAIN_KEYS})
    prior = match = fresh0 = prev_grid = prev_gt = None
    for i in rng:
        stem = pattern % i
        grid = topomap.load_map(Path(directory) / f"{stem}.yaml")
        gt = np.array(Image.open(Path(directory) / f"{stem}_gt.png")).astype(np.int64)
        if prev_grid is not None:
            grid = aligned(grid, prev_grid, prev_grid.free)
        t0 = time.perf_counter()
        fresh = topomap.segment(grid)
        t1 = time.perf_counter()
        st["t_segment"] += t1 - t0
        st["maps"] += 1
        p, r = _score(fresh, gt, grid)
        st["fresh_precision"] += p
        st["fresh_recall"] += r
        if prior is None:
            new_prior = new_match = fresh
            st["prior_precision"] += p
            st["prior_recall"] += r
            st["match_precision"] += p
            st["match_recall"] += r
        else:
            new_prior = topomap.segment(grid, previous=prior)
            t2 = time.perf_counter()
            new_match, ch_m = match_rooms(match, fresh)
            st["t_prior"] += t2 - t1
            st["t_match"] += time.perf_counter() - t2
            _chain_step(st, "prior_", prior, new_prior, new_prior.changes, prev_gt, prev_grid, gt, grid)
            _chain_step(st, "match_", match, new_match, ch_m, prev_gt, prev_grid, gt, grid)
            for pre, seg in (("prior_", new_prior), ("match_", new_match)):
                p, r = _score(seg, gt, grid)
                st[pre + "precision"] += p
                st[pre + "recall"] += r
            for g0, g1 in gt_pairs(prev_gt, prev_grid, gt, grid):
                a = room_of(fresh0.labels, fresh0.n_rooms, prev_gt, g0)
                b = room_of(fresh.labels, fresh.n_rooms, gt, g1)
                if a and b:
                    st["fresh_n"] += 1
                    st["fresh_kept"] += int(a == b)
        prior, match, fresh0, prev_grid, prev_gt = new_prior, new_match, fresh, grid, gt
    return st


def _pct(a, b):
    return f"{100 * a / b:.1f}" if b else "–"


def _f1(st, pre):
    p, r = st[pre + "precision"] / st["maps"], st[pre + "recall"] / st["maps"]
    return f"{100 * 2 * p * r / (p + r):.1f}" if p + r else "–"


def table(stats):
    """The Markdown table: one row per sequence and numbering, then the totals."""
    lines = ["| sequence | numbering | maps | GT rooms in two consecutive maps | keep their ID % "
             "| ID changes | explained by the change record % | of them between two kept rooms "
             "| new / vanished / split / merged (record) | room F1 % (mean over maps) | s |",
             "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | --- | ---: | ---: |"]
    tot = {k: 0 for k in stats[0] if k != "sequence"}
    for st in stats + [None]:
        if st is None:
            st = dict(tot, sequence="**all**")
        else:
            for k in tot:
                tot[k] += st[k]
        for pre, what in (("prior_", "previous doors kept (`previous=`)"), ("match_", "matched only"),
                          ("fresh_", "fresh")):
            if pre == "fresh_":
                lines.append(f"| {st['sequence']} | {what} | {st['maps']} | {st['fresh_n']} "
                             f"| {_pct(st['fresh_kept'], st['fresh_n'])} | | | | | {_f1(st, pre)} "
                             f"| {st['t_segment']:.1f} |")
                continue
            n = st[pre + "gt"] - st[pre + "uncovered"]
            lines.append(f"| {st['sequence']} | {what} | {st['maps']} | {n} | {_pct(st[pre + 'kept'], n)} "
                         f"| {st[pre + 'changed']} | {_pct(st[pre + 'explained'], st[pre + 'changed'])} "
                         f"| {st[pre + 'moved']} | {st[pre + 'new']} / {st[pre + 'vanished']} / {st[pre + 'split']} / "
                         f"{st[pre + 'merged']} | {_f1(st, pre)} | {st['t_' + pre[:-1]]:.1f} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = _section.parser(__doc__, "real maps directory", "70_identity.md")
    ap.add_argument("--jobs", type=int, default=1, help="run the two sequences in this many processes")
    args = ap.parse_args(argv)
    from topomap.bench.datasets import real_maps_dir

    directory = _section.directory(args.directory, real_maps_dir, "TOPOMAP_REAL_MAPS_DIR")
    t0 = time.perf_counter()
    load0 = os.getloadavg()[0]
    if args.jobs > 1:
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(min(args.jobs, len(SEQUENCES))) as ex:
            stats = list(ex.map(run_sequence, [directory] * len(SEQUENCES), list(SEQUENCES)))
    else:
        stats = [run_sequence(directory, name) for name in SEQUENCES]
    wall = time.perf_counter() - t0
    tab = table(stats)
    text = f"""## Room identities along exploration runs

`python benchmarks/identity.py REAL_DIR --jobs {args.jobs}` (commit `{_commit()}`; {_machine()}; load average {load0:.1f} at the start;
{wall:.0f} s wall time).

Each exploration sequence of the real maps (ROSE² data; every map a later state of the same
run) segmented map by map, three ways: *previous doors kept* is `topomap.segment(grid,
previous=...)` with the previous map's result (the previous doors are a prior of the door
stage, then the rooms get the previous IDs); *matched only* segments every map afresh and
gives its rooms the previous map's IDs (`topomap.core.identity.match_rooms`); *fresh* numbers rooms
by a row-major scan. A ground-truth room present in two consecutive maps
(the same true room: overlapping by at least half of the smaller in the map frame, both over
100 cells) *keeps its ID* when the room covering most of it has the same ID in both maps. An ID change
is *explained* when the change record links the two IDs (a split or a merge); "between two
kept rooms" counts the ID changes where both rooms are in both maps (the true room's larger
share moved from one room to the other: a boundary moved, no room changed its ID, and the
record has nothing to explain); the column "new / vanished / split / merged" counts the change
records' entries over the sequence. The
room F1 is the harmonic mean of the rooms' precision and recall against the ground truth (the
Bormann et al. metric, free cells scored), each the mean over the sequence's maps; "s" the
seconds of the sequence's runs (*matched only*: the matching after the fresh runs). The data set's YAML files give every map the origin
(0, 0) although the images were cropped anew as the map grew; the script recovers each map's
origin by aligning its free cells with the previous map's (a whole-cell shift), as a SLAM
map's own origin would.

{tab}"""
    _section.write(args.out, text, tab, wall)

if __name__ == "__main__":
    main()
