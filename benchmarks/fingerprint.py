#!/usr/bin/env python
"""Fingerprints of every output of the Voronoi methods, to prove a change
behaviour-preserving (issue 11) or to say exactly what it changed.

Run (not a test)::

    python benchmarks/fingerprint.py [DATA_DIR] [--out FILE.json] [--jobs N]
    python benchmarks/fingerprint.py [DATA_DIR] --compare OLD.json [--out NEW.json]

For the embedded example map and every map of the shared data sets, and for
the methods ``topomap`` and ``paper``, records:

* ``labels``: sha256 of the label image (shape, dtype and bytes);
* ``n_rooms``;
* ``threshold``: the map's door threshold in metres, rounded to 1e-9;
* ``doors``: per door its two rooms and its end points (pixels and metres),
  rounded to 1e-6;
* ``statuses``: the status of every candidate, in order.

Maps (``DATA_DIR`` defaults to ``../shared/datasets`` next to the
repository; a data set that is absent is skipped):

* ``ipa_room_segmentation``: ``NAME.png`` and ``NAME_furnitures.png`` of
  every ``NAME_gt_segmentation.png``, read as 8-bit gray and turned into a
  grid with :func:`topomap.io.from_array` by a fixed rule (free where
  gray >= 250, else occupied) at 0.05 m/px, independent of how
  :func:`topomap.io.load_map` treats bare images;
* ``rose2_real``: ``load_map(NAME.yaml)`` of every YAML file.

``--compare OLD.json`` prints every map / method / field that differs from
``OLD.json`` (and the maps present in only one of them) and exits with
status 1 when anything differs, 0 when the fingerprints are identical. The
JSON holds hashes and rounded numbers only, never map content.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import logging
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

log = logging.getLogger("fingerprint")

METHODS = ("topomap", "paper")
#: Gray level from which a pixel of a bare benchmark PNG counts as free.
IPA_FREE_GRAY = 250
IPA_RESOLUTION = 0.05
REPO = Path(__file__).resolve().parent.parent
DEFAULT_DATA = REPO.parent / "shared" / "datasets"


def map_list(data_dir: Path) -> list:
    """``(key, kind, path)`` of every map to fingerprint, in a fixed order."""
    out = [("example/example_office", "example", "")]
    ipa = data_dir / "ipa_room_segmentation"
    if ipa.is_dir():
        for gt in sorted(ipa.glob("*_gt_segmentation.png")):
            name = gt.name[: -len("_gt_segmentation.png")]
            for variant in (name, name + "_furnitures"):
                p = ipa / f"{variant}.png"
                if p.is_file():
                    out.append((f"ipa/{variant}", "ipa", str(p)))
    else:
        log.warning("no %s: skipped", ipa)
    rose = data_dir / "rose2_real"
    if rose.is_dir():
        for y in sorted(rose.glob("*.yaml")):
            out.append((f"rose2/{y.stem}", "yaml", str(y)))
    else:
        log.warning("no %s: skipped", rose)
    return out


def load(kind: str, path: str):
    """The occupancy grid of one map entry of :func:`map_list`."""
    import topomap
    from topomap.io import from_array, load_map

    if kind == "example":
        return load_map(topomap.example_map_path())
    if kind == "ipa":
        from PIL import Image

        gray = np.asarray(Image.open(path).convert("L"))
        return from_array(gray >= IPA_FREE_GRAY, resolution=IPA_RESOLUTION, source=Path(path).stem)
    return load_map(path)


def _r(v, nd=6):
    return [round(float(x), nd) for x in v]


def fingerprint(seg) -> dict:
    """The fingerprint of one :class:`topomap.core.segmentation.Segmentation`."""
    lab = np.ascontiguousarray(seg.labels)
    h = hashlib.sha256()
    h.update(repr((lab.shape, lab.dtype.str)).encode())
    h.update(lab.tobytes())
    return {
        "labels": h.hexdigest(),
        "n_rooms": int(seg.n_rooms),
        "threshold": None if seg.threshold is None else round(float(seg.threshold), 9),
        "doors": [{"rooms": [int(r) for r in d.rooms], "p1": _r(d.p1), "p2": _r(d.p2),
                   "xy1": _r(d.xy1), "xy2": _r(d.xy2)} for d in seg.doors],
        "statuses": [str(c.status) for c in seg.candidates],
    }


def run_one(entry) -> tuple:
    """Fingerprints of one map for every method: ``(key, {method: fp})``."""
    from topomap import segment

    key, kind, path = entry
    grid = load(kind, path)
    return key, {m: fingerprint(segment(grid, method=m)) for m in METHODS}


def compare(old: dict, new: dict) -> list:
    """Lines describing every difference between two fingerprint files."""
    lines = []
    for key in sorted(set(old) | set(new)):
        if key not in new:
            lines.append(f"{key}: only in the old fingerprints")
            continue
        if key not in old:
            lines.append(f"{key}: only in the new fingerprints")
            continue
        for m in sorted(set(old[key]) | set(new[key])):
            a, b = old[key].get(m), new[key].get(m)
            if a is None or b is None:
                lines.append(f"{key} [{m}]: method only in the {'new' if a is None else 'old'} fingerprints")
                continue
            for f in sorted(set(a) | set(b)):
                if a.get(f) == b.get(f):
                    continue
                va, vb = a.get(f), b.get(f)
                if isinstance(va, list) and isinstance(vb, list):
                    idx = [i for i in range(max(len(va), len(vb)))
                           if i >= len(va) or i >= len(vb) or va[i] != vb[i]]
                    lines.append(f"{key} [{m}] {f}: {len(va)} -> {len(vb)} entries, "
                                 f"{len(idx)} differ (first at index {idx[0]}: "
                                 f"{va[idx[0]] if idx[0] < len(va) else None} -> "
                                 f"{vb[idx[0]] if idx[0] < len(vb) else None})")
                else:
                    lines.append(f"{key} [{m}] {f}: {va} -> {vb}")
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("data_dir", nargs="?", default=str(DEFAULT_DATA))
    ap.add_argument("--out", help="write the fingerprints to this JSON file")
    ap.add_argument("--compare", metavar="OLD.json", help="compare with an earlier fingerprint file")
    ap.add_argument("--jobs", type=int, default=1, help="maps in this many processes")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    logging.getLogger("topomap").setLevel(logging.WARNING)
    entries = map_list(Path(args.data_dir))
    log.info("%d maps x %d methods", len(entries), len(METHODS))
    if args.jobs > 1:
        with ProcessPoolExecutor(args.jobs) as ex:
            results = dict(ex.map(run_one, entries))
    else:
        results = dict(run_one(e) for e in entries)
    results = {k: results[k] for k in sorted(results)}
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        # one line per map and method: small, and diffs show which one changed
        body = ",\n".join(f"{json.dumps(k)}: {{\n" + ",\n".join(
            f"  {json.dumps(m)}: {json.dumps(fp, sort_keys=True)}" for m, fp in sorted(v.items())) + "}"
            for k, v in results.items())
        Path(args.out).write_text("{\n" + body + "\n}\n")
        log.info("wrote %s", args.out)
    if args.compare:
        old = json.loads(Path(args.compare).read_text())
        diff = compare(old, results)
        for line in diff:
            log.info("%s", line)
        log.info("%s: %d maps compared, %s", args.compare, len(set(old) | set(results)),
                 "IDENTICAL" if not diff else f"{len(diff)} differences")
        return 1 if diff else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
