"""Regenerate docs/benchmarks.md from one run of the benchmark.

    python benchmarks/report.py --ipa IPA_DIR --real REAL_DIR --out-dir results/ > docs/benchmarks.md

runs ``topomap.bench.benchmark.run_benchmark`` once on the ipa_room_segmentation
maps (both variants) and once on the labelled real maps (ROSE² data), saves
the per-map rows (``ipa.csv``, ``real.csv``) and the run's metadata
(``meta.json``: command, commit, machine, times, load) in ``--out-dir``,
and prints the whole page as Markdown. ``--from-csv`` re-renders the page
from a saved run without running anything; ``--from-csv --readme-table``
prints the README's headline table from it. Every figure on the page comes
from that one run, except the reference figures of other methods, which are
quoted from their sources and labelled with their protocol.
"""

from __future__ import annotations

import argparse
import csv
import datetime as _dt
import json
import math
import os
import platform
import subprocess
import sys
from pathlib import Path

import numpy as np

from topomap.bench.benchmark import format_table, run_benchmark, write_rows
from topomap.bench.datasets import VARIANTS, benchmark_dir, real_maps_dir

IPA_METHODS = "topomap,paper,voronoi,watershed,morphological,distance"
REAL_METHODS = "topomap,paper"

#: Reference figures on the ipa_room_segmentation maps, ORIGINAL protocol
#: (P / R in %, unfurnished then furnished), as distributed with the copy of
#: the data set used here: the C++ ipa_room_segmentation methods and a
#: scikit-image watershed run on the same 14 maps.
IPA_REFERENCE = [
    ("ipa_room_segmentation Voronoi (C++)", (96.0, 94.6), (95.8, 86.4)),
    ("ipa_room_segmentation morphological (C++)", (89.8, 97.3), (91.2, 86.0)),
    ("ipa_room_segmentation distance (C++)", (90.4, 96.3), (90.7, 75.4)),
    ("watershed on the distance transform (scikit-image)", (98.8, 84.2), (98.1, 54.7)),
]
#: Published on all 20 maps of the data set, each with its own evaluation.
IPA_PUBLISHED = [
    ("Mora et al., the paper's method (its Tables 1, 2)", "published, 20 maps, its own evaluation",
     (89.3, 82.1), (83.9, 70.2)),
    ("ROSE² (Luperto et al. 2022)", "published, 19 maps, its own evaluation",
     (93.3, 97.6), (93.5, 91.0)),
]
#: ROSE²'s stored results on its own maps, its own evaluation (free cells,
#: no 100-cell rule), mean P / R in %.
REAL_GROUPS = [
    ("freiburg079_partial_*", "freiburg079_partial_*", (90.4, 97.1)),
    ("bremen_cartesium_partial_*", "bremen_cartesium_partial_*", (80.4, 94.3)),
    ("freiburg079_full", "freiburg079_full", (95.5, 99.6)),
    ("bremen_cartesium_full", "bremen_cartesium_full", (87.8, 89.6)),
]


def _git(*args) -> str:
    try:
        return subprocess.run(["git", *args], capture_output=True, text=True, check=True,
                              cwd=Path(__file__).resolve().parent).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def _machine() -> dict:
    cpu = platform.processor() or platform.machine()
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import numpy, scipy, skimage  # noqa: E401  (versions only)

    return {"cpu": cpu, "cpus": os.cpu_count(), "python": platform.python_version(),
            "os": f"{platform.system()} {platform.release()}",
            "numpy": numpy.__version__, "scipy": scipy.__version__,
            "scikit-image": skimage.__version__}


def _load() -> str:
    try:
        return " ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:
        return "unknown"


def _progress(done, total, row):
    print(f"\r{done}/{total} {row['method']} {row['variant']} {row['map']}      ",
          end="", file=sys.stderr, flush=True)


def run(args) -> dict:
    """Run both data sets once; save rows and metadata; return the metadata."""
    out = Path(args.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    dirty = _git("status", "--porcelain", "--", "topomap")
    meta = {"command": "python benchmarks/report.py " + " ".join(_argv_for_page(args)),
            "commit": _git("rev-parse", "--short", "HEAD"),
            "topomap_changes_uncommitted": bool(dirty and dirty != "unknown"),
            "machine": _machine(), "start": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
            "load_before": _load()}
    if args.ipa:
        rows = run_benchmark(args.ipa, methods=args.methods, variants=VARIANTS, progress=_progress)
        write_rows(rows, out / "ipa.csv")
    if args.real:
        rows = run_benchmark(args.real, methods=args.real_methods, progress=_progress)
        write_rows(rows, out / "real.csv")
    print(file=sys.stderr)
    meta.update(end=_dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
                load_after=_load())
    (out / "meta.json").write_text(json.dumps(meta, indent=1) + "\n")
    return meta


def _argv_for_page(args) -> list:
    """The command line, with the data directories as placeholders (no machine paths)."""
    argv = []
    if args.ipa:
        argv += ["--ipa", "IPA_DIR"]
    if args.real:
        argv += ["--real", "REAL_DIR"]
    if args.methods != IPA_METHODS:
        argv += ["--methods", args.methods]
    if args.real_methods != REAL_METHODS:
        argv += ["--real-methods", args.real_methods]
    return argv + ["--out-dir", "results/"]


def _read(path) -> list:
    if not Path(path).is_file():
        return []
    return list(csv.DictReader(open(path, newline="")))


def _f(v) -> float:
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


def _mean(rows, key) -> float:
    vals = [_f(r.get(key)) for r in rows if not r.get("error")]
    vals = [v for v in vals if np.isfinite(v)]
    return float(np.mean(vals)) if vals else math.nan


def _pr(rows, kp="precision", kr="recall") -> str:
    p, r = _mean(rows, kp), _mean(rows, kr)
    if not (np.isfinite(p) and np.isfinite(r)):
        return "–"
    return f"{100 * p:.1f} / {100 * r:.1f}"


def _by(rows, **kw) -> list:
    return [r for r in rows if all(r.get(k) == v for k, v in kw.items())]


def _methods(rows) -> list:
    return list(dict.fromkeys(r["method"] for r in rows))


def _header(meta) -> str:
    m = meta["machine"]
    dirty = " (with uncommitted changes to `topomap/`)" if meta.get("topomap_changes_uncommitted") else ""
    return f"""# Benchmarks

Every figure on this page comes from **one run** of

```sh
{meta["command"]} > docs/benchmarks.md
```

(`IPA_DIR`: the `ipa_room_segmentation` maps of Bormann et al. 2016;
`REAL_DIR`: the labelled real maps of ROSE², Luperto et al. 2022; neither
is shipped with topomap. The script runs `topomap.bench.benchmark.run_benchmark`,
the code behind `topomap benchmark`, saves the per-map rows in `results/`
and prints this page; `--from-csv` re-renders it from saved rows.) The
only other figures are other methods' reference figures, quoted from their
sources and labelled with the protocol they were measured with, and the
sections after the real maps' (method changes, speed of the whole job,
batches, room identities, tours), each written by its own script in
`benchmarks/` with its command and the commit it measured.

- Code: commit `{meta["commit"]}`{dirty}.
- Run: {meta["start"]} to {meta["end"]} (UTC); load average before
  {meta["load_before"]}, after {meta["load_after"]}.
- Machine: {m["cpu"]}, {m["cpus"]} CPUs, {m["os"]}; Python {m["python"]}, numpy
  {m["numpy"]}, scipy {m["scipy"]}, scikit-image {m["scikit-image"]}.
- Timings: one process, maps one after another, every method on a map
  before the next map, after one untimed warm-up call per method. A runtime
  is `load_map` + `segment` for one map (the job of `topomap segment`
  without writing the outputs). The machine may be shared with other jobs:
  runtimes vary by 10-30 % between runs; compare methods within one table.

## How the maps are read and scored

Each map is loaded exactly as a user loads it with the command line:
`topomap segment NAME.png --resolution 0.05` for the `ipa_room_segmentation`
maps (bare images: free where gray >= 250, gray 205 unknown, every other
gray occupied -- see "Inputs" in [Getting started](getting-started.md)) and
`topomap segment NAME.yaml` for the real maps (map_server thresholds of the
YAML). The labels scored are the labels the command writes.

Precision P and recall R are those of Bormann et al. (2016): P = mean over
predicted segments of the share of the segment inside its best-matching
true room; R = mean over true rooms of the share of the room covered by its
best-matching segment. Two protocols:

- **original** (the headline; the protocol of the original evaluation code,
  `EvaluationSegmentation::computePrecisionRecall` of ipa_room_segmentation,
  and of the published figures on those maps): true rooms are kept whole,
  furniture included; segments are restricted to the cells the method was
  given (the free cells of the map as loaded).
- **free-cells**: true rooms are restricted to those cells too (the
  protocol of ROSE²'s evaluation of its real maps).

In both, segments and rooms of 100 cells or fewer are ignored. The
**ceiling** is the ground truth itself scored under each protocol: the best
any method can reach (under the original protocol no method can label the
furniture, so even a perfect segmentation loses recall on furnished maps).
**Rooms found / true** counts every room a method reports (the room graph's nodes; fragments are not counted; the
rooms a user sees) against the true rooms of more than 100
cells.
"""


def _ipa_reference(rows) -> str:
    lines = ["| method | source | unfurnished P / R | furnished P / R |", "| --- | --- | --- | --- |"]
    for name, unf, furn in IPA_REFERENCE:
        lines.append(f"| {name} | reference run, 14 maps, original protocol "
                     f"| {unf[0]:.1f} / {unf[1]:.1f} | {furn[0]:.1f} / {furn[1]:.1f} |")
    for name, source, unf, furn in IPA_PUBLISHED:
        lines.append(f"| {name} | {source} "
                     f"| {unf[0]:.1f} / {unf[1]:.1f} | {furn[0]:.1f} / {furn[1]:.1f} |")
    for m in _methods(rows):
        unf, furn = _by(rows, method=m, variant="unfurnished"), _by(rows, method=m, variant="furnished")
        lines.append(f"| topomap `{m}` | this run, 14 maps, original protocol | {_pr(unf)} | {_pr(furn)} |")
    lines.append(f"| ground truth itself (ceiling) | this run, 14 maps, original protocol "
                 f"| {_pr(_by(rows, variant='unfurnished'), 'ceiling_precision', 'ceiling_recall')} "
                 f"| {_pr(_by(rows, variant='furnished'), 'ceiling_precision', 'ceiling_recall')} |")
    return "\n".join(lines) + "\n"


def _per_map(rows, variant, free=False) -> str:
    """One line per map: true rooms, ceiling R, then P / R (rooms found) per method."""
    kp, kr = ("precision_free", "recall_free") if free else ("precision", "recall")
    ck = "ceiling_recall_free" if free else "ceiling_recall"
    methods = _methods(rows)
    vr = _by(rows, variant=variant)
    names = list(dict.fromkeys(r["map"] for r in vr))
    head = "| map | true rooms | ceiling R | " + " | ".join(f"{m} P / R (rooms)" for m in methods) + " |"
    lines = [head, "| --- | ---: | ---: |" + " ---: |" * len(methods)]
    for n in names:
        first = _by(vr, map=n)[0]
        cells = []
        for m in methods:
            (r,) = _by(vr, map=n, method=m)
            cells.append("failed" if r.get("error") else
                         f"{100 * _f(r[kp]):.1f} / {100 * _f(r[kr]):.1f} ({int(_f(r['n_rooms']))})")
        lines.append(f"| {n} | {int(_f(first['n_true_rooms']))} | {100 * _f(first[ck]):.1f} | "
                     + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _ipa_section(rows) -> str:
    out = ["## ipa_room_segmentation: 14 floor plans, unfurnished and furnished\n",
           format_table(rows),
           "\n### Against reference figures (original protocol)\n",
           "Mean P / R in %. The reference run's figures come with the copy of the data set "
           "used here (same 14 maps, same original protocol, the methods' own code). The "
           "published figures are on all (ROSE²: 19) of the 20 maps of the data set, each "
           "with its authors' own evaluation, so they compare only roughly.\n",
           _ipa_reference(rows)]
    for v in VARIANTS:
        out += [f"\n### Per map, {v} (original protocol)\n",
                "P / R in %, rooms = rooms the method reports (room-graph nodes). Segments and rooms "
                "of <= 100 cells are ignored in P and R, not in the room count.\n",
                _per_map(rows, v)]
    return "\n".join(out)


def _real_groups(rows) -> str:
    import fnmatch

    methods = _methods(rows)
    head = ("| maps | n | ROSE² (its evaluation) | "
            + " | ".join(f"{m} free P / R | {m} original P / R | {m} rooms found / true" for m in methods)
            + " |")
    lines = [head, "| --- | ---: | --- |" + " --- | --- | ---: |" * len(methods)]
    for label, pat, ref in REAL_GROUPS:
        g = [r for r in rows if fnmatch.fnmatch(r["map"], pat)]
        if not g:
            continue
        n = len({r["map"] for r in g})
        cells = []
        for m in methods:
            gm = _by(g, method=m)
            found = sum(int(_f(r["n_rooms"])) for r in gm if not r.get("error"))
            true = sum(int(_f(r["n_true_rooms"])) for r in gm if not r.get("error"))
            cells.append(f"{_pr(gm, 'precision_free', 'recall_free')} | {_pr(gm)} | {found} / {true}")
        lines.append(f"| `{label}` | {n} | {ref[0]:.1f} / {ref[1]:.1f} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _real_section(rows) -> str:
    return "\n".join([
        "\n## Real SLAM maps with ground truth (ROSE² data)\n",
        "31 laser-SLAM maps of two buildings (noisy, cluttered, partly explored), read through "
        "their map_server YAML (free where gray > 230) and scored against their label images "
        "on the map's free cells.\n",
        format_table(rows),
        "\n### Per group, against ROSE²\n",
        "Mean P / R in %. ROSE²'s figures are its stored results with its own evaluation: free "
        "cells, like the free-cells protocol here but without the 100-cell rule. Compare them "
        "with the free-cells columns.\n",
        _real_groups(rows),
        "\n### Per map (free-cells protocol)\n",
        _per_map(rows, "map", free=True)])


def render(meta, ipa_rows, real_rows) -> str:
    """The whole page."""
    parts = [_header(meta)]
    if ipa_rows:
        parts.append(_ipa_section(ipa_rows))
    if real_rows:
        parts.append(_real_section(real_rows))
    parts.extend(_sections())
    return "\n".join(parts)


#: Sections written by the other benchmark scripts (speed of the whole job,
#: batches, room identities, ...): each script writes its own Markdown file
#: here, with its command and commit, and the page includes them in name order.
SECTIONS_DIR = Path(__file__).resolve().parent / "sections"


def _sections() -> list:
    """The other scripts' saved sections, in file-name order."""
    if not SECTIONS_DIR.is_dir():
        return []
    return ["\n" + p.read_text(encoding="utf-8").strip() + "\n"
            for p in sorted(SECTIONS_DIR.glob("*.md"))]


def readme_table(rows) -> str:
    """The README's headline table: default method and paper method, ipa maps, original protocol."""
    lines = ["| method | variant | P / R (original) | ceiling P / R | P / R (free-cells) "
             "| rooms found / true |", "| --- | --- | --- | --- | --- | ---: |"]
    for m in ("topomap", "paper"):
        for v in VARIANTS:
            g = [r for r in _by(rows, method=m, variant=v) if not r.get("error")]
            if not g:
                continue
            found = sum(int(_f(r["n_rooms"])) for r in g)
            true = sum(int(_f(r["n_true_rooms"])) for r in g)
            lines.append(f"| `{m}` | {v} | {_pr(g)} | {_pr(g, 'ceiling_precision', 'ceiling_recall')} "
                         f"| {_pr(g, 'precision_free', 'recall_free')} | {found} / {true} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--ipa", type=Path, default=None,
                    help="ipa_room_segmentation maps (default: topomap.bench.datasets.benchmark_dir())")
    ap.add_argument("--real", type=Path, default=None,
                    help="labelled real maps (default: topomap.bench.datasets.real_maps_dir())")
    ap.add_argument("--methods", default=IPA_METHODS, help=f"ipa methods (default {IPA_METHODS})")
    ap.add_argument("--real-methods", default=REAL_METHODS,
                    help=f"real-map methods (default {REAL_METHODS})")
    ap.add_argument("--out-dir", type=Path, default=Path("results"),
                    help="where the rows and metadata go (default results/)")
    ap.add_argument("--from-csv", action="store_true",
                    help="render the page from the rows saved in --out-dir; run nothing")
    ap.add_argument("--readme-table", action="store_true",
                    help="print the README's headline table (from the saved rows) instead of the page")
    args = ap.parse_args(argv)
    args.ipa = args.ipa or benchmark_dir()
    args.real = args.real or real_maps_dir()
    if not args.from_csv:
        if args.ipa is None and args.real is None:
            ap.error("no data set found: give --ipa and/or --real")
        run(args)
    if args.readme_table:
        sys.stdout.write(readme_table(_read(args.out_dir / "ipa.csv")))
        return 0
    meta = json.loads((args.out_dir / "meta.json").read_text())
    sys.stdout.write(render(meta, _read(args.out_dir / "ipa.csv"), _read(args.out_dir / "real.csv")))
    return 0


if __name__ == "__main__":
    sys.exit(main())
