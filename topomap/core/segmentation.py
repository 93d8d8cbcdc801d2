"""Segmentation pipelines and their common result.

``segment(grid, method=...)`` runs one of the registered methods and returns a
:class:`Segmentation`: the label image, the doors, the skeleton graphs, the
intermediate images and the per-stage timings. Methods:

``"topomap"`` (the default)
    The paper's two skeletons and map-measured threshold with a stronger door
    test: :func:`segment_topomap`, options :class:`~topomap.options.TopomapOptions`.
``"paper"``
    The method of Mora, Prados & Barber (ICAART 2023), step by step:
    :func:`segment_paper`, options :class:`~topomap.options.PaperOptions`.
``"watershed"``, ``"morphological"``, ``"distance"``, ``"voronoi"``
    The comparison methods of :mod:`topomap.core.baselines`.

Each Voronoi method is a short sequence of stages, each a function of the
module that owns its concern: crop and masks here, skeletons in
:mod:`topomap.core.skeleton` (the default method's coarse grid here), door
finding, judging and duplicate suppression in :mod:`topomap.core.doors`, cutting
rooms in :mod:`topomap.core.rooms`.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from typing import Optional

import numpy as np

from .._fast import BackgroundCall, edt
from ..errors import ParameterError
from ..grid import OccupancyGrid
from ..options import PaperOptions, TopomapOptions, check_keywords, options_from_kwargs
from . import baselines
from .masks import clutter_mask, clutter_parts, close_wall_gaps, preprocess_masks, solid_components, without_clutter
from .doors import (
    WALL_GAP,
    across_corridor,
    find_bottlenecks,
    intersection_points,
    judge_doors,
    occupied_skeleton_lines,
    opening_candidates,
    passage_candidates,
    seen_posts,
    select_doors,
    suppress_duplicates,
    wall_threshold,
)
from .outside import (
    FAN_OPEN,
    drop_outside,
    enclosure,
    outside_fans,
    outside_regions,
)
from .skeleton import (
    downsample,
    graph_endpoints,
    graph_from_topology,
    graph_pixels,
    prune_spurs,
    skeleton_graph,
    skeleton_topology,
    skeletonize,
)
from .walls import (
    WallIndex,
    across_walls_many,
    furniture_rows,
    long_wall_gaps,
    long_walls,
    partition_gaps,
    scale_walls,
    straight_lines,
    straight_share,
    wall_faces,
    wall_lines,
    thin_wall_gaps,
    wall_mask,
    wall_openings,
)
from .geometry import disk, metres_to_px, true_bbox
from .identity import DoorPrior, match_rooms
from .result import Intermediates, Segmentation, StageTimer, paste
from .rooms import cut_rooms, doors_between_rooms

log = logging.getLogger("topomap")

__all__ = ["Segmentation", "Intermediates", "segment", "segment_paper", "segment_topomap", "METHODS",
           "DEFAULT_METHOD", "check_method_options", "cut_rooms", "doors_between_rooms"]


# --------------------------------------------------------------------------
# Stages "skeletons" and "graphs" of the default method: the coarse grid
# --------------------------------------------------------------------------

def skeleton_factor(skeleton_cell: float, resolution: float) -> int:
    """How many map cells (per side) one cell of the skeleton grid holds (>= 1)."""
    return max(int(np.floor(skeleton_cell / resolution + 1e-9)), 1)


#: A map cell is split into at most this many cells per side for the walls (:func:`wall_split`): the
#: walls' grid then holds at most four times the map's cells, so its memory and time stay a bounded
#: multiple of the map's whatever the resolution (a map of 1 m cells, which indoor maps never use,
#: would otherwise be split 20 times per side, 400 times its cells). Laser maps at 0.10 m, the
#: coarsest common resolution, get their walls on 0.05 m cells.
MAX_WALL_SPLIT = 2


def wall_split(wall_cell: float, resolution: float) -> int:
    """Into how many cells (per side) each map cell is split on the grid walls are found on (1 to
    :data:`MAX_WALL_SPLIT`): on a map coarser than ``wall_cell`` each cell is split into cells of
    about that size, as a finer map's cells are joined (:func:`skeleton_factor`), so the wall rules
    counted in cells (a face grown by a cell, the band of a cell either side of a line) are the same
    lengths in metres."""
    return min(max(int(np.floor(resolution / wall_cell + 1e-9)), 1), MAX_WALL_SPLIT)


def coarse_skeletons(free_mask: np.ndarray, occupied_mask: np.ndarray, factor: int):
    """Stage "skeletons" of the default method: the skeletons of free and
    occupied space on a grid ``factor`` times coarser than the map.

    A coarse free cell is free only if every map cell in it is (a one-cell
    wall survives), a coarse occupied cell is occupied if any is.
    """

    # the two thinnings run in compiled code without Python's lock: free space's on a second core
    free_skeleton = BackgroundCall(lambda: skeletonize(downsample(free_mask, factor, keep="all")))
    occupied_skeleton = skeletonize(downsample(occupied_mask, factor, keep="any"))
    return free_skeleton.result(), occupied_skeleton


def coarse_skeleton_graph(skel: np.ndarray, factor: int, radius: np.ndarray, grid: OccupancyGrid):
    """The skeleton graph of a skeleton taken on a ``factor``-times coarser
    grid (:func:`coarse_skeletons`), given on the map's own cells.

    Paths and node pixels are the centre cell of each coarse block (clipped
    to the map), ``radius`` (clearance, pixels of the map) is sampled there
    and lengths use the map's resolution: the topology comes from the coarse
    skeleton, clearances and lengths from the map.
    """

    topo = skeleton_topology(skel)
    factor = max(int(factor), 1)
    if factor > 1 and topo.n_nodes:
        fh, fw = radius.shape
        off = (factor - 1) // 2
        lim = np.array([fh - 1, fw - 1])
        topo.rep = np.minimum(topo.rep * factor + off, lim)
        topo.mr, topo.mc = topo.mr * factor + off, topo.mc * factor + off
        if topo.edges:  # every path moved at once, then cut into its edges again (views of one array)
            first = np.cumsum([0] + [len(p) for _, _, p in topo.edges]).tolist()
            moved = np.minimum(np.concatenate([p for _, _, p in topo.edges]) * factor + off, lim)
            topo.edges = [(u, v, moved[a:b]) for (u, v, _), a, b in zip(topo.edges, first[:-1], first[1:])]
    return graph_from_topology(topo, radius=radius, resolution=grid.resolution, to_world=grid.pixel_to_world)


def topomap_graphs(free_skeleton, occupied_skeleton, factor, d_free, occupied_mask, grid, min_occupied_branch):
    """Stage "graphs" of the default method: the free and (spur-pruned)
    occupied skeleton graphs on the map's cells, and the occupied clearance
    (px, distance of each occupied-mask cell to the mask's edge) the
    threshold is measured on."""

    d_occ = edt(occupied_mask, exact=False)  # only averaged into the wall threshold
    free_graph = coarse_skeleton_graph(free_skeleton, factor, d_free, grid)
    occupied_graph = coarse_skeleton_graph(occupied_skeleton, factor, d_occ, grid)
    occupied_graph = prune_spurs(occupied_graph, min_occupied_branch, copy=False)
    return free_graph, occupied_graph, d_occ


# --------------------------------------------------------------------------
# Stage "crop": work on the part of the map that can hold rooms
# --------------------------------------------------------------------------

def crop_box(grid: OccupancyGrid, margin: int):
    """``(r0, r1, c0, c1)``: bounding box of the free cells grown by ``margin``
    cells, or None when it is the whole map (or there is no free cell)."""
    box = true_bbox(grid.free, margin)
    if box is None:
        return None
    r0, r1, c0, c1 = box
    H, W = grid.shape
    # start on a multiple of 4 cells, so the coarse skeleton grid (factors
    # 1, 2, 4) falls on the same cells as without cropping
    r0, c0 = r0 - r0 % 4, c0 - c0 % 4
    # and end where a multiple of 4 cells is left to the far edge, so that a
    # rotated or flipped map is cut into the same blocks
    r1, c1 = H - (H - r1) + ((H - r1) % 4), W - (W - c1) + ((W - c1) % 4)
    if (r0, r1, c0, c1) == (0, H, 0, W):
        return None
    return int(r0), int(r1), int(c0), int(c1)


def crop_grid(grid: OccupancyGrid, box) -> OccupancyGrid:
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



def uncrop(seg: Segmentation, full: OccupancyGrid, box) -> Segmentation:
    """Move a segmentation of ``crop_grid(full, box)`` back onto ``full``:
    labels and intermediate images pasted in, every pixel coordinate
    shifted (world coordinates are unchanged)."""
    r0, r1, c0, c1 = box
    off = np.array([r0, c0], float)
    labels = paste(seg.labels, full.shape, box)
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
        shift = np.array([r0, c0])
        for _, _, ed in G.edges(data=True):
            ed["path"] = ed["path"] + shift
    for c in seg.candidates:
        for name in ("centroid", "ip1", "ip2", "ep1", "ep2"):
            val = getattr(c, name)
            if val is not None:
                setattr(c, name, np.asarray(val, float) + off)
    if seg.intermediates is not None:
        im = seg.intermediates
        im._place_later(full.shape, box)
        if im.wall_lines is not None:
            im.wall_lines = im.wall_lines + np.array([r0, c0, r0, c0], float)
    seg.grid = full
    seg.labels = labels
    return seg


# --------------------------------------------------------------------------
# The two Voronoi methods
# --------------------------------------------------------------------------

def segment_paper(grid: OccupancyGrid, options: PaperOptions | None = None, **kwargs) -> Segmentation:
    """Segment ``grid`` with the paper's method (Mora, Prados & Barber).

    Stages: masks (:func:`preprocess_masks`, occupied space = the occupied
    cells), skeletons (:func:`topomap.core.skeleton.skeletonize`), graphs
    (:func:`topomap.core.skeleton.skeleton_graph`, spurs pruned), the threshold
    (:func:`topomap.core.doors.wall_threshold`), passage candidates and their
    intersection points, the paper's door conditions
    (:func:`topomap.core.doors.select_doors`), cutting rooms
    (:func:`topomap.core.rooms.cut_rooms`).

    Parameters
    ----------
    grid : OccupancyGrid
    options : PaperOptions, optional
        Default ``PaperOptions()``.
    **kwargs
        Fields of :class:`~topomap.options.PaperOptions` to override
        (``erosion_radius``, ``median_size``, ``dilation_size``,
        ``wall_band``, ``min_free_branch``, ``min_occupied_branch``,
        ``max_door_search``; metres).

    Returns
    -------
    Segmentation

    Raises
    ------
    ParameterError
        An unknown option or an invalid value.
    """

    opts = options_from_kwargs(PaperOptions, "paper", options, kwargs).resolved(grid.resolution)
    res = grid.resolution
    timer = StageTimer()
    with timer("preprocess"):
        # the paper: occupied space is the occupied cells (unknown ones are not)
        f, d_free, occ = preprocess_masks(grid, opts, occupied=grid.occupied)
    with timer("skeletons"):
        free_skeleton = skeletonize(f)
        occupied_skeleton = skeletonize(occ)
    with timer("graphs"):
        free_graph = prune_spurs(skeleton_graph(free_skeleton, radius=d_free, resolution=res, to_world=grid.pixel_to_world),
                           opts.min_free_branch)
        d_occ = edt(occ)
        occupied_graph = prune_spurs(skeleton_graph(occupied_skeleton, radius=d_occ, resolution=res, to_world=grid.pixel_to_world),
                           opts.min_occupied_branch)
    with timer("doors"):
        thr_px = wall_threshold(d_occ, graph_pixels(occupied_graph))
        cands = passage_candidates(free_graph, min_branch_px=opts.min_free_branch / res)
        intersection_points(cands, ~grid.free, max_px=opts.max_door_search / res)
        kept = select_doors(cands, graph_endpoints(occupied_graph), thr_px, occupied_skeleton_lines(occupied_graph))
        segs = [(c.ip1, c.ip2) for c in kept]
    with timer("rooms"):
        labels, door_objs, _ = cut_rooms(grid, segs)
    im = Intermediates(free_mask=f, occupied_mask=occ, clearance=d_free, occupied_clearance=d_occ)
    seg = Segmentation(grid=grid, labels=labels, doors=door_objs, method="paper", params=opts.as_params(),
                       threshold=thr_px * res, free_graph=free_graph, occupied_graph=occupied_graph, candidates=cands,
                       timings=timer.t, options=opts, intermediates=im)
    log.info("%s: %d rooms, %d doors, threshold %.3f m (%d candidates)", grid.name, seg.n_rooms,
             len(door_objs), thr_px * res, len(cands))
    return seg


def _near_hits(search: OccupancyGrid, occupied: np.ndarray, radius_px: float, *, faces=None):
    """The cells within ``radius_px`` of an occupied cell, when
    most of the cells that bound free space are such cells (a laser map,
    whose walls are hits and whose other bounds are unexplored space);
    None on a map whose walls are not occupied cells (a plan that draws
    them in mid-gray). ``faces``: :func:`topomap.core.walls.wall_faces` of
    ``search``, when the caller has them."""
    import cv2


    r = max(int(np.floor(radius_px + 1e-9)), 0)
    near = cv2.dilate(occupied.view(np.uint8), disk(r)).view(bool) if r else occupied
    if faces is None:
        faces = wall_faces(~search.free, search.free)
    n = int(faces.sum())
    return near if n > 0 and int((faces & near).sum()) >= 0.5 * n else None


class _WallGrid:
    """Stage "walls" of the default method on the grid walls are measured on:
    cells of about ``opts.wall_cell`` (``k`` map cells per side: the map's
    own cells joined when they are smaller, each split into ``split x
    split`` when they are larger, ``k = 1 / split``), so that a wall's
    gaps, its lines and the band around them are judged in metres whatever
    the resolution. The share of faces on straight lines
    (:meth:`straight_share`) is measured on the map's own cells when they
    are larger: a wall is drawn straight only to within one of its cells.

    ``faces``, ``hough`` (:func:`topomap.core.walls.wall_lines`), ``lines`` and
    ``long_walls`` (:func:`topomap.core.walls.long_walls`) are in the cells of that grid;
    :meth:`fine` turns its points into map cells and :attr:`index` holds the
    long walls in map cells. With ``runs``, ``lines`` are the straight runs of
    faces on the main directions and the Hough lines off them
    (:func:`topomap.core.walls.straight_lines`), and the long walls are chained
    from them; without, both are from the Hough lines only."""

    def __init__(self, search: OccupancyGrid, opts, *, runs: bool = True, split: int | None = None):

        self.split = split = wall_split(opts.wall_cell, search.resolution) if split is None else split
        self.k = k = skeleton_factor(opts.wall_cell, search.resolution) if split == 1 else 1 / split
        self.res = res = search.resolution * k
        self._own = (search.free, opts.min_wall_length / search.resolution) if split > 1 else None
        if split > 1:
            self.free = np.kron(search.free, np.ones((split, split), bool))
        else:
            self.free = downsample(search.free, k, keep="all") if k > 1 else search.free
        self.obstacle = ~self.free
        self.faces = wall_faces(self.obstacle, self.free)
        self.hough = wall_lines(self.faces, min_length_px=opts.min_wall_length / res)
        self.lines = (straight_lines(self.faces, min_length_px=opts.min_wall_length / res,
                                       max_gap_px=opts.face_gap / res, hough=self.hough) if runs else self.hough)
        self.long_walls = (long_walls(self.lines, max_gap_px=opts.max_door_width / res,
                                offset_px=opts.wall_wander / res, min_span_px=opts.long_wall / res)
                   if opts.long_wall > 0 else [])
        self.index = WallIndex(scale_walls(self.long_walls, k))

    def straight_share(self) -> float:
        """The share of wall faces on straight lines (:func:`topomap.core.walls.straight_share`), on the
        map's own cells when they are larger than the wall grid's (a plan drawn on 0.10 m cells draws
        a diagonal wall in steps of 0.10 m, off a line of 0.05 m cells: the drawn plans of the
        simulated corpus measured 0.52-0.95 resampled to 0.10 m and split, 0.73-0.97 at 0.05 m)."""

        if self._own is not None:
            free, min_px = self._own
            faces = wall_faces(~free, free)
            return straight_share(faces, wall_lines(faces, min_length_px=min_px))
        return straight_share(self.faces, self.hough)

    def cells(self, mask):
        """A bool mask of the map's cells on the wall grid (a wall cell set where a map cell in it is)."""
        if self.split > 1:
            return np.kron(mask, np.ones((self.split, self.split), bool))
        return downsample(mask, self.k, keep="any")

    def fine(self, pts):
        """Points ``(..., 2)`` of the wall grid in the map's cells."""
        return np.asarray(pts, float) * self.k + (self.k - 1) / 2

    def fine_lines(self):
        """The straight wall faces ``(r1, c1, r2, c2)`` in the map's cells."""
        return self.fine(np.asarray(self.lines, float).reshape(-1, 2, 2)).reshape(-1, 4)

    def mask(self, shape, keep=None):
        """The long walls' cells (:func:`topomap.core.walls.wall_mask`) on a map grid of ``shape``; with
        ``keep`` (a bool per long wall), those of the walls it marks only."""

        walls = self.long_walls if keep is None else [w for w, k in zip(self.long_walls, keep) if k]
        m = wall_mask(walls, self.free.shape)
        if self.split > 1:
            m = downsample(m, self.split, keep="any")[:shape[0], :shape[1]]
        elif self.k > 1:
            m = np.kron(m, np.ones((self.k, self.k), bool))[:shape[0], :shape[1]]
        return m

    def openings(self, opts, hits=None) -> list:
        """Openings in walls (:func:`topomap.core.walls.wall_openings`), at the
        ends of partitions (:func:`topomap.core.walls.partition_gaps`) and, with
        long walls, their gaps (:func:`topomap.core.walls.long_wall_gaps`), without
        those across a corridor, as segments in the map's cells. ``hits``:
        the map's occupied cells (laser hits, clutter included), the
        evidence of a partition going on."""

        res = self.res
        ops = wall_openings(self.obstacle, self.free, min_wall_px=opts.min_wall_length / res,
                              min_gap_px=opts.min_door_width / res, max_gap_px=opts.max_door_width / res,
                              side_px=opts.min_door_width / res, depth_px=opts.alcove_depth / res, faces=self.faces,
                              lines=self.lines, beside_px=opts.beside_wall / res,
                              closet_px=opts.closet_depth / res, behind_px=opts.closet_behind / res)
        if self.long_walls:
            # long straight walls: the gaps in them are openings, and an
            # opening from one of them to another spans a corridor
            ops = ops + long_wall_gaps(self.obstacle, self.free, self.long_walls, min_gap_px=opts.min_door_width / res,
                                         max_gap_px=opts.max_door_width / res, depth_px=opts.alcove_depth / res,
                                         closet_px=opts.closet_depth / res, behind_px=opts.closet_behind / res)
        if opts.partition_wall > 0:
            # partitions mapped in part: the gap from a partition's end to the
            # wall it points at, with laser hits along it
            ops = ops + partition_gaps(self.obstacle, self.free, self.lines, min_wall_px=opts.partition_wall / res,
                                         min_gap_px=opts.min_door_width / res, max_gap_px=opts.max_door_width / res,
                                         min_hits_px=opts.partition_hits / res, depth_px=opts.alcove_depth / res,
                                         hits_band_px=opts.wall_wander / res, min_structure_px=opts.partition_structure / res,
                                         hits=None if hits is None else self.cells(hits))
        if not ops:
            return []
        P, Q = self.fine(np.array([p for p, _ in ops])), self.fine(np.array([q for _, q in ops]))
        keep = np.ones(len(ops), bool)
        if self.long_walls:
            keep = ~across_walls_many(P, Q, self.index, tol_px=opts.wall_wander / (res / self.k))
        return [(P[i], Q[i]) for i in np.flatnonzero(keep)]

def _wall_grid(search: OccupancyGrid, opts) -> _WallGrid:
    """The walls of ``search`` (:class:`_WallGrid`). On a map coarser than ``opts.wall_cell`` they
    are found on its cells split to about that size (a laser map's: its walls wander and its clutter
    is blocky, and the band of a cell either side of a wall's line is 0.05 m, as measured, not a
    0.10 m cell's width, within which a chair's outline passes for a wall going on past a gap),
    unless the walls are straight on the split cells too (at least ``straight_walls`` of the faces
    on lines: a drawn plan, whose pieces of one wall may lie a whole map cell apart as drawn and
    keep that cell of tolerance on the map's own cells)."""
    grid = _WallGrid(search, opts)
    if grid.split > 1 and not opts.scanned(straight_share(grid.faces, grid.hough)):
        grid = _WallGrid(search, opts, split=1)
    return grid


def furniture_keep(grid: OccupancyGrid, looked: OccupancyGrid, clutter, opts, *, parts=None,
                   rows: bool = True) -> np.ndarray:
    """Stage "furniture": the cells of bulky furniture that are not looked through.

    They are the cells of the long walls of ``looked`` (``grid`` with its
    small clutter, ``clutter``, looked through). With ``rows`` (a scanned
    map) the long walls are chained from Hough lines only, and those at
    least half of whose cells are bulky furniture in two or more separate
    pieces — a row of desks or round tables
    (:func:`topomap.core.walls.furniture_rows`) — keep none of it. On a drawn
    plan (``rows=False``) such a row stays a wall, as a plan draws a
    partition of solid blocks, and the long walls are chained from the runs
    of wall faces (:func:`topomap.core.walls.straight_lines`), which find the
    row in every orientation of the map. ``parts``: :func:`clutter_parts`
    of ``grid.free`` with the furniture size, when already made.

    Returns
    -------
    (M, N) ndarray of bool
    """

    res = grid.resolution
    wall_grid = _WallGrid(looked, opts, runs=not rows)
    if not rows:
        return wall_grid.mask(looked.free.shape)
    every = clutter_mask(grid.free, opts.min_wall_length / res, furniture_px=opts.furniture_size / res,
                         wall_thickness_px=opts.wall_thickness / res, parts=parts)
    bulky = every if clutter is None else every & ~clutter
    rows = furniture_rows(scale_walls(wall_grid.long_walls, wall_grid.k), ~looked.free, bulky, band_px=opts.wall_wander / res)
    return wall_grid.mask(looked.free.shape, keep=~rows)


def _drop_outside(grid: OccupancyGrid, labels, doors, n_rooms: int, clearance, opts: TopomapOptions):
    """Stage "outside": the rooms a laser saw beyond the facade, and the solid fans of free space
    beyond it inside the other rooms, taken out of the rooms (:mod:`topomap.core.outside`).
    ``clearance``: the distance (cells) from each free cell to the nearest one that is not."""

    res = grid.resolution
    encl = enclosure(grid.free, grid.occupied, res, open_area=opts.open_unknown_area,
                       window=opts.enclosure_window, gray=grid.gray)
    threshold = 8 * opts.outside_enclosure
    if not (encl[labels > 0] < threshold).any():
        return labels, doors, n_rooms, ()  # every cell of a room enclosed: no fan, no room outside
    # a fan is a piece at least as large as the smallest room, holding a free square as wide as it
    fans = outside_fans(labels, n_rooms, encl, clearance, threshold=threshold,
                        min_cells=int(np.ceil(opts.min_room_area / res ** 2 - 1e-9)),
                        width_px=0.5 * np.sqrt(opts.min_room_area) / res, grow_threshold=8 * FAN_OPEN)
    is_out = outside_regions(labels, n_rooms, encl, threshold=threshold, fans=fans)
    return drop_outside(labels, doors, n_rooms, is_out, fans=fans)


@dataclass
class _Looked:
    """The map doors are searched in: ``looked`` (the map with its clutter made free), ``clutter`` (those
    cells, or None), ``search`` (``looked`` with the gaps narrower than ``wall_gap`` closed) and ``closed``
    (the cells of those gaps, or None)."""

    looked: OccupancyGrid
    clutter: Optional[np.ndarray]
    search: OccupancyGrid
    closed: Optional[np.ndarray]


def _look_through_clutter(rooms_grid: OccupancyGrid, opts: TopomapOptions, furniture: float):
    """Stage "preprocess" of the default method: the obstacles' components (labelled once for the clutter
    of every size asked later, None when clutter is not looked through), the clutter of size
    ``furniture`` (m) among them, and the map with that clutter made free and the wall gaps closed
    (a :class:`_Looked`)."""
    res = rooms_grid.resolution
    solid = solid_components(rooms_grid.free) if opts.min_wall_length > 0 else None
    parts = None if solid is None else clutter_parts(rooms_grid.free, opts.min_wall_length / res,
                                                     furniture_px=furniture / res,
                                                     wall_thickness_px=opts.wall_thickness / res, components=solid)
    looked, clutter = without_clutter(rooms_grid, opts.min_wall_length, furniture_size=furniture,
                                      wall_thickness=opts.wall_thickness, parts=parts)
    search, closed = close_wall_gaps(looked, opts.wall_gap)
    return solid, parts, _Looked(looked, clutter, search, closed)


def _look_through_furniture(rooms_grid: OccupancyGrid, opts: TopomapOptions, straight: float, seen: _Looked,
                            solid, small_parts):
    """Stage "furniture" of the default method: bulky free-standing furniture is looked through too,
    except where a long wall runs along it. The new :class:`_Looked`, or None when the furniture
    changes nothing.

    On a scanned map the long walls are chained from Hough lines only: the furniture is still on the
    map, and runs of its faces along a main direction (a row of desks or cupboards) would chain into
    long walls and keep it. On a drawn plan a row of solid blocks along a long wall is a partition,
    and the long walls keep only the bulky pieces along them: the small clutter is looked through as
    before, so a plan with no bulky piece at all is left as it is."""
    res = rooms_grid.resolution
    # the clutter of this size, found once for the furniture's long walls and with them
    parts = (clutter_parts(rooms_grid.free, opts.min_wall_length / res, furniture_px=opts.furniture_size / res,
                           wall_thickness_px=opts.wall_thickness / res, components=solid)
             if solid is not None else None)
    scanned = opts.scanned(straight)
    if parts is None or (not scanned and not (parts[1] & ~small_parts[1]).any()):
        return None
    keep = furniture_keep(rooms_grid, seen.looked, seen.clutter, opts, parts=parts, rows=scanned)
    looked, clutter = without_clutter(rooms_grid, opts.min_wall_length, furniture_size=opts.furniture_size,
                                      wall_thickness=opts.wall_thickness, keep=keep, parts=parts,
                                      also=None if scanned else seen.clutter)
    if clutter is None or (seen.clutter is not None and np.array_equal(clutter, seen.clutter)):
        return None
    search, closed = close_wall_gaps(looked, opts.wall_gap)
    return _Looked(looked, clutter, search, closed)


def _find_doors(free_graph, occupied_graph, occupied_clearance, wall_grid, seen: _Looked,
                rooms_grid: OccupancyGrid, opts: TopomapOptions):
    """Stage "doors" of the default method: the map's threshold (px), every bottleneck candidate, and
    the door segments kept (judged, not across a corridor between long walls, posts seen by the
    laser, duplicates suppressed)."""
    res = rooms_grid.resolution
    free = seen.search.free
    thr_px = wall_threshold(occupied_clearance, graph_pixels(occupied_graph))
    faces = wall_grid.faces if wall_grid.k == 1 else None  # the faces of the walls, when found on the map's cells
    cands = find_bottlenecks(free_graph, ~free, opts, res, thr_px, faces=faces)
    accepted = judge_doors(cands, free, graph_endpoints(occupied_graph), thr_px, opts, res)
    if wall_grid.long_walls and opts.pillar_depth > 0:
        accepted = across_corridor(accepted, wall_grid.index, opts.pillar_depth / res)
    if opts.frontier_post > 0:
        near = _near_hits(seen.search, rooms_grid.occupied, opts.frontier_post / res, faces=faces)
        if near is not None:
            accepted = seen_posts(accepted, near)
    return thr_px, cands, suppress_duplicates(accepted, res)


def _cut_gaps(free_graph, free, hits, segs, cands, wall_grid, opts: TopomapOptions, resolution: float,
              clearance):
    """Stage "gaps" of the default method: the gaps in thin walls
    (:func:`topomap.core.walls.thin_wall_gaps`) where no door is cut yet, one
    per doorway, not at a pillar or a bump on a wall (``pillar_depth``) nor across a corridor
    between long walls (as doors are not), added to the door segments ``segs`` and the candidates
    ``cands``."""
    res = resolution
    gaps = thin_wall_gaps(free_graph, free, hits, min_width_px=opts.min_door_width / res,
                          max_width_px=opts.max_door_width / res, along_px=opts.gap_wall / res,
                          thick_px=opts.wall_thickness / res, structure_px=opts.partition_structure / res,
                          pillar_px=opts.pillar_depth / res, max_radius=opts.max_door_width / 2,
                          clearance=clearance, kept=segs, step=max(opts.wall_cell / res, 1.0))
    found = opening_candidates(gaps, res, status=WALL_GAP)
    cands = cands + [c for _, c in found]
    if wall_grid.long_walls and opts.pillar_depth > 0:
        found = across_corridor(found, wall_grid.index, opts.pillar_depth / res)
    return segs + suppress_duplicates(found, res, kept=segs), cands


def _cut_rooms(rooms_grid: OccupancyGrid, segs, space, clearance, opts: TopomapOptions):
    """Stage "rooms" of the default method: labels, doors and room count of the rooms cut at ``segs``."""
    res = rooms_grid.resolution
    min_cells = int(np.ceil(opts.min_room_area / res ** 2 - 1e-9))
    wide = clearance >= 0.5 * opts.wall_gap / res - 1e-6 if opts.wall_gap > 0 else None
    return cut_rooms(rooms_grid, segs, space=space, min_room_cells=min_cells, wide=wide,
                     max_door_width=opts.max_door_width)


def segment_topomap(grid: OccupancyGrid, options: TopomapOptions | None = None, *, prior=None,
                    **kwargs) -> Segmentation:
    """Segment ``grid`` with topomap's default method.

    The paper's ideas — skeletons of free *and* occupied space, a threshold
    measured on the map (twice the mean wall half-thickness), doors where a
    narrow passage meets protruding walls, rooms by cutting at the doors with
    no merging step — with a different door test: bottlenecks of clearance
    along the free-space skeleton (and corridor mouths), door posts at the
    closest wall cells, and a protrusion test that accepts the paper's
    endpoint evidence or a measured convexity of the wall at the posts. See
    the "How it works" page for pictures of every step.

    Stages: crop (:func:`crop_box`), masks (:func:`without_clutter`,
    :func:`preprocess_masks`), skeletons (:func:`coarse_skeletons`), graphs
    (:func:`topomap_graphs`), bottlenecks
    (:func:`topomap.core.doors.find_bottlenecks`), door judging
    (:func:`topomap.core.doors.judge_doors`), duplicate suppression
    (:func:`topomap.core.doors.suppress_duplicates`), openings in walls
    (:func:`topomap.core.walls.wall_openings`), gaps in thin walls
    (:func:`topomap.core.walls.thin_wall_gaps`), cutting rooms
    (:func:`topomap.core.rooms.cut_rooms`).

    Parameters
    ----------
    grid : OccupancyGrid
        Free cells are ``grid.free``; every other cell is an obstacle.
    options : TopomapOptions, optional
        Default ``TopomapOptions()``; every option, its unit and its
        physical reason are documented there.
    **kwargs
        Fields of :class:`~topomap.options.TopomapOptions` to override, for
        example ``window=0.4``.
    prior : topomap.core.identity.DoorPrior, optional
        A previous result's doors: its doors are kept and new cuts in its
        unchanged rooms dropped (:meth:`~topomap.core.identity.DoorPrior.adjust`).

    Returns
    -------
    Segmentation
        ``method="topomap"``; ``candidates`` holds every bottleneck with its
        ``status``.

    Raises
    ------
    ParameterError
        An unknown option or an invalid value.
    """
    opts = options_from_kwargs(TopomapOptions, "topomap", options, kwargs)
    res = grid.resolution
    timer = StageTimer()
    # work on the bounding box of free space plus the wall band: the rest of
    # the map (unknown margins, solid outside) cannot hold a room or a door
    box = crop_box(grid, metres_to_px(opts.wall_band + opts.dilation_size + opts.max_door_width, res))
    rooms_grid = crop_grid(grid, box) if box is not None else grid
    furniture = opts.furniture_size or 0.0  # None: measured on the map below
    with timer("preprocess"):
        solid, small_parts, seen = _look_through_clutter(rooms_grid, opts, furniture)
    with timer("walls"):
        wall_grid = _wall_grid(seen.search, opts)
        straight = wall_grid.straight_share()
        opts = opts.resolved(res, straight)  # rise and furniture measured on the map
    if opts.furniture_size > furniture:
        with timer("furniture"):
            again = _look_through_furniture(rooms_grid, opts, straight, seen, solid, small_parts)
            if again is not None:
                seen = again
                wall_grid = _WallGrid(seen.search, opts, split=wall_grid.split)
    del solid, small_parts
    with timer("preprocess"):
        free = seen.search.free  # read, never written, from here on
        space = free if seen.clutter is None else free & ~seen.clutter
        # the clearance (an exact distance transform, in OpenCV without Python's lock) on a second
        # core while the masks and the skeletons are made: the same array, needed from the graphs on
        clearance = BackgroundCall(edt, free)
        free_mask, _, occupied_mask = preprocess_masks(seen.search, opts, clearance=False)
    factor = skeleton_factor(opts.skeleton_cell, res)
    with timer("skeletons"):
        free_skeleton, occupied_skeleton = coarse_skeletons(free_mask, occupied_mask, factor)
    with timer("graphs"):
        d_free = clearance.result()
        free_graph, occupied_graph, d_occ = topomap_graphs(free_skeleton, occupied_skeleton, factor, d_free,
                                                           occupied_mask, seen.search, opts.min_occupied_branch)
    with timer("doors"):
        thr_px, cands, segs = _find_doors(free_graph, occupied_graph, d_occ, wall_grid, seen, rooms_grid, opts)
    if opts.openings:
        with timer("openings"):
            ops = opening_candidates(wall_grid.openings(opts, hits=rooms_grid.occupied), res)
            segs = segs + suppress_duplicates(ops, res, kept=segs)
            cands = cands + [c for _, c in ops]
    if opts.gaps:
        with timer("gaps"):
            segs, cands = _cut_gaps(free_graph, free, rooms_grid.occupied, segs, cands, wall_grid, opts, res, d_free)
    if prior is not None:
        with timer("prior doors"):
            segs = prior.adjust(rooms_grid, segs, opts, walls=~free, space=space)
    with timer("rooms"):
        labels, door_objs, n_rooms = _cut_rooms(rooms_grid, segs, space, d_free, opts)
    outside = ()
    if opts.outside_enclosure > 0 and n_rooms:
        with timer("outside"):
            labels, door_objs, n_rooms, outside = _drop_outside(rooms_grid, labels, door_objs, n_rooms, d_free, opts)
    params = opts.as_params()
    if prior is not None:
        params["prior"] = prior.previous.where  # the previous result whose doors were the prior
    im = Intermediates(free_mask=free_mask, occupied_mask=occupied_mask, clearance=d_free,
                       occupied_clearance=d_occ, clutter=seen.clutter, skeleton_factor=factor,
                       closed_gaps=seen.closed, wall_lines=wall_grid.fine_lines(), straight_share=straight)
    seg = Segmentation(grid=rooms_grid, labels=labels, doors=door_objs, method="topomap", params=params,
                       threshold=thr_px * res, free_graph=free_graph, occupied_graph=occupied_graph,
                       candidates=cands, timings=timer.t, options=opts, intermediates=im, room_count=n_rooms,
                       outside=outside)
    if box is not None:
        seg = uncrop(seg, grid, box)
    log.info("%s: %d rooms, %d fragments, %d doors, threshold %.3f m (%d candidates)", grid.name, seg.n_rooms,
             seg.n_fragments, len(door_objs), thr_px * res, len(cands))
    return seg


def _baseline_keywords(name) -> set:
    """The keyword options of the baseline ``name`` (its function's keywords but ``resolution``)."""
    import inspect

    return {k for k, p in inspect.signature(getattr(baselines, name)).parameters.items()
            if p.kind is p.KEYWORD_ONLY and k != "resolution"}


def _baseline(name):
    def run(grid: OccupancyGrid, **params) -> Segmentation:
        fn = getattr(baselines, name)
        check_keywords(name, params, _baseline_keywords(name))
        timer = StageTimer()
        with timer("segment"):
            # every baseline ends with fill_unlabeled: all free cells labelled
            labels, segs = fn(grid.free, resolution=grid.resolution, **params)
        with timer("rooms"):
            doors = doors_between_rooms(grid, labels, segs)
        return Segmentation(grid=grid, labels=labels, doors=doors, method=name, params=params, timings=timer.t)

    run.__name__ = f"segment_{name}"
    run.__doc__ = f"Segment with :func:`topomap.core.baselines.{name}` and wrap the result."
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


def check_method_options(method, params: dict) -> dict:
    """The keyword options ``params`` of ``method`` (default :data:`DEFAULT_METHOD`), checked without
    segmenting anything: a copy of them.

    For ``"topomap"`` and ``"paper"`` every name must be a field of
    :class:`~topomap.options.TopomapOptions` / :class:`~topomap.options.PaperOptions` and every value
    valid for it; for the other methods, a keyword of their function in
    :mod:`topomap.core.baselines` (its values are checked when it runs).

    Raises
    ------
    ParameterError
        Unknown method, unknown option, invalid value (the message names both).
    """
    method = method or DEFAULT_METHOD
    if method not in METHODS:
        raise ParameterError(f"unknown method {method!r}; choose from {', '.join(sorted(METHODS))}")
    params = dict(params or {})
    if method in ("topomap", "paper"):
        options_from_kwargs(TopomapOptions if method == "topomap" else PaperOptions, method, kwargs=params)
    else:
        check_keywords(method, params, _baseline_keywords(method))
    return params


def segment(grid: OccupancyGrid, *, method: str = None, previous=None, **params) -> Segmentation:
    """Segment an occupancy grid into rooms and doors.

    :func:`topomap.segment` is this function with ``previous`` also read from a file.

    Parameters
    ----------
    grid : OccupancyGrid
        The map (see :func:`topomap.io.load_map`).
    method : str, optional
        One of :data:`METHODS` (default :data:`DEFAULT_METHOD`).
    previous : Segmentation or networkx.MultiGraph or DoorPrior, optional
        An earlier result of the same place (or its room graph): rooms
        keep its IDs (:func:`topomap.core.identity.match_rooms`; ``seg.changes``);
        with ``"topomap"`` its doors are a prior of the door stage
        (:class:`topomap.core.identity.DoorPrior`).
    **params
        Keyword options of the method, lengths in metres (for ``"topomap"``
        and ``"paper"`` the fields of :class:`~topomap.options.TopomapOptions`
        / :class:`~topomap.options.PaperOptions`, or ``options=`` an
        instance of it).

    Returns
    -------
    Segmentation

    Raises
    ------
    ParameterError
        Unknown method, not an OccupancyGrid, an unknown option of the
        method or an invalid value.
    """
    method = method or DEFAULT_METHOD
    if method not in METHODS:
        raise ParameterError(f"unknown method {method!r}; choose from {', '.join(sorted(METHODS))}")
    if not isinstance(grid, OccupancyGrid):
        raise ParameterError(f"segment() needs an OccupancyGrid (see topomap.load_map), got {type(grid).__name__}")
    t0 = time.perf_counter()
    t_prev = 0.0
    if previous is not None:
        if not isinstance(previous, DoorPrior):
            # read once, for the door stage and the matching (a room graph: only where it overlaps this map)
            previous = DoorPrior(previous, within=grid)
        t_prev = time.perf_counter() - t0
        if method == "topomap":
            params = {**params, "prior": previous}
    seg = METHODS[method](grid, **params)
    if previous is not None:
        t1 = time.perf_counter()
        seg, _ = match_rooms(previous.previous, seg)
        seg.timings["previous"] = t_prev
        seg.timings["match"] = time.perf_counter() - t1
    seg.timings["total"] = time.perf_counter() - t0
    return seg
