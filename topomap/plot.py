"""Pictures: the map with rooms coloured, doors, skeleton graphs, routes.

Each function draws on a matplotlib ``Axes`` (a new figure when ``ax`` is
None) and returns the ``Axes``, so they combine in a notebook with one call
each. Images are drawn in map-frame metres (``extent`` from the grid), so
world coordinates (door midpoints, plans) can be drawn on top directly.
"""

from __future__ import annotations

import numpy as np

__all__ = ["plot_map", "plot_rooms", "plot_doors", "plot_skeletons", "plot_room_graph",
           "plot_route", "plot_segmentation", "save_overlay", "room_colors"]


def _ax(ax, figsize=(8, 8)):
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=figsize)
    return ax


def _extent(grid):
    """(left, right, bottom, top) in metres, for ``imshow`` (yaw ignored)."""
    H, W = grid.shape
    ox, oy, _ = grid.origin
    r = grid.resolution
    return (ox, ox + W * r, oy, oy + H * r)


def room_colors(n: int, seed: int = 7) -> np.ndarray:
    """(n + 1, 4) RGBA colours: index 0 transparent, rooms in distinct pastel hues."""
    rng = np.random.default_rng(seed)
    import matplotlib.colors as mc

    hues = (np.arange(n) * 0.618033988749895 + rng.random()) % 1.0
    hsv = np.stack([hues, np.full(n, 0.55), np.full(n, 0.95)], 1)
    rgb = mc.hsv_to_rgb(hsv) if n else np.zeros((0, 3))
    out = np.zeros((n + 1, 4))
    out[1:, :3] = rgb
    out[1:, 3] = 1.0
    return out


def plot_map(grid, ax=None):
    """Draw the occupancy grid: free white, occupied black, unknown gray."""
    ax = _ax(ax)
    img = np.full(grid.shape, 0.75)
    img[grid.free] = 1.0
    img[grid.occupied] = 0.0
    ax.imshow(img, cmap="gray", vmin=0, vmax=1, extent=_extent(grid), interpolation="nearest")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_aspect("equal")
    return ax


#: RGBA colour of fragments (free regions too small to be a room) in pictures.
FRAGMENT_COLOR = (0.45, 0.25, 0.45, 1.0)


def plot_rooms(seg, ax=None, *, alpha: float = 0.75, ids: bool = True):
    """Colour every room of ``seg`` over its map (fragments all in
    :data:`FRAGMENT_COLOR`); label rooms with their ID."""
    ax = plot_map(seg.grid, ax)
    n = int(seg.room_labels.max()) if seg.labels.size else 0  # the largest room ID (IDs may have gaps)
    colors = np.vstack([room_colors(n), np.tile(FRAGMENT_COLOR, (int(seg.labels.max(initial=0)) - n, 1))])
    rgba = colors[seg.labels]
    rgba[..., 3] *= alpha
    ax.imshow(rgba, extent=_extent(seg.grid), interpolation="nearest")
    if ids and n:
        G = seg.room_graph
        big = [i for i in G.nodes if G.nodes[i]["area"] >= 1.0]
        for i in big:
            ax.text(G.nodes[i]["x"], G.nodes[i]["y"], str(i), ha="center", va="center", fontsize=7,
                    bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.7))
    return ax


def plot_doors(seg, ax=None, *, color="red", lw=2.0):
    """Draw every door of ``seg`` as a segment between its end points."""
    ax = _ax(ax)
    for d in seg.doors:
        ax.plot([d.xy1[0], d.xy2[0]], [d.xy1[1], d.xy2[1]], color=color, lw=lw, solid_capstyle="butt")
    return ax


def _draw_graph_paths(G, grid, ax, color, lw):
    for _, _, d in G.edges(data=True):
        p = d["path"]
        x, y = grid.pixel_to_world(p[:, 0], p[:, 1])
        ax.plot(x, y, color=color, lw=lw)


def plot_skeletons(seg, ax=None, *, free_color="limegreen", occupied_color="magenta", lw=0.8,
                   endpoints: bool = True):
    """Draw the free-space (green) and occupied-space (magenta) skeleton graphs,
    like the paper's Figure 1(b); occupied-space endpoints as dots."""
    ax = _ax(ax)
    grid = seg.grid
    if seg.free_graph is not None:
        _draw_graph_paths(seg.free_graph, grid, ax, free_color, lw)
    if seg.occupied_graph is not None:
        G = seg.occupied_graph
        _draw_graph_paths(G, grid, ax, occupied_color, lw)
        if endpoints:
            e = [G.nodes[n]["pixel"] for n in G.nodes if G.degree(n) == 1]
            if e:
                e = np.array(e, float)
                x, y = grid.pixel_to_world(e[:, 0], e[:, 1])
                ax.plot(x, y, "o", color=occupied_color, ms=2.5)
    return ax


def plot_room_graph(seg, ax=None, *, color="navy", node_size: float = 30):
    """Draw the room–door graph over the map: room centroids joined through door midpoints."""
    ax = _ax(ax)
    G = seg.room_graph
    for a, b, d in G.edges(data=True):
        xa, ya = G.nodes[a]["x"], G.nodes[a]["y"]
        xb, yb = G.nodes[b]["x"], G.nodes[b]["y"]
        ax.plot([xa, d["x"], xb], [ya, d["y"], yb], color=color, lw=1.2, alpha=0.8)
    xs = [G.nodes[n]["x"] for n in G.nodes if G.degree(n) or G.nodes[n]["area"] >= 1.0]
    ys = [G.nodes[n]["y"] for n in G.nodes if G.degree(n) or G.nodes[n]["area"] >= 1.0]
    ax.scatter(xs, ys, s=node_size, c=color, zorder=3)
    return ax


def plot_route(route, ax=None, *, color="darkorange", lw=2.5):
    """Draw a planned route: a sequence of ``(x, y)`` waypoints in metres
    (``route["waypoints"]`` of :func:`topomap.planning.plan_path`, or an (K, 2) array)."""
    ax = _ax(ax)
    pts = np.asarray(route["waypoints"] if isinstance(route, dict) else route, float)
    ax.plot(pts[:, 0], pts[:, 1], "-o", color=color, lw=lw, ms=4, zorder=4)
    return ax


def plot_segmentation(seg, ax=None, *, skeletons: bool = False, doors: bool = True, ids: bool = True,
                      graph: bool = False, title: str | None = None):
    """The paper's Figure 1 in one picture: rooms coloured, doors drawn,
    optionally both skeleton graphs and the room graph."""
    ax = plot_rooms(seg, ax, ids=ids)
    if skeletons:
        plot_skeletons(seg, ax)
    if doors:
        plot_doors(seg, ax)
    if graph:
        plot_room_graph(seg, ax)
    ax.set_title(title if title is not None else
                 f"{seg.grid.name}: {seg.n_rooms} rooms, {len(seg.doors)} doors ({seg.method})", fontsize=9)
    return ax


def save_overlay(seg, path, *, skeletons: bool = False, graph: bool = False, dpi: int = 150):
    """Write :func:`plot_segmentation` as a PNG, sized to the map."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    H, W = seg.grid.shape
    scale = 10.0 / max(H, W)
    fig, ax = plt.subplots(figsize=(max(W * scale, 3) + 1, max(H * scale, 3) + 0.6))
    try:
        plot_segmentation(seg, ax, skeletons=skeletons, graph=graph)
        fig.tight_layout()
        fig.savefig(path, dpi=dpi, format="png")
    finally:
        plt.close(fig)
    return path


def overlay_png(seg, *, skeletons: bool = False, graph: bool = False, dpi: int = 150) -> bytes:
    """:func:`save_overlay` as PNG bytes (the ``overlay.png`` of ``topomap segment``)."""
    import io

    buf = io.BytesIO()
    save_overlay(seg, buf, skeletons=skeletons, graph=graph, dpi=dpi)
    return buf.getvalue()
