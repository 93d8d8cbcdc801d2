#!/usr/bin/env python
"""How real a map looks: measured statistics of real SLAM maps and of simulated ones.

Run (not a test)::

    python benchmarks/realism.py [--real REAL_DIR] [SIMULATED ...]
        [--out benchmarks/sections/88_realism.md] [--figure docs/img/realism.png]

``REAL_DIR`` is the ``rose2_real`` directory (every ``*.yaml`` in it; found
as benchmarks/README.md says when not given). ``SIMULATED`` are simulated
maps: corpus folders (``CORPUS/*/map.yaml``, and the drawn plans
``CORPUS/*/plan.yaml`` as a row of their own), other folders (every
``*.yaml`` in them) or YAML files. Without any, the section gives the real
maps only. Each map is read with :func:`topomap.load_map` and measured by
:func:`map_statistics`:

* **wall thickness** (m): the median, over the cells of the skeleton of the
  occupied cells (:func:`skimage.morphology.skeletonize`, 8-connected), of
  ``2 d - 1`` cells, ``d`` the Euclidean distance of the skeleton cell to
  the nearest cell that is not occupied (a wall of 3 cells: ``d = 2`` on
  its middle line, 3 cells; even widths read one cell thinner). Occupied
  components of clutter size (below :data:`SPECK_AREA_M2`) are left out;
* **unknown in the box** (%): the share of unknown cells in the bounding box
  of the known (free or occupied) cells: the holes a robot leaves where it
  did not look;
* **free outside the outline** (%): the share of the free cells outside the
  building's outline, where laser rays that left through a door or window
  fan out into the open. The outline is the occupied cells grown by
  :data:`OUTLINE_GAP_M` / 2 (gaps in the walls up to :data:`OUTLINE_GAP_M`
  wide bridged: doors, windows, a lost wall segment), their holes filled
  (:func:`scipy.ndimage.binary_fill_holes`) and shrunk back by as much; a
  free cell outside that filled outline is outside the building. A building
  whose walls have a wider opening is not closed, so the measure then
  counts its rooms as outside (a partial map of an exploration, open where
  the robot has not been yet): read it with the next column;
* **thin spokes** (%): the share of the free cells in thin free pieces that
  run into the unknown: the free cells an opening of the free space with a
  disk of diameter :data:`SPOKE_WIDTH_M` removes (free space narrower than
  that), grouped 8-connected, the groups that touch an unknown cell. Single
  laser rays through a gap leave such spokes (inside a room behind
  clutter as well as outside the building); a drawn plan has none (its
  narrow corners end at walls);
* **specks per m²**: occupied components (8-connected) smaller than
  :data:`SPECK_AREA_M2` that touch no unknown cell and not the edge of the
  map (clutter, chair legs, scan noise inside the free space), per m² of
  free space.

The table gives, per group of maps, the median of each statistic over the
maps with its range. The figure (``--figure``) puts a simulated scan (the
first case) next to a real map of ROSE² (``freiburg079_partial_15``).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

#: Occupied components smaller than this (m²) are clutter specks, not walls (0.05 m²: 20 cells of
#: 5 cm, a chair leg or a bin seen by the laser; the thinnest wall piece worth the name is longer).
SPECK_AREA_M2 = 0.05
#: Gaps in the walls up to this width (m) are closed when the outline is drawn: a door (about 0.9 m),
#: a window, a short lost stretch of wall; the rooms of a house are wider, so they stay inside.
OUTLINE_GAP_M = 2.0

#: Free space narrower than this (m) is thin: a ray fan falls apart into spokes of a few cells,
#: while a person-sized passage (0.5 m, the narrowest a robot drives through) is not thin.
SPOKE_WIDTH_M = 0.5

#: The real map of the figure: the last (most complete) map of an exploration, as the SLAM run wrote it.
REAL_FIGURE_MAP = "freiburg079_partial_15"
COLUMNS = (("wall_thickness_m", "wall thickness (m)", "{:.2f}"),
           ("unknown_share", "unknown in the box (%)", "{:.1f}"),
           ("outside_free_share", "free outside the outline (%)", "{:.1f}"),
           ("spoke_share", "thin spokes (%)", "{:.1f}"),
           ("specks_per_m2", "specks per m²", "{:.3f}"))


def _occupied_components(occupied):
    """8-connected components of the occupied cells: ``(labels, sizes)`` (``sizes[0]`` unused)."""
    from scipy import ndimage as ndi

    lab, n = ndi.label(occupied, structure=np.ones((3, 3), bool))
    return lab, np.bincount(lab.ravel(), minlength=n + 1)


def wall_thickness(occupied, resolution, *, min_area_m2=SPECK_AREA_M2) -> float:
    """Median wall thickness (m) along the skeleton of the occupied cells (module notes).

    Parameters
    ----------
    occupied : (M, N) ndarray of bool
    resolution : float
        Metres per cell.
    min_area_m2 : float, optional
        Occupied components smaller than this are left out (clutter).

    Returns
    -------
    float
        NaN when no wall is left.
    """
    from scipy import ndimage as ndi
    from skimage.morphology import skeletonize

    lab, sizes = _occupied_components(occupied)
    keep = sizes * resolution ** 2 >= min_area_m2
    keep[0] = False
    walls = keep[lab]
    if not walls.any():
        return float("nan")
    # distance to the nearest cell that is not a wall; beyond the edge of the map counts as not a wall
    d = ndi.distance_transform_edt(np.pad(walls, 1))[1:-1, 1:-1]
    skel = skeletonize(walls)
    return float(np.median(2 * d[skel] - 1) * resolution)


def unknown_share(free, occupied) -> float:
    """Share (0..1) of unknown cells in the bounding box of the known cells; NaN on a map with none known."""
    from topomap.core.geometry import true_bbox

    known = free | occupied
    box = true_bbox(known)
    if box is None:
        return float("nan")
    r0, r1, c0, c1 = box
    return float(1 - known[r0:r1, c0:c1].mean())


def outline(occupied, resolution, *, gap_m=OUTLINE_GAP_M) -> np.ndarray:
    """The building's filled outline (bool): the occupied cells grown by ``gap_m / 2`` (gaps up to
    ``gap_m`` closed), their holes filled, shrunk back by as much."""
    import cv2
    from scipy import ndimage as ndi

    from topomap.core.geometry import disk

    k = disk(max(1, int(round(gap_m / 2 / resolution))))
    grown = cv2.dilate(occupied.astype(np.uint8), k, borderType=cv2.BORDER_CONSTANT, borderValue=0)
    filled = ndi.binary_fill_holes(grown).astype(np.uint8)
    return cv2.erode(filled, k, borderType=cv2.BORDER_REPLICATE).astype(bool)


def outside_free_share(free, occupied, resolution, *, gap_m=OUTLINE_GAP_M) -> float:
    """Share (0..1) of the free cells outside the building's filled outline (:func:`outline`)."""
    if not free.any():
        return float("nan")
    return float((free & ~outline(occupied, resolution, gap_m=gap_m)).sum() / free.sum())


def _touching(pieces, mask) -> np.ndarray:
    """The 8-connected components of ``pieces`` that touch (8-neighbour) a cell of ``mask`` (bool)."""
    from scipy import ndimage as ndi

    lab, n = ndi.label(pieces, structure=np.ones((3, 3), bool))
    near = ndi.binary_dilation(mask, np.ones((3, 3), bool))
    hit = np.zeros(n + 1, bool)
    hit[np.unique(lab[near & pieces])] = True
    hit[0] = False
    return hit[lab]


def spoke_share(free, unknown, resolution, *, width_m=SPOKE_WIDTH_M) -> float:
    """Share (0..1) of the free cells in thin free pieces (narrower than ``width_m``) touching unknown cells."""
    if not free.any():
        return float("nan")
    import cv2

    from topomap.core.geometry import disk

    k = disk(max(1, int(round(width_m / 2 / resolution))))
    # nothing beyond the map's edge is free
    opened = cv2.morphologyEx(free.astype(np.uint8), cv2.MORPH_OPEN, k, borderType=cv2.BORDER_CONSTANT,
                              borderValue=0)
    thin = free & ~opened.astype(bool)
    return float(_touching(thin, unknown).sum() / free.sum())


def specks(free, occupied, unknown, resolution, *, max_area_m2=SPECK_AREA_M2) -> int:
    """Occupied components (8-connected) under ``max_area_m2`` touching no unknown cell nor the map's edge."""
    from scipy import ndimage as ndi

    lab, sizes = _occupied_components(occupied)
    small = sizes * resolution ** 2 < max_area_m2
    small[0] = False
    near = ndi.binary_dilation(np.pad(unknown, 1, constant_values=True), np.ones((3, 3), bool))[1:-1, 1:-1]
    small[np.unique(lab[near & occupied])] = False
    return int(small[1:].sum())


def map_statistics(grid) -> dict:
    """Every statistic of the module notes for one map.

    Parameters
    ----------
    grid : topomap.io.OccupancyGrid

    Returns
    -------
    dict
        ``wall_thickness_m``, ``unknown_share`` (0..1), ``outside_free_share``
        (0..1), ``spoke_share`` (0..1), ``n_specks``, ``free_m2``, ``specks_per_m2``.
    """
    free, occ, unk, res = grid.free, grid.occupied, grid.unknown, grid.resolution
    n = specks(free, occ, unk, res)
    free_m2 = float(free.sum() * res ** 2)
    return {"wall_thickness_m": wall_thickness(occ, res), "unknown_share": unknown_share(free, occ),
            "outside_free_share": outside_free_share(free, occ, res), "spoke_share": spoke_share(free, unk, res),
            "n_specks": n, "free_m2": free_m2,
            "specks_per_m2": n / free_m2 if free_m2 else float("nan")}


def simulated_yamls(paths) -> dict:
    """``{"simulated scans": [...], "simulated plans": [...]}`` of the given corpus folders, folders and YAMLs."""
    scans, plans = [], []
    for p in map(Path, paths):
        if p.is_dir():
            cases = sorted(p.glob("*/map.yaml"))
            if cases:
                scans += cases
                plans += sorted(p.glob("*/plan.yaml"))
            else:
                scans += sorted(p.glob("*.yaml"))
        elif p.is_file():
            scans.append(p)
        else:
            sys.exit(f"error: {p}: no such file or folder")
    return {k: v for k, v in (("simulated scans", scans), ("simulated plans", plans)) if v}


def _measure(path):
    from topomap import load_map

    return str(path), map_statistics(load_map(path))


def _summary(name, stats) -> str:
    cells = []
    for key, _, fmt in COLUMNS:
        v = np.array([s[key] for s in stats], float)
        v = v[np.isfinite(v)]
        scale = 100 if key.endswith("_share") else 1
        if v.size == 0:
            cells.append("–")
            continue
        med, lo, hi = (fmt.format(scale * x) for x in (np.median(v), v.min(), v.max()))
        cells.append(f"{med} ({lo}–{hi})")
    return f"| {name} | {len(stats)} | " + " | ".join(cells) + " |"


def _panel(path, title, height=360):
    """A map drawn as map_server gray (free white, occupied black, unknown gray) under a title, as RGB."""
    from PIL import Image, ImageDraw, ImageFont

    from topomap import load_map
    from topomap.core.geometry import true_bbox

    g = load_map(path)
    img = np.full(g.shape, 205, np.uint8)
    img[g.free] = 254
    img[g.occupied] = 0
    box = true_bbox(~g.unknown, pad=5)
    if box is not None:
        img = img[box[0]:box[1], box[2]:box[3]]
    title += f" ({img.shape[1] * g.resolution:.0f} x {img.shape[0] * g.resolution:.0f} m)"
    pic = Image.fromarray(img).convert("RGB")
    pic = pic.resize((max(1, round(pic.width * height / pic.height)), height), Image.NEAREST)
    out = Image.new("RGB", (pic.width, height + 24), "white")
    out.paste(pic, (0, 24))
    try:  # a font with the ² of ROSE²
        from matplotlib import font_manager

        font = ImageFont.truetype(font_manager.findfont("DejaVu Sans"), 15)
    except (ImportError, OSError):
        font = ImageFont.load_default(size=15)
    ImageDraw.Draw(out).text((4, 4), title, fill="black", font=font)
    return out


def figure(out, real_map, simulated_map=None) -> None:
    """``out``: a simulated scan (when given) next to a real map, as a PNG, written atomically."""
    from PIL import Image

    from topomap.io import atomic_write

    panels = ([_panel(simulated_map, f"simulated scan: {simulated_map.parent.name}")] if simulated_map else [])
    panels.append(_panel(real_map, f"real map (ROSE²): {real_map.stem}"))
    w = sum(p.width for p in panels) + 12 * (len(panels) - 1)
    pic = Image.new("RGB", (w, max(p.height for p in panels)), "white")
    x = 0
    for p in panels:
        pic.paste(p, (x, 0))
        x += p.width + 12
    out.parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(out) as fh:
        pic.save(fh, format="PNG", optimize=True)


def main(argv=None) -> int:
    import argparse
    from concurrent.futures import ProcessPoolExecutor

    import _section
    from _section import _commit, _machine
    from topomap.bench.datasets import real_maps_dir

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("simulated", nargs="*", help="simulated corpus folders, folders of maps or YAML files")
    ap.add_argument("--real", type=Path, default=None, help="the rose2_real directory")
    ap.add_argument("--out", type=Path, default=_section.HERE / "sections" / "88_realism.md")
    ap.add_argument("--figure", type=Path, default=_section.HERE.parent / "docs" / "img" / "realism.png")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args(argv)
    real = _section.directory(a.real, real_maps_dir, "TOPOMAP_REAL_MAPS_DIR")
    t0 = time.perf_counter()
    groups = {"ROSE² real maps": sorted(real.glob("*.yaml"))}
    groups.update(simulated_yamls(a.simulated))
    with ProcessPoolExecutor(a.jobs) as ex:
        measured = {g: dict(ex.map(_measure, paths)) for g, paths in groups.items()}
    real_stats = measured["ROSE² real maps"]
    head = "| maps | n | " + " | ".join(c[1] for c in COLUMNS) + " |\n| --- | ---: |" + " ---: |" * len(COLUMNS)
    lines = [head]
    for g, stats in measured.items():
        lines.append(_summary(g, list(stats.values())))
        if g == "ROSE² real maps":
            for prefix in ("freiburg079_partial", "bremen_cartesium_partial", "freiburg079_full",
                           "bremen_cartesium_full"):
                sub = [s for p, s in stats.items() if Path(p).stem.startswith(prefix)]
                if sub:
                    lines.append(_summary(f"… `{prefix}{'_*' if 'partial' in prefix else ''}`", sub))
    table = "\n".join(lines) + "\n"
    sim = groups.get("simulated scans")
    fig_real = next((p for p in groups["ROSE² real maps"] if p.stem == REAL_FIGURE_MAP), groups["ROSE² real maps"][0])
    figure(a.figure, fig_real, sim[0] if sim else None)
    n_real = len(real_stats)
    if sim:
        cmd = "python benchmarks/realism.py CORPUS"
        what = (f"the {n_real} real maps of ROSE² against {len(sim)} simulated scans of a corpus "
                "written by `topomap simulate` (`CORPUS`) and their drawn plans")
        fig = "A simulated scan next to a real map of ROSE²:"
    else:
        cmd = "python benchmarks/realism.py"
        what = (f"the {n_real} real maps of ROSE² (run with a corpus written by `topomap simulate` "
                "as argument to set simulated maps beside them)")
        fig = "A real map of ROSE²:"
    rel = Path("img") / a.figure.name
    g = OUTLINE_GAP_M
    text = f"""## How real the maps look

`{cmd}` (the `rose2_real` directory found as benchmarks/README.md says), commit `{_commit()}`; {_machine()}.

Statistics measured on {what}, each map read with `topomap.load_map`;
median over the maps (range in brackets):

- **wall thickness**: the median of `2 d - 1` cells along the skeleton of
  the occupied cells, `d` the distance of a skeleton cell to the nearest
  cell that is not occupied (a 3-cell wall is 0.15 m at 0.05 m per cell;
  an even width reads one cell thinner); clutter (components under
  {SPECK_AREA_M2} m²) left out;
- **unknown in the box**: the share of unknown cells in the bounding box of
  the known cells;
- **free outside the outline**: the share of the free cells outside the
  building's outline: the occupied cells grown by {g / 2:.0f} m (which closes
  gaps up to {g:.0f} m, doors and windows), their holes filled, shrunk back by
  {g / 2:.0f} m. Laser rays that leave through an opening fan out there. A
  lower bound: rays that end on something leave occupied cells that close
  part of the fan into the outline;
- **thin spokes**: the share of the free cells in free pieces narrower than
  {SPOKE_WIDTH_M} m (removed by an opening with a disk of that diameter) that
  run into unknown cells: single rays through gaps, outside the building or
  behind clutter; a drawn plan has none;
- **specks per m²**: occupied components under {SPECK_AREA_M2} m² that touch no
  unknown cell, per m² of free space (clutter and scan noise).

{table}
The partial maps are the raw output of the SLAM runs (three gray levels,
walls one cell thick); the two full maps are gray-scale images drawn
differently (thicker walls, few specks).

{fig}

![maps side by side]({rel.as_posix()})
"""
    _section.write(a.out, text, table, time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
