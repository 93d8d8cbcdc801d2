"""Scoring room segmentations, doors and room graphs against ground truth.

The room metric is the one of Bormann et al., "Room segmentation: survey,
implementation, and analysis" (ICRA 2016), in two protocols
(:data:`PROTOCOLS`), both given the *scored* cells (the cells the method was
given: the free cells of the grid as loaded):

* ``"original"`` -- the protocol of the original evaluation code
  (ipa_room_segmentation's ``EvaluationSegmentation::computePrecisionRecall``)
  and of every published figure on the ipa_room_segmentation maps. A
  predicted segment ``S`` is the set of *scored* cells carrying one label
  ``k > 0``; a ground-truth room ``G`` is kept **whole**, furniture and other
  unscored cells included. No method can label those cells, so even the
  ground truth itself scores below 100 % recall on furnished maps (the
  *ceiling*, :func:`ceiling`).
* ``"free-cells"`` -- both ``S`` and ``G`` are restricted to the scored
  cells, so the ground truth scores 100 %. ROSE²'s evaluation of real SLAM
  maps (Luperto et al. 2022) is of this kind.

In both, sizes ``|S|`` and ``|G|`` are counted after that restriction and
segments and rooms of ``min_size`` (100) cells or fewer are ignored; a
segment cell in no (kept) room still counts in ``|S|`` but in no
intersection, and a room cell in no (kept) segment still counts in ``|G|``;
precision = mean over segments ``S`` of ``max_G |S ∩ G| / |S|`` (low on
under-segmentation), recall = mean over rooms ``G`` of ``max_S |S ∩ G| / |G|``
(low on over-segmentation). These plain means are the *micro* figures, the
headline; the *macro* figures weight each segment (room) by its size, i.e.
``sum_S max_G |S∩G| / sum_S |S|``.

Doors are scored by greedy one-to-one matching of detected door segments to
true door cell groups (:func:`score_doors`), the room graph by comparing
room-adjacency edges after mapping predicted rooms onto true rooms
(:func:`score_adjacency`).

Conventions for empty sets (used throughout): a precision over no
predictions is 1.0 and a recall over no true items is 1.0 (nothing was
wrong / nothing was missed), so F1 is 1.0 when both sets are empty and 0.0
when exactly one is. The room metric is the exception, see
:func:`score_segmentation`.

Pixel coordinates are ``(row, col)``; distances are in metres via the map
``resolution`` (metres per pixel).
"""

from __future__ import annotations

import math
from itertools import combinations
from typing import Iterable, Mapping, Sequence

import numpy as np
from scipy import ndimage as ndi
from scipy import sparse

from .._fast import label as _label
from ..errors import ParameterError
from ..core.geometry import point_segment_distances
from ..io.maps import FREE_GRAY  # noqa: F401  (re-exported: the benchmark's white level)

__all__ = [
    "FREE_GRAY",
    "MIN_SIZE",
    "PROTOCOLS",
    "score_segmentation",
    "ceiling",
    "gt_rooms_from_image",
    "gt_doors_from_images",
    "true_adjacency",
    "room_adjacency_from_doors",
    "points_to_segment_distance",
    "door_distance_matrix",
    "score_doors",
    "score_adjacency",
    "evaluate",
    "summarize",
]

#: Segments and rooms of this many cells or fewer are ignored.
MIN_SIZE = 100
#: The two scoring protocols of :func:`score_segmentation`, headline first.
PROTOCOLS = ("original", "free-cells")


# --------------------------------------------------------------------------
# room segmentation
# --------------------------------------------------------------------------

def _check_same_shape(name_a, a, name_b, b):
    if a.ndim != 2:
        raise ParameterError(f"<array>: {name_a} must be 2-D, got shape {a.shape}")
    if a.shape != b.shape:
        raise ParameterError(
            f"<array>: {name_a} shape {a.shape} differs from {name_b} shape {b.shape}")


def _as_inputs(labels, gt_rooms, scored):
    """Arrays of the same shape: labels, true rooms, scored mask (all True by default)."""
    labels = np.asarray(labels)
    gt_rooms = np.asarray(gt_rooms)
    _check_same_shape("labels", labels, "gt_rooms", gt_rooms)
    if scored is None:
        scored = np.ones(labels.shape, bool)
    else:
        scored = np.asarray(scored, bool)
        _check_same_shape("scored", scored, "labels", labels)
    return labels, gt_rooms, scored


def _contingency(labels, gt_rooms, scored):
    """Sparse contingency table of (segment, room) cell counts on scored cells.

    Returns ``(seg_ids, room_ids, table)`` where ``table[i, j]`` counts the
    scored cells with label ``seg_ids[i]`` and room ``room_ids[j]``; ids <= 0
    are kept as rows / columns too (they are "no segment" / "no room").
    """
    lab = np.asarray(labels)[scored].astype(np.int64, copy=False)
    gt = np.asarray(gt_rooms)[scored].astype(np.int64, copy=False)
    seg_ids, si = np.unique(lab, return_inverse=True)
    room_ids, gi = np.unique(gt, return_inverse=True)
    si = si.ravel()
    gi = gi.ravel()
    table = sparse.coo_matrix(
        (np.ones(si.size, np.int64), (si, gi)),
        shape=(max(seg_ids.size, 1), max(room_ids.size, 1))).tocsr()
    table.sum_duplicates()
    return seg_ids, room_ids, table


def _check_protocol(protocol) -> str:
    if protocol not in PROTOCOLS:
        raise ParameterError(
            f"<array>: protocol must be one of {', '.join(PROTOCOLS)}, got {protocol!r}")
    return protocol


def _table_inputs(labels, gt_rooms, scored, protocol):
    """Labels, rooms and the cells to tabulate for ``protocol``.

    ``original``: labels are zeroed outside the scored cells and every cell
    of a true room is tabulated as well, so rooms stay whole.
    """
    if protocol == "free-cells":
        return labels, gt_rooms, scored
    labels = np.where(scored, labels, 0)
    return labels, gt_rooms, scored | (gt_rooms > 0)


def score_segmentation(labels, gt_rooms, *, scored=None, min_size: int = MIN_SIZE,
                       protocol: str = "original") -> dict:
    """Score a room segmentation with the Bormann et al. (2016) metric.

    Parameters
    ----------
    labels : (M, N) array_like of int
        Predicted room label per cell; values <= 0 mean "no room".
    gt_rooms : (M, N) array_like of int
        Ground-truth room label per cell (e.g. from :func:`gt_rooms_from_image`);
        values <= 0 mean "no room". A room may be several pieces.
    scored : (M, N) array_like of bool, optional
        The cells the method was given (the free cells of the grid as
        loaded). Default: every cell.
    min_size : int, optional
        Segments and rooms with ``min_size`` cells or fewer (counted as the
        protocol counts them) are ignored (default 100).
    protocol : {"original", "free-cells"}, optional
        ``"original"`` (default): segments restricted to the scored cells,
        true rooms whole -- the original evaluation code's protocol.
        ``"free-cells"``: true rooms restricted to the scored cells too.
        See the module docstring.

    Returns
    -------
    dict
        ``precision``, ``recall`` (micro: plain means over segments / rooms),
        ``precision_macro``, ``recall_macro`` (each segment / room weighted by
        its size in cells), ``n_segments``, ``n_rooms`` (kept after the size
        filter) and ``room_count_error`` = ``n_segments - n_rooms``.

    Notes
    -----
    A segment cell in no kept room counts in ``|S|`` but in no intersection
    (and symmetrically for recall), so cells a method leaves unlabelled
    lower recall, and labels spilling over unlabelled ground truth lower
    precision.

    Degenerate cases: with no segments and no rooms both scores are 1.0; with
    no segments (but rooms) both are 0.0; with no rooms (but segments)
    precision is 0.0 (no segment overlaps a room) and recall is 0.0.

    The computation is a sparse contingency table of the cells, so it is
    linear in the number of cells.
    """
    labels, gt_rooms, scored = _as_inputs(labels, gt_rooms, scored)
    if int(min_size) < 0:
        raise ParameterError(f"<array>: min_size must be >= 0, got {min_size!r}")
    labels, gt_rooms, cells = _table_inputs(labels, gt_rooms, scored, _check_protocol(protocol))

    seg_ids, room_ids, table = _contingency(labels, gt_rooms, cells)
    if seg_ids.size == 0:  # nothing scored
        seg_ids = np.zeros(0, np.int64)
        room_ids = np.zeros(0, np.int64)
    seg_size = np.asarray(table.sum(axis=1)).ravel()[: seg_ids.size]
    room_size = np.asarray(table.sum(axis=0)).ravel()[: room_ids.size]
    seg_keep = np.flatnonzero((seg_ids > 0) & (seg_size > min_size))
    room_keep = np.flatnonzero((room_ids > 0) & (room_size > min_size))
    n_s, n_r = seg_keep.size, room_keep.size

    out = {"n_segments": int(n_s), "n_rooms": int(n_r),
           "room_count_error": int(n_s - n_r)}
    if n_s == 0 or n_r == 0:
        both_empty = n_s == 0 and n_r == 0
        v = 1.0 if both_empty else 0.0
        out.update(precision=v, recall=v, precision_macro=v, recall_macro=v)
        return out

    sub = table[seg_keep][:, room_keep]
    best_per_seg = np.asarray(sub.max(axis=1).todense()).ravel().astype(float)
    best_per_room = np.asarray(sub.max(axis=0).todense()).ravel().astype(float)
    s_size = seg_size[seg_keep].astype(float)
    r_size = room_size[room_keep].astype(float)
    out.update(
        precision=float(np.mean(best_per_seg / s_size)),
        recall=float(np.mean(best_per_room / r_size)),
        precision_macro=float(best_per_seg.sum() / s_size.sum()),
        recall_macro=float(best_per_room.sum() / r_size.sum()),
    )
    return out


def ceiling(gt_rooms, *, scored=None, min_size: int = MIN_SIZE) -> dict:
    """The ground truth itself, scored under each protocol: the best any method can do.

    The ground truth is given as the labels (restricted to the scored
    cells, as any method's labels are) and scored against itself.

    Returns
    -------
    dict
        ``{protocol: score_segmentation(...)}`` for every protocol of
        :data:`PROTOCOLS`. Under ``"original"`` the recall is below 1 where
        true rooms have cells the method is not given (furniture); under
        ``"free-cells"`` both are 1 unless the restriction leaves a room with
        ``min_size`` cells or fewer.
    """
    gt_rooms = np.asarray(gt_rooms)
    return {p: score_segmentation(gt_rooms, gt_rooms, scored=scored, min_size=min_size,
                                  protocol=p) for p in PROTOCOLS}


def _filter_small(lab: np.ndarray, min_size: int) -> np.ndarray:
    """Zero the components of ``lab`` with ``min_size`` cells or fewer, renumber 1..K."""
    sizes = np.bincount(lab.ravel())
    keep = sizes > min_size
    keep[0] = False
    new_id = np.zeros(sizes.size, np.int32)
    new_id[keep] = np.arange(1, int(keep.sum()) + 1, dtype=np.int32)
    return new_id[lab]


def gt_rooms_from_image(gt_gray, *, min_size: int = MIN_SIZE) -> np.ndarray:
    """Ground-truth rooms from a benchmark ``NAME_gt_segmentation.png`` image.

    Parameters
    ----------
    gt_gray : (M, N) array_like of uint8
        The ground-truth drawing as 8-bit gray: room space white, rooms
        separated by black lines across the doorways.
    min_size : int, optional
        Components of ``min_size`` pixels or fewer are dropped (default 100;
        the scan-based maps have white speckle).

    Returns
    -------
    (M, N) ndarray of int32
        0 outside rooms, rooms numbered 1..K in raster order of their first
        pixel: the 8-connected components of ``gt_gray >= 250``.
    """
    gt_gray = np.asarray(gt_gray)
    if gt_gray.ndim != 2:
        raise ParameterError(f"<array>: gt_gray must be 2-D, got shape {gt_gray.shape}")
    lab, _ = _label(gt_gray >= FREE_GRAY, 8)
    return _filter_small(lab, min_size)


_EIGHT = np.ones((3, 3), bool)


def _touching_labels(rc: np.ndarray, lab: np.ndarray, radius: int = 1) -> np.ndarray:
    """Distinct positive labels of ``lab`` within ``radius`` (chessboard) of cells ``rc``.

    ``rc`` is a (K, 2) array of in-bounds (row, col) cells; only their
    bounding box (plus margin) is dilated.
    """
    rc = np.asarray(rc, dtype=np.intp).reshape(-1, 2)
    if rc.shape[0] == 0:
        return np.zeros(0, lab.dtype)
    r0 = max(int(rc[:, 0].min()) - radius, 0)
    r1 = min(int(rc[:, 0].max()) + radius + 1, lab.shape[0])
    c0 = max(int(rc[:, 1].min()) - radius, 0)
    c1 = min(int(rc[:, 1].max()) + radius + 1, lab.shape[1])
    box = np.zeros((r1 - r0, c1 - c0), bool)
    box[rc[:, 0] - r0, rc[:, 1] - c0] = True
    if radius > 0:
        box = ndi.binary_dilation(box, _EIGHT, iterations=int(radius))
    vals = np.unique(lab[r0:r1, c0:c1][box])
    return vals[vals > 0]


def gt_doors_from_images(map_gray, gt_gray, *, min_size: int = 3, min_rooms: int = 2,
                         room_min_size: int = MIN_SIZE) -> list:
    """True doors: the door lines drawn into a benchmark ground truth.

    A door cell is free in the map (``map_gray >= 250``) but not white in the
    ground truth (``gt_gray < 250``): the black lines drawn across doorways.
    Door cells are grouped into 8-connected components.

    Parameters
    ----------
    map_gray, gt_gray : (M, N) array_like of uint8
        The map and its ground-truth drawing as 8-bit gray.
    min_size : int, optional
        Groups of fewer than ``min_size`` pixels are dropped as speckle
        (default 3, i.e. groups of 1 or 2 pixels are dropped).
    min_rooms : int, optional
        A group is kept only if its 1-pixel (8-neighbour) dilation touches at
        least ``min_rooms`` distinct ground-truth rooms (default 2: a door
        joins two rooms). This drops lines that cut off clutter or areas
        outside every room. Set to 0 to keep every group.
    room_min_size : int, optional
        ``min_size`` of the ground-truth rooms used for ``min_rooms``.

    Notes
    -----
    For the furnished benchmark variant pass the *unfurnished* map: the
    ground truth is drawn on it, and furniture touching a door line would
    otherwise change the door's cell group.

    Returns
    -------
    list of (K, 2) ndarray of int
        One array of pixel ``(row, col)`` coordinates per door, in raster
        order of the door's first pixel. Where several door lines meet (a
        line junction between three rooms) they form one group.
    """
    map_gray = np.asarray(map_gray)
    gt_gray = np.asarray(gt_gray)
    _check_same_shape("map_gray", map_gray, "gt_gray", gt_gray)
    door_mask = (map_gray >= FREE_GRAY) & (gt_gray < FREE_GRAY)
    lab, n = _label(door_mask, 8)
    if n == 0:
        return []
    rooms = gt_rooms_from_image(gt_gray, min_size=room_min_size) if min_rooms > 0 else None
    # group pixel coordinates by component without a per-component scan
    flat = lab.ravel()
    idx = np.flatnonzero(flat)
    order = np.argsort(flat[idx], kind="stable")
    idx = idx[order]
    counts = np.bincount(flat[idx], minlength=n + 1)[1:]
    groups = np.split(idx, np.cumsum(counts)[:-1])
    doors = []
    for g in groups:
        if g.size < min_size:
            continue
        rc = np.column_stack(np.unravel_index(g, lab.shape))
        if rooms is not None:
            if _touching_labels(rc, rooms, 1).size < min_rooms:
                continue
        doors.append(rc)
    return doors


def true_adjacency(gt_rooms, true_doors) -> set:
    """Room-adjacency edges of the ground truth.

    Parameters
    ----------
    gt_rooms : (M, N) array_like of int
        Ground-truth room labels.
    true_doors : list of (K, 2) array_like of int
        Door pixel groups (from :func:`gt_doors_from_images`).

    Returns
    -------
    set of tuple
        Pairs ``(a, b)`` with ``a < b`` of ground-truth rooms that both touch
        the 1-pixel dilation of one door (a door touching three rooms gives
        all three pairs).
    """
    gt_rooms = np.asarray(gt_rooms)
    edges = set()
    for door in true_doors:
        rc = np.asarray(door, dtype=np.intp).reshape(-1, 2)
        rooms = _touching_labels(rc, gt_rooms, 1)
        edges.update((int(a), int(b)) for a, b in combinations(sorted(rooms.tolist()), 2))
    return edges


def _as_segments(pred_doors) -> np.ndarray:
    segs = np.asarray(pred_doors, dtype=float)
    if segs.size == 0:
        return np.zeros((0, 2, 2))
    if segs.ndim != 3 or segs.shape[1:] != (2, 2):
        raise ParameterError(
            "<array>: door segments must be ((r1, c1), (r2, c2)) pairs, "
            f"got array of shape {segs.shape}")
    return segs


def room_adjacency_from_doors(labels, pred_doors, *, radius: int = 1) -> set:
    """Room-adjacency edges of a predicted segmentation, from its door segments.

    Each door segment is rasterised (Bresenham line) and dilated by
    ``radius`` pixels (8-neighbourhood); every pair of distinct labels > 0
    under that dilation is an edge.

    Parameters
    ----------
    labels : (M, N) array_like of int
        Predicted room labels (<= 0: no room).
    pred_doors : sequence of ((r1, c1), (r2, c2))
        Door segments in pixel coordinates.
    radius : int, optional
        Dilation radius in pixels (default 1).

    Returns
    -------
    set of tuple
        Pairs ``(a, b)``, ``a < b``, of predicted labels.
    """
    from skimage.draw import line

    labels = np.asarray(labels)
    segs = _as_segments(pred_doors)
    h, w = labels.shape
    edges = set()
    for (r1, c1), (r2, c2) in segs:
        rr, cc = line(int(round(r1)), int(round(c1)), int(round(r2)), int(round(c2)))
        ok = (rr >= 0) & (rr < h) & (cc >= 0) & (cc < w)
        if not ok.any():
            continue
        rooms = _touching_labels(np.column_stack((rr[ok], cc[ok])), labels, radius)
        edges.update((int(a), int(b)) for a, b in combinations(sorted(rooms.tolist()), 2))
    return edges


# --------------------------------------------------------------------------
# doors
# --------------------------------------------------------------------------

def points_to_segment_distance(points, a, b) -> np.ndarray:
    """Euclidean distance of each point to the closed segment ``a``–``b``.

    Parameters
    ----------
    points : (K, 2) array_like of float
    a, b : (2,) array_like of float
        Segment end points (same units as ``points``; ``a == b`` allowed).

    Returns
    -------
    (K,) ndarray of float
    """
    p = np.asarray(points, float).reshape(-1, 2)
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    ab = b - a
    den = float(ab @ ab)
    if den == 0.0:
        t = np.zeros(len(p))
    else:
        t = np.clip((p - a) @ ab / den, 0.0, 1.0)
    proj = a + t[:, None] * ab
    return np.hypot(*(p - proj).T)


def _prf(tp: int, n_pred: int, n_true: int) -> tuple:
    precision = tp / n_pred if n_pred else 1.0
    recall = tp / n_true if n_true else 1.0
    f1 = 2 * precision * recall / (precision + recall) if precision + recall > 0 else 0.0
    return float(precision), float(recall), float(f1)


def door_distance_matrix(pred_doors, true_doors, *, resolution: float) -> np.ndarray:
    """Median distance (metres) of each true door's cells to each detected segment.

    Returns a ``(n_pred, n_true)`` array; see :func:`score_doors`.
    """
    segs = _as_segments(pred_doors)
    res = float(resolution)
    D = np.full((len(segs), len(true_doors)), np.inf)
    if len(segs) == 0 or len(true_doors) == 0:
        return D
    for j, door in enumerate(true_doors):
        p = np.asarray(door, float).reshape(-1, 2)
        if p.size == 0:
            continue
        # (n_pred, K) distances of this door's K cells to every segment at once
        d = point_segment_distances(p[None, :, :], segs[:, None, 0, :], segs[:, None, 1, :])
        D[:, j] = np.median(d, axis=1) * res
    return D


def score_doors(pred_doors, true_doors, *, resolution: float, tol_m: float = 0.5) -> dict:
    """Score detected doors against true door cell groups.

    Parameters
    ----------
    pred_doors : sequence of ((r1, c1), (r2, c2))
        Detected door segments in pixel coordinates.
    true_doors : list of (K, 2) array_like
        True doors as pixel ``(row, col)`` cell groups
        (from :func:`gt_doors_from_images`).
    resolution : float
        Metres per pixel.
    tol_m : float, optional
        Matching tolerance in metres (default 0.5).

    Returns
    -------
    dict
        ``precision``, ``recall``, ``f1``, ``tp``, ``fp``, ``fn``,
        ``n_pred``, ``n_true`` and ``matches``: a list of
        ``(pred_index, true_index, distance_m)``.

    Notes
    -----
    A detected door and a true door *can match* when the **median** distance
    of the true door's cells to the detected segment is at most ``tol_m``
    (the median, not the maximum, so that a true line drawn longer than the
    doorway, e.g. into the wall, still matches a segment spanning only the
    opening). Matching is greedy and one-to-one: candidate pairs are taken in
    increasing distance order (ties by detection, then true-door index), each
    detection and each true door used at most once. Unmatched detections are
    false positives, unmatched true doors false negatives. With no
    detections precision is 1.0; with no true doors recall is 1.0; F1 is the
    harmonic mean (1.0 when both sets are empty).
    """
    res = float(resolution)
    if not res > 0:
        raise ParameterError(f"<array>: resolution must be > 0, got {resolution!r}")
    if not tol_m >= 0:
        raise ParameterError(f"<array>: tol_m must be >= 0, got {tol_m!r}")
    segs = _as_segments(pred_doors)
    n_pred, n_true = len(segs), len(true_doors)
    D = door_distance_matrix(segs, true_doors, resolution=res)
    pi, tj = np.nonzero(D <= tol_m)
    order = np.lexsort((tj, pi, D[pi, tj]))
    used_p = np.zeros(n_pred, bool)
    used_t = np.zeros(n_true, bool)
    matches = []
    for k in order:  # loop over candidate pairs only
        i, j = pi[k], tj[k]
        if used_p[i] or used_t[j]:
            continue
        used_p[i] = used_t[j] = True
        matches.append((int(i), int(j), float(D[i, j])))
    tp = len(matches)
    precision, recall, f1 = _prf(tp, n_pred, n_true)
    return {"precision": precision, "recall": recall, "f1": f1, "tp": tp,
            "fp": n_pred - tp, "fn": n_true - tp, "n_pred": n_pred, "n_true": n_true,
            "matches": matches}


# --------------------------------------------------------------------------
# room graph
# --------------------------------------------------------------------------

def _canon_edges(edges) -> set:
    out = set()
    for e in edges:
        a, b = (int(x) for x in e)
        if a != b:
            out.add((min(a, b), max(a, b)))
    return out


def score_adjacency(labels, gt_rooms, pred_edges, true_edges, *, scored=None,
                    min_size: int = MIN_SIZE) -> dict:
    """Score a predicted room-adjacency graph against the true one.

    Each predicted room (label > 0 with more than ``min_size`` scored cells)
    is mapped to the ground-truth room it overlaps most on the scored cells
    (ties: lowest room id); rooms overlapping no true room are unmapped.
    Each predicted edge ``(a, b)`` becomes the true-room pair
    ``(map[a], map[b])``; edges with an unmapped end and self-loops
    (both ends in one true room, e.g. across an over-segmentation cut) are
    dropped and duplicates merged. The resulting set is compared with
    ``true_edges``.

    Parameters
    ----------
    labels, gt_rooms : (M, N) array_like of int
        Predicted and ground-truth room labels (<= 0: no room).
    pred_edges : iterable of (int, int)
        Pairs of predicted labels joined by a door
        (e.g. :func:`room_adjacency_from_doors`).
    true_edges : iterable of (int, int)
        Pairs of ground-truth rooms joined by a door
        (e.g. :func:`true_adjacency`).
    scored : (M, N) array_like of bool, optional
        Cells used for the overlap (default: all).
    min_size : int, optional
        Predicted rooms of ``min_size`` scored cells or fewer are unmapped.

    Returns
    -------
    dict
        ``precision``, ``recall``, ``f1``, ``tp``, ``fp``, ``fn``,
        ``n_pred`` (mapped edges), ``n_true`` and ``mapping``
        (predicted label → true room).
    """
    labels, gt_rooms, scored = _as_inputs(labels, gt_rooms, scored)
    mapping = {}
    seg_ids, room_ids, table = _contingency(labels, gt_rooms, scored)
    if seg_ids.size and room_ids.size:
        seg_size = np.asarray(table.sum(axis=1)).ravel()[: seg_ids.size]
        rows = np.flatnonzero((seg_ids > 0) & (seg_size > min_size))
        cols = np.flatnonzero(room_ids > 0)
        if rows.size and cols.size:
            sub = table[rows][:, cols].toarray()
            best = sub.argmax(axis=1)
            has = sub[np.arange(rows.size), best] > 0
            mapping = {int(seg_ids[r]): int(room_ids[cols[b]])
                       for r, b, h in zip(rows, best, has) if h}
    mapped = set()
    for a, b in _canon_edges(pred_edges):
        if a in mapping and b in mapping and mapping[a] != mapping[b]:
            x, y = mapping[a], mapping[b]
            mapped.add((min(x, y), max(x, y)))
    true = _canon_edges(true_edges)
    tp = len(mapped & true)
    precision, recall, f1 = _prf(tp, len(mapped), len(true))
    return {"precision": precision, "recall": recall, "f1": f1, "tp": tp,
            "fp": len(mapped) - tp, "fn": len(true) - tp, "n_pred": len(mapped),
            "n_true": len(true), "mapping": mapping}


# --------------------------------------------------------------------------
# whole map and summaries
# --------------------------------------------------------------------------

def _room_scores(labels, gt, scored, min_size) -> dict:
    """Room scores under both protocols and their ceilings, flat keys.

    Headline keys (original protocol) have no suffix; the free-cells ones end
    in ``_free``; the ground truth's own scores start with ``ceiling_``.
    """
    out = {}
    ceil = ceiling(gt, scored=scored, min_size=min_size)
    for prot, suffix in zip(PROTOCOLS, ("", "_free")):
        sc = score_segmentation(labels, gt, scored=scored, min_size=min_size, protocol=prot)
        p, r = sc["precision"], sc["recall"]
        for k in ("precision", "recall", "precision_macro", "recall_macro"):
            out[k + suffix] = sc[k]
        out["f1" + suffix] = 2 * p * r / (p + r) if p + r > 0 else 0.0
        out["ceiling_precision" + suffix] = ceil[prot]["precision"]
        out["ceiling_recall" + suffix] = ceil[prot]["recall"]
        if prot == "original":
            out.update(n_segments=sc["n_segments"], n_true_rooms=sc["n_rooms"],
                       room_count_error=sc["room_count_error"])
    return out


def evaluate(labels, map_gray, gt_gray, *, pred_doors=None, resolution: float = 0.05,
             tol_m: float = 0.5, min_size: int = MIN_SIZE, door_map_gray=None,
             scored=None, gt_rooms=None, true_doors=None, true_edges=None) -> dict:
    """All scores of one benchmark map.

    Parameters
    ----------
    labels : (M, N) array_like of int
        Predicted room labels (<= 0: no room).
    map_gray : (M, N) array_like of uint8
        The benchmark map as 8-bit gray.
    gt_gray : (M, N) array_like of uint8 or None
        The ground-truth drawing (ipa_room_segmentation layout: rooms white,
        door lines black). None when the ground truth is a label image
        (``gt_rooms``); doors are then not scored.
    pred_doors : sequence of ((r1, c1), (r2, c2)), optional
        Detected door segments in pixels; if given (and ``gt_gray`` or
        ``true_doors`` is), door and adjacency scores are added under
        ``door_*`` and ``adjacency_*`` keys.
    resolution : float, optional
        Metres per pixel (benchmark: 0.05).
    tol_m : float, optional
        Door matching tolerance in metres.
    min_size : int, optional
        Size filter for segments and rooms (cells).
    door_map_gray : (M, N) array_like of uint8, optional
        Map the true doors are extracted from (default ``map_gray``). For the
        furnished variant pass the unfurnished map
        (:attr:`topomap.bench.datasets.BenchmarkMap.unfurnished_gray`).
    scored : (M, N) array_like of bool, optional
        The cells the method was given: the free cells of the grid as loaded
        (:attr:`topomap.io.OccupancyGrid.free`). Default ``map_gray >= 250``.
    gt_rooms : (M, N) array_like of int, optional
        Ground-truth room labels; default :func:`gt_rooms_from_image` of
        ``gt_gray``.
    true_doors : list of (K, 2) array_like of int, optional
        The true doors as pixel cell groups, when the ground truth lists them
        (e.g. :func:`topomap.bench.datasets.door_cells` of a simulated case);
        default the door lines of ``gt_gray`` (:func:`gt_doors_from_images`).
    true_edges : iterable of (int, int), optional
        The true room-adjacency edges (ground-truth labels) with
        ``true_doors``; default :func:`true_adjacency` of ``true_doors``.

    Returns
    -------
    dict
        Original protocol (the headline): ``precision``, ``recall``,
        ``precision_macro``, ``recall_macro``, ``f1`` (harmonic mean of micro
        precision and recall), ``n_segments``, ``n_true_rooms`` (true rooms
        of more than ``min_size`` cells) and ``room_count_error``
        (``n_segments - n_true_rooms``); the same scores under the
        free-cells protocol with the suffix ``_free``; the ground truth's own
        scores (:func:`ceiling`) as ``ceiling_precision``,
        ``ceiling_recall``, ``ceiling_precision_free``,
        ``ceiling_recall_free``. With doors: ``door_precision``,
        ``door_recall``, ``door_f1``, ``door_tp``, ``door_fp``,
        ``door_fn``, ``adjacency_precision``, ``adjacency_recall``,
        ``adjacency_f1`` (adjacency overlaps on the scored cells).
    """
    map_gray = np.asarray(map_gray)
    scored = map_gray >= FREE_GRAY if scored is None else np.asarray(scored, bool)
    if gt_rooms is None:
        if gt_gray is None:
            raise ParameterError("<array>: give gt_gray or gt_rooms")
        gt = gt_rooms_from_image(gt_gray, min_size=min_size)
    else:
        gt = np.asarray(gt_rooms)
    labels, gt, scored = _as_inputs(labels, gt, scored)
    out = _room_scores(labels, gt, scored, min_size)
    if pred_doors is not None and true_doors is None and gt_gray is not None:
        dmap = map_gray if door_map_gray is None else np.asarray(door_map_gray)
        true_doors = gt_doors_from_images(dmap, gt_gray, room_min_size=min_size)
    if pred_doors is not None and true_doors is not None:
        d = score_doors(pred_doors, true_doors, resolution=resolution, tol_m=tol_m)
        for k in ("precision", "recall", "f1", "tp", "fp", "fn"):
            out[f"door_{k}"] = d[k]
        edges = true_adjacency(gt, true_doors) if true_edges is None else true_edges
        a = score_adjacency(labels, gt, room_adjacency_from_doors(labels, pred_doors),
                            edges, scored=scored, min_size=min_size)
        for k in ("precision", "recall", "f1"):
            out[f"adjacency_{k}"] = a[k]
    return out


def summarize(rows: Iterable[Mapping], *, keys: Sequence[str] | None = None,
              ddof: int = 1) -> dict:
    """Mean, standard deviation and median over per-map result dicts.

    Parameters
    ----------
    rows : iterable of mapping
        One dict per map (e.g. from :func:`evaluate`). Non-numeric values
        (names, lists) and booleans are skipped.
    keys : sequence of str, optional
        Keys to summarise (default: every key holding a real number in at
        least one row, in first-seen order).
    ddof : int, optional
        Delta degrees of freedom of the standard deviation: 1 (default) is
        the *sample* standard deviation, 0 the population one.

    Returns
    -------
    dict
        ``{key: {"mean", "sd", "median", "min", "max", "n"}}`` computed over
        the finite values of that key (NaN and missing values are left out
        and not counted in ``n``). ``sd`` is NaN when ``n <= ddof``; every
        statistic is NaN when ``n == 0``.
    """
    rows = list(rows)

    def is_num(v):
        return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(
            v, (bool, np.bool_))

    if keys is None:
        keys = []
        for row in rows:
            for k, v in row.items():
                if k not in keys and is_num(v):
                    keys.append(k)
    out = {}
    for k in keys:
        vals = np.array([float(row[k]) for row in rows if k in row and is_num(row[k])])
        vals = vals[np.isfinite(vals)]
        n = int(vals.size)
        if n == 0:
            nan = math.nan
            out[k] = {"mean": nan, "sd": nan, "median": nan, "min": nan, "max": nan, "n": 0}
            continue
        sd = float(np.std(vals, ddof=ddof)) if n > ddof else math.nan
        out[k] = {"mean": float(vals.mean()), "sd": sd, "median": float(np.median(vals)),
                  "min": float(vals.min()), "max": float(vals.max()), "n": n}
    return out
