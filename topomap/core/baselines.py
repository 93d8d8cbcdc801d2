"""Baseline room segmentations that the benchmark compares topomap against.

Four classical methods, following the C++ implementations of
``ipa_room_segmentation`` (Bormann, Jordan, Li, Hampp and Hägele, "Room
segmentation: survey, implementation, and analysis", ICRA 2016), re-written
with vectorised numpy / scipy / scikit-image / OpenCV:

* :func:`watershed` -- distance-transform watershed (Fabrizi & Saffiotti 2000);
* :func:`morphological` -- iterated erosion;
* :func:`distance` -- iterated thresholds of the distance transform;
* :func:`voronoi` -- critical points on the Voronoi graph (Thrun 1998).

All are stateless functions of a free-space mask with keyword-only options
given in metres (or m²) and converted to pixels with ``resolution``. Each
returns ``(labels, doors)``:

``labels``
    (M, N) int32, ``0`` on non-free cells and ``1..N`` on *every* free cell.
``doors``
    list of door segments ``((r1, c1), (r2, c2))`` in float pixel
    coordinates; only :func:`voronoi` has doors (its critical lines), the
    others return ``[]``.
"""

from __future__ import annotations

import numpy as np

from .._fast import edt, label
from ..errors import MapError, ParameterError
from ..options import check_length
from .geometry import line_pixels, true_bbox
from .rooms import fill_unlabeled, relabel_sequential
from .skeleton import neighbour_count

__all__ = ["watershed", "morphological", "distance", "voronoi"]

_EIGHT = np.ones((3, 3), np.uint8)


# --------------------------------------------------------------------------- helpers
def _check(free, resolution, **positive):
    free = np.asarray(free)
    if free.ndim != 2:
        raise MapError(f"<array>: free-space mask must be 2-D, got shape {free.shape}")
    free = free.astype(bool, copy=False)
    if not np.isfinite(resolution) or resolution <= 0:
        raise ParameterError(f"resolution must be a positive number of metres per pixel, got {resolution!r}")
    for name, value in positive.items():
        check_length(name, value)
    return free


def _empty(free):
    return np.zeros(free.shape, np.int32), []


def _components_with_area(mask, connectivity=8):
    """Labels, count and pixel area per label (index 0 = background)."""
    import cv2

    m = np.ascontiguousarray(mask, dtype=np.uint8)
    n, lab, stats, _ = cv2.connectedComponentsWithStats(m, connectivity=connectivity, ltype=cv2.CV_32S)
    return lab, n - 1, stats[:, cv2.CC_STAT_AREA].astype(np.int64)


def _crop(free, pad=2):
    """Bounding box (slices) of the free cells, padded; lets big maps run on less."""
    r0, r1, c0, c1 = true_bbox(free, pad)
    return (slice(r0, r1), slice(c0, c1))


def _uncrop(sub_labels, box, shape):
    out = np.zeros(shape, np.int32)
    out[box] = sub_labels
    return out


# --------------------------------------------------------------------------- watershed
def watershed(free, *, resolution=0.05, min_distance=1.75):
    """Distance-transform watershed (Fabrizi & Saffiotti 2000).

    The Euclidean distance transform of free space is flooded from its local
    maxima (:func:`skimage.feature.peak_local_max`) with
    :func:`skimage.segmentation.watershed` on ``-dist``: every maximum of the
    clearance becomes a room, and rooms meet along the clearance "valleys",
    i.e. at narrow passages. This is the plain speed baseline of the project.

    Parameters
    ----------
    free : (M, N) ndarray of bool
        Free space.
    resolution : float, default 0.05
        Metres per pixel.
    min_distance : float, default 1.75
        Minimum distance (metres) between two markers. Clearance maxima closer
        than that are taken to lie in the same space; this suppresses most
        of the plateau maxima along corridors while neighbouring small rooms
        (offices are >= ~2.5 m wide, so their maxima are farther apart) keep
        a marker each. On the 14 ipa benchmark maps it reproduces the
        reference watershed's operating point (precision / recall 96.9 /
        83.3 % against 98.8 / 84.2 %; 1.0 m gives 98.8 / 73.0, 2.0 m
        96.7 / 88.4).

    Returns
    -------
    labels : (M, N) ndarray of int32
        ``1..N`` on every free cell, ``0`` elsewhere.
    doors : list
        Always ``[]`` (the watershed has no door model).

    References
    ----------
    C. Fabrizi and A. Saffiotti, "Extracting topology-based maps from
    gridmaps", ICRA 2000. Bormann et al., "Room segmentation: survey,
    implementation, and analysis", ICRA 2016 (section on the watershed).
    """
    import skimage.segmentation
    from skimage.feature import peak_local_max

    free = _check(free, resolution, min_distance=min_distance)
    if not free.any():
        return _empty(free)
    box = _crop(free)
    f = free[box]
    dist = edt(f)
    md = max(int(round(min_distance / resolution)), 1)
    comp, _ = label(f, 8)
    peaks = peak_local_max(dist, min_distance=md, labels=comp, exclude_border=False)
    markers = np.zeros(f.shape, np.int32)
    markers[tuple(peaks.T)] = np.arange(1, len(peaks) + 1, dtype=np.int32)
    lab = skimage.segmentation.watershed(-dist, markers, mask=f).astype(np.int32)
    return fill_unlabeled(_uncrop(lab, box, free.shape), free), []


# --------------------------------------------------------------------------- morphological
def morphological(free, *, resolution=0.05, room_area_min=0.8, room_area_max=47.0, max_erosion=2.5):
    """Iterated-erosion segmentation (ipa_room_segmentation, morphological).

    Free space is eroded one pixel (3x3 square) per step. After each step,
    every connected component whose area lies strictly within
    ``(room_area_min, room_area_max)`` is taken as a room seed and removed
    from the further erosion. The seeds are finally grown back over all free
    space geodesically (:func:`topomap.core.rooms.fill_unlabeled`, ipa's
    region spreading).

    Parameters
    ----------
    free : (M, N) ndarray of bool
        Free space.
    resolution : float, default 0.05
        Metres per pixel.
    room_area_min, room_area_max : float, default 0.8 and 47.0
        Room area range in m²: ipa's defaults for this method
        (``room_area_factor_lower/upper_limit_morphological`` in
        ``room_segmentation_action_server_params.yaml``).
    max_erosion : float, default 2.5
        Total erosion depth in metres: ipa erodes 50 times, i.e. 2.5 m at its
        0.05 m/px maps; anything still connected after that is a space more
        than 5 m wide at every narrowing and is grown back as one room.

    Returns
    -------
    labels : (M, N) ndarray of int32
    doors : list
        Always ``[]``.

    Notes
    -----
    Areas are pixel counts (ipa uses the polygon area of the outer contour,
    which differs by about half a perimeter pixel and includes holes).

    References
    ----------
    Bormann et al., ICRA 2016; ipa320/ipa_coverage_planning,
    ``ipa_room_segmentation/common/src/morphological_segmentation.cpp``.
    """
    import cv2

    free = _check(free, resolution, room_area_min=room_area_min, room_area_max=room_area_max,
                  max_erosion=max_erosion)
    if not free.any():
        return _empty(free)
    box = _crop(free)
    f = free[box]
    px = resolution * resolution
    amin, amax = room_area_min / px, room_area_max / px
    steps = max(int(round(max_erosion / resolution)), 1)
    work = f.astype(np.uint8)
    seeds = np.zeros(f.shape, np.int32)
    nxt = 1
    for _ in range(steps):
        work = cv2.erode(work, _EIGHT, borderType=cv2.BORDER_CONSTANT, borderValue=0)
        n, lab, stats, _ = cv2.connectedComponentsWithStats(work, connectivity=8, ltype=cv2.CV_32S)
        if n <= 1:
            break
        area = stats[:, cv2.CC_STAT_AREA]
        ok = np.flatnonzero((area > amin) & (area < amax))
        for k in ok[ok > 0].tolist():  # one room per accepted component
            x, y, w, h = stats[k, :4]
            sub = lab[y:y + h, x:x + w] == k
            seeds[y:y + h, x:x + w][sub] = nxt
            work[y:y + h, x:x + w][sub] = 0
            nxt += 1
    return fill_unlabeled(_uncrop(seeds, box, free.shape), free), []


# --------------------------------------------------------------------------- distance
def distance(free, *, resolution=0.05, room_area_min=0.35, room_area_max=163.0):
    """Distance-transform thresholding (ipa_room_segmentation, distance).

    The free space is eroded once (3x3) and its Euclidean distance transform
    rounded to whole pixels, as in ipa. For every threshold ``t`` (one pixel
    apart, from 1 px up to the largest clearance) the connected components of
    ``dist > t`` are counted; the threshold giving the most components with
    an area in ``[room_area_min, room_area_max]`` wins (ties: the lowest
    threshold, as ipa's descending loop with ``>=`` does). Those components
    are the room seeds, grown back over free space geodesically.

    Parameters
    ----------
    free : (M, N) ndarray of bool
        Free space.
    resolution : float, default 0.05
        Metres per pixel.
    room_area_min, room_area_max : float, default 0.35 and 163.0
        Room area range in m²: ipa's defaults for this method
        (``room_area_factor_lower/upper_limit_distance``).

    Returns
    -------
    labels : (M, N) ndarray of int32
    doors : list
        Always ``[]``.

    References
    ----------
    Bormann et al., ICRA 2016; ipa320/ipa_coverage_planning,
    ``ipa_room_segmentation/common/src/distance_segmentation.cpp``.
    """
    import cv2

    free = _check(free, resolution, room_area_min=room_area_min, room_area_max=room_area_max)
    if not free.any():
        return _empty(free)
    box = _crop(free)
    f = free[box]
    px = resolution * resolution
    amin, amax = room_area_min / px, room_area_max / px
    er = cv2.erode(f.astype(np.uint8), _EIGHT, borderType=cv2.BORDER_CONSTANT, borderValue=0)
    dist = np.rint(edt(er.astype(bool))).astype(np.int32) if er.any() else np.zeros(f.shape, np.int32)
    best_t, best_n = None, 0
    # each threshold only needs the bounding box of dist > t (shrinks fast)
    rowmax, colmax = dist.max(axis=1), dist.max(axis=0)
    hist = np.bincount(dist.ravel())
    above = hist[::-1].cumsum()[::-1]  # above[k] = #pixels with dist >= k
    for t in range(1, int(dist.max())):
        if above[t + 1] < (best_n + 1) * amin:
            break  # not enough pixels left for more rooms than the best so far
        rows, cols = np.flatnonzero(rowmax > t), np.flatnonzero(colmax > t)
        sub = dist[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1] > t
        _, _, area = _components_with_area(sub, 8)
        cnt = int(np.count_nonzero((area[1:] >= amin) & (area[1:] <= amax)))
        if cnt > best_n:
            best_t, best_n = t, cnt
    seeds = np.zeros(f.shape, np.int32)
    if best_t is not None:
        lab, n, area = _components_with_area(dist > best_t, 8)
        ok = (area >= amin) & (area <= amax)
        ok[0] = False
        seeds = np.where(ok[lab], lab, 0).astype(np.int32)
    return fill_unlabeled(_uncrop(seeds, box, free.shape), free), []


# --------------------------------------------------------------------------- voronoi


def _prune(skel, max_len):
    """Remove end branches: peel end pixels that are not original junctions, ``max_len`` times.

    This is ipa's ``pruneVoronoiGraph``: junction pixels (more than two
    neighbours on the unpruned graph) are never removed, so pruning stops at
    the first junction of every spur.
    """
    skel = skel.copy()
    nodes = skel & (neighbour_count(skel) > 2)
    for _ in range(max_len):
        ends = skel & (neighbour_count(skel) <= 1) & ~nodes
        if not ends.any():
            break
        skel &= ~ends
    return skel


def _region_stats(lab):
    """Shared-border counts between labels and wall contacts (4-neighbour edges)."""
    a = np.concatenate([lab[:, :-1].ravel(), lab[:-1, :].ravel()])
    b = np.concatenate([lab[:, 1:].ravel(), lab[1:, :].ravel()])
    diff = a != b
    a, b = a[diff], b[diff]
    pairs = np.stack([np.minimum(a, b), np.maximum(a, b)], 1)
    keys, counts = np.unique(pairs, axis=0, return_counts=True)
    border, wall = {}, {}
    for (x, y), c in zip(keys.tolist(), counts.tolist()):
        if x == 0:
            wall[y] = wall.get(y, 0) + c
        else:
            border.setdefault(x, {})[y] = c
            border.setdefault(y, {})[x] = c
    # edges to the image border count as wall
    for edge in (lab[0, :], lab[-1, :], lab[:, 0], lab[:, -1]):
        v, c = np.unique(edge[edge > 0], return_counts=True)
        for x, cc in zip(v.tolist(), c.tolist()):
            wall[x] = wall.get(x, 0) + cc
    return border, wall


def _merge_rooms(lab, resolution, max_area_for_merging, min_room_area):
    """ipa's main merge rules on a complete label image; returns the merged labels.

    Rooms are visited by ascending area and the scan restarts after each
    merge, as in ipa's ``AbstractVoronoiSegmentation::mergeRooms``:

    a) a room with one neighbour, area < ``max_area_for_merging`` and at most
       75 % of its perimeter on walls joins that neighbour;
    b) a room under ``min_room_area`` joins the neighbour it shares the
       longest border with, if that border is > 20 % of its perimeter and the
       neighbour is not almost all wall (wall ratio > 0.8);
    e) a room whose longest-border neighbour takes > 40 % of its perimeter
       joins that neighbour.

    (ipa's rules c and d -- parts of one room joined through 2-neighbour
    chains and mutual > 10-20 % borders -- are left out.)
    """
    n = int(lab.max())
    if n < 2:
        return lab
    area = np.bincount(lab.ravel(), minlength=n + 1).astype(float) * resolution**2
    border, wall = _region_stats(lab)
    alive = {i for i in range(1, n + 1) if area[i] > 0}
    parent = np.arange(n + 1)
    areas = {i: area[i] for i in alive}
    walls = {i: wall.get(i, 0) for i in alive}
    nb = {i: dict(border.get(i, {})) for i in alive}

    def perim(i):
        return walls[i] + sum(nb[i].values())

    def best(i):
        return max(nb[i].items(), key=lambda kv: (kv[1], -kv[0]))[0] if nb[i] else None

    def merge(src, dst):
        areas[dst] += areas.pop(src)
        walls[dst] += walls.pop(src)
        for k, c in nb.pop(src).items():
            nb[k].pop(src, None)
            if k == dst:
                continue
            nb[dst][k] = nb[dst].get(k, 0) + c
            nb[k][dst] = nb[k].get(dst, 0) + c
        nb[dst].pop(src, None)
        alive.discard(src)
        parent[src] = dst

    def rule_a(i):
        p = perim(i)
        if len(nb[i]) == 1 and areas[i] < max_area_for_merging and p and walls[i] / p <= 0.75:
            return best(i)

    def rule_b(i):
        j, p = best(i), perim(i)
        if j is not None and areas[i] < min_room_area and nb[i][j] / p > 0.2:
            pj = perim(j)
            if not (pj and walls[j] / pj > 0.8):
                return j

    def rule_e(i):
        j, p = best(i), perim(i)
        if j is not None and nb[i][j] / p > 0.4:
            return j

    for rule in (rule_a, rule_b, rule_e):
        changed = True
        while changed:
            changed = False
            for i in sorted(alive, key=lambda k: (areas[k], k)):
                j = rule(i)
                if j is not None:
                    merge(i, j)
                    changed = True
                    break
    # resolve parent chains
    root = parent.copy()
    for _ in range(n):
        nxt = root[root]
        if np.array_equal(nxt, root):
            break
        root = nxt
    return root[lab].astype(np.int32)


def _basis_points(cp, d, occ_rc, tree):
    """Two nearest obstacle points of ``cp`` on opposite sides (ipa's basis points)."""
    idx = tree.query_ball_point(cp, r=d * 2.0 + 3.0)
    if not idx:
        return None
    pts = occ_rc[idx].astype(float)
    v = pts - cp
    dd = np.hypot(v[:, 0], v[:, 1])
    i1 = int(np.argmin(dd))
    v1 = v[i1]
    # opposite side: pointing away from the first basis point
    opp = (v @ v1) < 0
    if not opp.any():
        return None
    cand = np.flatnonzero(opp)
    i2 = cand[np.argmin(dd[cand])]
    return pts[i1], pts[i2]


def voronoi(free, *, resolution=0.05, neighborhood=1.0, max_door_width=2.5, prune_length=5.0,
            room_area_min=0.1, max_area_for_merging=12.5, min_room_area=2.0):
    """Voronoi-graph critical-point segmentation (Thrun 1998; ipa's voronoi).

    1. The Voronoi graph is the medial axis (:func:`skimage.morphology.medial_axis`)
       of the free space after a 3x3 opening, as ipa smooths the map before
       building the diagram; end branches are pruned back to their first
       junction (``prune_length``). The medial axis, like ipa's generalised
       Voronoi diagram, has a branch to every convex corner, so a dead-end
       room keeps its junctions and its branch survives the pruning (a
       thinning skeleton, :func:`skimage.morphology.skeletonize`, is a bare
       path there and would be pruned away with the room's door).
    2. Critical points are skeleton pixels of degree 2 whose clearance (the
       distance transform) is the minimum over all skeleton pixels within
       ``neighborhood`` metres, and at most ``max_door_width / 2``.
       One point is kept per connected plateau of equal minima.
    3. The critical line joins each critical point to its nearest obstacle
       pixel and to the nearest obstacle pixel on the opposite side; the lines
       are drawn as occupied (:func:`skimage.draw.line`) and the pieces of
       free space labelled (4-connected, as a digital line only separates
       4-connected regions). Pieces under ``room_area_min`` are dropped and the
       rest grown over all free space.
    4. Small pieces are merged as ipa does (see :func:`_merge_rooms`: rules
       a, b and e of ipa's ``mergeRooms``).

    Parameters
    ----------
    free : (M, N) ndarray of bool
        Free space.
    resolution : float, default 0.05
        Metres per pixel.
    neighborhood : float, default 1.0
        Radius (metres) in which a critical point must be the clearance
        minimum. ipa grows its neighbourhood along the graph until
        ``280 / clearance_px`` pixels are found, about 1.5 m of graph at a
        0.45 m door clearance, i.e. about 0.75 m each side; 1.0 m plus the
        merging step gives about the same cut density.
    max_door_width : float, default 2.5
        Critical points whose clearance exceeds half this width are not cut.
        ipa has no such limit and relies on its merging to undo cuts in open
        space; 2.5 m keeps double doors and corridor narrowings and, on the
        14 ipa benchmark maps, reproduces the operating point of the C++
        implementation (precision / recall 96.3 / 94.5 % against 96.0 /
        94.6 %; 2.0 m gives 95.6 / 96.0, 3.0 m 96.6 / 93.5).
    prune_length : float, default 5.0
        Maximal spur length pruned (metres): ipa peels end points 100 times,
        5 m at 0.05 m/px.
    room_area_min : float, default 0.1
        Pieces under this area (m²) are not rooms of their own and are filled
        from their neighbours: ipa's ``room_area_factor_lower_limit_voronoi``.
    max_area_for_merging : float, default 12.5
        ipa's ``max_area_for_merging`` (m²) for merge rule a.
    min_room_area : float, default 2.0
        ipa's hard-coded small-room limit (m²) of merge rule b.

    Returns
    -------
    labels : (M, N) ndarray of int32
    doors : list of ((r1, c1), (r2, c2))
        The critical lines that separate two different final rooms, from
        one basis (obstacle) point to the other, in float pixel coordinates.

    References
    ----------
    S. Thrun, "Learning metric-topological maps for indoor mobile robot
    navigation", Artificial Intelligence 99, 1998. Bormann et al., ICRA 2016;
    ipa320/ipa_coverage_planning, ``voronoi_segmentation.cpp`` and
    ``abstract_voronoi_segmentation.cpp``.
    """
    import cv2
    from skimage.morphology import medial_axis

    free = _check(free, resolution, neighborhood=neighborhood, max_door_width=max_door_width,
                  prune_length=prune_length, room_area_min=room_area_min,
                  max_area_for_merging=max_area_for_merging, min_room_area=min_room_area)
    if not free.any():
        return _empty(free)
    box = _crop(free, pad=3)
    f = free[box]
    dist = edt(f)

    # 1. Voronoi graph = pruned skeleton of the opened free space
    opened = cv2.morphologyEx(f.astype(np.uint8), cv2.MORPH_OPEN, _EIGHT).astype(bool)
    skel = medial_axis(opened, rng=0) & f  # rng: deterministic tie-breaking
    skel = _prune(skel, max(int(round(prune_length / resolution)), 1))

    # 2. critical points and their critical lines
    lines = _critical_lines(f, skel, dist, max(int(round(neighborhood / resolution)), 1),
                            max_door_width / 2.0 / resolution)

    # 3. cut along the critical lines, label the pieces
    lab = _cut_along(f, lines, room_area_min / resolution**2)

    # 4. merge as ipa does
    lab = relabel_sequential(_merge_rooms(lab, resolution, max_area_for_merging, min_room_area))
    labels = fill_unlabeled(_uncrop(lab, box, free.shape), free)

    # doors: critical lines between two different final rooms
    doors = _critical_line_doors(lines, labels, np.array([box[0].start, box[1].start], float))
    return labels, doors


def _cut_along(f, lines, min_area_px):
    """Rooms of ``f`` cut along the critical lines (critical point to both
    basis points): the 4-connected pieces of at least ``min_area_px`` cells
    are seeds, every other free cell goes to the nearest seed."""
    cut = f.copy()
    for cp, p1, p2 in lines:
        for p in (p1, p2):
            cut[line_pixels(cp, p, cut.shape)] = False
    pieces, n, area = _components_with_area(cut, 4)
    keep = area >= min_area_px
    keep[0] = False
    seeds = np.where(keep[pieces], pieces, 0).astype(np.int32)
    return fill_unlabeled(seeds, f)


def _critical_line_doors(lines, labels, off):
    """The critical lines (in the crop, shifted by ``off`` onto ``labels``)
    with two different rooms 2 px on either side: door segments."""
    doors = []
    for cp, p1, p2 in lines:
        t = p2 - p1
        nrm = np.array([-t[1], t[0]])
        ln = np.hypot(*nrm)
        if ln == 0:
            continue
        nrm /= ln
        sides = []
        for sgn in (1, -1):
            q = np.rint(cp + off + sgn * 2.0 * nrm).astype(int)
            if 0 <= q[0] < labels.shape[0] and 0 <= q[1] < labels.shape[1]:
                sides.append(int(labels[q[0], q[1]]))
        if len(sides) == 2 and sides[0] and sides[1] and sides[0] != sides[1]:
            a, b = p1 + off, p2 + off
            doors.append(((float(a[0]), float(a[1])), (float(b[0]), float(b[1]))))
    return doors


def _critical_lines(f, skel, dist, r, max_clearance_px):
    """Critical points of the Voronoi graph ``skel`` (degree-2 pixels whose
    clearance ``dist`` is the minimum within ``r`` px and at most
    ``max_clearance_px``, one per plateau) with their two basis points:
    ``[(critical point, basis 1, basis 2), ...]`` in pixels of ``f``."""
    import cv2
    from scipy.spatial import cKDTree

    big = np.float32(1e9)
    on = np.where(skel, dist, big).astype(np.float32)
    disk = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1))
    local_min = cv2.erode(on, disk, borderType=cv2.BORDER_CONSTANT, borderValue=float(big))
    deg = neighbour_count(skel)
    cand = skel & (deg == 2) & (on <= local_min) & (dist <= max_clearance_px)
    clab, nc = label(cand, 8)
    lines = []
    if nc:
        # obstacle pixels touching free space: the candidates for basis points
        occ = ~f & cv2.dilate(f.astype(np.uint8), _EIGHT).astype(bool)
        occ_rc = np.argwhere(occ)
        # obstacles beyond the image border are not obstacles (as edt): nothing to add
        tree = cKDTree(occ_rc) if len(occ_rc) else None
        # one critical point per plateau: the plateau pixel nearest its centroid
        pts = np.argwhere(clab > 0)
        ids = clab[pts[:, 0], pts[:, 1]]
        order = np.argsort(ids, kind="stable")
        pts, ids = pts[order], ids[order]
        starts = np.r_[0, np.flatnonzero(np.diff(ids)) + 1, len(ids)]
        for s, e in zip(starts[:-1], starts[1:]):
            group = pts[s:e].astype(float)
            c = group.mean(0)
            cp = group[np.argmin(((group - c) ** 2).sum(1))]
            if tree is None:
                continue
            bp = _basis_points(cp, float(dist[int(cp[0]), int(cp[1])]), occ_rc, tree)
            if bp is not None:
                lines.append((cp, bp[0], bp[1]))
    return lines
