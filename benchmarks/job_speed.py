#!/usr/bin/env python
"""The whole job: ``topomap segment`` with all its outputs against a plain watershed job.

Run (not a test)::

    python benchmarks/job_speed.py [DATASET_DIR] [--rounds 3] [--variant both]
    python benchmarks/job_speed.py [DATASET_DIR] --quick      # one round, no scaling cases

Every job is a fresh subprocess given all maps at once, as a user runs it:

* ``topomap``: ``topomap segment MAPS... -o OUT --resolution 0.05 --profile``
  (default outputs: labels.png, rooms.graphml, rooms.json, rooms.geojson,
  overlay.png, with travel distances);
* ``watershed``: a plain script (this file with ``--_job watershed``): per
  map ``topomap.load_map``, :func:`scipy.ndimage.distance_transform_edt`,
  markers from :func:`skimage.feature.peak_local_max` (1.75 m apart, as
  :func:`topomap.core.baselines.watershed`), :func:`skimage.segmentation.watershed`
  on ``-dist``, a 16-bit label PNG written with Pillow;
* ``floor`` (the physical floor): per map ``topomap.load_map``, one OpenCV
  distance transform, the 16-bit PNG of the connected components written.

The topomap and watershed jobs alternate, ``--rounds`` times; reported: each
job's wall time per round, the ratio of the totals (median over the rounds)
and of the per-map medians (per-map time from loading to the last file, as
each job reports it), and the peak memory of each job (``ru_maxrss`` of
the child, from ``os.wait4``). Then ``--profile`` of the largest map, stage
by stage; how each stage grows with the area (``--growth-map`` upsampled
1x/2x/4x with ``np.kron``, resolution divided accordingly); and the 25 M-cell
synthetic building of ``benchmarks/speed.py --scaling`` (the example office
tiled 15 x 15), whole command, time and peak memory. Writes
``benchmarks/sections/50_job_speed.md`` (``--section`` to change) and prints it.

DATASET_DIR defaults to :func:`topomap.bench.datasets.benchmark_dir`.
"""

from __future__ import annotations

import argparse
import glob
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

# PIL and topomap are imported inside the functions that use them: this file is also the child process of
# the comparison jobs (``--_job``), which times its own imports.

HERE = Path(__file__).resolve().parent
SECTION = HERE / "sections" / "50_job_speed.md"
SYNTH_TILES = (15, 15)


# --------------------------------------------------------------------------
# the comparison jobs (run in a child process: --_job NAME OUT RES MAPS...)
# --------------------------------------------------------------------------

def _job(kind, out, res, maps):
    # the imports are the job's "import" stage: made here, timed
    t_start = time.perf_counter()
    import numpy as np
    from PIL import Image

    import topomap

    if kind == "watershed":
        from scipy import ndimage as ndi
        from skimage.feature import peak_local_max
        from skimage.segmentation import watershed
    else:
        import cv2
    imported = time.perf_counter() - t_start
    for path in maps:
        t = [time.perf_counter()]
        grid = topomap.load_map(path, resolution=res)
        free = grid.free
        t.append(time.perf_counter())
        if kind == "watershed":
            dist = ndi.distance_transform_edt(free)
            t.append(time.perf_counter())
            comp, _ = ndi.label(free, structure=np.ones((3, 3)))
            md = max(int(round(1.75 / grid.resolution)), 1)
            peaks = peak_local_max(dist, min_distance=md, labels=comp, exclude_border=False)
            markers = np.zeros(free.shape, np.int32)
            markers[tuple(peaks.T)] = np.arange(1, len(peaks) + 1, dtype=np.int32)
            labels = watershed(-dist, markers, mask=free)
        else:
            dist = cv2.distanceTransform(free.astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
            t.append(time.perf_counter())
            _, labels = cv2.connectedComponents((dist > 0).astype(np.uint8), connectivity=8, ltype=cv2.CV_32S)
        t.append(time.perf_counter())
        d = Path(out) / Path(path).stem
        d.mkdir(parents=True, exist_ok=True)
        Image.fromarray(labels.astype(np.uint16)).save(d / "labels.png")
        t.append(time.perf_counter())
        names = ["load", "distance", "segment", "write"]
        st = {k: b - a for k, a, b in zip(names, t[:-1], t[1:])}
        if imported is not None:
            st["import"], imported = imported, None
        st["job"] = t[-1] - t[0]
        print(f"{path}: " + ", ".join(f"{k} {v * 1000:.0f} ms" for k, v in st.items()), file=sys.stderr)


# --------------------------------------------------------------------------
# running jobs
# --------------------------------------------------------------------------

_STAGE = re.compile(r"(\w+) (\d+) ms")


def _cmd(kind, out, res, maps):
    if kind == "topomap":
        exe = Path(sys.executable).with_name("topomap")
        base = [str(exe)] if exe.exists() else [sys.executable, "-m", "topomap.cli"]
        return base + ["segment", *map(str, maps), "-o", str(out), "--resolution", str(res), "--profile"]
    return [sys.executable, str(Path(__file__).resolve()), "--_job", kind, str(out), str(res), *map(str, maps)]


def run(kind, maps, res, out):
    """Run one job over ``maps``: wall seconds, peak MB (ru_maxrss), per-map stage dicts."""
    t0 = time.perf_counter()
    with open(os.devnull, "w") as null, tempfile.TemporaryFile("w+") as err:
        p = subprocess.Popen(_cmd(kind, out, res, maps), stdout=null, stderr=err)
        _, status, ru = os.wait4(p.pid, 0)
        p.returncode = os.waitstatus_to_exitcode(status)
        wall = time.perf_counter() - t0
        err.seek(0)
        text = err.read()
    if p.returncode != 0:
        raise RuntimeError(f"{kind} job failed ({p.returncode}): {text.strip().splitlines()[-1:]}")
    stages = {}
    for line in text.splitlines():
        head, sep, rest = line.rpartition(": ")
        if sep and " ms" in rest:
            stages[Path(head).stem] = {k: int(v) / 1000 for k, v in _STAGE.findall(rest)}
    return wall, ru.ru_maxrss / 1024, stages


def _ipa_maps(directory, variant):
    names = sorted(p for p in glob.glob(os.path.join(directory, "*.png")) if "_gt_" not in p)
    if variant == "unfurnished":
        names = [p for p in names if "_furnitures" not in p]
    elif variant == "furnished":
        names = [p for p in names if "_furnitures" in p]
    return names


def _scaled(path, k, tmp):
    """``path`` upsampled ``k`` x ``k`` (PNG in ``tmp``); the map's own file when ``k`` is 1."""
    if k == 1:
        return path
    from PIL import Image

    img = np.asarray(Image.open(path))
    big = np.kron(img, np.ones((k, k) + (1,) * (img.ndim - 2), np.uint8))
    out = Path(tmp) / f"{Path(path).stem}_x{k}.png"
    Image.fromarray(big).save(out, compress_level=1)
    return str(out)


def _synthetic(tmp):
    from topomap.io.example import make_example_office
    from topomap.io import FREE, OCCUPIED, save_map

    gray = np.tile(make_example_office().gray, SYNTH_TILES)
    cells = np.where(gray >= 250, FREE, OCCUPIED).astype(np.int8)
    return str(save_map(cells, Path(tmp) / "synthetic_office", resolution=0.05))


def _commit():
    try:
        out = subprocess.run(["git", "-C", str(HERE), "rev-parse", "--short", "HEAD"], capture_output=True,
                             text=True, timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(HERE), "status", "--porcelain", "--", "../topomap"],
                               capture_output=True, text=True, timeout=10).stdout.strip()
        return out + (" (+ uncommitted changes in topomap/)" if dirty else "")
    except Exception:  # noqa: BLE001
        return "?"


def _machine():
    sys.path.insert(0, str(HERE))
    from speed import _machine as machine  # benchmarks/speed.py, found through the path just set

    return machine()


def _load():
    try:
        return "load average " + " / ".join(f"{v:.2f}" for v in os.getloadavg())
    except OSError:
        return "load average ?"


# --------------------------------------------------------------------------
# the report
# --------------------------------------------------------------------------

def topo_stages() -> list:
    """Every stage --profile reports (:data:`topomap.run.job.STAGES`), but the sums (segment/total,
    write, job) and those of a run with a previous result (previous, prior doors, match). Imported
    here, not at the top: the child jobs time their own imports."""
    from topomap.run.job import STAGES

    return [s for s in STAGES if s not in ("previous", "prior doors", "match", "segment", "total", "write", "job")]


def writes() -> list:
    """The stages that write one file each (``write_<file>``)."""
    return [s for s in topo_stages() if s.startswith("write_")]
#: The stages of the command itself, paid once before the first map.
ONCE = ("start", "import", "warmup")


def _arguments(argv):
    """The parsed command line (and the parser, for its errors)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("directory", nargs="?", default=None)
    ap.add_argument("--variant", choices=["unfurnished", "furnished", "both"], default="both")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--growth-map", default="office_e", help="map upsampled for the growth table")
    ap.add_argument("--scales", default="1,2,4")
    ap.add_argument("--quick", action="store_true", help="one round; no growth and synthetic cases")
    ap.add_argument("--section", default=str(SECTION))
    ap.add_argument("--_job", nargs="+", default=None, help=argparse.SUPPRESS)
    return ap, ap.parse_args(argv)


def _intro(args, maps, rounds):
    """The section's heading and the paragraphs on how the jobs were run."""
    cmdline = "python benchmarks/job_speed.py" + (" --quick" if args.quick else f" --rounds {rounds}") + \
        ("" if args.variant == "both" else f" --variant {args.variant}")
    return ["## Speed of the whole job", "",
            f"`{cmdline}` (the data set's directory as argument), commit `{_commit()}`; {_machine()}; "
            f"{_load()} at the start (the machine was shared: compare within the run).", "",
            f"{len(maps)} images of ipa_room_segmentation ({args.variant} variants; each `NAME.png` read with "
            "`--resolution 0.05`), every job one fresh process given all the maps. **topomap**: `topomap segment "
            "MAPS... -o OUT --profile` with its default outputs (labels.png, rooms.graphml, rooms.json, "
            "rooms.geojson, overlay.png; travel distances included). **watershed**: a plain script per map: "
            "`topomap.load_map`, `scipy.ndimage.distance_transform_edt`, `skimage.feature.peak_local_max` "
            "(markers 1.75 m apart), `skimage.segmentation.watershed`, a 16-bit label PNG (Pillow). The two "
            "alternate, round after round. Per-map time: loading to the last file written, as each job reports "
            "it; peak memory: `ru_maxrss` of the job's process.", ""]


def _alternate(maps, res, rounds, tmp):
    """Run the topomap and watershed jobs ``rounds`` times, alternating which goes first: a dict of each
    kind's wall seconds per round (``walls``), per-map job seconds (``per_map``), peak MB (``peak``), and
    the per-map stages of the last round (``stages``)."""
    runs = {"walls": {"topomap": [], "watershed": []}, "per_map": {"topomap": {}, "watershed": {}},
            "peak": {"topomap": 0.0, "watershed": 0.0}, "stages": {"topomap": {}, "watershed": {}}}
    for r in range(rounds):
        for kind in ("topomap", "watershed") if r % 2 == 0 else ("watershed", "topomap"):
            wall, mb, st = run(kind, maps, res, Path(tmp) / f"{kind}{r}")
            runs["walls"][kind].append(wall)
            runs["peak"][kind] = max(runs["peak"][kind], mb)
            for m, d in st.items():
                runs["per_map"][kind].setdefault(m, []).append(d["job"])
            runs["stages"][kind] = st
            print(f"round {r + 1} {kind}: {wall:.2f} s, {mb:.0f} MB", file=sys.stderr, flush=True)
    return runs


def _totals(runs, rounds, floor_wall, floor_mb):
    """The table of the rounds, the ratios of the totals and of the per-map medians, and the floor job."""
    walls, per_map, peak = runs["walls"], runs["per_map"], runs["peak"]
    lines = ["| round | topomap (s) | watershed (s) | ratio |", "| --- | ---: | ---: | ---: |"]
    for r in range(rounds):
        lines.append(f"| {r + 1} | {walls['topomap'][r]:.2f} | {walls['watershed'][r]:.2f} | "
                     f"{walls['topomap'][r] / walls['watershed'][r]:.2f} |")
    tt, tw = np.median(walls["topomap"]), np.median(walls["watershed"])
    mt = np.median([np.median(v) for v in per_map["topomap"].values()])
    mw = np.median([np.median(v) for v in per_map["watershed"].values()])
    return lines + ["", f"**Ratio of the totals (median of the rounds): {tt / tw:.2f}** ({tt:.2f} s against "
                        f"{tw:.2f} s); **ratio of the per-map medians: {mt / mw:.2f}** ({mt * 1000:.0f} ms against "
                        f"{mw * 1000:.0f} ms). Peak memory: topomap {peak['topomap']:.0f} MB, watershed "
                        f"{peak['watershed']:.0f} MB.", "",
                    f"Physical floor (one process: `topomap.load_map`, one OpenCV distance transform, the 16-bit "
                    f"PNG of the free space's components, per map): {floor_wall:.2f} s, {floor_mb:.0f} MB; the whole "
                    f"topomap job is **{tt / floor_wall:.1f} x** the floor, the watershed job {tw / floor_wall:.1f} x.",
                    ""]


def _time_split(profile, watershed):
    """Where the time of the whole topomap job goes, summed over the maps (last round), beside the
    watershed job's own stages."""
    groups = [("start, imports, warm-up (once)", list(ONCE)), ("load", ["load"]),
              ("segmentation (`segment()`)", ["total"]), ("room graph", ["room_graph"]),
              ("travel distances", ["travel"]), ("overlay drawn", ["overlay"]),
              ("files written", writes())]
    topo_sum = {k: sum(d.get(k, 0.0) for d in profile.values()) for k in
                [*ONCE, "load", "total", "room_graph", "travel", "overlay", *writes(), "job"]}
    water_sum = {k: sum(d.get(k, 0.0) for d in watershed.values())
                 for k in ["import", "load", "distance", "segment", "write", "job"]}
    lines = ["Where the time goes, summed over the maps (last round; the watershed job's own stages beside "
             "it):", "", "| topomap stage | s | watershed stage | s |", "| --- | ---: | --- | ---: |"]
    water_rows = [("imports (once)", water_sum["import"]), ("load", water_sum["load"]),
                  ("distance transform + watershed", water_sum["distance"] + water_sum["segment"]), ("", None),
                  ("", None), ("", None), ("label PNG written", water_sum["write"])]
    for (label, keys), (water_label, water_value) in zip(groups, water_rows):
        lines.append(f"| {label} | {sum(topo_sum[k] for k in keys):.2f} | {water_label} | "
                     f"{'' if water_value is None else f'{water_value:.2f}'} |")
    return lines + [f"| **maps, load to last file** | {topo_sum['job']:.2f} | **maps** | {water_sum['job']:.2f} |",
                    ""]


def _largest_map(maps, profile, floor):
    """The stages of the largest map from the last topomap round's ``--profile``, and its floor job."""
    big = max(maps, key=_cells)
    name = Path(big).stem
    st = dict(profile.get(name, {}))
    for d in profile.values():  # start and import: on the first map's line, once per command
        for k in ONCE:
            if k in d:
                st[k] = d[k]
    job = st.get("job", float("nan"))
    lines = [f"Stages of the largest map, {name} ({_cells(big) / 1e6:.2f} M cells), from `--profile` of the "
             "last topomap round (`start`: process start to the command; `import`: every module the "
             "command uses, loaded once before the first map; `warmup`: the job once on a tiny map, so "
             "one-off first-call costs are not in the first map; all three paid once per command, so "
             "shared by all maps of a batch; the clearance is computed on a second thread during "
             "`preprocess` and `skeletons`, and the overlay and the labels.png image during `travel`: "
             "`overlay` is what the job still waits for them after it):", "",
             "| stage | ms | share of the map's job |", "| --- | ---: | ---: |"]
    for k in topo_stages():
        if k in st:
            share = "" if k in ONCE else f"{100 * st[k] / job:.0f} %"
            lines.append(f"| {k} | {st[k] * 1000:.0f} | {share} |")
    lines.append(f"| **job** (load to last file) | {job * 1000:.0f} | 100 % |")
    floor_stages = floor.get(name, {})
    return lines + ["", f"Same map, floor job: load {floor_stages.get('load', 0) * 1000:.0f} ms, distance transform "
                        f"{floor_stages.get('distance', 0) * 1000:.0f} ms, write "
                        f"{floor_stages.get('write', 0) * 1000:.0f} ms.", ""]


def main(argv=None):
    ap, args = _arguments(argv)
    if args._job:
        kind, out, res, *maps = args._job
        _job(kind, out, float(res), maps)
        return 0
    from topomap.bench.datasets import benchmark_dir

    directory = args.directory or benchmark_dir()
    if directory is None:
        ap.error("no benchmark directory given and benchmark_dir() found none")
    maps = _ipa_maps(directory, args.variant)
    rounds = 1 if args.quick else args.rounds
    lines = _intro(args, maps, rounds)
    res = 0.05
    with tempfile.TemporaryDirectory() as tmp:
        runs = _alternate(maps, res, rounds, tmp)
        floor_wall, floor_mb, floor = run("floor", maps, res, Path(tmp) / "floor")
        lines += _totals(runs, rounds, floor_wall, floor_mb)
        lines += _time_split(runs["stages"]["topomap"], runs["stages"]["watershed"])
        lines += _largest_map(maps, runs["stages"]["topomap"], floor)
        if not args.quick:
            lines += _growth(directory, args.growth_map, [int(s) for s in args.scales.split(",")], tmp)
            lines += _synthetic_case(tmp)
    text = "\n".join(lines) + "\n"
    Path(args.section).parent.mkdir(parents=True, exist_ok=True)
    Path(args.section).write_text(text, encoding="utf-8")
    print(text)
    return 0


def _cells(path):
    from PIL import Image

    with Image.open(path) as im:
        return im.size[0] * im.size[1]


def _growth(directory, name, scales, tmp):
    src = os.path.join(directory, f"{name}.png")
    rows = {}
    for k in scales:
        p = _scaled(src, k, tmp)
        for kind in ("topomap", "watershed"):
            wall, mb, st = run(kind, [p], 0.05 / k, Path(tmp) / f"g{kind}{k}")
            rows[(kind, k)] = (wall, mb, next(iter(st.values())))
        print(f"growth x{k} done", file=sys.stderr, flush=True)
        if k == scales[-1]:  # the same map twice in one command: the second job on memory already in use
            twin = str(Path(p).with_name(f"again_{Path(p).name}"))
            shutil.copyfile(p, twin)
            _, _, st2 = run("topomap", [p, twin], 0.05 / k, Path(tmp) / f"twice{k}")
            rows["twice"] = [st2[n] for n in sorted(st2, key=lambda n: "again_" in str(n))]
            os.remove(twin)
        if k != 1:
            os.remove(p)
    cells = _cells(src)
    out = [f"Growth with the area: {name} upsampled (`np.kron`, resolution divided by the factor, so every "
           f"length in metres is the same), one process per case. Stage times in ms; the last columns are "
           f"each stage's time at the largest factor over its time at 1x (the area grew "
           f"{scales[-1] ** 2}x):", ""]
    head = "| stage | " + " | ".join(f"x{k} ({cells * k * k / 1e6:.1f} M)" for k in scales) + \
        f" | x{scales[-1]} / x1 |"
    out += [head, "| --- |" + " ---: |" * (len(scales) + 1)]
    for s in topo_stages() + ["job"]:
        vals = [rows[("topomap", k)][2].get(s) for k in scales]
        if all(v is None for v in vals):
            continue
        g = f"{vals[-1] / vals[0]:.1f}" if vals[0] and vals[-1] is not None else "–"
        out.append(f"| {s} | " + " | ".join("–" if v is None else f"{v * 1000:.0f}" for v in vals) + f" | {g} |")
    for lbl, kind, i in (("whole command, topomap (s)", "topomap", 0), ("whole command, watershed (s)", "watershed", 0),
                         ("peak memory, topomap (MB)", "topomap", 1), ("peak memory, watershed (MB)", "watershed", 1)):
        vals = [rows[(kind, k)][i] for k in scales]
        fmt = "{:.2f}" if i == 0 else "{:.0f}"
        out.append(f"| {lbl} | " + " | ".join(fmt.format(v) for v in vals) + f" | {vals[-1] / vals[0]:.1f} |")
    if "twice" in rows:
        first, second = rows["twice"]
        big = ", ".join(f"{s} {first[s] * 1000:.0f} -> {second[s] * 1000:.0f}" for s in ("preprocess", "doors", "rooms")
                        if s in first and s in second)
        out += ["", f"The x{scales[-1]} map given twice to one command (`topomap segment MAP COPY`): the first job "
                    f"takes {first['job'] * 1000:.0f} ms, the second {second['job'] * 1000:.0f} ms ({big} ms); the second "
                    f"is {second['job'] / rows[('topomap', scales[0])][2]['job']:.1f} x the x1 job for "
                    f"{scales[-1] ** 2} x the cells. Over several runs of this table the first job "
                    "took from less than the second's time to 2.5 times it: memory a fresh process touches for the "
                    "first time costs far more on this virtual machine than memory it reuses, and varies (a batch "
                    "pays it once, for its largest map). The rest is the finer grid: lengths in metres are more cells "
                    "there, so the steps sized in metres do more per cell (closing the wall gaps switches from "
                    "OpenCV's closing to two exact distance transforms from a radius of 12 cells), and the rooms "
                    "stage's fill of the cells no room seed holds (the cuts, closed gaps, small pieces) grows them "
                    "8 cells, not a length in metres: on the finer grid more of them are left between two rooms, "
                    "and one such stretch sends the fill to a watershed over the whole map (the room a cell "
                    "halfway between two seeds joins depends on that watershed's order, so it is not cut to a "
                    "window). At one resolution all of this stays linear in the area (the synthetic building "
                    "below)."]
    return out + [""]


def _synthetic_case(tmp):
    y = _synthetic(tmp)
    out = []
    cells = 280 * 400 * SYNTH_TILES[0] * SYNTH_TILES[1]
    res = {}
    for kind in ("topomap", "watershed"):
        wall, mb, st = run(kind, [y], 0.05, Path(tmp) / f"s{kind}")
        res[kind] = (wall, mb, next(iter(st.values())))
    print("synthetic done", file=sys.stderr, flush=True)
    t, w = res["topomap"], res["watershed"]
    out += [f"Synthetic building ({cells / 1e6:.1f} M cells: the example office tiled "
            f"{SYNTH_TILES[0]} x {SYNTH_TILES[1]}, as in `benchmarks/speed.py --scaling`), whole command with "
            f"every output: topomap **{t[0]:.1f} s, {t[1]:.0f} MB** peak "
            f"({t[0] / cells * 1e6 * 1000:.0f} ms and {t[1] / cells * 1e6:.0f} MB per million cells); "
            f"watershed job {w[0]:.1f} s, {w[1]:.0f} MB. topomap stages (ms): "
            + ", ".join(f"{k} {t[2][k] * 1000:.0f}" for k in topo_stages() if k in t[2]) + ".", ""]
    return out


if __name__ == "__main__":
    sys.exit(main())
