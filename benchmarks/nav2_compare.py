#!/usr/bin/env python
"""topomap's Nav2 route graphs beside Nav2's hand-made ones for its depot and warehouse maps.

Run (not a test)::

    python benchmarks/nav2_compare.py NAV2_DIR [--picture docs/img/nav2_compare.png]
        [--kinds-picture docs/img/room_kinds.png --kinds-map WILLOW_FULL.yaml] [--all]

``NAV2_DIR`` holds Nav2's sample maps and graphs (``depot.yaml``,
``depot_graph.geojson``, ``warehouse.yaml``, ``warehouse_graph.geojson``, from
``nav2_bringup``). Each map is segmented at the defaults and its route graph
made with :func:`topomap.planning.nav2.route_graph` at the default clearance; both
graphs are measured the same way: nodes, edges (one per direction, as the
files hold them), the share of the map's free cells within 1 m of an edge,
and the edges that come closer than the clearance to a cell that is not free
(sampled every 1/20 cell). Prints a Markdown table; draws both graphs of
both maps side by side.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np
from scipy import ndimage as ndi

MAPS = ("depot", "warehouse")
NEAR = 1.0  # m: "within reach of an edge"


def measure(grid, graph: dict, clearance: float) -> dict:
    """Nodes, edges, share of free cells within NEAR m of an edge, edges closer than ``clearance`` to a wall."""
    nodes = {f["properties"]["id"]: f["geometry"]["coordinates"][:2] for f in graph["features"]
             if f["geometry"]["type"] == "Point"}
    edges = [(f["properties"]["startid"], f["properties"]["endid"]) for f in graph["features"]
             if f["geometry"]["type"] in ("LineString", "MultiLineString")]
    res = grid.resolution
    H, W = grid.shape
    free = np.pad(grid.free, 1)
    clear = ndi.distance_transform_edt(free)[1:-1, 1:-1] * res - res / 2
    on = np.zeros((H, W), bool)
    close = 0
    for s, e in edges:
        (x0, y0), (x1, y1) = nodes[s], nodes[e]
        n = int(math.dist((x0, y0), (x1, y1)) / res * 20) + 2
        t = np.linspace(0, 1, n)
        row, col = grid.world_to_pixel(x0 + (x1 - x0) * t, y0 + (y1 - y0) * t)
        rr, cc = np.floor(row + 0.5).astype(int), np.floor(col + 0.5).astype(int)
        inside = (rr >= 0) & (cc >= 0) & (rr < H) & (cc < W)
        on[rr[inside], cc[inside]] = True
        if not inside.all() or clear[rr[inside], cc[inside]].min() < clearance:
            close += 1
    near = ndi.distance_transform_edt(~on) * res <= NEAR
    cover = float((near & grid.free).sum() / max(grid.free.sum(), 1))
    return {"nodes": len(nodes), "edges": len(edges), "cover": cover, "close": close, "xy": nodes, "pairs": edges}


def draw(ax, grid, m, title):
    img = np.where(grid.free, 1.0, np.where(grid.occupied, 0.0, 0.75))
    x0, y0 = grid.pixel_to_world(grid.shape[0] - 0.5, -0.5)
    x1, y1 = grid.pixel_to_world(-0.5, grid.shape[1] - 0.5)
    ax.imshow(img, cmap="gray", vmin=0, vmax=1, extent=(x0, x1, y0, y1), interpolation="nearest")
    for s, e in m["pairs"]:
        (a, b), (c, d) = m["xy"][s], m["xy"][e]
        ax.plot([a, c], [b, d], "-", color="tab:blue", lw=1.2)
    xy = np.array(list(m["xy"].values()))
    ax.plot(xy[:, 0], xy[:, 1], "o", color="tab:red", ms=3)
    ax.set_title(title, fontsize=9)
    ax.set_xticks([])
    ax.set_yticks([])


KIND_COLOURS = {"corridor": (0.95, 0.6, 0.1), "doorway": (0.85, 0.2, 0.2), "hall": (0.3, 0.5, 0.9),
                "room": (0.55, 0.8, 0.55)}


def draw_kinds(seg, out, plt):
    """The rooms of ``seg`` coloured by their ``room_kind``, with their IDs, doors as black lines."""
    from matplotlib.patches import Patch

    grid, G = seg.grid, seg.room_graph
    img = np.where(grid.occupied, 0.0, np.where(grid.free, 1.0, 0.8))[..., None].repeat(3, axis=2)
    for n, k in G.nodes(data="room_kind"):
        img[seg.room_labels == n] = KIND_COLOURS[k]
    x0, y0 = grid.pixel_to_world(grid.shape[0] - 0.5, -0.5)
    x1, y1 = grid.pixel_to_world(-0.5, grid.shape[1] - 0.5)
    fig, ax = plt.subplots(figsize=(10, 5.4))
    ax.imshow(img, extent=(x0, x1, y0, y1), interpolation="nearest")
    for *_, d in G.edges(data=True):
        ax.plot([d["x1"], d["x2"]], [d["y1"], d["y2"]], "k-", lw=2)
    for n, d in G.nodes(data=True):
        ax.text(d["x"], d["y"], f"{n}\n{d['width']:.1f} m", ha="center", va="center", fontsize=7)
    ax.legend(handles=[Patch(color=c, label=k) for k, c in KIND_COLOURS.items()], loc="upper right", fontsize=8)
    ax.set_xticks([])
    ax.set_yticks([])
    ax.set_title("room_kind of each room (room ID and mean width)", fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=80)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("directory", type=Path, help="folder of Nav2's sample maps and graphs")
    ap.add_argument("--picture", type=Path, default=None, help="PNG of both graphs of both maps")
    ap.add_argument("--kinds-picture", type=Path, default=None,
                    help="PNG of the rooms of --kinds-map coloured by their room_kind")
    ap.add_argument("--kinds-map", type=Path, default=None,
                    help="map YAML for --kinds-picture (default: the depot)")
    ap.add_argument("--all", action="store_true",
                    help="also make and measure the route graph of every map of ipa_room_segmentation and "
                         "rose2_real (found as for topomap benchmark)")
    args = ap.parse_args()

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import topomap
    from topomap.planning.nav2 import DEFAULT_CLEARANCE, route_graph

    rows = ["| map | graph | nodes | edges | free space within 1 m of an edge | edges closer than "
            f"{DEFAULT_CLEARANCE} m to a wall |", "| --- | --- | --- | --- | --- | --- |"]
    fig, axes = plt.subplots(len(MAPS), 2, figsize=(10, 4.2 * len(MAPS)))
    for i, name in enumerate(MAPS):
        grid = topomap.load_map(args.directory / f"{name}.yaml")
        hand = json.loads((args.directory / f"{name}_graph.geojson").read_text())
        ours = route_graph(topomap.segment(grid))
        for j, (who, g) in enumerate((("Nav2, hand-made", hand), ("topomap", ours))):
            m = measure(grid, g, DEFAULT_CLEARANCE)
            rows.append(f"| {name} | {who} | {m['nodes']} | {m['edges']} | {100 * m['cover']:.0f} % | {m['close']} |")
            draw(axes[i, j], grid, m, f"{name}: {who} ({m['nodes']} nodes, {m['edges']} edges)")
    fig.tight_layout()
    if args.picture:
        fig.savefig(args.picture, dpi=80)
    if args.kinds_picture:
        draw_kinds(topomap.segment(topomap.load_map(args.kinds_map or args.directory / "depot.yaml")),
                   args.kinds_picture, plt)
    sys.stdout.write("\n".join(rows) + "\n")
    if args.all:
        from topomap.bench.datasets import benchmark_dir, load_benchmark, load_labelled, real_maps_dir

        grids = [bm.load() for v in ("unfurnished", "furnished") for bm in load_benchmark(benchmark_dir(), variant=v)]
        grids += [bm.load() for bm in load_labelled(real_maps_dir())]
        n = e = close = 0
        for grid in grids:
            m = measure(grid, route_graph(topomap.segment(grid)), DEFAULT_CLEARANCE)
            n, e, close = n + m["nodes"], e + m["edges"], close + m["close"]
        print(f"{len(grids)} benchmark maps: {n} nodes, {e} edges, {close} closer than {DEFAULT_CLEARANCE} m to a wall")


if __name__ == "__main__":
    main()
