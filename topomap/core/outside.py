"""The outside of the building: free space a laser saw beyond the facade.

A laser SLAM map holds free space that belongs to no room: rays that passed
a window or an open outer door fan out beyond the facade, and the free
space they leave is bounded by nothing the laser hit. A room is bounded by
walls (or furniture) in almost every direction; such a fan in few. This
module measures that, cell by cell, and names the regions of the
segmentation that are outside.

The measure, :func:`enclosure`: from each free cell, look along the eight
grid directions (the axes and the diagonals) to the first cell that is not
free. Where that cell is an obstacle (occupied, a wall a map draws in a
gray the thresholds leave unknown, or a small patch of unknown inside free
space: clutter seen in part) the direction is *enclosed*; where
it is the open unknown (unknown cells of a large region, or the map's edge),
it is not. The count, 0 to 8, is averaged over a small window of free
cells, since a scanned wall has gaps a single ray slips through.

:func:`outside_regions` marks the rooms whose cells are, on average,
enclosed in fewer than ``TopomapOptions.outside_enclosure`` of the eight
directions; :func:`drop_outside` takes them out of the rooms (they become
regions of kind "outside", after the fragments) with their doors, so the
room graph never joins two rooms through the space outside.

A fan the door stage did not cut from the room it enters (the window or
the open outer door is no bottleneck the doors stage accepts) leaves the
room's mean high. :func:`outside_fans` finds such fans inside rooms: the
parts of a room enclosed in fewer than ``outside_enclosure`` of the
directions, cell by cell, that are solid free space (a piece as large as
the smallest room, holding a free disk as wide as it): they are taken
out of the room as regions outside, and a room more of whose cells are
such fans than not is outside whole. A thin bundle of rays (a room
glimpsed through its door on a map still being explored) is no such
piece: across a single ray the unknown is next to every cell whatever
lies beyond, so its enclosure says nothing about inside or outside.

Each of the eight directions costs one pass over the map: time and memory
grow linearly with the map's area.
"""

from __future__ import annotations

import numpy as np

from .._fast import label, label_stats
from .geometry import true_bbox
from .skeleton import downsample

__all__ = ["DIRECTIONS", "FAN_OPEN", "unknown_cells", "open_unknown", "enclosure", "outside_fans", "outside_regions",
           "drop_outside"]

#: Share of the eight directions below which a cell next to a fan found by :func:`outside_fans` belongs
#: to that fan: a half. A fan's cells near the facade see its wall in three directions or more (the
#: wall itself and the two diagonals back to it, and through the window the room's far walls), so the
#: fan test's own ``outside_enclosure`` leaves a band of the fan along the facade in the room; a cell
#: more open than enclosed (more of its directions end in the unexplored world than at an obstacle) is
#: no cell of a room, and joined to a fan it is the rest of that fan. Only a fan grows: on a map with
#: no solid fan (the partial maps of the benchmark) nothing changes.
FAN_OPEN = 0.5

#: The eight grid directions ``(d_row, d_col)`` :func:`enclosure` looks along.
DIRECTIONS = ((0, 1), (0, -1), (1, 0), (-1, 0), (1, 1), (1, -1), (-1, 1), (-1, -1))


def unknown_cells(free: np.ndarray, occupied: np.ndarray, gray=None, *, tolerance: int = 8) -> np.ndarray:
    """The cells nothing was seen in: neither free nor occupied and, when the map's gray image is
    given, of the gray the map writes for the unknown (its most common gray among those cells,
    within ``tolerance`` levels).

    A map drawn in grays (a SLAM map saved with its probabilities) draws its walls in grays between
    free and occupied, which the thresholds leave unknown; they are obstacles the laser saw, not the
    unexplored world.
    """
    unknown = ~free & ~occupied
    if gray is None or not unknown.any():
        return unknown
    at = np.flatnonzero(unknown)  # the grays of those cells only, not of the whole map
    g = np.asarray(gray).ravel()[at]
    mode = int(np.argmax(np.bincount(g, minlength=256)))
    out = np.zeros(unknown.shape, bool)
    out.ravel()[at[np.abs(g.astype(np.int16) - mode) <= tolerance]] = True
    return out


def open_unknown(free: np.ndarray, occupied: np.ndarray, resolution: float, *, min_area: float,
                 gray=None) -> np.ndarray:
    """Unknown cells of the open unknown: of a region of at least ``min_area`` m² or at the map's edge.

    Parameters
    ----------
    free, occupied : (M, N) ndarray of bool
    resolution : float
        Metres per cell.
    min_area : float
        m²: smaller unknown regions inside free space are clutter seen in
        part (a chair, a box), not the unexplored world.
    gray : (M, N) ndarray of uint8, optional
        The map's gray image (:func:`unknown_cells`).

    Returns
    -------
    (M, N) ndarray of bool
    """
    return _open(unknown_cells(free, occupied, gray), resolution, min_area)


def _open(unknown: np.ndarray, resolution: float, min_area: float) -> np.ndarray:
    """The cells of ``unknown`` in a region of at least ``min_area`` m² or at the map's edge.
    Labelled on the box of the unknown cells only (a drawn plan has a few, a scan the world round
    the building)."""
    H, W = unknown.shape
    out = np.zeros((H, W), bool)
    box = true_bbox(unknown)
    if box is None:
        return out
    r0, r1, c0, c1 = box
    n, lab, stats, _ = label_stats(unknown[r0:r1, c0:c1], connectivity=8)
    x, y, w, h, area = stats.T
    x, y = x + c0, y + r0
    keep = (area * resolution ** 2 >= min_area) | (x == 0) | (y == 0) | (x + w == W) | (y + h == H)
    keep[0] = False
    out[r0:r1, c0:c1] = keep[lab]
    return out


def _first_hit(free: np.ndarray, hit: np.ndarray, direction) -> np.ndarray:
    """Per cell: is the first cell that is not free, looking along ``direction`` from the cell
    itself, a ``hit`` cell (False where it is the map's edge).

    Row by row, each row from the one before it along the direction (shifted by a column on a
    diagonal): a pass of small vector operations, linear in the map's area. Along the rows
    themselves, the same on the transposed map.
    """
    dr, dc = direction
    if dr == 0:
        return _first_hit(np.ascontiguousarray(free.T), np.ascontiguousarray(hit.T), (dc, 0)).T
    H, W = free.shape
    out = np.empty((H, W), bool)
    prev = np.zeros(W, bool)
    ahead = np.zeros(W, bool)
    for r in (range(H - 1, -1, -1) if dr > 0 else range(H)):
        if dc > 0:
            ahead[:-1] = prev[1:]
        elif dc < 0:
            ahead[1:] = prev[:-1]
        else:
            ahead = prev
        prev = np.where(free[r], ahead, hit[r])
        out[r] = prev
    return out


def enclosure(free: np.ndarray, occupied: np.ndarray, resolution: float, *, open_area: float,
              window: float, cell: float = 0.1, gray=None) -> np.ndarray:
    """How many of the eight directions from each free cell end at an obstacle.

    Parameters
    ----------
    free, occupied : (M, N) ndarray of bool
    resolution : float
        Metres per cell.
    open_area : float
        m², see :func:`open_unknown`.
    window : float
        Side of the square window the counts are averaged over, m.
    gray : (M, N) ndarray of uint8, optional
        The map's gray image: non-free cells of another gray than the
        unknown's are obstacles (:func:`unknown_cells`).
    cell : float
        The counts are taken on blocks of about this size (m; a block is
        free where all its cells are, an obstacle where any is): 0.1 m, finer
        than any door, and a quarter of the work of 0.05 m cells.

    Returns
    -------
    (M, N) ndarray of float32
        The mean count (0 to 8) over the free blocks of the window around
        each free cell; 0 on the other cells. The obstacles are grown by one
        cell first (a ray slips diagonally between the dots of a scanned
        wall); a block with any obstacle cell is an obstacle.
    """
    import cv2

    free = np.asarray(free, bool)
    H, W = free.shape
    ring = np.ones((3, 3), np.uint8)
    enclosed = np.where(free, np.float32(8.0), np.float32(0.0))
    unknown = unknown_cells(free, occupied, gray)
    if not (cv2.dilate(unknown.view(np.uint8), ring).view(bool) & free).any():
        return enclosed  # no free cell meets the unknown (a drawn plan): nothing is open
    opened = _open(unknown, resolution, open_area)
    if not (cv2.dilate(opened.view(np.uint8), ring).view(bool) & free).any():
        return enclosed  # no free cell meets the open unknown: all enclosed
    hit = cv2.dilate((~free & ~opened).view(np.uint8), ring).view(bool)
    k = max(1, int(round(cell / resolution)))
    inner, hit = downsample(free & ~hit, k, keep="all"), downsample(hit, k, keep="any")
    count = np.zeros(inner.shape, np.float32)
    inner_t, hit_t = np.ascontiguousarray(inner.T), np.ascontiguousarray(hit.T)  # once, for both ways along rows
    for dr, dc in DIRECTIONS:
        count += _first_hit(inner_t, hit_t, (dc, 0)).T if dr == 0 else _first_hit(inner, hit, (dr, dc))
    count[~inner] = 0
    w = max(1, int(round(window / (resolution * k)))) | 1
    num = cv2.boxFilter(count, -1, (w, w), normalize=False, borderType=cv2.BORDER_CONSTANT)
    den = cv2.boxFilter(inner.astype(np.float32), -1, (w, w), normalize=False, borderType=cv2.BORDER_CONSTANT)
    mean = np.where(den > 0.5, num / np.maximum(den, 1e-6), 8.0).astype(np.float32)  # no open block near: enclosed
    if k > 1:
        mean = np.repeat(np.repeat(mean, k, axis=0), k, axis=1)[:H, :W]
    return np.where(free, mean, 0).astype(np.float32)


def outside_fans(labels: np.ndarray, n_rooms: int, encl: np.ndarray, clearance: np.ndarray, *,
                 threshold: float, min_cells: int, width_px: float,
                 grow_threshold: float | None = None) -> np.ndarray:
    """The cells of rooms that are solid fans of free space beyond the facade.

    A piece is a connected part (8-connected, within one room) of the
    room's cells whose :func:`enclosure` is below ``threshold``; it is a
    fan outside when it has at least ``min_cells`` cells and holds a cell
    at least ``width_px`` from every cell that is not free (solid free
    space as wide as a room, not a bundle of single rays). With
    ``grow_threshold``, a fan also takes the cells of its room connected to
    it whose enclosure is below that (:data:`FAN_OPEN` of the directions:
    the part of the fan near the facade, whose cells still see the facade's
    wall in a few directions).

    Parameters
    ----------
    labels : (M, N) ndarray of int
        Rooms ``1..n_rooms`` (fragments after them are not judged).
    n_rooms : int
    encl : (M, N) ndarray of float
        :func:`enclosure`.
    clearance : (M, N) ndarray of float
        Distance (cells) from each free cell to the nearest cell that is
        not free.
    threshold : float
        Directions out of 8.
    min_cells : int
        Least cells of a piece (the smallest room).
    width_px : float
        Least clearance (cells) of a piece's widest cell.
    grow_threshold : float, optional
        Directions out of 8; default: the fans are not grown.

    Returns
    -------
    (M, N) ndarray of bool
    """
    import cv2

    lab = np.asarray(labels)
    room = np.where((lab > 0) & (lab <= n_rooms), lab, 0).astype(np.float32)
    # the cells whose 3 x 3 neighbourhood holds no other room: a piece never runs from one room into the next
    high = cv2.dilate(room, np.ones((3, 3), np.uint8))
    low_lab = cv2.erode(np.where(room > 0, room, np.float32(n_rooms + 1)), np.ones((3, 3), np.uint8))
    inner = (room > 0) & (high == room) & (low_lab == room)
    low = inner & (np.asarray(encl) < threshold)
    comp, n = label(low, 8)
    if n == 0:
        return low
    size = np.bincount(comp[low], minlength=n + 1)
    wide = np.bincount(comp[low & (np.asarray(clearance) >= width_px)], minlength=n + 1)
    keep = (size >= min_cells) & (wide > 0)
    keep[0] = False
    fans = keep[comp]
    if grow_threshold is not None and grow_threshold > threshold and fans.any():
        # the fans go on through the cells more open than enclosed next to them
        more = inner & (np.asarray(encl) < grow_threshold)
        comp, n = label(more, 8)
        reached = np.zeros(n + 1, bool)
        reached[comp[fans]] = True
        reached[0] = False
        fans |= reached[comp]
    return fans


def outside_regions(labels: np.ndarray, n_rooms: int, encl: np.ndarray, *, threshold: float,
                    fans=None) -> np.ndarray:
    """Which rooms are outside: the mean :func:`enclosure` of their cells below ``threshold``.

    Parameters
    ----------
    labels : (M, N) ndarray of int
        Rooms ``1..n_rooms`` (fragments after them are not judged).
    n_rooms : int
    encl : (M, N) ndarray of float
        :func:`enclosure`.
    threshold : float
        Directions out of 8.
    fans : (M, N) ndarray of bool, optional
        :func:`outside_fans`: a room more of whose cells are fans than not
        is outside too.

    Returns
    -------
    (n_rooms + 1,) ndarray of bool
        True for the rooms outside (index 0 unused, False). None is outside
        when every room would be: without a building (a map of free space
        and nothing else, a plan drawn without walls) there is no outside.
    """
    lab = np.asarray(labels)
    m = (lab > 0) & (lab <= n_rooms)
    cells = np.bincount(lab[m], minlength=n_rooms + 1)
    total = np.bincount(lab[m], weights=encl[m], minlength=n_rooms + 1)
    out = (cells > 0) & (total < threshold * cells)
    if fans is not None:
        out |= 2 * np.bincount(lab[m & fans], minlength=n_rooms + 1) > cells
    out[0] = False
    if out[1:].all():
        out[:] = False
    return out[:n_rooms + 1]


def drop_outside(labels: np.ndarray, doors: list, n_rooms: int, is_out: np.ndarray, fans=None):
    """Rooms marked ``is_out`` taken out of the rooms, with their doors.

    With ``fans`` (:func:`outside_fans`), the fan cells of the rooms kept
    are taken out of them too: each 8-connected piece of them becomes an
    outside region, after the rooms taken out whole.

    Returns
    -------
    labels : (M, N) ndarray of int32
        The kept rooms ``1..n_kept`` (in their order), then the fragments
        (in their order), then the outside regions.
    doors : list of Door
        The doors between two kept rooms, renumbered, their ``rooms`` in
        the new labels.
    n_kept : int
    outside : tuple of int
        The labels of the outside regions.
    """
    out_rooms = np.flatnonzero(is_out[1:n_rooms + 1]) + 1
    if out_rooms.size:
        labels, doors, n_rooms, outside = _drop_rooms(labels, doors, n_rooms, is_out, out_rooms)
    else:
        outside = ()
    if fans is not None:
        cut = np.asarray(fans, bool) & (labels > 0) & (labels <= n_rooms)
        if cut.any():
            cut = _whole_rooms(labels, cut)
            comp, n = label(cut, 8)
            top = int(labels.max())
            labels = np.where(cut, top + comp, labels).astype(np.int32)
            outside = tuple(outside) + tuple(range(top + 1, top + n + 1))
    return labels, doors, n_rooms, outside


def _whole_rooms(labels: np.ndarray, cut: np.ndarray) -> np.ndarray:
    """``cut`` (fan cells of rooms) with the pieces of each room that the fan cuts off from the
    room's largest 8-connected part: a room stays one piece of free space."""
    cut = cut.copy()
    for r in np.unique(labels[cut]):
        rows, cols = np.nonzero(labels == r)
        r0, r1, c0, c1 = rows.min(), rows.max() + 1, cols.min(), cols.max() + 1
        rest = (labels[r0:r1, c0:c1] == r) & ~cut[r0:r1, c0:c1]
        comp, n = label(rest, 8)
        if n > 1:
            size = np.bincount(comp[rest], minlength=n + 1)
            size[0] = 0
            cut[r0:r1, c0:c1] |= rest & (comp != int(np.argmax(size)))
    return cut


def _drop_rooms(labels: np.ndarray, doors: list, n_rooms: int, is_out: np.ndarray, out: np.ndarray):
    """:func:`drop_outside` of the rooms ``out`` (the labels where ``is_out``)."""
    top = int(labels.max()) if labels.size else 0
    lut = np.zeros(top + 1, np.int32)
    keep = np.flatnonzero(~is_out[1:n_rooms + 1]) + 1
    n_kept = len(keep)
    lut[keep] = np.arange(1, n_kept + 1, dtype=np.int32)
    frag = np.arange(n_rooms + 1, top + 1)
    lut[frag] = np.arange(n_kept + 1, n_kept + 1 + len(frag), dtype=np.int32)
    first_out = n_kept + 1 + len(frag)
    lut[out] = np.arange(first_out, first_out + len(out), dtype=np.int32)
    new = lut[labels]
    kept_doors = []
    for d in doors:
        a, b = d.rooms
        if is_out[a] or is_out[b]:
            continue
        d.rooms = (int(lut[a]), int(lut[b]))
        d.id = len(kept_doors)
        kept_doors.append(d)
    return new, kept_doors, n_kept, tuple(range(first_out, first_out + len(out)))
