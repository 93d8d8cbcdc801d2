"""Pictures: the map with rooms coloured, doors, skeleton graphs, routes.

Each ``plot_*`` function draws on a matplotlib ``Axes`` (a new figure when
``ax`` is None) and returns the ``Axes``, so they combine in a notebook with
one call each. Images are drawn in map-frame metres (``extent`` from the
grid), so world coordinates (door midpoints, plans) can be drawn on top
directly.

:func:`overlay_image` / :func:`overlay_png` draw the same picture straight
into a raster at the map's own resolution with OpenCV (one pixel per map
cell; fast even for large maps): the ``overlay.png`` of ``topomap segment``.
"""

from __future__ import annotations

import io

import numpy as np

from .._fast import lookup
from ..grid import FREE, OCCUPIED

__all__ = ["plot_map", "plot_rooms", "plot_doors", "plot_skeletons", "plot_room_graph",
           "plot_route", "plot_segmentation", "save_overlay", "room_colors", "overlay_image", "overlay_png"]


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
    hues = (np.arange(n) * 0.618033988749895 + rng.random()) % 1.0
    rgb = _hsv_to_rgb(hues, np.full(n, 0.55), np.full(n, 0.95)) if n else np.zeros((0, 3))
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


def _anchor(node: dict, metres: bool = True):
    """Where a room's label and graph node are drawn: its interior point (a cell of the room), or
    its centroid for a graph without one. ``(x, y)`` in metres, or ``(row, col)`` in pixels."""
    keys = (("interior_x", "interior_y"), ("x", "y")) if metres else (("interior_row", "interior_col"),
                                                                       ("row", "col"))
    for a, b in keys:
        if a in node and b in node and np.isfinite(node[a]) and np.isfinite(node[b]):
            return float(node[a]), float(node[b])
    return float(node[keys[1][0]]), float(node[keys[1][1]])


def plot_rooms(seg, ax=None, *, alpha: float = 0.75, ids: bool = True):
    """Colour every room of ``seg`` over its map (fragments all in
    :data:`FRAGMENT_COLOR`); label rooms with their ID, at their interior
    point (inside the room, unlike the centroid of an L-shaped room)."""
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
            ax.text(*_anchor(G.nodes[i]), str(i), ha="center", va="center", fontsize=7,
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
    """Draw the room–door graph over the map: the rooms' interior points joined through door midpoints."""
    ax = _ax(ax)
    G = seg.room_graph
    for a, b, d in G.edges(data=True):
        (xa, ya), (xb, yb) = _anchor(G.nodes[a]), _anchor(G.nodes[b])
        ax.plot([xa, d["x"], xb], [ya, d["y"], yb], color=color, lw=1.2, alpha=0.8)
    pts = [_anchor(G.nodes[n]) for n in G.nodes if G.degree(n) or G.nodes[n]["area"] >= 1.0]
    xs, ys = [p[0] for p in pts], [p[1] for p in pts]
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


def _hsv_to_rgb(h, s, v):
    """HSV in [0, 1] to RGB in [0, 1] (arrays), as matplotlib.colors.hsv_to_rgb."""
    i = np.floor(h * 6.0).astype(int) % 6
    f = h * 6.0 - np.floor(h * 6.0)
    p, q, t = v * (1 - s), v * (1 - s * f), v * (1 - s * (1 - f))
    r = np.choose(i, [v, q, p, p, t, v])
    g = np.choose(i, [t, v, v, q, p, p])
    b = np.choose(i, [p, p, t, v, v, q])
    return np.stack([r, g, b], -1)


#: Palette of the overlay: free, unknown, occupied (walls), door, free skeleton, occupied
#: skeleton, room graph, number box; then fragments and rooms (RGB).
_PALETTE = ((255, 255, 255), (191, 191, 191), (0, 0, 0), (255, 0, 0), (50, 205, 50), (255, 0, 255),
            (0, 0, 128), (235, 235, 235))
_FREE, _UNKNOWN, _WALL, _DOOR, _FREE_SKEL, _OCC_SKEL, _GRAPH, _BOX = range(8)
#: Colours available for rooms in the 256-colour overlay; further rooms reuse them in turn.
_ROOM_COLOURS = 256 - len(_PALETTE) - 1


def _overlay_indexed(seg, skeletons=False, graph=False, alpha=0.75):
    """(M, N) uint8 palette indices and the (K, 3) uint8 RGB palette of the overlay."""
    import cv2

    grid = seg.grid
    H, W = grid.shape
    n, nf = seg.n_rooms, seg.n_fragments
    k = min(n, _ROOM_COLOURS)
    first = len(_PALETTE) + 1  # palette index of room 1; fragments just before
    colours = np.vstack([np.asarray(FRAGMENT_COLOR[:3])[None], room_colors(k)[1:, :3]])
    palette = np.vstack([np.asarray(_PALETTE, float),
                         np.rint(255 * (alpha * colours + (1 - alpha)))]).astype(np.uint8)  # rooms over white
    lut = np.empty(n + nf + 1, np.uint8)
    lut[0] = _FREE
    lut[1:n + 1] = first + (np.arange(n) % max(k, 1))
    lut[n + 1:] = first - 1
    labels = np.asarray(seg.labels)
    if labels.size and labels.min() >= 0 and labels.max() <= n + nf:
        idx = lookup(lut, labels)
    else:
        idx = np.take(lut, np.clip(labels, 0, n + nf))
    # cells without a label: walls black, unknown grey, free white (one lookup on the cell values)
    by_cell = np.full(256, _UNKNOWN, np.uint8)
    by_cell[np.uint8(OCCUPIED)], by_cell[np.uint8(FREE)] = _WALL, _FREE
    np.copyto(idx, lookup(by_cell, np.ascontiguousarray(grid.cells).view(np.uint8)), where=labels == 0)
    t = max(1, int(round(min(H, W) / 400)))  # line width in pixels
    if skeletons:
        for G, col in ((seg.free_graph, _FREE_SKEL), (seg.occupied_graph, _OCC_SKEL)):
            if G is None:
                continue
            paths = [np.asarray(d["path"])[:, ::-1].astype(np.int32).reshape(-1, 1, 2)
                     for _, _, d in G.edges(data=True) if len(d["path"])]
            cv2.polylines(idx, paths, False, col, max(1, t // 2))
    for d in seg.doors:
        p = tuple(int(v) for v in np.rint(d.p1[::-1]))
        q = tuple(int(v) for v in np.rint(d.p2[::-1]))
        cv2.line(idx, p, q, _DOOR, t + 1)
    if n == 0:
        return idx, palette
    G = seg.room_graph
    if graph:
        for a, b, d in G.edges(data=True):
            pts = [_anchor(G.nodes[a], False), tuple(np.mean([d["p1"], d["p2"]], 0)), _anchor(G.nodes[b], False)]
            pts = np.rint(np.asarray(pts)[:, ::-1]).astype(np.int32).reshape(-1, 1, 2)
            cv2.polylines(idx, [pts], False, _GRAPH, t)
        for i in G.nodes:
            if G.degree(i) or G.nodes[i]["area"] >= 1.0:
                r, c = _anchor(G.nodes[i], False)
                cv2.circle(idx, (int(round(c)), int(round(r))), 2 * t + 1, _GRAPH, -1)
    scale = max(0.35, min(H, W) / 1600)
    th = max(1, int(round(scale * 1.5)))
    font = cv2.FONT_HERSHEY_SIMPLEX
    for i in G.nodes:
        if G.nodes[i]["area"] < 1.0:
            continue
        text = str(i)
        (tw, tht), below = cv2.getTextSize(text, font, scale, th)
        r, c = _anchor(G.nodes[i], False)  # inside the room
        x0 = int(round(c)) - tw // 2
        y0 = int(round(r)) + tht // 2
        cv2.rectangle(idx, (x0 - 2, y0 - tht - 2), (x0 + tw + 1, y0 + below - 1), _BOX, -1)
        # the glyphs into their own mask (text may be drawn antialiased), then set in one colour
        r0, c0 = max(y0 - tht - 2, 0), max(x0 - 2, 0)
        sub = idx[r0:max(y0 + below, 0), c0:max(x0 + tw + 2, 0)]
        mask = np.zeros(sub.shape, np.uint8)
        cv2.putText(mask, text, (x0 - c0, y0 - r0), font, scale, 255, th, cv2.LINE_8)
        sub[mask > 127] = _WALL
    return idx, palette


def overlay_image(seg, *, skeletons: bool = False, graph: bool = False, alpha: float = 0.75) -> np.ndarray:
    """The segmentation drawn into an RGB raster at the map's own resolution.

    Rooms coloured (:func:`room_colors`, fragments in
    :data:`FRAGMENT_COLOR`; beyond 247 rooms colours are reused) over the
    map (free white, unknown grey, walls black), doors as red lines, room
    IDs at the centroids of rooms of at least 1 m², optionally both skeleton
    graphs (free space green, occupied space magenta) and the room graph
    (centroids joined through door midpoints, navy). Drawn with OpenCV in
    256 colours: no matplotlib figure.

    Parameters
    ----------
    seg : Segmentation
    skeletons, graph : bool
        Also draw the skeleton graphs / the room graph.
    alpha : float
        Opacity of the room colours over the white of free space.

    Returns
    -------
    (M, N, 3) ndarray of uint8
        RGB, one pixel per map cell, the map image's orientation (row 0 at
        the top).
    """
    idx, palette = _overlay_indexed(seg, skeletons, graph, alpha)
    return palette[idx]


def overlay_png(seg, *, skeletons: bool = False, graph: bool = False, dpi: int | None = None) -> bytes:
    """PNG bytes of the overlay picture (the ``overlay.png`` of ``topomap segment``).

    Parameters
    ----------
    seg : Segmentation
    skeletons, graph : bool
        Also draw the skeleton graphs / the room graph.
    dpi : int, optional
        None (default): :func:`overlay_image`, one pixel per map cell, drawn
        with OpenCV, saved as a 256-colour PNG. A number: the matplotlib figure of :func:`save_overlay`
        at that resolution (axes in metres, title; much slower).

    Returns
    -------
    bytes
    """
    buf = io.BytesIO()
    if dpi is not None:
        save_overlay(seg, buf, skeletons=skeletons, graph=graph, dpi=dpi)
        return buf.getvalue()
    from PIL import Image

    idx, palette = _overlay_indexed(seg, skeletons, graph)
    img = Image.fromarray(idx, "P")
    img.putpalette(palette.ravel().tolist())
    img.save(buf, format="PNG", compress_level=1)
    return buf.getvalue()
