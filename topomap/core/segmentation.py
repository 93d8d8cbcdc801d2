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
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from ..errors import ParameterError
from .geometry import disk, metres_to_px, true_bbox
from ..io.maps import FREE, OCCUPIED, OccupancyGrid
from ..options import PaperOptions, TopomapOptions, check_keywords, options_from_kwargs
from .rooms import cut_rooms, doors_between_rooms

log = logging.getLogger("topomap")

__all__ = ["Segmentation", "Intermediates", "segment", "segment_paper", "segment_topomap", "METHODS",
           "DEFAULT_METHOD", "cut_rooms", "doors_between_rooms"]


@dataclass
class Intermediates:
    """Images a Voronoi method computed on the way, in the map's pixels.

    Kept on :attr:`Segmentation.intermediates` so that a user (or the
    pictures of the "How it works" page) can see what the skeletons were
    taken from without re-running any stage.

    Attributes
    ----------
    free_mask : (M, N) ndarray of bool
        Free space after erosion and median filter: the free-space skeleton
        was taken from it (on the coarse skeleton grid for ``"topomap"``).
    occupied_mask : (M, N) ndarray of bool
        Occupied space restricted to the wall band and dilated: the
        occupied-space skeleton was taken from it.
    clearance : (M, N) ndarray of float
        Distance (pixels) of every free cell to the nearest non-free cell:
        the ``radius`` along the free-space skeleton graph.
    occupied_clearance : (M, N) ndarray of float
        Distance (pixels) of every cell of ``occupied_mask`` to free space:
        its mean over the occupied-skeleton pixels, doubled, is the
        threshold.
    clutter : (M, N) ndarray of bool or None
        ``"topomap"``: the free-standing obstacle cells looked through while
        doors are searched (``min_wall_length``); None when that is off or
        for ``"paper"``.
    skeleton_factor : int
        Map cells per side of one cell of the grid the skeletons were taken
        on (1 = the map's own grid).
    closed_gaps : (M, N) ndarray of bool or None
        ``"topomap"``: the free cells of the gaps narrower than ``wall_gap``
        that were closed before doors were searched and rooms cut.
    wall_lines : (K, 4) ndarray of float or None
        ``"topomap"``: the straight wall faces ``(r1, c1, r2, c2)`` (pixels)
        found on the map (:func:`topomap.core.walls.straight_lines`).
    straight_share : float or None
        ``"topomap"``: the share of wall-face cells on the map's Hough lines
        (:func:`topomap.core.walls.wall_lines`, :func:`topomap.core.walls.straight_share`),
        which decides the ``rise`` the method ran with.

    Notes
    -----
    For ``"topomap"`` the masks and clearances are those of the map with the
    clutter made free (the map doors are searched in). The default method
    works on the bounding box of the free space; its images are placed on
    the whole map when first read.
    """

    free_mask: np.ndarray
    occupied_mask: np.ndarray
    clearance: np.ndarray
    occupied_clearance: np.ndarray
    clutter: Optional[np.ndarray] = None
    skeleton_factor: int = 1
    closed_gaps: Optional[np.ndarray] = None
    wall_lines: Optional[np.ndarray] = None
    straight_share: Optional[float] = None

    #: The images that :func:`uncrop` places back on the whole map.
    IMAGES = ("free_mask", "occupied_mask", "clearance", "occupied_clearance", "clutter", "closed_gaps")

    def _place_later(self, shape, box) -> None:
        """Hold the images as crops ``box`` of a map of ``shape``: each is
        placed on the whole map when first read (most jobs never read them)."""
        self.__dict__["_crops"] = {n: self.__dict__.pop(n) for n in self.IMAGES}
        self.__dict__["_box"] = (shape, box)

    def __getattr__(self, name):
        crops = self.__dict__.get("_crops")
        if crops is None or name not in crops:
            raise AttributeError(name)
        shape, box = self.__dict__["_box"]
        value = _paste(crops.pop(name), shape, box)
        self.__dict__[name] = value
        return value


@dataclass
class Segmentation:
    """The result of a segmentation.

    Attributes
    ----------
    grid : OccupancyGrid
        The input map.
    labels : (M, N) ndarray of int32
        Label per cell, on every free cell, ``0`` elsewhere: rooms are
        ``1..n_rooms``; the labels after them (``n_rooms + 1 ..``) are
        fragments, free regions too small to be a room (scan specks, rays
        through walls) and, last, the regions outside the building
        (:attr:`outside`), which are not in the room graph.
    doors : list of Door
        Doors between two different rooms (see :class:`topomap.core.doors.Door`).
    method : str
        Name of the method that produced the result.
    params : dict
        The complete record of the options that ran (metres where they are
        lengths): ``dataclasses.asdict(options)`` for the Voronoi methods,
        the keyword options given for the baselines.
    threshold : float or None
        The map's own door threshold (metres), for the Voronoi methods.
    free_graph, occupied_graph : networkx.MultiGraph or None
        Skeleton graphs of free and occupied space (pixel paths, metres).
    candidates : list of Candidate
        Every narrow-passage candidate with the reason it was kept or not
        (``status``, one of :data:`topomap.core.doors.STATUSES`).
    timings : dict
        Seconds per pipeline stage.
    options : TopomapOptions or PaperOptions or None
        The options object that ran (Voronoi methods; defaults that depend
        on the map filled in).
    intermediates : Intermediates or None
        Masks and clearance images the Voronoi methods computed (see
        :class:`Intermediates`).
    room_count : int or None
        Number of rooms when fragments follow them in ``labels`` (see
        :attr:`n_rooms`); None: every label is a room.
    outside : tuple of int
        The labels (after the rooms, among the fragments' labels) of the
        regions *outside* the building: free space a laser saw beyond the
        facade, through a window or an open outer door
        (``TopomapOptions.outside_enclosure``). Neither rooms nor in the
        room graph; :attr:`outside_area` is their area.
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
    options: object = None
    intermediates: Optional[Intermediates] = field(default=None, repr=False)
    room_count: Optional[int] = None
    outside: tuple = ()
    _room_graph: object = field(default=None, repr=False)

    @property
    def n_rooms(self) -> int:
        """Number of rooms: the labels ``1..n_rooms`` (the room graph's nodes)."""
        if self.room_count is not None:
            return int(self.room_count)
        return int(self.labels.max()) if self.labels.size else 0

    @property
    def top_room_id(self) -> int:
        """The largest room label (``n_rooms``; 0 without rooms): labels above it are fragments."""
        return self.n_rooms

    @property
    def n_fragments(self) -> int:
        """Number of fragments: the labels above :attr:`top_room_id` (free
        regions too small to be a room, see ``TopomapOptions.min_room_area``,
        and the regions outside the building, :attr:`outside`)."""
        top = int(self.labels.max()) if self.labels.size else 0
        return max(top - self.top_room_id, 0)

    @property
    def room_labels(self) -> np.ndarray:
        """``labels`` with the fragments set to 0: rooms only."""
        if self.n_fragments == 0:
            return self.labels
        return np.where(self.labels <= self.top_room_id, self.labels, 0)

    @property
    def fragment_area(self) -> float:
        """Total area of the fragments, m²."""
        return float((self.labels > self.top_room_id).sum()) * self.grid.resolution ** 2

    @property
    def outside_area(self) -> float:
        """Total area of the regions outside the building (:attr:`outside`), m²."""
        if not self.outside:
            return 0.0
        return float(np.isin(self.labels, self.outside).sum()) * self.grid.resolution ** 2

    @property
    def room_graph(self):
        """The room–door graph (:func:`topomap.core.roomgraph.room_graph`), built once."""
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


# --------------------------------------------------------------------------
# Stage "masks": preprocessed free and occupied space
# --------------------------------------------------------------------------

def preprocess_masks(grid: OccupancyGrid, opts, *, occupied=None, clearance: bool = True):
    """Stage "masks": the free mask, clearance and occupied mask the skeletons are taken from.

    Free space is eroded with a disk of ``opts.erosion_radius`` and
    median-filtered (``opts.median_size``); occupied space (``occupied``,
    default every non-free cell) is restricted to the band within
    ``opts.wall_band`` of free space and dilated with a square of
    ``opts.dilation_size``.

    Parameters
    ----------
    grid : OccupancyGrid
    opts : TopomapOptions or PaperOptions
    occupied : (M, N) ndarray of bool, optional
        The cells occupied space is made of (the paper: ``grid.occupied``).
    clearance : bool
        Whether to compute the clearance (False: None is returned in its
        place, for a caller that computes ``edt(grid.free)`` itself).

    Returns
    -------
    free_mask : (M, N) ndarray of bool
    clearance : (M, N) ndarray of float32 or None
        Distance (px) of every free cell to the nearest non-free cell (of
        the map before preprocessing).
    occupied_mask : (M, N) ndarray of bool
    """
    import cv2

    from .._fast import edt

    res = grid.resolution
    er = metres_to_px(opts.erosion_radius, res)
    med = metres_to_px(opts.median_size, res)
    dil = metres_to_px(opts.dilation_size, res)
    band = metres_to_px(opts.wall_band, res, 1)
    free = grid.free
    f = free.view(np.uint8)
    if er > 0:
        f = cv2.erode(f, disk(er), borderType=cv2.BORDER_CONSTANT, borderValue=0)
    if med >= 3:
        k = med if med % 2 else med + 1
        if k <= 5:
            f = cv2.medianBlur(f, k).view(bool)  # the median of 0 / 1 values is 0 / 1
        else:  # the same (a majority of the k x k cells, edges replicated), in time independent of k
            f = cv2.boxFilter(f, cv2.CV_16U, (k, k), normalize=False, borderType=cv2.BORDER_REPLICATE) > k * k // 2
    else:
        f = f.astype(bool)
    d_free = edt(free) if clearance else None
    solid = ~free
    dist_out = edt(solid, exact=False)  # only compared with the band width
    occ = (solid if occupied is None else occupied & solid) & (dist_out <= band)
    if dil > 1:
        occ = cv2.dilate(occ.view(np.uint8), np.ones((dil, dil), np.uint8)).view(bool)  # 0 / 1
    return f, d_free, occ


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
    from . import walls as W

    res = grid.resolution
    wk = _Walls(looked, opts, runs=not rows)
    if not rows:
        return wk.mask(looked.free.shape)
    every = clutter_mask(grid.free, opts.min_wall_length / res, furniture_px=opts.furniture_size / res,
                         wall_thickness_px=opts.wall_thickness / res, parts=parts)
    bulky = every if clutter is None else every & ~clutter
    rows = W.furniture_rows(W.scale_walls(wk.lw, wk.k), ~looked.free, bulky, band_px=opts.wall_wander / res)
    return wk.mask(looked.free.shape, keep=~rows)


def close_wall_gaps(grid: OccupancyGrid, wall_gap: float):
    """Stage "masks": the map with gaps between obstacles narrower than
    ``wall_gap`` (m) closed (a morphological closing of the non-free cells
    with a disk of that diameter): scan gaps in walls, and the gap between a
    cupboard and the wall behind it, neither make a door nor join two rooms.

    Returns
    -------
    grid : OccupancyGrid
        ``grid`` itself when nothing was closed (or ``wall_gap`` is 0).
    closed : (M, N) ndarray of bool or None
        The free cells that were closed (None when ``wall_gap`` is 0).
    """
    import cv2

    r = metres_to_px(wall_gap / 2, grid.resolution)
    if r <= 0:
        return grid, None
    free = grid.free
    if r < _CLOSE_BY_DISTANCE:
        shut = cv2.morphologyEx(np.logical_not(free).view(np.uint8), cv2.MORPH_CLOSE, disk(r),
                                borderType=cv2.BORDER_CONSTANT, borderValue=0).view(bool)  # 0 / 1
    else:
        shut = _close_by_distance(free, r)
    closed = shut & free
    if closed.any():
        grid = OccupancyGrid(np.where(closed, np.int8(OCCUPIED), grid.cells), grid.resolution,
                             grid.origin, grid.source)
    return grid, closed


#: Disk radius (cells) from which :func:`close_wall_gaps` closes with two exact distance transforms
#: (time linear in the map's area) instead of OpenCV's closing (time growing with the radius too).
_CLOSE_BY_DISTANCE = 12


def _close_by_distance(free: np.ndarray, r: int) -> np.ndarray:
    """The closing of the non-free cells with ``disk(r)`` (nothing outside the image), exactly:
    dilated = within ``r`` of a non-free cell, then eroded = farther than ``r`` from every cell
    not dilated or outside the image (exact Euclidean distances: ``d <= r`` iff ``d**2 <= r**2``)."""
    import cv2

    from .._fast import edt

    if free.all():
        return np.zeros(free.shape, bool)
    grown = edt(free) <= r
    pad = cv2.copyMakeBorder(grown.view(np.uint8), r + 1, r + 1, r + 1, r + 1, cv2.BORDER_CONSTANT, value=0)
    return edt(pad)[r + 1:-(r + 1), r + 1:-(r + 1)] > r


def solid_components(free: np.ndarray):
    """The 8-connected components of the non-free cells: ``(solid, comp, stats)``, the non-free
    cells (uint8 0/1), their labels (0: the free cells) and OpenCV's statistics per label."""
    from .._fast import label_stats

    solid = np.logical_not(free).view(np.uint8)
    _, comp, stats, _ = label_stats(solid, connectivity=8)
    return solid, comp, stats


def clutter_parts(free: np.ndarray, max_extent_px: float, *, furniture_px: float = 0.0,
                  wall_thickness_px: float = np.inf, components=None):
    """The 8-connected components of the non-free cells and which of them are
    free-standing clutter (:func:`clutter_mask` before ``keep``).
    ``components``: :func:`solid_components` of ``free``, when already made.

    Returns
    -------
    comp : (M, N) ndarray of uint16 or int32
        Component labels (0: the free cells).
    clutter : (n + 1,) ndarray of bool
        Per component: less than ``max_extent_px`` across, or less than
        ``furniture_px`` across and thicker than ``wall_thickness_px``.
    """
    import cv2

    solid, comp, stats = components if components is not None else solid_components(free)
    extent = np.maximum(stats[:, cv2.CC_STAT_WIDTH], stats[:, cv2.CC_STAT_HEIGHT])
    small = extent < max_extent_px
    bulky = (extent < furniture_px) & ~small
    bulky[0] = False
    H, W = free.shape
    for i in np.flatnonzero(bulky):
        # the largest inscribed radius: the distance transform on the component's box grown by one cell
        # (every cell beside the component is free, so its distances are those of the whole map's)
        c0, r0, w, h = (int(v) for v in stats[i, :4])
        r0, c0, r1, c1 = max(r0 - 1, 0), max(c0 - 1, 0), min(r0 + h + 1, H), min(c0 + w + 1, W)
        inside = cv2.distanceTransform(np.ascontiguousarray(solid[r0:r1, c0:c1]), cv2.DIST_L2, 3)
        small[i] = 2 * float(inside[comp[r0:r1, c0:c1] == i].max()) >= wall_thickness_px
    small[0] = False  # label 0: the free cells themselves
    return comp, small


def clutter_mask(free: np.ndarray, max_extent_px: float, *, furniture_px: float = 0.0,
                 wall_thickness_px: float = np.inf, keep=None, parts=None) -> np.ndarray:
    """Obstacle cells of free-standing clutter (8-connected components of the
    non-free cells): components less than ``max_extent_px`` across (bounding
    box) — chairs, plants, small tables, pillars — and components less than
    ``furniture_px`` across that are thicker than ``wall_thickness_px``
    (twice their largest inscribed radius) — desks, cupboards, tables with
    their chairs: no free-standing piece of wall is that thick — unless
    it touches a cell of ``keep`` (a long wall runs along it).

    ``parts``: :func:`clutter_parts` of the same arguments, when already
    made (the furniture stage asks twice, with and without ``keep``)."""
    from .._fast import lookup

    comp, clutter = parts if parts is not None else clutter_parts(
        free, max_extent_px, furniture_px=furniture_px, wall_thickness_px=wall_thickness_px)
    if keep is not None:
        clutter = clutter.copy()
        clutter[np.unique(comp[keep])] = False
    return lookup(clutter.view(np.uint8), comp).view(bool)


def without_clutter(grid: OccupancyGrid, min_wall_length: float, *, furniture_size: float = 0.0,
                    wall_thickness: float = np.inf, keep=None, parts=None, also=None):
    """The map doors are searched in: free-standing clutter smaller than a
    wall piece (``min_wall_length`` m across, 0 = none), and bulky furniture
    (less than ``furniture_size`` m across, thicker than ``wall_thickness``
    m, touching no cell of ``keep``; see :func:`clutter_mask`), made free.
    ``parts``: :func:`clutter_parts` of ``grid.free`` with these sizes, when
    already made. ``also``: cells looked through in any case (bool, the
    map's shape), whatever ``keep`` says.

    Returns
    -------
    grid : OccupancyGrid
        ``grid`` itself when there is no clutter.
    clutter : (M, N) ndarray of bool or None
        The clutter cells (None when ``min_wall_length`` is 0).
    """
    if min_wall_length <= 0:
        return grid, None
    # doors are in walls: free-standing clutter smaller than a wall piece
    # is looked through while doors are searched (rooms still use the map)
    res = grid.resolution
    clutter = clutter_mask(grid.free, min_wall_length / res, furniture_px=furniture_size / res,
                           wall_thickness_px=wall_thickness / res, keep=keep, parts=parts)
    if also is not None:
        clutter |= also
    if clutter.any():
        grid = OccupancyGrid(np.where(clutter, np.int8(FREE), grid.cells), grid.resolution,
                             grid.origin, grid.source)
    return grid, clutter


# --------------------------------------------------------------------------
# Stages "skeletons" and "graphs" of the default method: the coarse grid
# --------------------------------------------------------------------------

def skeleton_factor(skeleton_cell: float, resolution: float) -> int:
    """How many map cells (per side) one cell of the skeleton grid holds (>= 1)."""
    return max(int(np.floor(skeleton_cell / resolution + 1e-9)), 1)


def coarse_skeletons(free_mask: np.ndarray, occupied_mask: np.ndarray, factor: int):
    """Stage "skeletons" of the default method: the skeletons of free and
    occupied space on a grid ``factor`` times coarser than the map.

    A coarse free cell is free only if every map cell in it is (a one-cell
    wall survives), a coarse occupied cell is occupied if any is.
    """
    from . import skeleton as S
    from .._fast import Beside

    # the two thinnings run in compiled code without Python's lock: free space's on a second core
    fs = Beside(lambda: S.skeletonize(S.downsample(free_mask, factor, keep="all")))
    os_ = S.skeletonize(S.downsample(occupied_mask, factor, keep="any"))
    return fs.result(), os_


def coarse_skeleton_graph(skel: np.ndarray, factor: int, radius: np.ndarray, grid: OccupancyGrid):
    """The skeleton graph of a skeleton taken on a ``factor``-times coarser
    grid (:func:`coarse_skeletons`), given on the map's own cells.

    Paths and node pixels are the centre cell of each coarse block (clipped
    to the map), ``radius`` (clearance, pixels of the map) is sampled there
    and lengths use the map's resolution: the topology comes from the coarse
    skeleton, clearances and lengths from the map.
    """
    from . import skeleton as S

    topo = S.skeleton_topology(skel)
    factor = max(int(factor), 1)
    if factor > 1 and topo.n_nodes:
        fh, fw = radius.shape
        off = (factor - 1) // 2
        lim = np.array([fh - 1, fw - 1])
        topo.rep = np.minimum(topo.rep * factor + off, lim)
        topo.mr, topo.mc = topo.mr * factor + off, topo.mc * factor + off
        if topo.edges:  # every path moved at once, then cut into its edges again (views of one array;
            # 0.86 -> 0.19 ms per graph on the free graphs of 4 ipa mid maps, min of 25)
            first = np.cumsum([0] + [len(p) for _, _, p in topo.edges]).tolist()
            moved = np.minimum(np.concatenate([p for _, _, p in topo.edges]) * factor + off, lim)
            topo.edges = [(u, v, moved[a:b]) for (u, v, _), a, b in zip(topo.edges, first[:-1], first[1:])]
    return S.graph_from_topology(topo, radius=radius, resolution=grid.resolution, to_world=grid.pixel_to_world)


def topomap_graphs(fs, os_, factor, d_free, occupied_mask, grid, min_occupied_branch):
    """Stage "graphs" of the default method: the free and (spur-pruned)
    occupied skeleton graphs on the map's cells, and the occupied clearance
    (px, distance of each occupied-mask cell to the mask's edge) the
    threshold is measured on."""
    from . import skeleton as S
    from .._fast import edt

    d_occ = edt(occupied_mask, exact=False)  # only averaged into the wall threshold
    Gf = coarse_skeleton_graph(fs, factor, d_free, grid)
    Go = coarse_skeleton_graph(os_, factor, d_occ, grid)
    Go = S.prune_spurs(Go, min_occupied_branch, copy=False)
    return Gf, Go, d_occ


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


def _paste(a, shape, box):
    """``a`` (a crop ``box`` of an image) placed on zeros of ``shape``."""
    if a is None:
        return None
    r0, r1, c0, c1 = box
    out = np.zeros(shape, a.dtype)
    out[r0:r1, c0:c1] = a
    return out


def uncrop(seg: Segmentation, full: OccupancyGrid, box) -> Segmentation:
    """Move a segmentation of ``crop_grid(full, box)`` back onto ``full``:
    labels and intermediate images pasted in, every pixel coordinate
    shifted (world coordinates are unchanged)."""
    r0, r1, c0, c1 = box
    off = np.array([r0, c0], float)
    labels = _paste(seg.labels, full.shape, box)
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
    from . import doors as D
    from . import skeleton as S
    from .._fast import edt

    opts = options_from_kwargs(PaperOptions, "paper", options, kwargs).resolved(grid.resolution)
    res = grid.resolution
    T = _Timer()
    with T("preprocess"):
        # the paper: occupied space is the occupied cells (unknown ones are not)
        f, d_free, occ = preprocess_masks(grid, opts, occupied=grid.occupied)
    with T("skeletons"):
        fs = S.skeletonize(f)
        os_ = S.skeletonize(occ)
    with T("graphs"):
        Gf = S.prune_spurs(S.skeleton_graph(fs, radius=d_free, resolution=res, to_world=grid.pixel_to_world),
                           opts.min_free_branch)
        d_occ = edt(occ)
        Go = S.prune_spurs(S.skeleton_graph(os_, radius=d_occ, resolution=res, to_world=grid.pixel_to_world),
                           opts.min_occupied_branch)
    with T("doors"):
        thr_px = D.wall_threshold(d_occ, S.graph_pixels(Go))
        cands = D.passage_candidates(Gf, min_branch_px=opts.min_free_branch / res)
        D.intersection_points(cands, ~grid.free, max_px=opts.max_door_search / res)
        kept = D.select_doors(cands, S.graph_endpoints(Go), thr_px, D.occupied_skeleton_lines(Go))
        segs = [(c.ip1, c.ip2) for c in kept]
    with T("rooms"):
        labels, door_objs, _ = cut_rooms(grid, segs)
    im = Intermediates(free_mask=f, occupied_mask=occ, clearance=d_free, occupied_clearance=d_occ)
    seg = Segmentation(grid=grid, labels=labels, doors=door_objs, method="paper", params=opts.as_params(),
                       threshold=thr_px * res, free_graph=Gf, occupied_graph=Go, candidates=cands,
                       timings=T.t, options=opts, intermediates=im)
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

    from . import walls as W

    r = max(int(np.floor(radius_px + 1e-9)), 0)
    near = cv2.dilate(occupied.view(np.uint8), disk(r)).view(bool) if r else occupied
    if faces is None:
        faces = W.wall_faces(~search.free, search.free)
    n = int(faces.sum())
    return near if n > 0 and int((faces & near).sum()) >= 0.5 * n else None


class _Walls:
    """Stage "walls" of the default method on the grid walls are measured on:
    the map's own cells, or cells of ``opts.wall_cell`` when the map's are
    smaller (``k`` map cells per side), so that a wall's straightness, its
    gaps and its lines are judged in metres whatever the resolution.

    ``faces``, ``hough`` (:func:`topomap.core.walls.wall_lines`), ``lines`` and
    ``lw`` (:func:`topomap.core.walls.long_walls`) are in the cells of that grid;
    :meth:`fine` turns its points into map cells and :attr:`index` holds the
    long walls in map cells. With ``runs``, ``lines`` are the straight runs of
    faces on the main directions and the Hough lines off them
    (:func:`topomap.core.walls.straight_lines`), and the long walls are chained
    from them; without, both are from the Hough lines only."""

    def __init__(self, search: OccupancyGrid, opts, *, runs: bool = True):
        from . import skeleton as S
        from . import walls as W

        self.k = k = skeleton_factor(opts.wall_cell, search.resolution)
        self.res = res = search.resolution * k
        self.free = S.downsample(search.free, k, keep="all") if k > 1 else search.free
        self.obstacle = ~self.free
        self.faces = W.wall_faces(self.obstacle, self.free)
        self.hough = W.wall_lines(self.faces, min_length_px=opts.min_wall_length / res)
        self.lines = (W.straight_lines(self.faces, min_length_px=opts.min_wall_length / res,
                                       max_gap_px=opts.face_gap / res, hough=self.hough) if runs else self.hough)
        self.lw = (W.long_walls(self.lines, max_gap_px=opts.max_door_width / res,
                                offset_px=opts.wall_wander / res, min_span_px=opts.long_wall / res)
                   if opts.long_wall > 0 else [])
        self.index = W.WallIndex(W.scale_walls(self.lw, k))

    def straight_share(self) -> float:
        """The share of wall faces on straight lines (:func:`topomap.core.walls.straight_share`)."""
        from . import walls as W

        return W.straight_share(self.faces, self.hough)

    def fine(self, pts):
        """Points ``(..., 2)`` of the wall grid in the map's cells."""
        return np.asarray(pts, float) * self.k + (self.k - 1) / 2

    def fine_lines(self):
        """The straight wall faces ``(r1, c1, r2, c2)`` in the map's cells."""
        return self.fine(np.asarray(self.lines, float).reshape(-1, 2, 2)).reshape(-1, 4)

    def mask(self, shape, keep=None):
        """The long walls' cells (:func:`topomap.core.walls.wall_mask`) on a map grid of ``shape``; with
        ``keep`` (a bool per long wall), those of the walls it marks only."""
        from . import walls as W

        lw = self.lw if keep is None else [w for w, k in zip(self.lw, keep) if k]
        m = W.wall_mask(lw, self.free.shape)
        if self.k > 1:
            m = np.kron(m, np.ones((self.k, self.k), bool))[:shape[0], :shape[1]]
        return m

    def openings(self, opts, hits=None) -> list:
        """Openings in walls (:func:`topomap.core.walls.wall_openings`), at the
        ends of partitions (:func:`topomap.core.walls.partition_gaps`) and, with
        long walls, their gaps (:func:`topomap.core.walls.long_wall_gaps`), without
        those across a corridor, as segments in the map's cells. ``hits``:
        the map's occupied cells (laser hits, clutter included), the
        evidence of a partition going on."""
        from . import skeleton as S
        from . import walls as W

        res = self.res
        ops = W.wall_openings(self.obstacle, self.free, min_wall_px=opts.min_wall_length / res,
                              min_gap_px=opts.min_door_width / res, max_gap_px=opts.max_door_width / res,
                              side_px=opts.min_door_width / res, depth_px=opts.alcove_depth / res, faces=self.faces,
                              lines=self.lines, beside_px=opts.beside_wall / res,
                              closet_px=opts.closet_depth / res, behind_px=opts.closet_behind / res)
        if self.lw:
            # long straight walls: the gaps in them are openings, and an
            # opening from one of them to another spans a corridor
            ops = ops + W.long_wall_gaps(self.obstacle, self.free, self.lw, min_gap_px=opts.min_door_width / res,
                                         max_gap_px=opts.max_door_width / res, depth_px=opts.alcove_depth / res,
                                         closet_px=opts.closet_depth / res, behind_px=opts.closet_behind / res)
        if opts.partition_wall > 0:
            # partitions mapped in part: the gap from a partition's end to the
            # wall it points at, with laser hits along it
            ops = ops + W.partition_gaps(self.obstacle, self.free, self.lines, min_wall_px=opts.partition_wall / res,
                                         min_gap_px=opts.min_door_width / res, max_gap_px=opts.max_door_width / res,
                                         min_hits_px=opts.partition_hits / res, depth_px=opts.alcove_depth / res,
                                         hits_band_px=opts.wall_wander / res, min_structure_px=opts.partition_structure / res,
                                         hits=None if hits is None else S.downsample(hits, self.k, keep="any"))
        if not ops:
            return []
        P, Q = self.fine(np.array([p for p, _ in ops])), self.fine(np.array([q for _, q in ops]))
        keep = np.ones(len(ops), bool)
        if self.lw:
            keep = ~W.across_walls_many(P, Q, self.index, tol_px=opts.wall_wander / (res / self.k))
        return [(P[i], Q[i]) for i in np.flatnonzero(keep)]


def _drop_outside(grid: OccupancyGrid, labels, doors, n_rooms: int, opts: TopomapOptions):
    """Stage "outside": the rooms a laser saw beyond the facade taken out of the rooms
    (:mod:`topomap.core.outside`)."""
    from . import outside as O

    encl = O.enclosure(grid.free, grid.occupied, grid.resolution, open_area=opts.open_unknown_area,
                       window=opts.enclosure_window, gray=grid.gray)
    is_out = O.outside_regions(labels, n_rooms, encl, threshold=8 * opts.outside_enclosure)
    return O.drop_outside(labels, doors, n_rooms, is_out)


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
    (:func:`topomap.core.doors.suppress_duplicates`), cutting rooms
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
    from . import doors as D
    from . import skeleton as S
    from . import walls as W
    from .._fast import Beside, edt

    opts = options_from_kwargs(TopomapOptions, "topomap", options, kwargs)
    res = grid.resolution
    T = _Timer()
    # work on the bounding box of free space plus the wall band: the rest of
    # the map (unknown margins, solid outside) cannot hold a room or a door
    full = grid
    box = crop_box(grid, metres_to_px(opts.wall_band + opts.dilation_size + opts.max_door_width, res))
    rooms_grid = crop_grid(grid, box) if box is not None else grid
    furniture = opts.furniture_size or 0.0  # None: measured on the map below
    with T("preprocess"):
        # the obstacles' components, labelled once for the clutter of every size asked below
        solid = solid_components(rooms_grid.free) if opts.min_wall_length > 0 else None
        parts0 = None if solid is None else clutter_parts(rooms_grid.free, opts.min_wall_length / res,
                                                          furniture_px=furniture / res,
                                                          wall_thickness_px=opts.wall_thickness / res,
                                                          components=solid)
        looked, clutter = without_clutter(rooms_grid, opts.min_wall_length, furniture_size=furniture,
                                          wall_thickness=opts.wall_thickness, parts=parts0)
        search, closed = close_wall_gaps(looked, opts.wall_gap)
    with T("walls"):
        wl = _Walls(search, opts)
        straight = wl.straight_share()
        opts = opts.resolved(res, straight)  # rise and furniture measured on the map
    if opts.furniture_size > furniture:
        with T("furniture"):
            # bulky free-standing furniture is looked through too, except
            # where a long wall runs along it; on a scanned map those long walls
            # are chained from Hough lines only: on this map the furniture is still there,
            # and runs of its faces along a main direction (a row of desks or
            # cupboards) would chain into long walls and keep it (measured:
            # precision -2.0 on the Freiburg partial maps, -4.6 on
            # bremen_cartesium_full)
            # the clutter of this size is found once, for the furniture's long walls and with them
            parts = (clutter_parts(rooms_grid.free, opts.min_wall_length / res, furniture_px=opts.furniture_size / res,
                                   wall_thickness_px=opts.wall_thickness / res, components=solid)
                     if solid is not None else None)
            # on a drawn plan a row of solid blocks along a long wall is a partition, and the long walls
            # keep only the bulky pieces along them: the small clutter is looked through as before,
            # so a plan with no bulky piece at all is left as it is
            scanned = opts.scanned(straight)
            if parts is None or (not scanned and not (parts[1] & ~parts0[1]).any()):
                looked2, clutter2 = looked, clutter
            else:
                looked2, clutter2 = without_clutter(rooms_grid, opts.min_wall_length,
                                                    furniture_size=opts.furniture_size,
                                                    wall_thickness=opts.wall_thickness,
                                                    keep=furniture_keep(rooms_grid, looked, clutter, opts,
                                                                        parts=parts, rows=scanned),
                                                    parts=parts, also=None if scanned else clutter)
            del parts
            if clutter2 is not None and (clutter is None or not np.array_equal(clutter2, clutter)):
                looked, clutter = looked2, clutter2
                search, closed = close_wall_gaps(looked, opts.wall_gap)
                wl = _Walls(search, opts)
    del solid, parts0
    with T("preprocess"):
        free = search.free  # read, never written, from here on
        space = free if clutter is None else free & ~clutter
        # the clearance (an exact distance transform, in OpenCV without Python's lock) on a second
        # core while the masks and the skeletons are made: the same array, needed from the graphs on
        clearance = Beside(edt, free)
        f, _, occ = preprocess_masks(search, opts, clearance=False)
    walls = ~free  # what bounds free space: door posts and wall faces lie on these cells
    factor = skeleton_factor(opts.skeleton_cell, res)
    with T("skeletons"):
        fs, os_ = coarse_skeletons(f, occ, factor)
    with T("graphs"):
        d_free = clearance.result()
        Gf, Go, d_occ = topomap_graphs(fs, os_, factor, d_free, occ, search, opts.min_occupied_branch)
    with T("doors"):
        thr_px = D.wall_threshold(d_occ, S.graph_pixels(Go))
        faces = wl.faces if wl.k == 1 else None  # the faces of ``walls``, when walls were found on the map's cells
        cands = D.find_bottlenecks(Gf, walls, opts, res, thr_px, faces=faces)
        accepted = D.judge_doors(cands, free, S.graph_endpoints(Go), thr_px, opts, res)
        if wl.lw and opts.pillar_depth > 0:
            accepted = D.across_corridor(accepted, wl.index, opts.pillar_depth / res)
        if opts.frontier_post > 0:
            seen = _near_hits(search, rooms_grid.occupied, opts.frontier_post / res, faces=faces)
            if seen is not None:
                accepted = D.seen_posts(accepted, seen)
        segs = D.suppress_duplicates(accepted, res)
    if opts.openings:
        with T("openings"):
            ops = D.opening_candidates(wl.openings(opts, hits=rooms_grid.occupied), res)
            segs = segs + D.suppress_duplicates(ops, res, kept=segs)
            cands = cands + [c for _, c in ops]
    if prior is not None:
        with T("prior doors"):
            segs = prior.adjust(rooms_grid, segs, opts, walls=walls, space=space)
    with T("rooms"):
        min_cells = int(np.ceil(opts.min_room_area / res ** 2 - 1e-9))
        wide = d_free >= 0.5 * opts.wall_gap / res - 1e-6 if opts.wall_gap > 0 else None
        labels, door_objs, n_rooms = cut_rooms(rooms_grid, segs, space=space, min_room_cells=min_cells, wide=wide,
                                               max_door_width=opts.max_door_width)
    outside = ()
    if opts.outside_enclosure > 0 and n_rooms:
        with T("outside"):
            labels, door_objs, n_rooms, outside = _drop_outside(rooms_grid, labels, door_objs, n_rooms, opts)
    im = Intermediates(free_mask=f, occupied_mask=occ, clearance=d_free, occupied_clearance=d_occ,
                       clutter=clutter, skeleton_factor=factor, closed_gaps=closed, wall_lines=wl.fine_lines(),
                       straight_share=straight)
    seg = Segmentation(grid=rooms_grid, labels=labels, doors=door_objs, method="topomap",
                       params=opts.as_params(), threshold=thr_px * res, free_graph=Gf, occupied_graph=Go,
                       candidates=cands, timings=T.t, options=opts, intermediates=im, room_count=n_rooms,
                       outside=outside)
    if box is not None:
        seg = uncrop(seg, full, box)
    log.info("%s: %d rooms, %d fragments, %d doors, threshold %.3f m (%d candidates)", full.name, seg.n_rooms,
             seg.n_fragments, len(door_objs), thr_px * res, len(cands))
    return seg


def _baseline(name):
    def run(grid: OccupancyGrid, **params) -> Segmentation:
        import inspect

        from . import baselines as baselines

        fn = getattr(baselines, name)
        allowed = {k for k, p in inspect.signature(fn).parameters.items()
                   if p.kind is p.KEYWORD_ONLY and k != "resolution"}
        check_keywords(name, params, allowed)
        T = _Timer()
        with T("segment"):
            # every baseline ends with fill_unlabeled: all free cells labelled
            labels, segs = fn(grid.free, resolution=grid.resolution, **params)
        with T("rooms"):
            doors = doors_between_rooms(grid, labels, segs)
        return Segmentation(grid=grid, labels=labels, doors=doors, method=name, params=params, timings=T.t)

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


def segment(grid: OccupancyGrid, *, method: str = None, previous=None, **params) -> Segmentation:
    """Segment an occupancy grid into rooms and doors.

    Parameters
    ----------
    grid : OccupancyGrid
        The map (see :func:`topomap.io.load_map`).
    method : str, optional
        One of :data:`METHODS` (default :data:`DEFAULT_METHOD`).
    previous : Segmentation or networkx.MultiGraph or str or os.PathLike, optional
        An earlier result (or saved room graph file) of the same place: rooms
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
        from .identity import DoorPrior

        previous = DoorPrior(previous, within=grid)  # read once, for the door stage and the matching (of
        # a previous room graph: only where it overlaps this map)
        t_prev = time.perf_counter() - t0
        if method == "topomap":
            params = {**params, "prior": previous}
    seg = METHODS[method](grid, **params)
    if previous is not None:
        from .identity import match_rooms

        t1 = time.perf_counter()
        seg, _ = match_rooms(previous.previous, seg)
        seg.timings["previous"] = t_prev
        seg.timings["match"] = time.perf_counter() - t1
    seg.timings["total"] = time.perf_counter() - t0
    return seg
