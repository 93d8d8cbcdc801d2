"""Rooms: turning cuts (doors) or seeds into a complete label image.

Every function here guarantees the library's invariant: every free cell ends
up with exactly one label and only free cells are labelled (``0``
elsewhere). Labels are rooms, except where :func:`cut_rooms` has put fragments (free
cells no room reaches) after the rooms.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy import ndimage as ndi

from .._fast import label, lookup, ranges
from ..grid import OccupancyGrid
from .doors import Door
from .geometry import line_pixels

__all__ = ["fill_unlabeled", "relabel_sequential", "cut_rooms", "doors_between_rooms", "join_touching_rooms",
           "EIGHT", "FOUR", "NEIGHBOUR_ROWS", "NEIGHBOUR_COLS"]

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
    return lookup(lut, lab)


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


def _wall_to_wall(rc, p, q, space, reach: int = 2):
    """The cells ``rc`` of a cut from ``p`` to ``q``, carried on past each end
    cell of ``space``, for at most ``reach`` cells, while they are cells of ``space``: a
    cut whose end was rounded onto the free cell beside a wall would leave a
    4-connected way round it. The steps follow the cut's direction turned
    to the nearest of the 8 neighbours (integer steps: the same cells
    whichever way the map is turned)."""
    H, W = space.shape
    # on Python floats and ints, not tiny arrays (the same values, quicker), the cells only copied
    # when the cut goes on
    v0, v1 = float(q[0]) - float(p[0]), float(q[1]) - float(p[1])
    a0, a1 = abs(v0), abs(v1)
    top = max(a0, a1)
    if top < 1e-9:
        return rc
    # a component counts when it is at least tan(22.5 deg) of the other
    s0 = ((v0 > 0) - (v0 < 0)) if a0 >= _TAN_22_5 * top else 0
    s1 = ((v1 > 0) - (v1 < 0)) if a1 >= _TAN_22_5 * top else 0
    rr, cc = [], []
    for r, c, d0, d1 in ((int(rc[0][-1]), int(rc[1][-1]), s0, s1), (int(rc[0][0]), int(rc[1][0]), -s0, -s1)):
        if not (0 <= r < H and 0 <= c < W) or not space[r, c]:
            continue  # an end on a wall: past it lies the far side of the wall, not this cut's way round
        for _ in range(reach):
            r, c = r + d0, c + d1
            if not (0 <= r < H and 0 <= c < W) or not space[r, c]:
                break
            rr.append(r)
            cc.append(c)
    if not rr:
        return rc
    return np.concatenate([rc[0], np.array(rr, rc[0].dtype)]), np.concatenate([rc[1], np.array(cc, rc[1].dtype)])


_TAN_22_5 = float(np.tan(np.pi / 8))


def cut_rooms(grid: OccupancyGrid, segments, *, space=None, min_room_cells: int = 0, wide=None,
              max_door_width=None):
    """Cut free space along door segments and label the rooms (and fragments).

    Parameters
    ----------
    grid : OccupancyGrid
    segments : list of ((r1, c1), (r2, c2))
        Door segments in pixels.
    space : (M, N) ndarray of bool, optional
        The free cells rooms are cut from (default ``grid.free``); the
        default method passes the free space with narrow wall gaps closed
        (:func:`topomap.core.segmentation.close_wall_gaps`).
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
    max_door_width : float, optional
        Widest door (m). Two rooms that touch with no door between them
        (:func:`join_touching_rooms`) along more than this are one room
        (merged); default: never merged, a door is added.

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
        See :func:`doors_between_rooms`; only doors between two rooms. Every
        two rooms whose cells touch have a door between them
        (:func:`join_touching_rooms`).
    n_rooms : int
        Number of rooms.
    """
    free = grid.free
    space = free if space is None else (space & free)
    # stage "cutting rooms" of the Voronoi methods: the door segments' cells taken out of the space
    lines = [_wall_to_wall(line_pixels(p, q, free.shape), p, q, space) for p, q in segments]
    whole = space.copy()
    for rc in lines:
        whole[rc] = False
    # the pieces without OpenCV's statistics (connectedComponents is much quicker without them);
    # areas, first cells and cells from the row runs
    pieces, n = label(whole, connectivity=4, small=True)
    runs = _runs(whole, pieces)
    area = np.bincount(runs[2], weights=runs[1] - runs[0], minlength=n + 1).astype(np.int64)
    seed = np.arange(n + 1, dtype=np.int32)  # piece -> its seed label (0: none)
    small = np.zeros(n + 1, bool)
    # cells where a robot fits, per piece
    piece_wide = np.bincount(pieces[wide], minlength=n + 1) if wide is not None and min_room_cells > 0 else None
    if n and min_room_cells > 0:
        # a piece smaller than a room is never a room of its own: its
        # cells join the room they are connected to, or become a fragment
        small = area < min_room_cells
        if piece_wide is not None:
            small |= piece_wide == 0
        small[0] = False
        seed[small] = 0
        area[small] = 0
    if n > 1:
        # number pieces by area (largest = highest id): cut cells then go to
        # the larger neighbour, whatever the map's orientation
        area[0] = -1
        rank = np.empty(n + 1, np.int32)
        rank[np.argsort(area, kind="stable")] = np.arange(n + 1, dtype=np.int32)
        seed = np.where(small, 0, rank).astype(np.int32)
    labels, n_rooms = _fill_pieces(pieces, seed, runs, free, free > whole, min_room_cells, wide, piece_wide)
    doors = [d for d in _doors_between(grid, labels, segments, lines) if max(d.rooms) <= n_rooms]
    for k, d in enumerate(doors):
        d.id = k
    return join_touching_rooms(grid, labels, doors, n_rooms, max_door_width=max_door_width)


def _runs(whole: np.ndarray, pieces: np.ndarray):
    """The row runs of ``whole`` in raster order: ``(start, end, piece)``, the flat index of each
    run's first cell, one past its last, and its piece in ``pieces``.

    A piece's runs give its area, its first cell (row-major: its first run's start) and its cells
    without a look at the rest of the map.
    """
    H, W = whole.shape
    # a band of rows at a time (its temporaries a few MB, whatever the map's size: at once they
    # raised the peak memory of large maps markedly); each row after a 0,
    # and a 0 at the end: the changes alternate run start, run end
    rows = max(1, _RUN_BAND // (W + 1))
    starts, ends = [], []
    for r0 in range(0, H, rows):
        h = min(rows, H - r0)
        flat = np.zeros(h * (W + 1) + 1, np.uint8)
        flat[:-1].reshape(h, W + 1)[:, 1:] = whole[r0:r0 + h]
        t = np.flatnonzero(flat[1:] != flat[:-1]) + 1
        s, e = t[0::2], t[1::2]
        starts.append(s - s // (W + 1) - 1 + r0 * W)
        ends.append(starts[-1] + (e - s))
    start = np.concatenate(starts) if starts else np.zeros(0, np.intp)
    end = np.concatenate(ends) if ends else np.zeros(0, np.intp)
    return start, end, pieces.ravel()[start].astype(np.intp)


#: Cells of the band of rows :func:`_runs` scans at a time.
_RUN_BAND = 1 << 20


def _fill_pieces(pieces: np.ndarray, seed: np.ndarray, runs, free: np.ndarray, between: np.ndarray,
                 min_cells: int, wide=None, piece_wide=None):
    """``_rooms_first(fill_unlabeled(seed[pieces], free), min_cells, wide)``, cell for cell, touching only the
    cells without a seed.

    ``pieces``: the cut pieces (OpenCV components, ``runs`` their row
    runs, :func:`_runs`); ``seed``: each piece's seed label (0: none); ``between``:
    the free cells in no piece; ``wide``, ``piece_wide``: the cells where a
    robot fits and their number in each piece. The seeds' label image is
    never made: the free cells without a seed (few: the
    cuts, the small pieces, the closed gaps) are grown one 8-neighbourhood
    step at a time as :func:`_grow` does (it dilates the whole image). Of
    the cells left, an 8-connected component with one label beside it is
    all that label (what the watershed of :func:`fill_unlabeled` makes of
    it); only when a component lies between two labels does that watershed
    run, on the whole map as there (its order of flooding decides). The
    components no label touches become labels of their own; the
    renumbering in order of first appearance (:func:`relabel_sequential`)
    and rooms before fragments (:func:`_rooms_first`) are one lookup table
    applied once.
    """
    top = int(seed.max()) if seed.size else 0
    if top == 0 or top >= 2 ** 24:  # no seed, or more than _grow handles: the general route
        return _rooms_first(fill_unlabeled(lookup(seed, pieces), free), min_cells, wide)
    todo = _unseeded_cells(seed, runs, between)
    val = np.zeros(todo.size, np.int32)  # the label of each of them (0: none yet)
    n_rest = 0
    if todo.size:
        pos, inside, fixed = _unseeded_neighbours(todo, pieces, seed)
        left = _grow_unseeded(val, pos, inside, fixed)
        if left.size:
            n_rest = _fill_left(val, left, todo, pos, inside, fixed, seed, pieces, free)
    return _renumber_filled(pieces, seed, runs, todo, val, top + n_rest + 1, min_cells, wide, piece_wide)


def _unseeded_cells(seed: np.ndarray, runs, between: np.ndarray) -> np.ndarray:
    """The free cells without a seed (flat indices, ascending): the cells of ``between`` and those
    of the pieces too small to be rooms (``seed`` 0; their cells from their row ``runs``)."""
    start, end, run_piece = runs
    todo = np.flatnonzero(between)
    unseeded = seed == 0
    unseeded[0] = False
    if unseeded.any():  # pieces too small to be rooms: the cells of their runs
        on = unseeded[run_piece]
        todo = np.sort(np.concatenate([todo, ranges(start[on], end[on])]))
    return todo


def _unseeded_neighbours(todo: np.ndarray, pieces: np.ndarray, seed: np.ndarray):
    """``(pos, inside, fixed)``, each ``(len(todo), 8)``, for the unseeded cells ``todo`` (flat,
    ascending, not empty) and their 8 neighbours (:data:`NEIGHBOUR_ROWS`, :data:`NEIGHBOUR_COLS`):
    the neighbour's place in ``todo`` (any place when it is none), whether it is one of ``todo``,
    and the seed label of a neighbour that is not (0 off the image)."""
    H, W = pieces.shape
    flat = pieces.ravel()
    r, c = np.divmod(todo, W)
    rn, cn = r[:, None] + NEIGHBOUR_ROWS, c[:, None] + NEIGHBOUR_COLS
    ok = (rn >= 0) & (rn < H) & (cn >= 0) & (cn < W)
    nb = np.where(ok, rn * W + cn, 0)
    # each neighbour's place in todo (any place when it is none: inside says which), by a table
    # over the flat indices todo's neighbours span, faster than a binary search; the search when
    # that span is larger than :data:`_DENSE_CELLS`
    lo, hi = max(int(todo[0]) - W - 1, 0), int(todo[-1]) + W + 2
    if hi - lo <= _DENSE_CELLS:
        at = np.zeros(hi - lo, np.int32)
        at[todo - lo] = np.arange(todo.size, dtype=np.int32)
        pos = np.take(at, nb - lo, mode="clip")
    else:
        pos = np.minimum(np.searchsorted(todo, nb), todo.size - 1)
    inside = ok & (np.take(todo, pos) == nb)  # the neighbour is itself a cell without a seed
    fixed = np.where(ok & ~inside, seed[flat[nb]], 0)
    return pos, inside, fixed


def _grow_unseeded(val: np.ndarray, pos: np.ndarray, inside: np.ndarray, fixed: np.ndarray) -> np.ndarray:
    """:func:`_grow`'s steps on the unseeded cells (:func:`_unseeded_neighbours`), all at once: their
    labels set in ``val`` (in place); returns the cells (indices into ``val``) still without one.

    A cell still open after a step gets a label in the next only beside a cell labelled in this one,
    so each step after the first looks at those cells only (the scan specks no seed reaches are
    looked at once, not eight times).
    """
    is_open = np.ones(val.size, bool)
    look = np.arange(val.size)
    for _ in range(8):
        cur = np.where(inside[look], val[pos[look]], fixed[look]).max(axis=1)
        hit = cur > 0
        if not hit.any():
            break
        new = look[hit]
        val[new] = cur[hit]
        is_open[new] = False
        near = np.zeros(val.size, bool)
        near[pos[new][inside[new]]] = True
        look = np.flatnonzero(near & is_open)
        if not look.size:
            break
    return np.flatnonzero(is_open)


def _fill_left(val: np.ndarray, open_: np.ndarray, todo: np.ndarray, pos: np.ndarray, inside: np.ndarray,
               fixed: np.ndarray, seed: np.ndarray, pieces: np.ndarray, free: np.ndarray) -> int:
    """Label the unseeded cells ``open_`` the growth left (in ``val``, in place) as
    :func:`fill_unlabeled` does; returns the number of new labels (free cells no seed reaches, one
    per 8-connected component), numbered after the seeds' labels.

    The cells left are taken in 8-connected components: a component with one label beside it is all
    that label; one between two labels (8 steps or more from their seeds) is left to
    :func:`fill_unlabeled`'s watershed, on its very input.
    """
    top = int(seed.max())
    comp, n_comp = _components(open_, todo, pos, inside, free.shape)
    near = np.where(inside[open_], val[pos[open_]], fixed[open_])
    hit = near > 0
    # the (component, label) pairs, as one int key each (faster than np.unique along an axis)
    span = int(near.max()) + 1
    key = np.unique(np.broadcast_to(comp[:, None], near.shape)[hit].astype(np.int64) * span + near[hit])
    pairs = np.stack([key // span, key % span])
    if pairs.shape[1] and np.bincount(pairs[0]).max() > 1:
        from skimage.segmentation import watershed

        out = lookup(seed, pieces)
        out.ravel()[todo] = val
        out = watershed(np.zeros(free.shape, np.float32), markers=out, mask=free, connectivity=2)
        val[:] = out.ravel()[todo].astype(np.int32)
        open_ = np.flatnonzero(val == 0)
        if open_.size:
            comp, n_comp = _components(open_, todo, pos, inside, free.shape)
    elif pairs.shape[1]:
        # one label beside a component: the watershed floods all of it with that label
        lab = np.zeros(n_comp + 1, np.int32)
        lab[pairs[0]] = pairs[1]
        val[open_] = lab[comp]
        keep = lab[comp] == 0
        open_, comp = open_[keep], comp[keep]
        if open_.size:
            _, comp = np.unique(comp, return_inverse=True)
            comp = comp.ravel() + 1
            n_comp = int(comp.max())
    if not open_.size:
        return 0
    # free cells no seed reaches: one label per 8-connected component
    val[open_] = comp + top
    return n_comp


def _renumber_filled(pieces: np.ndarray, seed: np.ndarray, runs, todo: np.ndarray, val: np.ndarray, n_lab: int,
                     min_cells: int, wide, piece_wide):
    """``(labels, n_rooms)``: the label image of the seeded pieces and the unseeded cells ``todo``
    (labels ``val``), renumbered in order of first appearance (:func:`relabel_sequential`), rooms
    before fragments (:func:`_rooms_first`), by one lookup table; ``n_lab``: one more than the
    largest label."""
    start, end, run_piece = runs
    # first cell (row-major) and number of cells of every label
    first = np.full(n_lab, np.iinfo(np.int64).max, np.int64)
    count = np.zeros(n_lab, np.int64)
    # a seeded piece: its first run's start, its runs' cells
    on = seed[run_piece] > 0
    np.minimum.at(first, seed[run_piece[on]], start[on])
    np.add.at(count, seed[run_piece[on]], (end - start)[on])
    if todo.size:
        np.minimum.at(first, val, todo)
        count += np.bincount(val, minlength=n_lab)
    ids = np.flatnonzero(count[1:]) + 1
    order = ids[np.argsort(first[ids], kind="stable")]  # relabel_sequential's numbering
    if min_cells > 0:  # _rooms_first: rooms, then fragments, each in that order
        is_room = count[order] >= min_cells
        if wide is not None:
            n_wide = np.zeros(n_lab, np.int64)
            np.add.at(n_wide, seed, piece_wide)
            if todo.size:
                n_wide += np.bincount(val[wide.ravel()[todo]], minlength=n_lab)
            is_room &= n_wide[order] > 0
        order = np.concatenate([order[is_room], order[~is_room]])
        n_rooms = int(is_room.sum())
    else:
        n_rooms = int(order.size)
    final = np.zeros(n_lab, np.int32)
    final[order] = np.arange(1, order.size + 1, dtype=np.int32)
    labels = lookup(final[seed], pieces)
    if todo.size:
        labels.ravel()[todo] = final[val]
    return labels, n_rooms


def _components(cells: np.ndarray, todo: np.ndarray, pos: np.ndarray, inside: np.ndarray, shape):
    """8-connected components of the cells ``cells`` (indices into the unseeded cells ``todo``,
    flat, ascending, whose 8 neighbours are ``pos`` where ``inside``) of an image of ``shape``:
    the component (1..n) of each cell, and n. The caller uses only which cells share a
    component, never its number.

    OpenCV's labelling of the cells' bounding box when that box holds at most :data:`_BOX_CELLS`
    cells (quicker), else the graph's components in scipy (for larger boxes: a few cells far apart
    on a large map, or a large map's many cells).
    """
    H, W = shape
    flat = todo[cells]
    r, c = np.divmod(flat, W)
    r0, c0 = int(r[0]), int(c.min())
    h, w = int(r[-1]) - r0 + 1, int(c.max()) - c0 + 1
    if h * w <= _BOX_CELLS:
        r -= r0
        c -= c0
        box = np.zeros((h, w), np.uint8)
        box[r, c] = 1
        lab, n = label(box, connectivity=8)
        return lab[r, c], n
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import connected_components

    m = cells.size
    at = np.full(pos.shape[0], -1, np.int64)
    at[cells] = np.arange(m)
    nbr = np.where(inside[cells], at[pos[cells]], -1)
    ok = nbr >= 0
    A = csr_matrix((np.ones(int(ok.sum()), np.int8), (np.repeat(np.arange(m), nbr.shape[1])[ok.ravel()], nbr[ok])),
                   shape=(m, m))
    n, comp = connected_components(A, directed=False)
    return comp.astype(np.int32) + 1, int(n)


#: Largest span of flat indices (cells) in which :func:`_fill_pieces` finds the unseeded cells'
#: neighbours by a table (32 MB at most: a table over a larger span, for the many cells of a large
#: map, raised the peak memory markedly).
_DENSE_CELLS = 2 ** 23

#: Largest bounding box (cells) :func:`_components` labels with OpenCV (10 MB of images at most;
#: its empty cells cost time too).
_BOX_CELLS = 2 ** 21


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
        labels = lookup(lut, labels)
    return labels, n_rooms


#: Row steps to the 8 neighbours of a cell (with :data:`NEIGHBOUR_COLS`: up-left, up, up-right,
#: left, right, down-left, down, down-right).
NEIGHBOUR_ROWS = np.array([-1, -1, -1, 0, 0, 1, 1, 1])
#: Column steps to the 8 neighbours of a cell (see :data:`NEIGHBOUR_ROWS`).
NEIGHBOUR_COLS = np.array([-1, 0, 1, -1, 1, -1, 0, 1])


def doors_between_rooms(grid: OccupancyGrid, labels: np.ndarray, segments) -> list:
    """The segments that separate two different rooms, as :class:`Door` objects.

    A segment's rooms are the two labels most frequent among the 8-neighbours
    of its pixels on free space; a segment with fewer than two labels around it separates
    nothing and is dropped, and so is a repeat of a kept segment. (Only the
    method's own segments: rooms that touch where no segment lies get no door
    here; :func:`join_touching_rooms` adds them.)
    """
    return _doors_between(grid, labels, segments, [line_pixels(p, q, labels.shape) for p, q in segments])


def _doors_between(grid: OccupancyGrid, labels: np.ndarray, segments, lines) -> list:
    """:func:`doors_between_rooms` given the cells of every segment (``lines``: ``(rows, cols)`` each)."""
    H, W = labels.shape
    doors, seen = [], set()
    if not len(segments):
        return doors
    # the segments' cells on free space (a post on a wall has the far side of a thin wall among its
    # neighbours: a room the segment does not touch)
    lines = [(rr[on], cc[on]) for rr, cc in lines for on in (labels[rr, cc] > 0,)]
    sizes = np.array([len(rr) for rr, _ in lines])
    rr = np.concatenate([rr for rr, _ in lines])
    cc = np.concatenate([cc for _, cc in lines])
    # one flat take (fancy indexing with two index arrays: twice the time)
    labs = np.take(labels, (np.clip(rr[:, None] + NEIGHBOUR_ROWS, 0, H - 1) * W
                            + np.clip(cc[:, None] + NEIGHBOUR_COLS, 0, W - 1)).ravel())
    seg = np.repeat(np.repeat(np.arange(len(segments)), sizes), NEIGHBOUR_ROWS.size)[labs > 0]
    labs = labs[labs > 0].astype(np.int64)
    # per segment its labels, the most frequent first (ties: the smaller label first)
    span = int(labs.max()) + 1 if labs.size else 1
    key, counts = np.unique(seg * span + labs, return_counts=True)
    seg, labs = key // span, key % span
    order = np.lexsort((labs, -counts, seg))
    seg, labs = seg[order], labs[order]
    start = np.searchsorted(seg, np.arange(len(segments))).tolist()
    end = np.searchsorted(seg, np.arange(len(segments)), side="right").tolist()
    labs = labs.tolist()
    # the doors' ends first, then their metres and widths for all at once (the same values as
    # point by point, quicker)
    kept = []
    for k, (p, q) in enumerate(segments):
        if end[k] - start[k] < 2:
            continue
        a, b = labs[start[k]], labs[start[k] + 1]
        if a > b:
            a, b = b, a
        p, q = (float(p[0]), float(p[1])), (float(q[0]), float(q[1]))
        key = (a, b, round(p[0]), round(p[1]), round(q[0]), round(q[1]))
        if key in seen:
            continue
        seen.add(key)
        kept.append((p, q, (a, b)))
    if not kept:
        return doors
    ends = np.array([p + q for p, q, _ in kept])
    x1, y1 = (v.tolist() for v in grid.pixel_to_world(ends[:, 0], ends[:, 1]))
    x2, y2 = (v.tolist() for v in grid.pixel_to_world(ends[:, 2], ends[:, 3]))
    width = (np.hypot(ends[:, 0] - ends[:, 2], ends[:, 1] - ends[:, 3]) * grid.resolution).tolist()
    for k, (p, q, rooms) in enumerate(kept):
        doors.append(Door(id=k, p1=p, p2=q, xy1=(x1[k], y1[k]), xy2=(x2[k], y2[k]), width=width[k], rooms=rooms))
    return doors


def join_touching_rooms(grid: OccupancyGrid, labels: np.ndarray, doors: list, n_rooms: int, *,
                        max_door_width=None):
    """Join every two rooms whose cells touch: by a door between them, or as one room.

    :func:`cut_rooms` (the methods ``"topomap"`` and ``"paper"``) ends with it;
    the baselines keep the doors of their own segments only (the watershed
    has none), as the methods they reproduce do.

    Rooms are cut apart along door segments, yet two rooms can still touch
    where no door joins them: two cuts across the two faces of a doorway in a
    thick wall share the sliver between them out to the rooms on either side
    (each cut then has one room beside it and makes no door); the cells of a
    gap in a wall narrower than ``wall_gap`` belong to the rooms on either
    side; a cut beside three rooms makes one door, between the two it
    touches most. Without this the room graph falls apart where the free
    space does not, and no route or tour crosses there.

    Each two rooms whose cells are 8-neighbours and that no door joins are

    * merged into one room when they touch along more than ``max_door_width``
      (m) in one place: a boundary wider than any door is no narrowing of
      free space, so nothing a robot passes through separates the two;
    * otherwise joined by a new door, at the widest place where they touch
      (a run of touching cells, 8-connected): its end points are the two
      farthest points of the boundary between the rooms there, carried on
      by half a cell at each end, so its ``width`` (m) is the length of that
      boundary (one cell for rooms that touch at one cell). It may be
      narrower than ``min_door_width`` (a scan gap in a wall): a planner
      given the robot's width leaves such a door out.

    Parameters
    ----------
    grid : OccupancyGrid
        The map (its resolution and frame).
    labels : (M, N) ndarray of int
        Rooms ``1..n_rooms``, fragments after them, 0 = no free cell.
    doors : list of Door
        The doors between rooms so far (ids ``0..len(doors) - 1``).
    n_rooms : int
        Number of rooms.
    max_door_width : float, optional
        Widest door (m); default: rooms are never merged, only joined by doors.

    Returns
    -------
    labels : (M, N) ndarray of int32
        ``labels`` itself when no rooms were merged; else the merged rooms
        renumbered ``1..n_rooms`` in order of first appearance (row-major),
        the fragments after them.
    doors : list of Door
        The doors (of merged rooms: renamed, a door between two merged rooms
        dropped) and then the new doors, ids ``0..`` in that order.
    n_rooms : int
        Number of rooms.
    """
    pairs = _doorless_contacts(labels, n_rooms, doors)
    if pairs is None:
        return labels, doors, n_rooms
    if max_door_width is not None:
        res = grid.resolution
        wide = [(a, b) for (a, b), runs in pairs.items() if max(_extent(m) for m in runs) * res > max_door_width]
        if wide:
            labels, doors, n_rooms = _merge_rooms(labels, doors, n_rooms, wide)
            pairs = _doorless_contacts(labels, n_rooms, doors)
            if pairs is None:
                return labels, doors, n_rooms
    new = []
    for (a, b), runs in sorted(pairs.items()):
        mids = max(runs, key=_extent)  # the widest place the two rooms touch
        p, q = _far_ends(mids)
        new.append((p, q, (a, b)))
    ends = np.array([p + q for p, q, _ in new], float)
    x1, y1 = (v.tolist() for v in grid.pixel_to_world(ends[:, 0], ends[:, 1]))
    x2, y2 = (v.tolist() for v in grid.pixel_to_world(ends[:, 2], ends[:, 3]))
    width = (np.hypot(ends[:, 0] - ends[:, 2], ends[:, 1] - ends[:, 3]) * grid.resolution).tolist()
    k0 = len(doors)
    doors = list(doors) + [Door(id=k0 + k, p1=p, p2=q, xy1=(x1[k], y1[k]), xy2=(x2[k], y2[k]), width=width[k],
                                rooms=rooms) for k, (p, q, rooms) in enumerate(new)]
    return labels, doors, n_rooms


#: The forward half of the 8-neighbourhood ``(drow, dcol)``: each two neighbours once.
_FORWARD = ((0, 1), (1, -1), (1, 0), (1, 1))


def _doorless_contacts(labels: np.ndarray, n_rooms: int, doors):
    """``{(a, b): [mids, ...]}``: the rooms ``a < b`` whose cells are 8-neighbours and that no door in
    ``doors`` joins, each with the runs where they touch (8-connected groups of their touching
    cells), a run as the ``(k, 2)`` float array of the midpoints ``(row, col)`` of its touching cell
    pairs; None when there are none. One pass over the labels per direction."""
    H, W = labels.shape
    if n_rooms < 2 or H == 0 or W == 0:
        return None
    ii, jj = [], []
    fragments = int(labels.max()) > n_rooms
    for dr, dc in _FORWARD:
        a = labels[:H - dr, max(0, -dc):W - max(0, dc)]
        b = labels[dr:, max(0, dc):W - max(0, -dc)]
        m = a != b  # in place from here on: one mask of the image's size at a time, and a test's
        m &= a > 0
        m &= b > 0
        if fragments:
            m &= a <= n_rooms
            m &= b <= n_rooms
        r, c = np.nonzero(m)
        del m
        c = c + max(0, -dc)
        ii.append(r * W + c)
        jj.append((r + dr) * W + c + dc)
    i, j = np.concatenate(ii).astype(np.int64), np.concatenate(jj).astype(np.int64)
    if not i.size:
        return None
    la, lb = labels.ravel()[i].astype(np.int64), labels.ravel()[j].astype(np.int64)
    lo, hi = np.minimum(la, lb), np.maximum(la, lb)
    span = n_rooms + 1
    key = lo * span + hi
    joined = np.array(sorted({min(d.rooms) * span + max(d.rooms) for d in doors}), np.int64)
    keep = ~np.isin(key, joined)
    if not keep.any():
        return None
    i, j, key = i[keep], j[keep], key[keep]
    # the runs: the touching cells of each pair (a cell once per pair), joined by their contacts and
    # by 8-adjacency among the pair's own cells
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    size = labels.size
    code = np.unique(np.concatenate([key * size + i, key * size + j]))
    ei = [np.searchsorted(code, key * size + i)]
    ej = [np.searchsorted(code, key * size + j)]
    cells = code % size
    for dr, dc in _FORWARD:
        nb = code + (dr * W + dc)
        at = np.minimum(np.searchsorted(code, nb), code.size - 1)
        ok = ((code[at] == nb) & (cells + (dr * W + dc) < size)
              & (np.abs((cells + dr * W + dc) % W - cells % W) <= 1))
        ei.append(np.flatnonzero(ok))
        ej.append(at[ok])
    ei, ej = np.concatenate(ei), np.concatenate(ej)
    A = coo_matrix((np.ones(ei.size, np.int8), (ei, ej)), shape=(code.size, code.size))
    _, comp = connected_components(A, directed=False)
    run = comp[np.searchsorted(code, key * size + i)]
    ri, ci = np.divmod(i, W)
    rj, cj = np.divmod(j, W)
    mid = np.stack([(ri + rj) / 2.0, (ci + cj) / 2.0], 1)
    order = np.lexsort((run, key))
    key, run, mid = key[order], run[order], mid[order]
    cut = np.flatnonzero(np.r_[True, (key[1:] != key[:-1]) | (run[1:] != run[:-1]), True])
    out = {}
    for s, e in zip(cut[:-1].tolist(), cut[1:].tolist()):
        k = int(key[s])
        out.setdefault((k // span, k % span), []).append(mid[s:e])
    return out


def _far_ends(mids: np.ndarray):
    """The two farthest of the points ``mids`` ((k, 2), row/col), each carried on by half a cell
    away from the other (across the contact for one point): ``((r1, c1), (r2, c2))``."""
    if len(mids) == 1:  # (the same as below, without the arrays: a map of many rooms has millions of these)
        r, c = float(mids[0, 0]), float(mids[0, 1])
        if r - np.floor(r) > 0.25:
            return (r, c - 0.5), (r, c + 0.5)
        return (r - 0.5, c), (r + 0.5, c)
    if len(mids) > 3:
        import cv2

        hull = cv2.convexHull(np.ascontiguousarray(mids[:, ::-1], np.float32), returnPoints=False).ravel()
        pts = mids[hull]
    else:
        pts = mids
    d = np.hypot(pts[:, None, 0] - pts[None, :, 0], pts[:, None, 1] - pts[None, :, 1])
    a, b = np.unravel_index(int(np.argmax(d)), d.shape)
    p, q = pts[a].astype(float), pts[b].astype(float)
    u = q - p
    n = float(np.hypot(*u))
    if n < 1e-9:
        # one point: a half-cell contact across an edge (its pair's axis is a cell's side: take the
        # cell's other axis) or at a corner; either way, one cell wide along a side of the cell
        frac = p - np.floor(p)
        u = np.array([0.0, 1.0]) if frac[0] > 0.25 else np.array([1.0, 0.0])
        n = 1.0
    u = u / n / 2
    return (float(p[0] - u[0]), float(p[1] - u[1])), (float(q[0] + u[0]), float(q[1] + u[1]))


def _extent(mids: np.ndarray) -> float:
    """Length (cells) of a boundary run between two rooms: the distance between its farthest points
    plus a cell (:func:`_far_ends`)."""
    if len(mids) == 1:
        return 1.0  # a contact at one cell: one cell wide (exactly what _far_ends gives)
    p, q = _far_ends(mids)
    return float(np.hypot(q[0] - p[0], q[1] - p[1]))


def _merge_rooms(labels: np.ndarray, doors: list, n_rooms: int, pairs):
    """Merge the rooms of each pair in ``pairs`` (joined transitively): ``(labels, doors, n_rooms)``
    with the rooms renumbered in order of first appearance and the fragments after them, the doors
    renamed, those between two merged rooms dropped, ids renumbered."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    a = np.array([p[0] for p in pairs])
    b = np.array([p[1] for p in pairs])
    A = coo_matrix((np.ones(a.size, np.int8), (a, b)), shape=(n_rooms + 1, n_rooms + 1))
    _, comp = connected_components(A, directed=False)
    rep = np.zeros(n_rooms + 1, np.int64)
    first = np.full(comp.max() + 1, n_rooms + 1, np.int64)
    np.minimum.at(first, comp, np.arange(n_rooms + 1))
    rep[:] = first[comp]
    rep[0] = 0
    top = int(labels.max(initial=0))
    lut = np.zeros(top + 1, np.int32)
    lut[:n_rooms + 1] = rep
    rooms = relabel_sequential(lookup(lut, labels))  # the merged rooms, numbered by first appearance
    n_new = int(rooms.max(initial=0))
    frag = labels > n_rooms
    out = np.where(frag, labels - n_rooms + n_new, rooms).astype(np.int32)
    # each old room's new label: read at one of its cells (the rooms renumbered as a whole)
    new_of = np.zeros(n_rooms + 1, np.int64)
    flat_old, flat_new = labels.ravel(), out.ravel()
    idx = np.flatnonzero((flat_old > 0) & (flat_old <= n_rooms))
    new_of[flat_old[idx]] = flat_new[idx]
    kept = []
    for d in doors:
        x, y = int(new_of[d.rooms[0]]), int(new_of[d.rooms[1]])
        if x != y:
            kept.append(dataclasses.replace(d, id=len(kept), rooms=(min(x, y), max(x, y))))
    return out, kept, n_new
