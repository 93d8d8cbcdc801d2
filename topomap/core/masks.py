"""Stage "masks": the free and occupied space the skeletons are taken from, the clutter looked through
while doors are searched, and the gaps in walls closed before rooms are cut."""

from __future__ import annotations

import numpy as np

from .._fast import edt, label_stats, lookup
from ..grid import FREE, OCCUPIED, OccupancyGrid
from .geometry import disk, metres_to_px

__all__ = ["preprocess_masks", "close_wall_gaps", "solid_components", "clutter_parts",
           "clutter_mask", "without_clutter"]

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

    if free.all():
        return np.zeros(free.shape, bool)
    grown = edt(free) <= r
    pad = cv2.copyMakeBorder(grown.view(np.uint8), r + 1, r + 1, r + 1, r + 1, cv2.BORDER_CONSTANT, value=0)
    return edt(pad)[r + 1:-(r + 1), r + 1:-(r + 1)] > r


def solid_components(free: np.ndarray):
    """The 8-connected components of the non-free cells: ``(solid, comp, stats)``, the non-free
    cells (uint8 0/1), their labels (0: the free cells) and OpenCV's statistics per label."""

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
