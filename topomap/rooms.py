"""Rooms: turning cuts (doors) or seeds into a complete label image.

Every function here guarantees the library's invariant: every free cell ends
up with exactly one label and only free cells are labelled (``0``
elsewhere). Labels are rooms, except where :func:`cut_rooms` has put fragments (free
cells no room reaches) after the rooms.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from scipy import ndimage as ndi

from .geometry import line_pixels

if TYPE_CHECKING:  # pragma: no cover
    from .io import OccupancyGrid

__all__ = ["fill_unlabeled", "relabel_sequential", "cut_rooms", "doors_between_rooms", "EIGHT", "FOUR"]

EIGHT = np.ones((3, 3), bool)
FOUR = ndi.generate_binary_structure(2, 1)


def fill_unlabeled(labels: np.ndarray, free: np.ndarray, *, cost=None) -> np.ndarray:
    """Give every free cell without a room the room of the nearest labelled cell.

    "Nearest" is geodesic: the labels flood through free space only (never
    through walls), with :func:`skimage.segmentation.watershed` on ``cost``
    (flat by default). Free components that hold no label at all become new
    rooms, one per 8-connected component.

    Parameters
    ----------
    labels : (M, N) ndarray of int
        Seed labels, ``0`` = unassigned. Labels on non-free cells are dropped.
    free : (M, N) ndarray of bool
        Free space.
    cost : (M, N) ndarray of float, optional
        Flooding priority (lower floods first); default: uniform.

    Returns
    -------
    (M, N) ndarray of int32
        Labels ``1..N`` on every free cell, ``0`` elsewhere, renumbered to be
        consecutive in order of first appearance (row-major scan).
    """
    from skimage.segmentation import watershed

    free = np.asarray(free, bool)
    seeds = np.where(free, labels, 0).astype(np.int32)
    todo = free & (seeds == 0)
    if cost is None and seeds.any() and todo.any():
        seeds = _grow(seeds, todo)
    if seeds.any() and (free & (seeds == 0)).any():
        if cost is None:
            cost = np.zeros(free.shape, np.float32)
        out = watershed(cost, markers=seeds, mask=free, connectivity=2).astype(np.int32)
    else:
        out = seeds
    rest = free & (out == 0)
    if rest.any():
        extra, n = ndi.label(rest, structure=EIGHT)
        out = np.where(rest, extra + out.max(), out).astype(np.int32)
    return relabel_sequential(out)


def relabel_sequential(labels: np.ndarray) -> np.ndarray:
    """Renumber labels to ``1..N`` in order of first appearance (row-major).

    This makes room IDs deterministic for the same input: room 1 is the room
    that contains the top-most (then left-most) free cell, and so on.
    Negative labels count as 0. One C pass over the image
    (:func:`scipy.ndimage.find_objects`) plus a look at each label's top row.
    """
    labels = np.asarray(labels)
    if labels.dtype == np.int32 and (labels.size == 0 or labels.min() >= 0):
        lab = labels
    else:
        lab = np.where(labels > 0, labels, 0).astype(np.int64, copy=False)
    top = int(lab.max()) if lab.size else 0
    if top == 0:
        return np.zeros(labels.shape, np.int32)
    if top > 4 * lab.size:  # sparse huge ids: compact them first
        vals, inv = np.unique(lab, return_inverse=True)
        lab = inv.reshape(lab.shape)
        top = vals.size - 1
    slices = ndi.find_objects(lab if lab.dtype == np.int32 else lab.astype(np.int32), max_label=top)
    first = np.full(top + 1, -1, np.int64)
    W = lab.shape[1]
    for i, sl in enumerate(slices, start=1):
        if sl is None:
            continue
        r, cs = sl[0].start, sl[1]
        c = cs.start + int(np.flatnonzero(lab[r, cs] == i)[0])
        first[i] = r * W + c
    ids = np.flatnonzero(first >= 0)
    order = ids[np.argsort(first[ids], kind="stable")]
    lut = np.zeros(top + 1, np.int32)
    lut[order] = np.arange(1, order.size + 1, dtype=np.int32)
    return lut[lab]


def _grow(seeds: np.ndarray, todo: np.ndarray, max_steps: int = 8) -> np.ndarray:
    """Grow labels one cell per step (8-neighbourhood) into ``todo`` cells.

    A fast path for the common case of thin unlabelled seams (door cuts):
    a few whole-image dilations with OpenCV instead of a priority flood. A
    cell reached by several labels in the same step takes the largest label
    id (deterministic). Stops after ``max_steps``; what is left is flooded by
    the caller.
    """
    import cv2

    top = int(seeds.max())
    if top >= 2 ** 24:  # float32 holds integers exactly up to 2**24
        return seeds
    # OpenCV dilates uint16 and float32 images; uint16 needs no conversion back
    dtype = np.uint16 if top < 2 ** 16 else np.float32
    out = seeds.astype(dtype)
    todo = todo.copy()
    k = np.ones((3, 3), np.uint8)
    for _ in range(max_steps):
        grown = cv2.dilate(out, k)
        hit = todo & (grown > 0)
        if not hit.any():
            break
        out[hit] = grown[hit]
        todo &= ~hit
        if not todo.any():
            break
    return out.astype(np.int32)


def cut_rooms(grid: OccupancyGrid, segments, *, space=None, min_room_cells: int = 0, wide=None):
    """Cut free space along door segments and label the rooms (and fragments).

    Parameters
    ----------
    grid : OccupancyGrid
    segments : list of ((r1, c1), (r2, c2))
        Door segments in pixels.
    space : (M, N) ndarray of bool, optional
        The free cells rooms are cut from (default ``grid.free``); the
        default method passes the free space with narrow wall gaps closed
        (:func:`topomap.segmentation.close_wall_gaps`).
    min_room_cells : int
        Smallest room, in cells. A piece smaller than this is no room of its
        own: its cells join the room they are connected to through free
        space (a sliver cut off by a door joins the room beside it). A free
        region smaller than this that no room reaches is a *fragment* (a
        free speck, a patch of scan rays). 0 (default): every region is a
        room.
    wide : (M, N) ndarray of bool, optional
        Cells where a robot fits (the default method: free cells at least
        half of ``wall_gap`` from every obstacle). With it, a piece or region
        without such a cell — a strip of free cells along the map's edge, a
        single scan ray — is treated like one smaller than ``min_room_cells``.

    Returns
    -------
    labels : (M, N) ndarray of int32
        Every free cell labelled, 0 elsewhere: rooms ``1..n_rooms`` (the
        4-connected pieces of ``space`` between the cuts; cut cells and the
        other free cells go to the nearest room through free space; a free
        region no piece reaches is a label of its own), then the fragments
        ``n_rooms + 1 ..``; each group in order of first appearance
        (row-major).
    doors : list of Door
        See :func:`doors_between_rooms`; only doors between two rooms.
    n_rooms : int
        Number of rooms.
    """
    from ._fast import label as cc_label

    free = grid.free
    space = free if space is None else (space & free)
    cut = np.zeros_like(free)  # stage "cutting rooms" of the Voronoi methods
    for p, q in segments:
        cut[line_pixels(p, q, free.shape)] = True
    pieces, n = cc_label(space & ~cut, 4)
    if n:
        area = np.bincount(pieces.ravel(), minlength=n + 1)
        if min_room_cells > 0:
            # a piece smaller than a room is never a room of its own: its
            # cells join the room they are connected to, or become a fragment
            small = area < min_room_cells
            if wide is not None:
                small |= np.bincount(pieces[wide], minlength=n + 1) == 0
            small[0] = False
            pieces = np.where(small[pieces], 0, pieces)
            area[small] = 0
    if n > 1:
        # number pieces by area (largest = highest id): cut cells then go to
        # the larger neighbour, whatever the map's orientation
        area[0] = -1
        rank = np.empty(n + 1, np.int32)
        rank[np.argsort(area, kind="stable")] = np.arange(n + 1, dtype=np.int32)
        pieces = rank[pieces]
    labels, n_rooms = _rooms_first(fill_unlabeled(pieces, free), min_room_cells, wide)
    doors = [d for d in doors_between_rooms(grid, labels, segments) if max(d.rooms) <= n_rooms]
    for k, d in enumerate(doors):
        d.id = k
    return labels, doors, n_rooms


def _rooms_first(labels: np.ndarray, min_cells: int, wide=None):
    """``(labels, n_rooms)``: labels of at least ``min_cells`` cells (rooms;
    with a ``wide`` mask, only those with a cell in it) renumbered
    ``1..n_rooms`` and the others (fragments) after them, each group keeping
    its order (of first appearance)."""
    top = int(labels.max()) if labels.size else 0
    if min_cells <= 0 or top == 0:
        return labels, top
    is_room = np.bincount(labels.ravel(), minlength=top + 1) >= min_cells
    if wide is not None:
        is_room &= np.bincount(labels[wide], minlength=top + 1) > 0
    is_room[0] = False
    n_rooms = int(is_room.sum())
    if n_rooms < top:
        ids = np.arange(1, top + 1)
        lut = np.zeros(top + 1, np.int32)
        lut[ids[is_room[1:]]] = np.arange(1, n_rooms + 1, dtype=np.int32)
        lut[ids[~is_room[1:]]] = np.arange(n_rooms + 1, top + 1, dtype=np.int32)
        labels = lut[labels]
    return labels, n_rooms


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
        rr, cc = line_pixels(p, q, labels.shape)
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
