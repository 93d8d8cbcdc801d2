"""Regenerate the pictures in ``docs/img`` from the embedded example map.

Run from the repository root::

    python docs/make_figures.py            # writes docs/img/*.png
    python docs/make_figures.py --out DIR  # somewhere else

Every picture is drawn from ``topomap/data/example_office.yaml`` (the
synthetic example office shipped with topomap) and nothing else: no
benchmark map may be pictured in the repository.

The small private helpers below draw what :mod:`topomap.io.plot` has no
function for yet (the preprocessed free / occupied masks, the candidates with
their status, the threshold histogram), from what the methods ran: the
masks and clearances are ``seg.intermediates``, nothing is re-computed.

The module is also the site's mkdocs hook (``hooks:`` in ``mkdocs.yml``):
:func:`on_page_markdown` only rewrites links that leave ``docs/``, and
importing the module draws nothing.
"""

from __future__ import annotations

import argparse
import logging
import re
from pathlib import Path

HERE = Path(__file__).resolve().parent
DPI = 110
log = logging.getLogger("make_figures")


def _imports():
    """Heavy imports, only for drawing (the mkdocs hook needs none of them)."""
    global matplotlib, plt, np, topomap, planning, _extent, plot_map, plot_route, plot_segmentation
    global plot_skeletons, METHODS, segment
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    import topomap
    from topomap import planning
    from topomap.io.plot import _extent, plot_map, plot_route, plot_segmentation, plot_skeletons
    from topomap.core.segmentation import METHODS, segment


def _status_colors():
    """Colour per candidate status (:data:`topomap.core.doors.STATUSES`; anything else: gray)."""
    from topomap.core import doors as D

    return {
        D.DOOR: "red",
        D.DUPLICATE: "orange",
        D.NO_PROTRUDING_WALL: "royalblue",
        D.NO_PROTRUDING_WALL_NEAR: "royalblue",
        D.CENTRES_APART: "purple",
        D.CROSSES_WALL_SKELETON: "saddlebrown",
        D.WIDTH_OUT_OF_RANGE: "deepskyblue",
        D.NO_WALL_BOTH_SIDES: "gray",
        D.NO_ENDPOINTS: "gray",
    }


# --------------------------------------------------------------------------
# mkdocs hook (mkdocs.yml: ``hooks: [docs/make_figures.py]``)
# --------------------------------------------------------------------------

_OUTSIDE_LINK = re.compile(r"\[([^\]]+)\]\((\.\./[^)\s]+)\)")


def on_page_markdown(markdown, page, **kwargs):
    """Turn links that leave ``docs/`` (``[text](../benchmarks/README.md)``,
    as in the benchmarks page) into plain text naming the repository file.

    mkdocs cannot link outside ``docs_dir`` and ``--strict`` fails on such
    links; the file is still named so a reader can find it in the repository.
    """
    def repl(m):
        target = m.group(2)[3:]
        return m.group(1) if m.group(1).strip("`") == target else f"{m.group(1)} (`{target}` in the repository)"

    return _OUTSIDE_LINK.sub(repl, markdown)


# --------------------------------------------------------------------------
# private helpers
# --------------------------------------------------------------------------

def _show_mask(grid, mask, ax, color):
    rgba = np.zeros(mask.shape + (4,))
    rgba[mask] = matplotlib.colors.to_rgba(color, 0.55)
    ax.imshow(rgba, extent=_extent(grid), interpolation="nearest")


def _px_xy(grid, p):
    x, y = grid.pixel_to_world(p[0], p[1])
    return float(x), float(y)


def plot_candidates(seg, ax, *, legend=True):
    """Every candidate of ``seg``: bottleneck dot, IP1–IP2 segment (and EP1–EP2
    for the paper method), coloured by ``status``."""
    grid = seg.grid
    seen = set()
    colors = _status_colors()
    for c in seg.candidates:
        col = colors.get(c.status, "gray")
        label = c.status if c.status not in seen else None
        seen.add(c.status)
        cx, cy = _px_xy(grid, c.centroid)
        ax.plot(cx, cy, "o", color=col, ms=4, mec="k", mew=0.4, label=label, zorder=5)
        if c.ip1 is not None and c.ip2 is not None:
            (x1, y1), (x2, y2) = _px_xy(grid, c.ip1), _px_xy(grid, c.ip2)
            ax.plot([x1, x2], [y1, y2], "-", color=col, lw=1.8, zorder=4)
        if getattr(c, "ep1", None) is not None and getattr(c, "ep2", None) is not None:
            (x1, y1), (x2, y2) = _px_xy(grid, c.ep1), _px_xy(grid, c.ep2)
            ax.plot([x1, x2], [y1, y2], ":", color="magenta", lw=1.2, zorder=4)
    if legend and seen:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, title="status",
                  title_fontsize=8, frameon=False)


def _endpoints(seg, ax):
    from topomap.core.skeleton import graph_endpoints

    e = graph_endpoints(seg.occupied_graph)
    x, y = seg.grid.pixel_to_world(e[:, 0], e[:, 1])
    ax.plot(x, y, "o", color="magenta", ms=3.5, mec="k", mew=0.3, label="occupied-skeleton endpoint")
    return e


def _title(seg):
    # not plot_segmentation's default title, which shows the absolute path of the map file
    return f"example office: {seg.n_rooms} rooms, {len(seg.doors)} doors ({seg.method})"


def _save(fig, out, name):
    path = out / name
    fig.savefig(path, dpi=DPI, bbox_inches="tight")
    plt.close(fig)
    log.info("%s", path)
    return path


def _wall_half_thickness(seg):
    """Distance to free space (m) on every occupied-skeleton pixel: the
    values the threshold is the (doubled) mean of, as the method measured
    them (``seg.intermediates.occupied_clearance``)."""
    from topomap.core import skeleton as S

    d = seg.intermediates.occupied_clearance * seg.grid.resolution
    px = S.graph_pixels(seg.occupied_graph)
    return d[px[:, 0], px[:, 1]]


# --------------------------------------------------------------------------
# figures
# --------------------------------------------------------------------------

def main(out: Path):
    _imports()
    out.mkdir(parents=True, exist_ok=True)
    grid = topomap.load_map(topomap.example_map_path())
    segs = {m: segment(grid, method=m) for m in ("topomap", "paper")}
    seg = segs["topomap"]

    # README / index picture
    fig, ax = plt.subplots(figsize=(8, 5.8))
    plot_segmentation(seg, ax, skeletons=True, graph=True, title=_title(seg))
    _save(fig, out, "example_overlay.png")

    # the input map
    fig, ax = plt.subplots(figsize=(7, 5))
    plot_map(grid, ax)
    ax.set_title("example office map: free white, occupied black, unknown gray", fontsize=9)
    _save(fig, out, "step0_map.png")

    # step 1: preprocessing, both methods
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6))
    for ax, m in zip(axes, ("paper", "topomap")):
        im = segs[m].intermediates
        plot_map(grid, ax)
        _show_mask(grid, im.free_mask, ax, "limegreen")
        _show_mask(grid, im.occupied_mask, ax, "magenta")
        ax.set_title(f"{m}: free after erosion + median (green), occupied after band + dilation (magenta)",
                     fontsize=8)
    _save(fig, out, "step1_preprocess.png")

    # step 2: skeleton graphs
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6))
    for ax, m in zip(axes, ("paper", "topomap")):
        s = segs[m]
        plot_map(grid, ax)
        plot_skeletons(s, ax)
        ax.set_title(f"{m}: free-space skeleton graph (green, {s.free_graph.number_of_edges()} branches), "
                     f"occupied-space (magenta, {s.occupied_graph.number_of_edges()})", fontsize=8)
    _save(fig, out, "step2_skeletons.png")

    # step 3: wall thickness threshold
    fig, axes = plt.subplots(1, 2, figsize=(12, 3.8))
    for ax, m in zip(axes, ("paper", "topomap")):
        s = segs[m]
        v = _wall_half_thickness(s)
        ax.hist(2 * v, bins=np.arange(0, 2 * v.max() + 0.05, 0.05), color="magenta", alpha=0.6)
        ax.axvline(s.threshold, color="k", lw=2, label=f"threshold {s.threshold:.3f} m")
        ax.set_xlabel("2 × distance to free space on the occupied skeleton [m]")
        ax.set_ylabel("skeleton pixels")
        ax.set_title(f"{m}: wall thickness along the occupied-space skeleton", fontsize=9)
        ax.legend(fontsize=8)
    _save(fig, out, "step3_threshold.png")

    # step 4: candidates, endpoints, status (one picture per method)
    for m in ("paper", "topomap"):
        s = segs[m]
        fig, ax = plt.subplots(figsize=(10, 6))
        plot_map(grid, ax)
        plot_skeletons(s, ax, endpoints=False, lw=0.6)
        _endpoints(s, ax)
        plot_candidates(s, ax)
        ax.set_title(f"{m}: {len(s.candidates)} candidate passages, {len(s.doors)} doors "
                     f"(threshold {s.threshold:.3f} m)", fontsize=9)
        _save(fig, out, f"step4_candidates_{m}.png")

    # step 5: rooms and doors, both methods
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6))
    for ax, m in zip(axes, ("paper", "topomap")):
        plot_segmentation(segs[m], ax, title=_title(segs[m]))
    _save(fig, out, "step5_rooms.png")

    # room graph and a route
    G = planning.travel_graph(seg)
    route = planning.plan_path(G, (-6.0, 4.0), (6.0, -4.0))
    fig, ax = plt.subplots(figsize=(8, 5.8))
    plot_segmentation(seg, ax, graph=True, title=f"route: rooms {route['rooms']}, doors {route['doors']}, "
                                                 f"{route['length']:.1f} m")
    plot_route(route, ax)
    _save(fig, out, "room_graph_route.png")

    # every method side by side
    names = list(METHODS)
    ncol = 3
    nrow = -(-len(names) // ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(5 * ncol, 3.7 * nrow))
    for ax, m in zip(axes.ravel(), names):
        s = segs[m] if m in segs else segment(grid, method=m)
        plot_segmentation(s, ax, title=_title(s))
    for ax in axes.ravel()[len(names):]:
        ax.axis("off")
    _save(fig, out, "compare_methods.png")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=HERE / "img", help="output directory (default docs/img)")
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main(ap.parse_args().out)
