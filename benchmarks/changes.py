"""The default method, commit by commit: one row per change.

Every listed commit is checked out in its own git worktree (the working copy
of this repository is never touched) and run *as it was*: a subprocess with
``PYTHONPATH=<worktree>`` imports that commit's ``topomap``, builds each
benchmark grid the way the floor-plan benchmark always read its maps (free
where the gray value of ``NAME.png`` / ``NAME_furnitures.png`` is >= 250,
occupied everywhere else -- old commits have no other common loader), calls ``segment(grid, method=<that commit's DEFAULT_METHOD>)`` after
one untimed warm-up call, and saves labels, door segments and the wall time
of the ``segment`` call to ``OUT/<commit>/<variant>__<map>.npz``.

All saved results are then scored by *this* checkout's
``topomap.bench.evaluation.evaluate`` exactly as ``topomap.bench.benchmark.run_map``
does (true doors from the unfurnished map in both variants), so every row
uses the same metric. Printed: a Markdown table, per variant the mean over
maps of the Bormann et al. precision and recall (micro, the original
protocol: true rooms whole, segments on the free cells) and of the door F1,
each with its change from the row above, and the median seconds per map.

Usage (from the repository root)::

    python benchmarks/changes.py                     # the default list of commits
    python benchmarks/changes.py --data DIR --commits 8fa33f8,16a3c73,HEAD
    python benchmarks/changes.py --score-only        # re-score saved results
    python benchmarks/changes.py --csv per_map.csv   # also write per-map rows

Runs one commit at a time, maps one after the other in one process (like
``topomap benchmark --jobs 1``). Takes a few minutes per commit.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent

#: Commits that changed the default segmentation, oldest first, with what changed.
CHANGES = [
    ("8fa33f8", "paper method (baseline; default method then: \"paper\")"),
    ("16a3c73", "topomap method: bottleneck candidates with rise test, nearest door posts, "
                "protrusion test"),
    ("680089d", "skeleton graph fix (branch ends without nodes, explicit path start); "
                "vectorised duplicate suppression; one-sided rule \"oneflat\" added but the "
                "default rule is still \"either\""),
    ("680089d:rule=oneflat", "the one-sided rule alone: 680089d's code with rule=\"oneflat\" "
                             "(not a commit; splits df0b655's two changes)"),
    ("df0b655", "free-space skeleton on a 0.1 m grid (and default rule becomes \"oneflat\": delta vs the row above is the skeleton alone)"),
    ("1bd043d", "sparse skeleton graph (speed only)"),
    ("8459fd4", "door posts averaged across the passage; cut cells to the larger neighbour"),
    ("8c9091d", "corridor mouths"),
    ("521b737", "passage_minima look-ahead with running maxima (speed only)"),
    ("4eda052", "corridor mouths only at corridors >= 1 m long opening into a space 2*rise wider; "
                "O(cells) relabel"),
    ("HEAD", "current main"),
]

# Run inside the old commit's code (PYTHONPATH=<worktree>): argv = out_dir, data_dir, names...
_RUNNER = r'''
import gc, inspect, json, os, sys, time
from pathlib import Path
import numpy as np
from PIL import Image
import topomap
from topomap.io import from_array
# the pipeline module was renamed from topomap/segment.py to topomap/segmentation.py;
# choose by the worktree's own files (an editable install of main must not answer)
if os.path.exists(os.path.join(os.environ["PYTHONPATH"], "topomap", "segmentation.py")):
    import topomap.core.segmentation as S
else:
    import topomap.segment as S

out, data = Path(sys.argv[1]), Path(sys.argv[2])
names = sys.argv[3:]
wt = os.environ["PYTHONPATH"]
# (early commits have no topomap/__init__.py: topomap is then a namespace package)
assert os.path.realpath(S.__file__).startswith(os.path.realpath(wt)), S.__file__
method = S.DEFAULT_METHOD
extra = json.loads(os.environ.get("TOPOMAP_CHANGES_PARAMS", "{}"))
info = {"method": method, "segment_file": S.__file__, "extra": extra}
if method == "topomap":
    info["params"] = {k: (p.default if isinstance(p.default, (int, float, str, bool)) else repr(p.default))
                      for k, p in inspect.signature(S.segment_topomap).parameters.items()
                      if p.default is not inspect.Parameter.empty}
    info["params"].update(extra)
free = np.zeros((80, 120), bool)
free[5:75, 5:58] = True
free[5:75, 62:115] = True
free[35:47, 58:62] = True
try:
    S.segment(from_array(free, resolution=0.05), method=method, **extra)   # untimed warm-up
except Exception:
    pass
for variant, suffix in (("unfurnished", ""), ("furnished", "_furnitures")):
    for name in names:
        gray = np.asarray(Image.open(data / f"{name}{suffix}.png").convert("L"), dtype=np.uint8)
        grid = from_array(gray >= 250, resolution=0.05)
        gc.collect()
        t0 = time.perf_counter()
        err = ""
        try:
            seg = S.segment(grid, method=method, **extra)
            runtime = time.perf_counter() - t0
            labels = np.asarray(seg.labels, np.int32)
            doors = np.array([[tuple(d.p1), tuple(d.p2)] for d in seg.doors], float).reshape(-1, 2, 2)
        except Exception as exc:
            runtime = time.perf_counter() - t0
            err = f"{type(exc).__name__}: {exc}"[:300]
            labels = np.zeros(gray.shape, np.int32)
            doors = np.zeros((0, 2, 2))
        np.savez_compressed(out / f"{variant}__{name}.npz", labels=labels, doors=doors,
                            runtime=runtime, error=err, method=method)
        print(f"  {variant:11s} {name:20s} {runtime:7.3f} s  {len(doors):3d} doors {err}", flush=True)
(out / "info.json").write_text(json.dumps(info, indent=1))
'''


def _git(*args, cwd=REPO) -> str:
    return subprocess.run(["git", *args], cwd=cwd, check=True, capture_output=True,
                          text=True).stdout.strip()


def map_names(data: Path) -> list:
    return sorted(p.name[: -len("_gt_segmentation.png")] for p in data.glob("*_gt_segmentation.png"))


def parse_spec(spec: str) -> tuple:
    """``"REF"`` or ``"REF:key=value:key=value"`` -> (ref, {key: value}) (values JSON, else str)."""
    ref, *kvs = spec.split(":")
    params = {}
    for kv in kvs:
        k, _, v = kv.partition("=")
        try:
            params[k] = json.loads(v)
        except ValueError:
            params[k] = v
    return ref, params


def _out_name(short: str, params: dict) -> str:
    return short + "".join(f"_{k}-{v}" for k, v in params.items())


def run_commit(spec: str, data: Path, out_root: Path, wt_root: Path, keep: bool) -> tuple:
    ref, params = parse_spec(spec)
    full = _git("rev-parse", "--verify", f"{ref}^{{commit}}")
    short = full[:7]
    out = out_root / _out_name(short, params)
    if (out / "info.json").is_file():
        print(f"{ref} ({short}): results already in {out}, not rerun", flush=True)
        return short, out
    out.mkdir(parents=True, exist_ok=True)
    wt = wt_root / full
    created = False
    if not (wt / "topomap").is_dir():
        wt_root.mkdir(parents=True, exist_ok=True)
        _git("worktree", "add", "--detach", str(wt), full)
        created = True
    print(f"{ref} ({short}): running in {wt}", flush=True)
    env = dict(os.environ, PYTHONPATH=str(wt), TOPOMAP_CHANGES_PARAMS=json.dumps(params))
    try:
        subprocess.run([sys.executable, "-c", _RUNNER, str(out), str(data), *map_names(data)],
                       env=env, cwd=str(wt), check=True)
    finally:
        if created and not keep:
            _git("worktree", "remove", "--force", str(wt))
    return short, out


def score_commit(out: Path, data: Path) -> list:
    sys.path.insert(0, str(REPO))
    from topomap.bench.datasets import load_benchmark
    from topomap.bench.evaluation import evaluate

    rows = []
    for variant in ("unfurnished", "furnished"):
        for bm in load_benchmark(data, variant=variant):
            f = np.load(out / f"{variant}__{bm.name}.npz")
            doors = [(tuple(a), tuple(b)) for a, b in f["doors"]]
            ev = evaluate(f["labels"], bm.map_gray, bm.gt_gray, pred_doors=doors,
                          resolution=bm.resolution, door_map_gray=bm.unfurnished_gray)
            rows.append({"variant": variant, "map": bm.name, "precision": float(ev["precision"]),
                         "recall": float(ev["recall"]), "door_f1": float(ev["door_f1"]),
                         "n_doors": len(doors), "runtime_s": float(f["runtime"]),
                         "error": str(f["error"])})
    return rows


def summary(rows: list, variant: str) -> dict:
    r = [x for x in rows if x["variant"] == variant]
    mean = lambda k: 100 * float(np.nanmean([x[k] for x in r]))  # noqa: E731
    return {"P": mean("precision"), "R": mean("recall"), "F": mean("door_f1"),
            "t": float(np.median([x["runtime_s"] for x in r])), "n": len(r),
            "failed": sum(bool(x["error"]) for x in r)}


def _cell(v, prev):
    if prev is None or math.isnan(prev):
        return f"{v:.1f}"
    d = v - prev
    return f"{v:.1f} ({'±0.0' if abs(d) < 0.05 else f'{d:+.1f}'})"


def table(results: list) -> str:
    lines = ["P / R: Bormann et al., original protocol (true rooms whole; segments on the free "
             "cells; segments and rooms of <= 100 cells ignored).", "",
             "| commit | what changed | method | unfurnished P (%) | R (%) | door F1 (%) "
             "| furnished P (%) | R (%) | door F1 (%) | median s/map (unf. / furn.) |",
             "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    prev = None
    for short, what, method, rows in results:
        s = {v: summary(rows, v) for v in ("unfurnished", "furnished")}
        cells = []
        for v in ("unfurnished", "furnished"):
            for k in ("P", "R", "F"):
                cells.append(_cell(s[v][k], None if prev is None else prev[v][k]))
        failed = s["unfurnished"]["failed"] + s["furnished"]["failed"]
        note = f" ({failed} maps failed)" if failed else ""
        lines.append(f"| {short} | {what}{note} | {method} | " + " | ".join(cells)
                     + f" | {s['unfurnished']['t']:.2f} / {s['furnished']['t']:.2f} |")
        prev = s
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", type=Path, default=None,
                    help="benchmark directory (default: topomap.bench.datasets.benchmark_dir())")
    ap.add_argument("--commits", default=",".join(c for c, _ in CHANGES),
                    help="comma-separated commits, oldest first (default: every change of the default method)")
    ap.add_argument("--out", type=Path, default=Path("/tmp/wt_out"), help="where results are saved")
    ap.add_argument("--worktrees", type=Path, default=Path("/tmp/wt"), help="where worktrees are created")
    ap.add_argument("--keep-worktrees", action="store_true", help="do not remove the worktrees afterwards")
    ap.add_argument("--score-only", action="store_true", help="only score results already saved")
    ap.add_argument("--csv", type=Path, default=None, help="also write the per-map rows here")
    a = ap.parse_args(argv)

    sys.path.insert(0, str(REPO))
    if a.data is None:
        from topomap.bench.datasets import benchmark_dir
        a.data = Path(benchmark_dir())
    data = a.data.resolve()
    what = dict(CHANGES)
    results, per_map = [], []
    for spec in [c.strip() for c in a.commits.split(",") if c.strip()]:
        ref, params = parse_spec(spec)
        if a.score_only:
            short = _git("rev-parse", "--short=7", f"{ref}^{{commit}}")
            out = a.out / _out_name(short, params)
        else:
            short, out = run_commit(spec, data, a.out, a.worktrees, a.keep_worktrees)
        info = json.loads((out / "info.json").read_text())
        rows = score_commit(out, data)
        label = what.get(spec, what.get(ref, what.get(short, _git("log", "-1", "--format=%s", short))))
        if params and spec not in what:
            label = f"{label}; run with " + ", ".join(f"{k}={v!r}" for k, v in params.items())
        method = info["method"]
        if method == "topomap" and "rule" in info.get("params", {}):
            method += f" (rule {info['params']['rule']})"
        shown = f"`{short}`" + "".join(f" + {k}={v}" for k, v in params.items())
        results.append((shown, label, method, rows))
        per_map += [dict(commit=_out_name(short, params), **r) for r in rows]
    print()
    print(f"# scored with topomap.bench.evaluation at {_git('rev-parse', '--short=7', 'HEAD')}; data {data}")
    print(table(results))
    if a.csv:
        with open(a.csv, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(per_map[0]))
            w.writeheader()
            w.writerows(per_map)
    return 0


if __name__ == "__main__":
    sys.exit(main())
