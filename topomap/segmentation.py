"""Segmentation pipelines and their common result.

``segment(grid, method=...)`` runs one of the registered methods and returns a
:class:`Segmentation`: the label image, the doors, the skeleton graphs and the
per-stage timings. Methods:

``"topomap"`` (the default)
    The paper's two skeletons and map-measured threshold with a stronger door
    test: :func:`segment_topomap`.
``"paper"``
    The method of Mora, Prados & Barber (ICAART 2023), step by step:
    :func:`segment_paper`.
``"watershed"``, ``"morphological"``, ``"distance"``, ``"voronoi"``
    The comparison methods of :mod:`topomap.baselines`.
"""

from __future__ import annotations

import logging
import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from .errors import ParameterError
from .io import FREE, OccupancyGrid

log = logging.getLogger("topomap")

__all__ = ["Segmentation", "segment", "segment_paper", "METHODS", "DEFAULT_METHOD"]


@dataclass
class Segmentation:
    """The result of a segmentation.

    Attributes
    ----------
    grid : OccupancyGrid
        The input map.
    labels : (M, N) ndarray of int32
        Room label per cell: ``1..N`` on every free cell, ``0`` elsewhere.
    doors : list of Door
        Doors between two different rooms (see :class:`topomap.doors.Door`).
    method : str
        Name of the method that produced the result.
    params : dict
        The method's parameters (metres where they are lengths).
    threshold : float or None
        The map's own door threshold (metres), for the Voronoi methods.
    free_graph, occupied_graph : networkx.MultiGraph or None
        Skeleton graphs of free and occupied space (pixel paths, metres).
    candidates : list
        Every narrow-passage candidate with the reason it was kept or not.
    timings : dict
        Seconds per pipeline stage.
    """

    grid: OccupancyGrid
    labels: np.ndarray
    doors: list
    method: str
    params: dict = field(default_factory=dict)
    threshold: Optional[float] = None
    free_graph: object = None
    occupied_graph: object = None
    candidates: list = field(default_factory=list)
    timings: dict = field(default_factory=dict)
    _room_graph: object = field(default=None, repr=False)

    @property
    def n_rooms(self) -> int:
        """Number of rooms (labels ``1..n_rooms``)."""
        return int(self.labels.max()) if self.labels.size else 0

    @property
    def room_graph(self):
        """The room–door graph (:func:`topomap.roomgraph.room_graph`), built once."""
        if self._room_graph is None:
            from .roomgraph import room_graph

            t = time.perf_counter()
            self._room_graph = room_graph(self)
            self.timings["room_graph"] = time.perf_counter() - t
        return self._room_graph

    def room_at(self, x: float, y: float) -> int:
        """Room label at map-frame point ``(x, y)`` metres (0 = not in a room)."""
        r, c = self.grid.world_to_pixel(x, y)
        r, c = int(np.rint(r)), int(np.rint(c))
        if 0 <= r < self.labels.shape[0] and 0 <= c < self.labels.shape[1]:
            return int(self.labels[r, c])
        return 0


class _Timer:
    def __init__(self):
        self.t = {}

    @contextmanager
    def __call__(self, name):
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.t[name] = self.t.get(name, 0.0) + time.perf_counter() - t0


def _px(metres: float, resolution: float, name: str, minimum: int = 0) -> int:
    try:
        m = float(metres)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a length in metres, got {metres!r}") from None
    if not np.isfinite(m) or m < 0:
        raise ParameterError(f"{name} must be a length >= 0 m, got {metres!r}")
    return max(int(round(m / resolution)), minimum)


def _disk(r: int) -> np.ndarray:
    y, x = np.ogrid[-r:r + 1, -r:r + 1]
    return (x * x + y * y <= r * r).astype(np.uint8)


def segment_paper(grid: OccupancyGrid, *, erosion_radius: float = 0.10, median_size: float = 0.25,
                  dilation_size: float = 0.15, wall_band: float = 0.5,
                  min_free_branch: float = 0.5, min_occupied_branch: float = 1.0,
                  max_door_search: float = 3.0) -> Segmentation:
    """Segment ``grid`` with the paper's method (Mora, Prados & Barber).

    Parameters
    ----------
    grid : OccupancyGrid
    erosion_radius : float
        Radius (m) of the disk free space is eroded with before its skeleton
        is taken. 0.10 m (2 px at 0.05 m/px) removes free-space speckle and
        one-cell slits, which would otherwise add skeleton branches; it is
        far below any door's half width.
    median_size : float
        Side (m) of the median filter that rounds corners after the erosion.
        0.25 m (5 px): the smallest window that rounds a right-angled corner
        by more than one cell.
    dilation_size : float
        Side (m) of the square occupied space is dilated with. 0.15 m (3 px)
        closes one-cell gaps in scanned walls without rounding corners.
    wall_band : float
        Occupied cells farther than this (m) from free space are left out of
        the occupied-space analysis: what lies beyond is the outside of the
        building (or solid rock), not wall shape. 0.5 m keeps any wall up to
        1 m thick whole.
    min_free_branch : float
        Free-space branches shorter than this (m) are not analysed: the
        paper's 10 px at 0.05 m/px.
    min_occupied_branch : float
        Occupied-space end branches shorter than this (m) are pruned: the
        paper's 20 px at 0.05 m/px.
    max_door_search : float
        Longest ray (m) searched for a wall on either side of a passage.

    Returns
    -------
    Segmentation
    """
    from shapely.geometry import MultiLineString

    from . import doors as D
    from . import skeleton as S
    from ._fast import edt

    res = grid.resolution
    T = _Timer()
    params = dict(erosion_radius=erosion_radius, median_size=median_size, dilation_size=dilation_size,
                  wall_band=wall_band, min_free_branch=min_free_branch,
                  min_occupied_branch=min_occupied_branch, max_door_search=max_door_search)
    free = grid.free
    nonfree = ~free
    with T("preprocess"):
        # the paper: occupied space is the occupied cells (unknown ones are not)
        f, d_free, occ = _free_and_occupied(grid, erosion_radius=erosion_radius, median_size=median_size,
                                            dilation_size=dilation_size, wall_band=wall_band,
                                            occupied=grid.occupied)
    with T("skeletons"):
        fs = S.skeletonize(f)
        os_ = S.skeletonize(occ)
    with T("graphs"):
        Gf = S.skeleton_graph(fs, radius=d_free, resolution=res, to_world=grid.pixel_to_world)
        Gf = S.prune_spurs(Gf, min_free_branch)
        d_occ = edt(occ)
        Go = S.skeleton_graph(os_, radius=d_occ, resolution=res, to_world=grid.pixel_to_world)
        Go = S.prune_spurs(Go, min_occupied_branch)
    with T("doors"):
        thr_px = D.wall_threshold(d_occ, S.graph_pixels(Go))
        cands = D.passage_candidates(Gf, min_branch_px=min_free_branch / res)
        D.intersection_points(cands, nonfree, max_px=max_door_search / res)
        paths = [d["path"][:, ::-1].astype(float) for _, _, d in Go.edges(data=True) if d["path"].shape[0] >= 2]
        lines = MultiLineString([p.tolist() for p in paths]) if paths else None
        kept = D.select_doors(cands, S.graph_endpoints(Go), thr_px, lines)
        segs = [(c.ip1, c.ip2) for c in kept]
    with T("rooms"):
        labels, door_objs = cut_rooms(grid, segs)
    seg = Segmentation(grid=grid, labels=labels, doors=door_objs, method="paper", params=params,
                       threshold=thr_px * res, free_graph=Gf, occupied_graph=Go,
                       candidates=cands, timings=T.t)
    log.info("%s: %d rooms, %d doors, threshold %.3f m (%d candidates)", grid.name, seg.n_rooms,
             len(door_objs), thr_px * res, len(cands))
    return seg


def _free_and_occupied(grid, *, erosion_radius, median_size, dilation_size, wall_band, occupied=None):
    """Preprocessed free mask, clearance (px) and occupied mask for the skeletons.

    Free space is eroded with a disk and median-filtered; occupied space
    (``occupied``, default every non-free cell) is restricted to the band
    within ``wall_band`` of free space and dilated with a square.
    """
    import cv2

    from ._fast import edt

    res = grid.resolution
    er = _px(erosion_radius, res, "erosion_radius")
    med = _px(median_size, res, "median_size")
    dil = _px(dilation_size, res, "dilation_size")
    band = _px(wall_band, res, "wall_band", 1)
    free = grid.free
    f = free.astype(np.uint8)
    if er > 0:
        f = cv2.erode(f, _disk(er), borderType=cv2.BORDER_CONSTANT, borderValue=0)
    if med >= 3:
        k = med if med % 2 else med + 1
        f = cv2.medianBlur(f * 255, k) > 127
    else:
        f = f.astype(bool)
    d_free = edt(free)
    dist_out = edt(~free, exact=False)  # only compared with the band width
    occ = (~free if occupied is None else occupied & ~free) & (dist_out <= band)
    if dil > 1:
        occ = cv2.dilate(occ.astype(np.uint8), np.ones((dil, dil), np.uint8)) > 0
    return f, d_free, occ


def segment_topomap(grid: OccupancyGrid, *, erosion_radius: float = 0.05, median_size: float = 0.25,
                    dilation_size: float = 0.15, wall_band: float = 0.5,
                    min_occupied_branch: float = 0.3, min_door_width: float = 0.5,
                    max_door_width: float = 3.0, window: float = 0.5, rise: float | None = None, reach: float = 1.5,
                    protrusion_min: float = 0.6, flat_min: float = 0.45, rule: str = "oneflat",
                    skeleton_cell: float = 0.1, mouths: bool = True,
                    corridor_length: float = 1.0, min_wall_length: float = 1.0,
                    facing: float = 0.9) -> Segmentation:
    """Segment ``grid`` with topomap's default method.

    The paper's ideas — skeletons of free *and* occupied space, a threshold
    measured on the map (twice the mean wall half-thickness), doors where a
    narrow passage meets protruding walls, rooms by cutting at the doors with
    no merging step — with a different door test: bottlenecks of clearance
    along the free-space skeleton (and corridor mouths), door posts at the
    closest wall cells, and a protrusion test that accepts the paper's
    endpoint evidence or a measured convexity of the wall at the posts. See
    the "How it works" page for pictures of every step.

    Parameters
    ----------
    grid : OccupancyGrid
        Free cells are ``grid.free``; every other cell is an obstacle.
    erosion_radius : float
        Radius (m) of the disk free space is eroded with before its skeleton
        is taken: 0.05 m (one cell at 0.05 m/px) removes free-space speckle
        without narrowing any door by more than a cell on each side.
    median_size : float
        Side (m) of the median filter that smooths the eroded free space:
        0.25 m rounds corners so they add no skeleton spurs.
    dilation_size : float
        Side (m) of the square occupied space is dilated with before its
        skeleton: 0.15 m closes one-cell gaps in scanned walls.
    wall_band : float
        Obstacle cells farther than this (m) from free space are left out of
        the occupied-space analysis (the outside of the building): 0.5 m
        keeps walls up to 1 m thick whole.
    min_occupied_branch : float
        End branches of the occupied skeleton shorter than this (m) are
        pruned: 0.3 m, about a wall's thickness — a spur shorter than the
        wall is thick is a corner artefact, not a protrusion (the paper's
        1 m also removes real wall stubs beside doors).
    min_door_width, max_door_width : float
        Range of door widths (m): 0.5 m is narrower than any door a person
        or robot uses; 3.0 m admits double doors and the wide openings
        between a room and a hall or an open office bay, which floor plans
        separate as rooms of their own.
    window : float
        A bottleneck is the narrowest point within this distance (m) along
        the skeleton: 0.5 m, half a door's width either way.
    rise : float, optional
        The clearance must grow by this much (m) on both sides of a
        bottleneck within ``reach``: doors lead from one space into a wider
        one. Default: the discretisation noise of a clearance read along the
        skeleton — the skeleton may run half a cell's diagonal off the true
        medial axis, and clearances are compared to half a cell — so
        ``(sqrt(2)/2 + 1/2) * skeleton_cell`` (0.12 m): any smaller rise may
        be the grid's, not the building's. Independent of the map's
        resolution.
    reach : float
        How far (m) along the skeleton the rise is looked for: 1.5 m, a
        door's frame and the first step into the room behind it.
    protrusion_min : float
        Fraction of free cells in a disk of the map's wall-thickness
        threshold (at least 0.25 m) around a door post above which the wall
        protrudes there: 0.6 lies between a straight wall (0.5) and a
        right-angled convex corner (0.75).
    flat_min : float
        With ``rule="oneflat"``, the other post must be at least this
        (0.45): a straight wall, not a concave corner (0.25).
    rule : {"oneflat", "either", "ep", "frac", "one"}
        Which protrusion evidence accepts a door: ``"ep"`` the paper's
        endpoint test at both posts; ``"frac"`` the convexity test at both
        posts; ``"either"`` one of these; ``"one"`` convexity at one post;
        ``"oneflat"`` (default) ``"either"``, or convexity at one post and a
        straight wall at the other (a door beside a wall).
    skeleton_cell : float
        Cell size (m) of the grid the free-space skeleton is taken on; the
        clearances are always sampled at the map's own resolution. 0.1 m:
        the narrowest door (0.5 m) is still five cells wide. Maps coarser
        than this use their own grid.
    mouths : bool
        Also look for corridor mouths: one-sided bottlenecks where a run of
        even clearance opens into a space at least ``2 * rise`` wider; they
        are doors only where the walls protrude on both sides.
    min_wall_length : float
        Free-standing obstacles less than this (m) across (bounding box) are
        clutter — chairs, plants, small tables, pillars — and are looked
        through while doors are searched: doors are in walls, and 1.0 m is
        shorter than any wall piece between two doors. Rooms are still cut
        from the map as it is (clutter cells stay out of every room). 0
        turns this off.
    facing : float
        The posts must face each other across the bottleneck: their distance
        must be at least ``facing`` times the bottleneck's diameter (0.9:
        about 130° apart seen from the narrowest point). Posts at a right
        angle to each other are a room's corner, not a doorway.
    corridor_length : float
        A run of even clearance (within one cell) must be at least this long
        (m) to count as a corridor whose mouth can be a door: 1.0 m, longer
        than any door frame or gap between pieces of furniture.

    Returns
    -------
    Segmentation
        ``method="topomap"``; ``candidates`` holds every bottleneck with its
        ``status``.
    """
    from . import doors as D
    from . import skeleton as S
    from ._fast import edt

    res = grid.resolution
    T = _Timer()
    if rise is None:
        rise = max(skeleton_cell, res) * (np.sqrt(2) / 2 + 0.5)
    # work on the bounding box of free space plus the wall band: the rest of
    # the map (unknown margins, solid outside) cannot hold a room or a door
    full, box = grid, _free_box(grid, _px(wall_band + dilation_size + max_door_width, grid.resolution, "wall_band"))
    if box is not None:
        grid = _crop(grid, box)
    params = dict(erosion_radius=erosion_radius, median_size=median_size, dilation_size=dilation_size,
                  wall_band=wall_band, min_occupied_branch=min_occupied_branch,
                  min_door_width=min_door_width, max_door_width=max_door_width, window=window, rise=rise, reach=reach,
                  protrusion_min=protrusion_min, rule=rule, skeleton_cell=skeleton_cell, mouths=mouths,
                  corridor_length=corridor_length, min_wall_length=min_wall_length, facing=facing)
    rooms_grid = grid
    with T("preprocess"):
        if min_wall_length > 0:
            # doors are in walls: free-standing clutter smaller than a wall piece
            # is looked through while doors are searched (rooms still use the map)
            clutter = _clutter(grid.free, min_wall_length / res)
            if clutter.any():
                grid = OccupancyGrid(np.where(clutter, FREE, grid.cells).astype(np.int8), grid.resolution,
                                     grid.origin, grid.source)
        free = grid.free
        f, d_free, occ = _free_and_occupied(grid, erosion_radius=erosion_radius, median_size=median_size,
                                            dilation_size=dilation_size, wall_band=wall_band)
    fac = max(int(np.floor(skeleton_cell / res + 1e-9)), 1)
    with T("skeletons"):
        fs = S.skeletonize(S.downsample(f, fac, keep="all"))
        os_ = S.skeletonize(S.downsample(occ, fac, keep="any"))
    with T("graphs"):
        d_occ = edt(occ, exact=False)  # only averaged into the wall threshold
        Gf = _coarse_graph(fs, fac, d_free, grid)
        Go = _coarse_graph(os_, fac, d_occ, grid)
        Go = S.prune_spurs(Go, min_occupied_branch)
    with T("doors"):
        thr_px = D.wall_threshold(d_occ, S.graph_pixels(Go))
        cands = D.passage_minima(Gf, window_px=window / res, rise_px=rise / res, reach_px=reach / res,
                                 mouths=mouths, min_run_px=corridor_length / res,
                                 max_radius_px=max_door_width / np.sqrt(2) / res)
        D.nearest_wall_points(cands, ~free, max_px=max_door_width / res, depth_px=max(thr_px, 2.0))
        # the protrusion of a wall end: the most protruding obstacle cell
        # within half the wall thickness of each door post
        ends = S.graph_endpoints(Go)
        from scipy.spatial import cKDTree

        tree = cKDTree(ends) if ends.shape[0] else None
        judged = []
        for c in cands:
            if c.ip1 is None or c.ip2 is None:
                c.status = "no wall on both sides"
                continue
            width = np.linalg.norm(c.ip1 - c.ip2) * res
            if not (min_door_width <= width <= max_door_width):
                c.status = "width out of range"
                continue
            if width < facing * 2 * c.radius * res:
                # the posts do not face each other across the bottleneck: it
                # lies beside a corner, not in a doorway
                c.status = "posts not facing"
                continue
            judged.append((width, c))
        # the protrusion of a wall end: the most protruding obstacle cell
        # within half the wall thickness of each door post
        posts = [p for _, c in judged for p in (c.ip1, c.ip2)]
        look = max(int(round(thr_px / 2)), 1)
        pvals = D.protrusion_at(free, posts, max(thr_px, 0.25 / res), look)
        accepted = []
        for n, (width, c) in enumerate(judged):
            f1, f2 = pvals[2 * n], pvals[2 * n + 1]
            p1, p2 = f1 >= protrusion_min, f2 >= protrusion_min
            e_ok = False
            if tree is not None:
                d1, _ = tree.query(c.ip1)
                d2, _ = tree.query(c.ip2)
                e_ok = d1 <= thr_px and d2 <= thr_px
            f_ok = p1 and p2
            if c.status == "mouth":
                # a corridor opening into a room: walls must end on both sides
                if not f_ok:
                    c.status = "mouth without protruding walls"
                    continue
                c.status = "door"
                accepted.append((width, c))
                continue
            ok = {"either": e_ok or f_ok, "ep": e_ok, "frac": f_ok, "one": (p1 or p2),
                  "oneflat": e_ok or f_ok or (max(f1, f2) >= protrusion_min and min(f1, f2) >= flat_min)}[rule]
            if not ok:
                c.status = "no protruding wall"
                continue
            c.status = "door"
            accepted.append((width, c))
        accepted.sort(key=lambda t: t[0])
        segs = []
        A = np.zeros((len(accepted), 2))
        B = np.zeros((len(accepted), 2))
        for width, c in accepted:
            mid = (c.ip1 + c.ip2) / 2
            k = len(segs)
            if k and (_point_segment_distances(mid, A[:k], B[:k]) < 0.5 * width / res).any():
                c.status = "duplicate"
                continue
            A[k], B[k] = c.ip1, c.ip2
            segs.append((c.ip1, c.ip2))
    with T("rooms"):
        labels, door_objs = cut_rooms(rooms_grid, segs)
    seg = Segmentation(grid=rooms_grid, labels=labels, doors=door_objs, method="topomap", params=params,
                       threshold=thr_px * res, free_graph=Gf, occupied_graph=Go,
                       candidates=cands, timings=T.t)
    if box is not None:
        seg = _uncrop(seg, full, box)
    log.info("%s: %d rooms, %d doors, threshold %.3f m (%d candidates)", full.name, seg.n_rooms,
             len(door_objs), thr_px * res, len(cands))
    return seg


def _coarse_graph(skel, fac, radius, grid):
    """Skeleton graph of a skeleton taken on a ``fac``-times coarser grid,
    mapped back to the grid's cells with ``radius`` (pixels) sampled there."""
    from . import skeleton as S

    return S.skeleton_graph(skel, radius=radius, resolution=grid.resolution, to_world=grid.pixel_to_world,
                            scale=max(int(fac), 1))


def _clutter(free: np.ndarray, max_extent_px: float) -> np.ndarray:
    """Obstacle cells of free-standing components less than ``max_extent_px``
    across (bounding box, 8-connected): chairs, plants, small tables."""
    import cv2

    n, comp, stats, _ = cv2.connectedComponentsWithStats((~free).astype(np.uint8), connectivity=8)
    extent = np.maximum(stats[:, cv2.CC_STAT_WIDTH], stats[:, cv2.CC_STAT_HEIGHT])
    small = extent < max_extent_px
    small[0] = False  # label 0: the free cells themselves
    return small[comp]


def _free_box(grid: OccupancyGrid, margin: int):
    """``(r0, r1, c0, c1)``: bounding box of the free cells grown by ``margin``
    cells, or None when it is the whole map (or there is no free cell)."""
    free = grid.free
    rows = np.flatnonzero(free.any(axis=1))
    if rows.size == 0:
        return None
    cols = np.flatnonzero(free.any(axis=0))
    H, W = free.shape
    r0, r1 = max(rows[0] - margin, 0), min(rows[-1] + margin + 1, H)
    c0, c1 = max(cols[0] - margin, 0), min(cols[-1] + margin + 1, W)
    # start on a multiple of 4 cells, so the coarse skeleton grid (factors
    # 1, 2, 4) falls on the same cells as without cropping
    r0, c0 = r0 - r0 % 4, c0 - c0 % 4
    # and end where a multiple of 4 cells is left to the far edge, so that a
    # rotated or flipped map is cut into the same blocks
    r1, c1 = H - (H - r1) + ((H - r1) % 4), W - (W - c1) + ((W - c1) % 4)
    if (r0, r1, c0, c1) == (0, H, 0, W):
        return None
    return int(r0), int(r1), int(c0), int(c1)


def _crop(grid: OccupancyGrid, box) -> OccupancyGrid:
    """The part ``box`` of ``grid``, with the origin moved so that every cell
    keeps its world coordinates."""
    r0, r1, c0, c1 = box
    H = grid.shape[0]
    ox, oy, yaw = grid.origin
    u, v = c0 * grid.resolution, (H - r1) * grid.resolution
    cy, sy = np.cos(yaw), np.sin(yaw)
    origin = (ox + cy * u - sy * v, oy + sy * u + cy * v, yaw)
    gray = grid.gray[r0:r1, c0:c1] if grid.gray is not None else None
    return OccupancyGrid(grid.cells[r0:r1, c0:c1], grid.resolution, origin, grid.source, gray)


def _uncrop(seg: Segmentation, full: OccupancyGrid, box) -> Segmentation:
    """Move a segmentation of ``_crop(full, box)`` back onto ``full``: labels
    pasted in, every pixel coordinate shifted (world coordinates are unchanged)."""
    r0, r1, c0, c1 = box
    off = np.array([r0, c0], float)
    labels = np.zeros(full.shape, np.int32)
    labels[r0:r1, c0:c1] = seg.labels
    for d in seg.doors:
        d.p1 = (d.p1[0] + r0, d.p1[1] + c0)
        d.p2 = (d.p2[0] + r0, d.p2[1] + c0)
    for G in (seg.free_graph, seg.occupied_graph):
        if G is None:
            continue
        for _, nd in G.nodes(data=True):
            nd["pixel"] = (nd["pixel"][0] + r0, nd["pixel"][1] + c0)
            nd["row"] += r0
            nd["col"] += c0
        for _, _, ed in G.edges(data=True):
            ed["path"] = ed["path"] + np.array([r0, c0])
    for c in seg.candidates:
        for name in ("centroid", "ip1", "ip2", "ep1", "ep2"):
            val = getattr(c, name)
            if val is not None:
                setattr(c, name, np.asarray(val, float) + off)
    seg.grid = full
    seg.labels = labels
    return seg


def _point_segment_distances(p, a, b) -> np.ndarray:
    """Distances from point ``p`` (2,) to the segments ``a[i]``-``b[i]`` ((K, 2) arrays)."""
    ab = b - a
    den = (ab * ab).sum(1)
    t = np.where(den > 0, ((p - a) * ab).sum(1) / np.where(den > 0, den, 1), 0.0)
    t = np.clip(t, 0, 1)
    proj = a + t[:, None] * ab
    return np.hypot(*(p - proj).T)


def _line_px(p, q, shape):
    from skimage.draw import line

    H, W = shape
    r0, c0 = np.clip(np.rint(p), 0, [H - 1, W - 1]).astype(int)
    r1, c1 = np.clip(np.rint(q), 0, [H - 1, W - 1]).astype(int)
    return line(r0, c0, r1, c1)


def cut_rooms(grid: OccupancyGrid, segments):
    """Cut free space along door segments and label the pieces.

    Parameters
    ----------
    grid : OccupancyGrid
    segments : list of ((r1, c1), (r2, c2))
        Door segments in pixels.

    Returns
    -------
    labels : (M, N) ndarray of int32
        4-connected pieces of free space between the cuts, each a room
        (``1..N``, deterministic order); the cut cells themselves and any free
        cell the pieces miss are given to the nearest room.
    doors : list of Door
        See :func:`doors_between_rooms`.
    """
    from ._fast import label as cc_label
    from .rooms import fill_unlabeled

    free = grid.free
    cut = np.zeros_like(free)
    for p, q in segments:
        cut[_line_px(p, q, free.shape)] = True
    pieces, n = cc_label(free & ~cut, 4)
    if n > 1:
        # number pieces by area (largest = highest id): cut cells then go to
        # the larger neighbour, whatever the map's orientation
        area = np.bincount(pieces.ravel(), minlength=n + 1)
        area[0] = -1
        rank = np.empty(n + 1, np.int32)
        rank[np.argsort(area, kind="stable")] = np.arange(n + 1, dtype=np.int32)
        pieces = rank[pieces]
    labels = fill_unlabeled(pieces, free)
    return labels, doors_between_rooms(grid, labels, segments)


_NR = np.array([-1, -1, -1, 0, 0, 1, 1, 1])
_NC = np.array([-1, 0, 1, -1, 1, -1, 0, 1])


def doors_between_rooms(grid: OccupancyGrid, labels: np.ndarray, segments) -> list:
    """The segments that separate two different rooms, as :class:`Door` objects.

    A segment's rooms are the two labels most frequent among the 8-neighbours
    of its pixels; a segment with fewer than two labels around it separates
    nothing and is dropped, and so is a repeat of a kept segment.
    """
    from .doors import Door

    H, W = labels.shape
    doors, seen = [], set()
    for p, q in segments:
        rr, cc = _line_px(p, q, labels.shape)
        labs = labels[np.clip(rr[:, None] + _NR, 0, H - 1), np.clip(cc[:, None] + _NC, 0, W - 1)].ravel()
        vals, counts = np.unique(labs[labs > 0], return_counts=True)
        if vals.size < 2:
            continue
        a, b = sorted(int(v) for v in vals[np.argsort(-counts, kind="stable")[:2]])
        p = tuple(float(v) for v in p)
        q = tuple(float(v) for v in q)
        key = (a, b) + tuple(int(round(v)) for v in p + q)
        if key in seen:
            continue
        seen.add(key)
        x1, y1 = grid.pixel_to_world(*p)
        x2, y2 = grid.pixel_to_world(*q)
        doors.append(Door(id=len(doors), p1=p, p2=q, xy1=(float(x1), float(y1)), xy2=(float(x2), float(y2)),
                          width=float(np.hypot(p[0] - q[0], p[1] - q[1]) * grid.resolution), rooms=(a, b)))
    return doors


def _baseline(name):
    def run(grid: OccupancyGrid, **params) -> Segmentation:
        from . import baselines

        T = _Timer()
        with T("segment"):
            # every baseline ends with fill_unlabeled: all free cells labelled
            labels, segs = getattr(baselines, name)(grid.free, resolution=grid.resolution, **params)
        with T("rooms"):
            doors = doors_between_rooms(grid, labels, segs)
        return Segmentation(grid=grid, labels=labels, doors=doors, method=name, params=params, timings=T.t)

    run.__name__ = f"segment_{name}"
    run.__doc__ = f"Segment with :func:`topomap.baselines.{name}` and wrap the result."
    return run


METHODS = {
    "topomap": segment_topomap,
    "paper": segment_paper,
    "watershed": _baseline("watershed"),
    "morphological": _baseline("morphological"),
    "distance": _baseline("distance"),
    "voronoi": _baseline("voronoi"),
}
DEFAULT_METHOD = "topomap"


def segment(grid: OccupancyGrid, *, method: str = None, **params) -> Segmentation:
    """Segment an occupancy grid into rooms and doors.

    Parameters
    ----------
    grid : OccupancyGrid
        The map (see :func:`topomap.io.load_map`).
    method : str, optional
        One of :data:`METHODS` (default :data:`DEFAULT_METHOD`).
    **params
        Keyword options of the method, lengths in metres.

    Returns
    -------
    Segmentation
    """
    method = method or DEFAULT_METHOD
    if method not in METHODS:
        raise ParameterError(f"unknown method {method!r}; choose from {', '.join(sorted(METHODS))}")
    if not isinstance(grid, OccupancyGrid):
        raise ParameterError(f"segment() needs an OccupancyGrid (see topomap.load_map), got {type(grid).__name__}")
    t0 = time.perf_counter()
    seg = METHODS[method](grid, **params)
    seg.timings["total"] = time.perf_counter() - t0
    return seg
