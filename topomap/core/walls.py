"""Walls: straight wall faces and the openings between collinear pieces of them.

A doorway in a real building is a gap in a straight wall: the wall's face
runs on, on the same line, past the gap. On a laser SLAM map the clearance
along the free-space skeleton often does not narrow at such a gap (a room
opening onto a corridor through a wide door, a door beside a corridor's
end), but the wall lines show it. This module finds straight faces of
walls (the obstacle cells that border free space) with a probabilistic
Hough transform and, from the end of each face, looks along the face's
line for the wall to go on: a gap between two collinear wall pieces, as
wide as a door, is an *opening* and is cut like a door.

All coordinates are pixel ``(row, col)`` floats; lengths in metres are
converted with the map's resolution by the caller's options.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["wall_faces", "wall_lines", "straight_share", "wall_openings", "wall_directions", "long_walls",
           "across_walls", "across_walls_many", "WallIndex", "long_wall_gaps", "partition_gaps", "face_runs",
           "straight_lines", "furniture_rows", "wall_mask", "scale_walls", "thin_wall_gaps",
           "gaps_without_doors", "clearance_lookup"]


#: The 4-neighbours of a cell (not the cell itself), as a morphology kernel.
_FOUR = np.array([[0, 1, 0], [1, 0, 1], [0, 1, 0]], np.uint8)


def wall_faces(obstacle: np.ndarray, free: np.ndarray) -> np.ndarray:
    """Obstacle cells with a free 4-neighbour: the faces of walls.

    Parameters
    ----------
    obstacle, free : (M, N) ndarray of bool

    Returns
    -------
    (M, N) ndarray of bool
    """
    import cv2

    f = np.ascontiguousarray(free, dtype=bool)
    if f.size == 0:
        return obstacle & f
    # the maximum over the 4 neighbours (none outside the map), one pass
    touch = cv2.dilate(f.view(np.uint8), _FOUR, borderType=cv2.BORDER_CONSTANT, borderValue=0).view(bool)
    return obstacle & touch


def wall_lines(faces: np.ndarray, *, min_length_px: float, max_gap_px: float = 3.0) -> np.ndarray:
    """Straight runs of wall faces: ``(K, 4)`` segments ``(r1, c1, r2, c2)``.

    A probabilistic Hough transform (:func:`cv2.HoughLinesP`) over the face
    cells, each grown by one cell (a laser scan draws a straight wall a cell
    or two off its line), in 2-cell and 2° bins; a segment is at least
    ``min_length_px`` long and bridges gaps of at most ``max_gap_px`` (scan
    noise), so that a doorway is never bridged.
    """
    import cv2

    if not faces.any():
        return np.zeros((0, 4))
    grown = cv2.dilate(faces.astype(np.uint8), np.ones((3, 3), np.uint8))
    thr = max(int(round(0.5 * min_length_px)), 2)
    lines = cv2.HoughLinesP(grown, 2, np.pi / 90, thr, minLineLength=float(min_length_px),
                            maxLineGap=float(max_gap_px))
    if lines is None:
        return np.zeros((0, 4))
    x1, y1, x2, y2 = lines.reshape(-1, 4).T.astype(float)
    return np.stack([y1, x1, y2, x2], 1)


def straight_share(faces: np.ndarray, lines: np.ndarray) -> float:
    """Share (0..1) of the wall-face cells within a cell of a straight wall line.

    Drawn floor plans have straight walls (on the benchmark's plans 0.77-0.98
    of the face cells lie on lines of at least 1 m); a laser scanner's map
    draws walls that wander a cell or two off their line (0.14-0.67 there).
    1.0 when there are no faces.
    """
    n = np.count_nonzero(faces)
    if n == 0:
        return 1.0
    return float(np.count_nonzero(faces & _line_mask(lines, faces.shape, 3))) / n


def _line_mask(lines, shape, width: int) -> np.ndarray:
    """The cells of the segments ``lines`` (``(K, 4)``, ends rounded as
    :func:`round` does), each drawn ``width`` cells wide: ``shape`` bool."""
    import cv2

    m = np.zeros(shape, np.uint8)
    ends = np.rint(np.asarray(lines, float).reshape(-1, 4)).astype(np.int32)
    if len(ends):  # one 2-point polyline per segment: the pixels of cv2.line, in one call
        cv2.polylines(m, np.ascontiguousarray(ends[:, [1, 0, 3, 2]]).reshape(-1, 2, 2), False, 1, width)
    return m.view(bool)


def _sample_cells(shape, starts, dirs, n, offsets):
    """Cells ``start + t d + o n_perp`` for ``t = 1..n`` and each offset ``o``,
    for every row of ``starts`` / ``dirs`` (``(E, 2)``): ``(E, len(offsets), n)``
    flat indices into a C-ordered array of ``shape`` (0 for a sample outside
    the map: every caller masks those), and a mask of the samples inside it."""
    H, W = shape
    starts, dirs = np.asarray(starts, float), np.asarray(dirs, float)
    t = np.arange(1, n + 1, dtype=float)[None, None, :]
    o = np.asarray(offsets, float)[None, :, None]
    # rows and cols apart (the same sums as one (..., 2) array, without it);
    # the one offset 0 adds nothing (x + 0.0 rounds as x), so is not added
    if o.size == 1 and o.flat[0] == 0:
        r = starts[:, 0, None, None] + t * dirs[:, 0, None, None]
        c = starts[:, 1, None, None] + t * dirs[:, 1, None, None]
    else:
        r = starts[:, 0, None, None] + t * dirs[:, 0, None, None] + o * -dirs[:, 1, None, None]
        c = starts[:, 1, None, None] + t * dirs[:, 1, None, None] + o * dirs[:, 0, None, None]
    # rounded in place, the flat index made from the whole floats (exact) with
    # the samples outside set to 0 instead of clipped, and 32-bit indices when
    # they fit (a faster cast); the callers gather with np.take (faster than
    # indexing)
    np.rint(r, out=r)
    np.rint(c, out=c)
    inside = (r >= 0) & (r < H) & (c >= 0) & (c < W)
    r *= W
    r += c
    np.copyto(r, 0.0, where=~inside)
    return r.astype(np.int32 if H * W < 2 ** 31 else np.intp), inside


def _perp(d):
    """The normals ``(-d_c, d_r)`` of the rows of ``d``."""
    return np.stack([-d[:, 1], d[:, 0]], 1)


def _free_runs(obstacle, starts, dirs, n):
    """Samples from each row of ``starts`` along the row of ``dirs`` (at most
    ``n``) before the first obstacle cell or the map's edge: ``(E,)``."""
    at, inside = _sample_cells(obstacle.shape, starts, dirs, n, [0])
    stop = np.take(obstacle, at[:, 0]) | ~inside[:, 0]
    return np.where(stop.any(axis=1), np.argmax(stop, axis=1), n)


def _face_runs(faces, starts, dirs, n, offsets):
    """Whether a wall face runs on past each row of ``starts`` along the row
    of ``dirs`` for ``n`` samples (within the band of ``offsets``), at 70 %
    of them at least: ``(E,)`` bool."""
    at, inside = _sample_cells(faces.shape, starts, dirs, n, offsets)
    return (np.take(faces, at) & inside).any(axis=1).mean(axis=1) >= 0.7


def _depth_ok(obstacle, p, q, depth_px, *, closet_px: float = 0.0, behind_px: float = 0.0):
    """Whether the space on both sides of each segment ``p``-``q`` (rows of
    ``(E, 2)`` arrays) reaches at least ``depth_px`` from it, perpendicular
    to it, along one of three probes (at a quarter, half and three quarters
    of its length): ``(E,)`` bool.

    With ``closet_px`` and ``behind_px``, a side at least ``closet_px`` deep
    counts too where the space there runs on past an end of the segment, along
    it, for at least ``behind_px``: a closet or a balcony behind a door, wider
    than its door, rather than a niche as wide as its mouth.
    """
    p, q = np.atleast_2d(np.asarray(p, float)), np.atleast_2d(np.asarray(q, float))
    v = q - p
    L = np.hypot(*v.T)
    d = v / np.maximum(L, 1e-9)[:, None]
    n = _perp(d)
    k = max(int(np.ceil(depth_px)), 1)
    # the six probes (two sides, three points) of every segment in one call
    starts = np.concatenate([p + f * v for _ in (n, -n) for f in (0.25, 0.5, 0.75)])
    dirs = np.concatenate([side for side in (n, -n) for _ in (0.25, 0.5, 0.75)])
    runs = _free_runs(obstacle, starts, dirs, k).reshape(2, 3, len(p))
    deep = (runs == k).any(axis=1)
    if closet_px > 0 and behind_px > 0 and not deep.all():
        # a shallow side: along the segment, half the closet's depth behind its middle, both ways
        mid = (p + q) / 2
        h = 0.5 * closet_px
        reach = int(np.ceil(L.max() / 2 + behind_px)) + 1
        along = np.concatenate([mid + h * side for side in (n, -n) for _ in (1, -1)])
        ways = np.concatenate([sign * d for _ in (n, -n) for sign in (1, -1)])
        wide = (_free_runs(obstacle, along, ways, reach).reshape(2, 2, len(p)) >= (L / 2 + behind_px)).any(axis=1)
        deep |= (runs.max(axis=1) >= closet_px) & wide
    return deep.all(axis=0)


def _spans_passage(obstacle, p, q, depth_px, slack: float = 1.25):
    """Whether each segment ``p``-``q`` (rows of ``(E, 2)`` arrays) lies
    across a passage as wide as it: on both sides, somewhere within
    ``depth_px`` of it, the free space along the segment's direction is at
    most ``slack`` times its length (a corridor running on through the gap;
    a room opening off a corridor's wall has the whole corridor beside it):
    ``(E,)`` bool."""
    p, q = np.atleast_2d(np.asarray(p, float)), np.atleast_2d(np.asarray(q, float))
    v = q - p
    L = np.hypot(*v.T)
    d = v / np.maximum(L, 1e-9)[:, None]
    n = _perp(d)
    mid = (p + q) / 2
    cap = np.ceil(slack * L).astype(int) + 2
    out = np.zeros(len(p), bool)
    # both ways along the segment from 4 points on each side, in two calls per group of segments
    # of similar length (caps within a factor of 4; each ray sampled as far as the group's
    # longest needs)
    group = np.ceil(np.log2(np.maximum(cap, 1))).astype(int) // 2
    for g in np.unique(group):
        k = np.flatnonzero(group == g)
        cs = np.concatenate([mid[k] + t * side[k] for side in (n, -n)
                             for t in (0.25 * depth_px, 0.5 * depth_px, 0.75 * depth_px, depth_px)])
        kk = np.tile(k, 8)  # the segment of each point
        dk, most = d[kk], slack * L[kk]
        # a run (both ways) of a narrow passage is shorter than floor(most): each run
        # is sampled only that far (one sample more tells a longer one), the run on
        # first, the run back (from a step back) only from the points whose run on
        # leaves room for it (a quarter of them)
        on = _free_runs(obstacle, cs, dk, int(np.floor(most.max())) + 1)
        j = np.flatnonzero(on + 1 <= most)
        narrow = np.zeros(kk.size, bool)
        if j.size:
            back = _free_runs(obstacle, cs[j] - dk[j], -dk[j], int(np.floor((most[j] - on[j]).max())) + 1)
            narrow[j] = back + on[j] + 1 <= most[j]
        out[k] = narrow.reshape(2, 4, k.size).any(axis=1).all(axis=0)
    return out


def _gaps(obstacle, free, segs, back, n_gap, offsets, min_gap_px, max_gap_px, chunk: int = 1024):
    """The gaps past the ends of the wall segments ``segs``, in the order of
    the segments (each segment's second end first): arrays ``(end, d, s0,
    e0)`` of the end points, the outward directions and the indices of the
    first free sample and of the first obstacle sample after it (sample
    ``i`` at ``end + (i - back) * d``). Only gaps that start within the wall
    piece's last cells, are ``min_gap_px``-``max_gap_px`` long and free
    along at least half their line are given. Vectorised over the ends,
    ``chunk`` ends at a time."""
    segs = np.asarray(segs, float).reshape(-1, 4)
    a, b = segs[:, :2], segs[:, 2:]
    L = np.hypot(*(b - a).T)
    a, b, L = a[L > 0], b[L > 0], L[L > 0]
    u = (b - a) / L[:, None]
    ends = np.stack([b, a], 1).reshape(-1, 2)
    dirs = np.stack([u, -u], 1).reshape(-1, 2)
    # the first samples tell the ends where the wall piece ends (a gap starts
    # within its last cells): only those are followed further
    m = min(back + 3, n_gap)
    ob, fr = np.ravel(obstacle), np.ravel(free)
    at, inside = _sample_cells(obstacle.shape, ends - (back + 1) * dirs, dirs, m, offsets)
    hit = (np.take(ob, at) & inside).any(axis=1)
    todo = np.flatnonzero(hit[:, 0] & ~hit[:, 1:].all(axis=1))
    ends, dirs = ends[todo], dirs[todo]
    centre = len(offsets) // 2
    idx = np.arange(n_gap)
    out = []
    for k in range(0, ends.shape[0], chunk):
        E, D = ends[k:k + chunk], dirs[k:k + chunk]
        at, inside = _sample_cells(obstacle.shape, E - (back + 1) * D, D, n_gap, offsets)
        hit = (np.take(ob, at) & inside).any(axis=1)
        clear = ~hit
        s0 = np.argmax(clear, axis=1)
        ok = clear.any(axis=1) & (s0 != 0) & (s0 <= back + 2)
        after = hit & (idx[None, :] >= s0[:, None])
        e0 = np.argmax(after, axis=1)
        ok &= after.any(axis=1)
        gap = e0 - s0 + 1
        ok &= (gap >= min_gap_px) & (gap <= max_gap_px)
        lf = np.take(fr, at[:, centre]) & inside[:, centre]
        cs = np.concatenate([np.zeros((lf.shape[0], 1), int), np.cumsum(lf, axis=1)], axis=1)
        rows = np.arange(lf.shape[0])
        n_free = cs[rows, e0] - cs[rows, s0]
        ok &= n_free >= 0.5 * np.maximum(e0 - s0, 1)
        out.append((E[ok], D[ok], s0[ok], e0[ok]))
    if not out:
        return np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0, int), np.zeros(0, int)
    return tuple(np.concatenate(x) for x in zip(*out))


def wall_openings(obstacle: np.ndarray, free: np.ndarray, *, min_wall_px: float, min_gap_px: float,
                  max_gap_px: float, side_px: float, depth_px: float = 0.0, band_px: int = 1,
                  faces: np.ndarray | None = None, lines: np.ndarray | None = None,
                  beside_px: float = 0.0, closet_px: float = 0.0, behind_px: float = 0.0) -> list:
    """Openings between collinear pieces of straight walls.

    From each end of every straight wall face (:func:`wall_lines`, at least
    ``min_wall_px`` long) the line is followed outwards. The first obstacle
    cell on it (within ``band_px`` of the line) ends the gap; it is an
    opening when

    - the gap is between ``min_gap_px`` and ``max_gap_px`` long,
    - at least half the cells on the line across the gap are free (the
      rest may be unknown, never obstacles: a gap seen through, not a wall
      seen at a grazing angle), and
    - the wall goes on past the gap: a wall *face* (an obstacle cell next to
      free space, within ``band_px`` of the line) at least 70 % of the way
      along the next ``side_px``, so that a wall met end-on (a corner, the
      thickness of a perpendicular wall) is no opening,
    - neither end lies on a wall face that crosses the line (runs on for
      ``side_px`` on both sides of it): a gap that ends there spans a
      passage, such as a corridor between the side walls of two rooms
      that happen to be collinear, and
    - the space behind it is deep: free of obstacles for at least
      ``depth_px`` on both sides of the gap, perpendicular to the wall, so
      that the mouth of a niche or an alcove is no opening, and
    - it does not lie across a passage as wide as itself: where, on both
      sides and somewhere within ``depth_px``, the free space along the
      gap's line is at most 1.25 times its width, the gap is the width of a
      corridor running through it (between the ends of two partitions), not
      a doorway.

    Parameters
    ----------
    obstacle, free : (M, N) ndarray of bool
        The cells walls are made of (every non-free cell: occupied, or
        unknown where a map draws its walls in mid-gray), and free space.
    min_wall_px, min_gap_px, max_gap_px, side_px, depth_px : float
        Lengths in pixels.
    band_px : int
        Half-width of the band around the line that cells are looked for in
        (scan noise on a straight wall).
    beside_px : float
        A gap at most this long that ends on a wall face crossing the line
        (instead of the same wall going on) is an opening too: a door beside
        a wall. 0 (default): none.
    closet_px, behind_px : float
        A side shallower than ``depth_px`` is deep enough where it is at
        least ``closet_px`` deep and the space there runs on past an end of
        the gap for ``behind_px`` (:func:`_depth_ok`): a closet or a balcony
        behind a door. 0 (default): never.
    faces, lines : ndarray, optional
        :func:`wall_faces` of ``obstacle`` and ``free`` and their
        :func:`wall_lines` (at least ``min_wall_px`` long), when the caller
        has them already.

    Returns
    -------
    list of ((r1, c1), (r2, c2))
        Opening segments, from the end of one wall piece to the start of the
        next, each once.
    """
    if faces is None:
        faces = wall_faces(obstacle, free)
    segs = wall_lines(faces, min_length_px=min_wall_px) if lines is None else lines
    back = 3  # samples start this far inside the wall piece: Hough's end may be off by a cell or two
    n_gap = int(np.ceil(max_gap_px)) + back + 1
    n_side = max(int(np.ceil(side_px)), 1)
    offsets = np.arange(-band_px, band_px + 1)
    end, d, s0, e0 = _gaps(obstacle, free, segs, back, n_gap, offsets, min_gap_px, max_gap_px)
    if not len(end):
        return []
    start = end - (back + 1) * d
    gap = e0 - s0 + 1
    p = start + s0[:, None] * d            # last wall sample before each gap
    far = start + (e0 + 1)[:, None] * d    # first wall sample after it
    perp = _perp(d)
    # the five probes of every gap in one call: across the line at both of
    # its ends, both ways, and along it past the gap
    probe = _face_runs(faces, np.concatenate([p - perp, p + perp, far - perp, far + perp, far - d]),
                       np.concatenate([perp, -perp, perp, -perp, d]), n_side, offsets).reshape(5, -1)
    crossed = [probe[0] & probe[1], probe[2] & probe[3]]
    goes_on = probe[4]
    # no wall end where the piece's end lies on a wall crossing its line; where
    # the wall goes on, a far end on a crossing wall makes the gap a passage's
    # width; where it does not, only a door-wide gap ending on a wall is kept
    ok = ~crossed[0] & np.where(goes_on, ~crossed[1], crossed[1] & (gap <= beside_px))
    if depth_px > 0 and ok.any():
        k = np.flatnonzero(ok)
        ok[k] = _depth_ok(obstacle, p[k], far[k], depth_px, closet_px=closet_px, behind_px=behind_px)
        k = np.flatnonzero(ok)
        if k.size:
            ok[k] = ~_spans_passage(obstacle, p[k], far[k], depth_px)
    out, seen = [], set()
    k = np.flatnonzero(ok)
    keys = np.rint(np.concatenate([np.minimum(p[k], far[k]), np.maximum(p[k], far[k])], axis=1)).astype(int)
    for i, key in zip(k.tolist(), map(tuple, keys.tolist())):
        if key in seen:
            continue
        seen.add(key)
        out.append((p[i], far[i]))
    return out


def wall_directions(lines: np.ndarray) -> float:
    """The building's main wall direction (radians, in [0, pi/2)): the peak
    of the segments' directions modulo a right angle, weighted by length
    (most buildings are built on two perpendicular directions)."""
    segs = np.asarray(lines, float).reshape(-1, 4)
    if segs.shape[0] == 0:
        return 0.0
    v = segs[:, 2:] - segs[:, :2]
    L = np.hypot(*v.T)
    th = np.mod(np.arctan2(v[:, 0], v[:, 1]), np.pi / 2)
    bins = np.arange(90)
    h = np.bincount(np.floor(np.degrees(th)).astype(int) % 90, weights=L, minlength=90)
    hp = np.concatenate([h[-3:], h, h[:3]])
    hs = sum(hp[3 - k:93 - k] for k in range(-3, 4))  # np.roll(h, k) for k = -3..3, summed in that order
    return float(np.radians(bins[int(np.argmax(hs))] + 0.5))


#: Wall segments within this angle (radians) of one of the building's two main directions lie on
#: it (:func:`straight_lines`, :func:`long_walls`, :func:`partition_gaps`): 12 degrees, wider than
#: the 2-degree bins of the Hough lines and a scanned wall's wander over a metre or two, and well
#: short of a wing built at an angle (typically 30-45 degrees), whose walls keep their own lines.
MAIN_DIRECTION_TOL = float(np.deg2rad(12.0))


def _main_classes(segs: np.ndarray, angle_tol: float):
    """The segments ``(K, 4)`` within ``angle_tol`` of each of the
    building's two main directions (:func:`wall_directions`): for each, its
    unit vector ``u`` (row, col) and the indices of its segments."""
    v = segs[:, 2:] - segs[:, :2]
    th = np.mod(np.arctan2(v[:, 0], v[:, 1]), np.pi)
    out = []
    for tk, u in _main_directions(segs):
        dth = np.abs(np.mod(th - tk + np.pi / 2, np.pi) - np.pi / 2)
        out.append((u, np.flatnonzero(dth <= angle_tol)))
    return out


def _main_directions(segs: np.ndarray):
    """The building's two main directions (:func:`wall_directions` of the
    segments ``(K, 4)``): ``(angle, unit vector (row, col))`` for each."""
    th0 = wall_directions(segs)
    return [(tk, np.array([np.sin(tk), np.cos(tk)])) for tk in (th0, th0 + np.pi / 2)]


def face_runs(faces: np.ndarray, *, min_length_px: float, band_px: int = 1, max_gap_px: int = 2,
              lines: np.ndarray | None = None) -> np.ndarray:
    """Straight runs of wall faces along the building's two main directions.

    The face cells are projected onto each main direction (:func:`wall_directions`
    of ``lines``, or of the faces' own Hough lines): the cells within
    ``band_px`` of a line along it, following each other with gaps of at
    most ``max_gap_px``, for at least ``min_length_px``, are a run. Unlike
    the Hough transform of :func:`wall_lines`, which on a large map may miss
    a short wall (its cells vote for lines across the whole map), every run
    is found, in time linear in the faces.

    Returns
    -------
    (K, 4) ndarray
        Segments ``(r1, c1, r2, c2)`` in pixels.
    """
    if lines is None:
        lines = wall_lines(faces, min_length_px=min_length_px)
    segs = np.asarray(lines, float).reshape(-1, 4)
    at = np.flatnonzero(faces)  # the face cells, in raster order
    if not at.size:
        return np.zeros((0, 4))
    pts = np.empty((at.size, 2))
    pts[:, 0], pts[:, 1] = np.divmod(at, faces.shape[1])
    out = []
    for _, u in _main_directions(segs):
        n = np.array([-u[1], u[0]])
        t = np.rint(pts @ u).astype(np.int64)
        rb = np.rint(pts @ n).astype(np.int64)
        t_lo = int(t.min())
        # one integer per cell, by line, then along it, lines apart by more
        # than a gap so that a run never goes on from one line to the next
        span = int(t.max()) - t_lo + int(max_gap_px) + 3
        rb_lo = int(rb.min()) - band_px
        v = np.sort((rb - rb_lo) * span + (t - t_lo))
        # the cells of each line shifted by -band_px..band_px lines: the
        # sorted copies merge
        v = np.sort(np.concatenate([v + o * span for o in range(-band_px, band_px + 1)]), kind="stable")
        new = np.ones(v.size, bool)
        np.greater(np.diff(v), max_gap_px + 1, out=new[1:])
        start = np.flatnonzero(new)
        end = np.r_[start[1:], v.size] - 1
        t0, t1 = v[start] % span + t_lo, v[end] % span + t_lo
        keep = t1 - t0 >= min_length_px
        kb = (v[start[keep]] // span + rb_lo)[:, None]
        t0, t1 = t0[keep], t1[keep]
        out.append(np.concatenate([kb * n + t0[:, None] * u, kb * n + t1[:, None] * u], axis=1))
    return np.concatenate(out).astype(float).reshape(-1, 4)


def straight_lines(faces: np.ndarray, *, min_length_px: float, max_gap_px: float,
                   hough: np.ndarray | None = None, angle_tol: float = MAIN_DIRECTION_TOL) -> np.ndarray:
    """The straight wall faces of a map: its runs of faces along the building's
    two main directions, and its Hough lines off them.

    Along the main directions (:func:`wall_directions` of ``hough``, the
    Hough lines of :func:`wall_lines`) the lines are the runs of
    :func:`face_runs` (faces within one cell of a line, gaps of at most
    ``max_gap_px``, at least ``min_length_px`` long). Every face cell counts
    only for the lines through it, so the lines do not depend on the order
    in which a random sample visits the cells, and a change to one part of
    the map changes only the lines there. The Hough lines more than
    ``angle_tol`` off both main directions (the walls of a wing built at an
    angle) are added as they are.

    Returns
    -------
    (K, 4) ndarray
        Segments ``(r1, c1, r2, c2)`` in pixels.
    """
    if hough is None:
        hough = wall_lines(faces, min_length_px=min_length_px)
    hough = np.asarray(hough, float).reshape(-1, 4)
    runs = face_runs(faces, min_length_px=min_length_px, max_gap_px=int(round(max_gap_px)), lines=hough)
    if not len(hough):
        return runs
    on = np.zeros(len(hough), bool)
    for _, sel in _main_classes(hough, angle_tol):
        on[sel] = True
    return np.concatenate([runs, hough[~on]])


def long_walls(lines: np.ndarray, *, max_gap_px: float, offset_px: float, min_span_px: float,
               angle_tol: float = MAIN_DIRECTION_TOL, support: float = 0.5) -> list:
    """Long straight walls along the building's main directions.

    Wall segments within ``angle_tol`` of the main direction
    (:func:`wall_directions`) or of its perpendicular are turned onto it
    (a laser map's wall wanders off its line by a few cells and degrees)
    and grouped: pieces whose lines lie within ``offset_px`` of each other
    and that follow each other with gaps of at most ``max_gap_px`` are one
    wall. Walls at least ``min_span_px`` long whose pieces cover at least
    ``support`` of them are returned as ``(origin, u, n, runs)``: the
    wall's line is ``origin + t u`` and ``runs`` the ``[t0, t1]`` pieces of
    it along ``u``, in order."""
    segs = np.asarray(lines, float).reshape(-1, 4)
    out = []
    if segs.shape[0] < 2:
        return out
    L = np.hypot(*(segs[:, 2:] - segs[:, :2]).T)
    for u, sel in _main_classes(segs, angle_tol):
        if sel.size < 2:
            continue
        n = np.array([-u[1], u[0]])
        mid = (segs[sel, :2] + segs[sel, 2:]) / 2
        rho = mid @ n
        t1, t2 = segs[sel, :2] @ u, segs[sel, 2:] @ u
        lo, hi = np.minimum(t1, t2), np.maximum(t1, t2)
        order = np.argsort(rho)
        rl = rho.tolist()  # the grouping loop on Python floats: the same comparisons, faster
        bounds, g0 = [0], int(order[0])
        for i, (a, b) in enumerate(zip(order[:-1].tolist(), order[1:].tolist()), 1):
            if not (rl[b] - rl[a] <= offset_px and rl[b] - rl[g0] <= 2 * offset_px):
                bounds.append(i)
                g0 = b
        bounds.append(len(order))
        # the pieces of each group (order[bounds[g]:bounds[g + 1]]) along the
        # wall, all groups at once: by group, then by their start
        gid = np.repeat(np.arange(len(bounds) - 1), np.diff(bounds))
        by = order[np.lexsort((lo[order], gid))]
        glo, ghi = lo[by], hi[by]
        # the pieces so far reach the running maximum of their ends within the
        # group (of the ranks of the ends, offset by group: exact): a piece
        # starting within a cell of it extends the run, one within max_gap_px
        # starts the next run of the chain, any other the next chain
        m = len(by)
        rank = np.empty(m, np.int64)
        rank[np.argsort(ghi, kind="stable")] = np.arange(m)
        acc = np.sort(ghi, kind="stable")[np.maximum.accumulate(gid * m + rank) - gid * m]
        head = np.ones(m, bool)
        np.not_equal(gid[1:], gid[:-1], out=head[1:])
        reach = np.empty(m)
        reach[0], reach[1:] = -np.inf, acc[:-1]
        run = head | ~(glo <= reach + 1.0)
        chain = head | (run & ~(glo - reach <= max_gap_px))
        first = np.flatnonzero(run)
        last = np.empty_like(first)
        last[:-1], last[-1] = first[1:] - 1, m - 1
        run_lo, run_hi = glo[first], acc[last]
        c_first = np.flatnonzero(chain[first])                 # the first run of each chain
        c_last = np.empty_like(c_first)
        c_last[:-1], c_last[-1] = c_first[1:] - 1, len(first) - 1
        span = run_hi[c_last] - run_lo[c_first]
        r0 = {}
        for c in np.flatnonzero(span >= min_span_px).tolist():
            runs = [[a, b] for a, b in zip(run_lo[c_first[c]:c_last[c] + 1].tolist(),
                                           run_hi[c_first[c]:c_last[c] + 1].tolist())]
            if sum(r[1] - r[0] for r in runs) >= support * float(span[c]):
                k = int(gid[first[c_first[c]]])
                if k not in r0:
                    grp = order[bounds[k]:bounds[k + 1]]
                    w = L[sel[grp]]
                    r0[k] = float((rho[grp] * w).sum() / w.sum())
                out.append((r0[k] * n, u, n, [[np.float64(a), np.float64(b)] for a, b in runs]))
    return out


def partition_gaps(obstacle: np.ndarray, free: np.ndarray, lines: np.ndarray, *, min_wall_px: float,
                   min_gap_px: float, max_gap_px: float, min_hits_px: float, depth_px: float,
                   hits: np.ndarray | None = None, hits_band_px: float = 1.0,
                   min_structure_px: float = 0.0, angle_tol: float = MAIN_DIRECTION_TOL,
                   band_px: int = 1) -> list:
    """Openings between the free end of a partition and the wall it points at.

    A partition between two rooms is often mapped only in part: the laser
    saw its face near one end, and along the rest of its line it returned
    only scattered hits (glass, a wall seen edge-on, an open door leaf). From
    the end of every straight wall face (:func:`wall_lines`) at least
    ``min_wall_px`` long and on one of the building's main directions, the
    line is followed outwards; where it meets a straight wall face of the
    other main direction (a wall crossing it) after a gap of
    ``min_gap_px``-``max_gap_px``, the gap is an opening when

    - cells of ``hits`` (within ``hits_band_px`` of the line: a wall's
      thickness and wander about the line of its face) lie along at least
      ``min_hits_px`` of it: the partition goes on, seen in pieces (a gap
      the laser saw nothing in is the way past a cupboard's end, not a
      wall's),
    - at least half the cells on its line are free (not a wall seen at a
      grazing angle),
    - the space on both sides is ``depth_px`` deep (not a niche's mouth),
      and it does not lie across a passage as wide as itself (the rules of
      :func:`wall_openings`).

    Parameters
    ----------
    obstacle, free : (M, N) ndarray of bool
        As for :func:`wall_openings`.
    lines : (K, 4) ndarray
        :func:`wall_lines` of their faces.
    hits : (M, N) ndarray of bool, optional
        The cells the laser hit: the map's occupied cells, specks that
        ``obstacle`` looks through as clutter included. Default
        ``obstacle``.
    min_structure_px : float
        The partition's face is one of an obstacle (8-connected) at least
        this long or wide: a wall of the building, joined to its other
        walls, not a free-standing table or cupboard. 0: any.

    Returns
    -------
    list of ((r1, c1), (r2, c2))
        Opening segments in pixels, from the partition's end to the crossing
        wall.
    """
    if hits is None:
        hits = obstacle
    segs = np.asarray(lines, float).reshape(-1, 4)
    if segs.shape[0] < 2:
        return []
    classes = _main_classes(segs, angle_tol)
    crossing = {}  # the cells of each class's lines, drawn when the other class needs them
    ob, fr = np.ravel(obstacle), np.ravel(free)
    back = 3  # samples start inside the piece, as in wall_openings
    n_gap = int(np.ceil(max_gap_px)) + back + 1
    offsets = np.arange(-band_px, band_px + 1)
    j = np.arange(n_gap)[None, :]
    out = []
    for k, (u, sel) in enumerate(classes):
        a, b = segs[sel, :2], segs[sel, 2:]
        keep = np.hypot(*(b - a).T) >= min_wall_px
        if not keep.any():
            continue
        a, b = a[keep], b[keep]
        line_of = np.tile(sel[keep], 2)
        d = np.sign((b - a) @ u)[:, None] * u
        ends, dirs = np.concatenate([b, a]), np.concatenate([d, -d])
        start = ends - (back + 1) * dirs
        # only the ends where the piece ends within its last cells (the first
        # samples tell) are followed further
        m = min(back + 3, n_gap)
        at, inside = _sample_cells(obstacle.shape, start, dirs, m, offsets)
        hit = (np.take(ob, at) & inside).any(axis=1)
        todo = np.flatnonzero(hit[:, 0] & ~hit[:, 1:].all(axis=1))
        if not todo.size:
            continue
        s0 = np.argmax(~hit[todo], axis=1)  # the first free sample, among those
        start, dirs, line_of = start[todo], dirs[todo], line_of[todo]
        if 1 - k not in crossing:
            crossing[1 - k] = np.ravel(_line_mask(segs[classes[1 - k][1]], obstacle.shape, 3))
        at, inside = _sample_cells(obstacle.shape, start, dirs, n_gap, offsets)
        met = (np.take(crossing[1 - k], at) & inside).any(axis=1) & (j >= s0[:, None])
        e0 = np.argmax(met, axis=1)
        ok = met.any(axis=1)
        # the gap ends at the crossing wall's first cell on the line
        wall = np.take(ob, at[:, band_px]) & inside[:, band_px] & (j >= e0[:, None])
        e1 = np.argmax(wall, axis=1)
        ok &= wall.any(axis=1) & (e1 - e0 <= 2 * band_px + 1)
        gap = e1 - s0
        ok &= (gap >= min_gap_px) & (gap <= max_gap_px)
        within = (j >= s0[:, None]) & (j < e1[:, None])
        line_free = np.take(fr, at[:, band_px]) & inside[:, band_px]
        ok &= (line_free & within).sum(axis=1) >= 0.5 * np.maximum(gap, 1)
        i = np.flatnonzero(ok)
        if not i.size:
            continue
        hb = max(int(round(hits_band_px)), band_px)
        ah, inh = _sample_cells(obstacle.shape, start[i], dirs[i], n_gap, np.arange(-hb, hb + 1))
        seen = (np.take(hits, ah) & inh).any(axis=1)
        i = i[(seen & within[i]).sum(axis=1) >= min_hits_px]
        if not i.size:
            continue
        p = start[i] + s0[i, None] * dirs[i]
        q = start[i] + (e1[i] + 1)[:, None] * dirs[i]
        good = _depth_ok(obstacle, p, q, depth_px)
        good[good] = ~_spans_passage(obstacle, p[good], q[good], depth_px)
        if min_structure_px > 0:  # the costliest test last
            for t in np.flatnonzero(good):
                good[t] = _on_structure(obstacle, segs[line_of[i[t]]], min_structure_px)
        out.extend((p[t], q[t]) for t in np.flatnonzero(good))
    return out


def _on_structure(obstacle: np.ndarray, seg, min_px: float) -> bool:
    """Whether the obstacle (8-connected) at the middle of the face line
    ``seg`` (or a cell beside it) is at least ``min_px`` long or wide. Its
    components are filled only in a window of ``min_px`` (and a margin)
    round the line: one that leaves the window at a side inside the map is
    at least that large."""
    import cv2

    H, W = obstacle.shape
    # on Python floats and ints, quicker than tiny arrays (the same values; round()
    # rounds half to even as np.rint does)
    a0, a1, b0, b1 = (float(x) for x in seg)
    m = math.ceil(min_px) + 3
    r0 = max(int(min(a0, b0)) - m, 0)
    r1 = min(int(max(a0, b0)) + m + 1, H)
    c0 = max(int(min(a1, b1)) - m, 0)
    c1 = min(int(max(a1, b1)) + m + 1, W)
    win = obstacle[r0:r1, c0:c1].astype(np.uint8)  # a copy: the fill marks it
    mr, mc = round((a0 + b0) / 2), round((a1 + b1) / 2)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            rr, cc = min(max(mr + dr, 0), H - 1), min(max(mc + dc, 0), W - 1)
            if not (r0 <= rr < r1 and c0 <= cc < c1) or win[rr - r0, cc - c0] != 1:
                continue  # outside the window, free, or on a component seen already
            # the component through the cell (8-connected) and its bounding box
            _, _, _, (x, y, w, h) = cv2.floodFill(win, None, (int(cc - c0), int(rr - r0)), 2, 0, 0, 8)
            # as long or wide as min_px, or leaving the window at a side that
            # is not the map's edge
            if (max(w, h) >= min_px or (x == 0 and c0 > 0) or (y == 0 and r0 > 0)
                    or (x + w == c1 - c0 and c1 < W) or (y + h == r1 - r0 and r1 < H)):
                return True
    return False


def furniture_rows(walls: list, obstacle: np.ndarray, part: np.ndarray, *, band_px: float,
                   min_share: float = 0.5, min_pieces: int = 2) -> np.ndarray:
    """Which long walls are rows of furniture.

    A long wall (:func:`long_walls`, in the cells of ``obstacle``) is a row
    of furniture when at least ``min_share`` of the obstacle cells on its
    pieces (within ``band_px`` of its line) are cells of ``part`` (bulky
    free-standing furniture) and those cells belong to at least
    ``min_pieces`` separate pieces (8-connected): desks or round tables set
    in line, whose sides line up like a wall's. One piece is not a row: a
    long cupboard or a counter along a wall lines up with the wall itself.

    Returns
    -------
    (len(walls),) ndarray of bool
    """
    import cv2

    H, W = obstacle.shape
    out = np.zeros(len(walls), bool)
    if not len(walls) or not part.any():
        return out
    img = part.view(np.uint8) if part.dtype == bool and part.flags.c_contiguous else part.astype(np.uint8)
    try:  # 16-bit labels when they fit (half the memory of 32-bit ones)
        _, lab = cv2.connectedComponents(img, connectivity=8, ltype=cv2.CV_16U)
    except cv2.error:
        _, lab = cv2.connectedComponents(img, connectivity=8, ltype=cv2.CV_32S)
    b = int(np.ceil(band_px))
    o = np.arange(-b, b + 1, dtype=float)
    for k, (origin, u, n, runs) in enumerate(walls):
        ts = np.concatenate([np.arange(np.ceil(t0), np.floor(t1) + 1) for t0, t1 in runs])
        pts = origin + ts[:, None, None] * u + o[None, :, None] * n
        r = np.clip(np.rint(pts[..., 0]).astype(np.intp), 0, H - 1)
        c = np.clip(np.rint(pts[..., 1]).astype(np.intp), 0, W - 1)
        on = int(obstacle[r, c].sum())
        pieces = lab[r, c]
        pieces = pieces[pieces > 0]
        out[k] = bool(on) and pieces.size >= min_share * on and np.unique(pieces).size >= min_pieces
    return out


def scale_walls(walls: list, k: int) -> list:
    """Long walls (:func:`long_walls`) found on a grid ``k`` times coarser,
    in the cells of the fine grid (a coarse cell's centre is the centre of
    its ``k x k`` fine cells)."""
    if k == 1:
        return walls
    h = (k - 1) / 2
    out = []
    for origin, u, n, runs in walls:
        rho = k * float(origin @ n) + h * float(n.sum())
        dt = h * float(u.sum())
        out.append((rho * n, u, n, [[k * a + dt, k * b + dt] for a, b in runs]))
    return out


def wall_mask(walls: list, shape, *, width_px: int = 5) -> np.ndarray:
    """The cells of the long walls (:func:`long_walls`): each piece drawn
    ``width_px`` cells wide (the wander of a scanned wall about its line)."""
    segs = [np.r_[origin + t0 * u, origin + t1 * u] for origin, u, _, runs in walls for t0, t1 in runs]
    return _line_mask(np.array(segs, float).reshape(-1, 4), shape, width_px)


class WallIndex:
    """Long walls (:func:`long_walls`) sorted by their offset along each of
    the two main directions, for :func:`across_walls`: a query looks only at
    the walls within its tolerance (time logarithmic in the walls)."""

    def __init__(self, walls: list):
        groups: dict = {}
        for origin, u, n, runs in walls:
            key = (round(float(u[0]), 9), round(float(u[1]), 9))
            g = groups.setdefault(key, (u, n, [], [], []))
            g[2].append(float(origin @ n))
            g[3].append(runs[0][0])
            g[4].append(runs[-1][1])
        self.classes = []
        for u, n, rho, t0, t1 in groups.values():
            order = np.argsort(rho)
            self.classes.append((np.asarray(u, float), np.asarray(n, float), np.asarray(rho)[order],
                                 np.asarray(t0)[order], np.asarray(t1)[order]))


def across_walls(p, q, walls, *, tol_px: float, min_angle: float = np.deg2rad(60.0)) -> bool:
    """Whether both ends of the segment ``p``-``q`` lie on long walls
    (:func:`long_walls`, within ``tol_px``, inside their span) that it
    crosses at ``min_angle`` or steeper: it spans a passage between two
    walls, such as a corridor between its side walls.

    ``walls`` is a :class:`WallIndex` (or the list of walls, indexed on
    every call). :func:`across_walls_many` answers for many segments at
    once."""
    return bool(across_walls_many(np.reshape(np.asarray(p, float), (1, 2)), np.reshape(np.asarray(q, float), (1, 2)),
                                  walls, tol_px=tol_px, min_angle=min_angle)[0])


def across_walls_many(P, Q, walls, *, tol_px: float, min_angle: float = np.deg2rad(60.0),
                      past_px: float | None = None) -> np.ndarray:
    """:func:`across_walls` of the segments ``P[i]``-``Q[i]`` (``(E, 2)``
    arrays): ``(E,)`` bool.

    With ``past_px``, one of the two walls must also run on at least
    ``past_px`` past its end of the segment, both ways along it: the
    passage goes on past the segment (a corridor past a narrowing of its
    own), rather than ending there (the corridor's mouth, where both side
    walls end)."""
    if not isinstance(walls, WallIndex):
        walls = WallIndex(walls)
    P, Q = np.asarray(P, float).reshape(-1, 2), np.asarray(Q, float).reshape(-1, 2)
    v = Q - P
    d = v / np.maximum(np.hypot(v[:, 0], v[:, 1]), 1e-9)[:, None]
    hit = np.zeros((2, len(P)), bool)
    inside = np.zeros((2, len(P)), bool)
    for u, n, rho, t0, t1 in walls.classes:
        steep = np.abs(d[:, 0] * u[0] + d[:, 1] * u[1]) <= np.cos(min_angle)
        for k, X in enumerate((P, Q)):
            todo = steep & ~(hit[k] if past_px is None else hit[k] & inside[k])
            if not todo.any():
                continue
            x = X[todo]
            r = x[:, 0] * n[0] + x[:, 1] * n[1]
            t = x[:, 0] * u[0] + x[:, 1] * u[1]
            lo = np.searchsorted(rho, r - tol_px)
            hi = np.searchsorted(rho, r + tol_px, side="right")
            on = np.zeros(len(x), bool)
            deep = np.zeros(len(x), bool)
            for step in range(int((hi - lo).max(initial=0))):  # the walls within tol_px of each end
                w = np.minimum(lo + step, len(rho) - 1)
                near = lo + step < hi
                on |= near & (t0[w] - tol_px <= t) & (t <= t1[w] + tol_px)
                if past_px is not None:
                    deep |= near & (t0[w] + past_px <= t) & (t <= t1[w] - past_px)
            idx = np.flatnonzero(todo)
            hit[k, idx] |= on
            inside[k, idx] |= deep
    if past_px is None:
        return hit[0] & hit[1]
    return hit[0] & hit[1] & (inside[0] | inside[1])


def long_wall_gaps(obstacle: np.ndarray, free: np.ndarray, walls: list, *, min_gap_px: float,
                   max_gap_px: float, depth_px: float, closet_px: float = 0.0, behind_px: float = 0.0) -> list:
    """Openings in long straight walls (:func:`long_walls`).

    Every gap of ``min_gap_px`` to ``max_gap_px`` between two pieces of a
    long wall, free along at least half of the wall's line across it, with
    space at least ``depth_px`` deep on both sides (no niche; or, with
    ``closet_px`` and ``behind_px``, a closet or balcony wider than the gap:
    :func:`_depth_ok`), is an opening: a corridor's side wall or a façade runs on past its doorways,
    so a gap in it is a way through it even where the laser saw a speck in
    the doorway (an open door leaf, a person) or did not see the wall's
    end. The opening spans the free cells of the gap.

    Returns
    -------
    list of ((r1, c1), (r2, c2))
        Opening segments in pixels.
    """
    H, W = free.shape
    # every gap of every wall, its cells on the wall's line in a row of a
    # (gaps, cells) array: cell j of gap g at origin + (ceil(e) + j) u
    gaps = [(origin, u, e, s0) for origin, u, _, runs in walls
            for (_, e), (s0, _) in zip(runs[:-1], runs[1:]) if min_gap_px <= s0 - e <= max_gap_px]
    if not gaps:
        return []
    origin = np.array([g[0] for g in gaps], float)
    u = np.array([g[1] for g in gaps], float)
    t_lo = np.ceil([g[2] for g in gaps])
    count = (np.floor([g[3] for g in gaps]) + 1 - t_lo).astype(int)
    cols = np.arange(max(int(count.max()), 1))
    valid = cols[None, :] < count[:, None]
    ts = t_lo[:, None] + cols[None, :]
    pts = origin[:, None, :] + ts[:, :, None] * u[:, None, :]
    rr = np.rint(pts[..., 0]).astype(int)
    cc = np.rint(pts[..., 1]).astype(int)
    inside = (rr >= 0) & (rr < H) & (cc >= 0) & (cc < W)
    fr = np.take(free, np.clip(rr, 0, H - 1) * W + np.clip(cc, 0, W - 1)) & valid
    n_free = fr.sum(axis=1)
    ok = (count > 0) & (inside | ~valid).all(axis=1) & ~(n_free / np.maximum(count, 1) < 0.5)
    # the first and last free cell of every gap at once (each has one: n_free >= 1), not gap by
    # gap
    g = np.flatnonzero(ok)
    k0 = np.argmax(fr[g], axis=1)
    k1 = fr.shape[1] - 1 - np.argmax(fr[g, ::-1], axis=1)
    p = origin[g] + (ts[g, k0] - 1)[:, None] * u[g]
    q = origin[g] + (ts[g, k1] + 1)[:, None] * u[g]
    wide = np.flatnonzero(np.hypot(*(q - p).T) >= min_gap_px)
    if not wide.size:
        return []
    p, q = p[wide], q[wide]
    deep = _depth_ok(obstacle, p, q, depth_px, closet_px=closet_px, behind_px=behind_px)
    return [(p[i], q[i]) for i in np.flatnonzero(deep)]


def _cross_sections(free_graph, step: float, max_radius: float = np.inf):
    """Points every ``step`` pixels along the free-space skeleton's branches (not within 2
    pixels of a branch's end) and the unit vector across the branch there: ``(K, 2)``,
    ``(K, 2)``. A coarse skeleton's paths step over several cells: the points lie between
    them too, so that no wall thicker than ``step`` is stepped over. Points of a clearance
    (``radius``, metres) above ``max_radius`` are left out. Every branch at once: the paths
    laid end to end, each on its own stretch of one arc length."""
    from .._fast import ranges

    paths = [(np.asarray(d["path"], float), d.get("radius")) for _, _, d in free_graph.edges(data=True)
             if len(d["path"]) >= 3]
    if not paths:
        return np.zeros((0, 2)), np.zeros((0, 2))
    P = np.concatenate([p for p, _ in paths])
    n = np.array([len(p) for p, _ in paths])
    first = np.cumsum(n) - n
    steps = np.hypot(*np.diff(P, axis=0).T)
    steps[first[1:] - 1] = 8.0  # between two paths: a stretch no sample reaches (t +- 2 stays inside)
    arc = np.r_[0.0, np.cumsum(steps)]
    lo, hi = arc[first] + 2.0, arc[first + n - 1] - 2.0
    count = np.maximum(np.ceil((hi - lo) / step).astype(np.int64), 0)
    t = np.repeat(lo, count) + (ranges(np.zeros_like(count), count) * step)
    if t.size == 0:
        return np.zeros((0, 2)), np.zeros((0, 2))

    def at(x):
        return np.stack([np.interp(x, arc, P[:, 0]), np.interp(x, arc, P[:, 1])], 1)

    v = at(t + 2) - at(t - 2)
    norm = np.hypot(v[:, 0], v[:, 1])
    ok = norm > 0
    if np.isfinite(max_radius) and all(r is not None for _, r in paths):
        R = np.concatenate([np.asarray(r, float) for _, r in paths])
        ok &= np.interp(t, arc, R) <= max_radius
    return at(t[ok]), np.stack([-v[ok, 1], v[ok, 0]], 1) / norm[ok, None]


def thin_wall_gaps(free_graph, free: np.ndarray, hits: np.ndarray, *, min_width_px: float,
                   max_width_px: float, along_px: float, thick_px: float, structure_px: float,
                   pillar_px: float = 0.0, step: float = 1.0, max_radius: float = np.inf,
                   clearance=None, kept=()) -> list:
    """Gaps in thin walls across the free-space skeleton: doorways that narrow nothing.

    A doorway into a passage no wider than itself (the end of a hallway, a
    glass door onto a balcony strip) is no clearance bottleneck, yet it is a
    gap in a wall. Every ``step`` pixels along the skeleton the line across
    the branch meets obstacles at two *posts*; the gap between them is a
    doorway when

    - the posts are ``min_width_px`` to ``max_width_px`` apart;
    - each post is a laser hit or a drawn wall (``hits`` within a cell of
      it), not the edge of unknown space;
    - beyond each post the obstacle goes on *along the line* for
      ``along_px`` (90 % of its cells): the wall the doorway is in, not a
      wall crossed across its thickness;
    - that stretch of wall is thin: free space within ``thick_px`` on both
      of its faces at 90 % of its cells. A corridor's cross-section meets
      its side walls face on: beyond its posts the wall runs across the
      line, and moving along the corridor stays inside it;
    - neither post is a pillar: an obstacle thin for less than
      ``pillar_px`` beyond the post, then the wall it stands against (solid
      on to ``pillar_px``, not thin): a narrowing at a pillar, a column, a
      cupboard or a bump on a wall is the room's own (a doorway closer than
      that to a corner is left to the other rules too);
    - the obstacle at each post belongs to a structure at least
      ``structure_px`` long or wide (8-connected): a free-standing piece of
      furniture beside a wall is no door post.

    Parameters
    ----------
    free_graph : networkx.MultiGraph
        Free-space skeleton graph (``path`` per edge, map pixels).
    free, hits : (M, N) ndarray of bool
        The free cells doors are searched in, and the map's occupied cells.
    min_width_px, max_width_px, along_px, thick_px, pillar_px, structure_px : float
        Pixels, as above (``pillar_px`` 0: no pillar test).
    step : float
        The skeleton is tried every ``step`` pixels along its branches, and
        the walls beyond the posts are sampled every ``step`` pixels: 1 on
        maps of 0.05 m cells, the size of a wall's cell (``wall_cell``) on
        finer maps, so that the work per metre does not grow as the cells
        shrink.
    kept : list of ((r, c), (r, c)), optional
        Door segments cut already: a gap whose midpoint lies within its own
        width of one of them is that doorway (:func:`gaps_without_doors`).
    clearance : (M, N) ndarray of float, optional
        Distance (pixels) of every free cell to the nearest obstacle (the
        method's clearance; computed when not given).
    max_radius : float
        Points of the skeleton with a clearance above this (metres, the
        graph's ``radius``) are not tried: their posts are further apart
        than ``max_width_px`` (half of it, in metres).

    Returns
    -------
    list of ((r, c), (r, c))
        The two posts of each gap found, pixels: several along one doorway
        (the caller keeps one, :func:`topomap.core.doors.suppress_duplicates`).
    """
    P, N = _cross_sections(free_graph, step, max_radius=max_radius)
    if len(P) == 0:
        return []
    free = np.asarray(free, bool)
    H, W = free.shape

    def is_solid(Q):  # outside the map: obstacle
        r, c = np.rint(Q[..., 0]).astype(np.intp), np.rint(Q[..., 1]).astype(np.intp)
        inside = (r >= 0) & (r < H) & (c >= 0) & (c < W)
        return ~(inside & free[np.clip(r, 0, H - 1), np.clip(c, 0, W - 1)])

    if clearance is None:
        from .._fast import edt

        clearance = edt(free)
    clear_at = clearance_lookup(clearance)

    # march across the branch one way, then (where the obstacle came near enough) the other
    # the posts are no nearer than the point's clearance on either side: neither is further than
    # max_width_px less that
    f1 = _first_obstacle(is_solid, clear_at, P, N, int(max_width_px) + 1 - np.floor(clear_at(P)))
    sel = np.flatnonzero((f1 > 0) & (f1 < max_width_px))
    P, N, f1 = P[sel], N[sel], f1[sel]
    f2 = _first_obstacle(is_solid, clear_at, P, -N, int(max_width_px) + 1 - f1)
    width = f1 + f2
    sel = np.flatnonzero((f2 > 0) & (width >= min_width_px) & (width <= max_width_px))
    N, p1, p2 = N[sel], P[sel] + N[sel] * f1[sel, None], P[sel] - N[sel] * f2[sel, None]
    sel = np.flatnonzero(_near_any(hits, p1) & _near_any(hits, p2))
    N, p1, p2 = N[sel], p1[sel], p2[sel]
    a, k = _samples(along_px, step), _samples(thick_px, step)
    # beyond each post, the wall the doorway is in: the obstacle goes on along the line ...
    keep = _goes_on(is_solid, p1, N, a) & _goes_on(is_solid, p2, -N, a)
    N, p1, p2 = N[keep], p1[keep], p2[keep]
    # ... and is thin there
    keep = _thin_beyond(is_solid, p1, N, a, k)
    N, p1, p2 = N[keep], p1[keep], p2[keep]
    keep = _thin_beyond(is_solid, p2, -N, a, k)
    N, p1, p2 = N[keep], p1[keep], p2[keep]
    if pillar_px > along_px:
        # a pillar: thin for a stretch, then the wall it stands against (solid, not thin) before
        # ``pillar_px``; a gap at one is the room's own, not a doorway (a bump on a wall across
        # from clutter passes every other test)
        b = _samples(pillar_px, step)
        pillar = [_goes_on(is_solid, p, D, b) & ~_thin_beyond(is_solid, p, D, b, k) for p, D in ((p1, N), (p2, -N))]
        keep = ~(pillar[0] | pillar[1])
        N, p1, p2 = N[keep], p1[keep], p2[keep]
    if kept:  # a doorway a door is cut in already needs no second cut
        sel = gaps_without_doors(p1, p2, kept)
        N, p1, p2 = N[sel], p1[sel], p2[sel]
    # last, on the few left: the obstacle beyond each post is part of a structure
    obstacle = ~free
    seen = {}  # a doorway's jambs are met again at every step through it

    def on_structure(q):
        key = (int(round(q[0])), int(round(q[1])))
        if key not in seen:
            seen[key] = _on_structure(obstacle, (*q, *q), structure_px)
        return seen[key]

    return [(tuple(u.tolist()), tuple(v.tolist())) for u, v, n in zip(p1, p2, N)
            if on_structure(u + n) and on_structure(v - n)]


def clearance_lookup(clearance: np.ndarray):
    """A function of points ``Q`` (``(..., 2)`` pixels, inside the map or not) giving the clearance
    of their cells, for :func:`_first_obstacle`: the distance transform counts no cell beyond the
    map's edge, where a march stops, so the nearer of it and the edge (0 outside the map)."""
    near = np.asarray(clearance, np.float32)
    H, W = near.shape

    def clear_at(Q):
        r, c = np.rint(Q[..., 0]).astype(np.intp), np.rint(Q[..., 1]).astype(np.intp)
        edge = np.minimum(np.minimum(r + 1, H - r), np.minimum(c + 1, W - c))
        return np.minimum(near[np.clip(r, 0, H - 1), np.clip(c, 0, W - 1)], np.maximum(edge, 0))

    return clear_at


def _samples(length_px: float, step: float) -> np.ndarray:
    """The offsets ``step, 2 step, ...`` up to ``length_px`` (rounded to whole steps, at least one):
    one per pixel on a map of ``step`` 1, as many per metre whatever the resolution."""
    return step * np.arange(1, max(int(round(length_px / step)), 1) + 1, dtype=float)


def _goes_on(is_solid, post, D, a) -> np.ndarray:
    """Whether the obstacle goes on from each post ``(K, 2)`` along ``D`` for the steps ``a``
    (90 % of them)."""
    return is_solid(post[:, None, :] + D[:, None, :] * a[None, :, None]).mean(1) >= 0.9


def _thin_beyond(is_solid, post, D, a, k) -> np.ndarray:
    """Whether the obstacle from each post ``(K, 2)`` on along ``D`` (the steps ``a``) is thin: free
    within the steps ``k`` on both of its faces (across ``D``) at 90 % of the steps."""
    keep = np.ones(len(post), bool)
    for lo in range(0, len(post), 4096):  # in chunks: the probes of a point are len(a) * len(k) * 2 cells
        line = post[lo:lo + 4096, None, :] + D[lo:lo + 4096, None, :] * a[None, :, None]
        across = D[lo:lo + 4096, ::-1] * np.array([1.0, -1.0])
        for side in (1.0, -1.0):
            probe = line[:, :, None, :] + side * across[:, None, None, :] * k[None, None, :, None]
            keep[lo:lo + 4096] &= (~is_solid(probe)).any(2).mean(1) >= 0.9
    return keep


#: The steps :func:`_first_obstacle` gives where there is no obstacle within its limit.
_FAR = 1 << 40


def _first_obstacle(is_solid, clearance, P, D, n) -> np.ndarray:
    """Steps (pixels) from each point ``P`` along ``D`` to the first obstacle cell (``is_solid``), at
    most ``n`` (per point, or one for all); :data:`_FAR` where there is none within ``n``. The
    same whole steps as a march one pixel at a time, by sphere tracing: at a point whose cell is
    ``c`` (``clearance``, pixels) from every obstacle cell, a point at most ``c - 1.5`` further on
    lies in a cell less than ``c`` from it (each point is within half a diagonal of its cell's
    centre), so no obstacle cell: the march jumps ``floor(c - 1.5)`` steps (at least one)."""
    n = np.broadcast_to(np.asarray(n, float), (len(P),))
    t = np.zeros(len(P))
    live = np.arange(len(P))
    while live.size:
        Q = P[live] + D[live] * t[live, None]
        hit = is_solid(Q)
        go = live[~hit]
        t[go] += np.maximum(np.floor(clearance(Q[~hit]) - 1.5), 1.0)
        live = go[t[go] <= n[go]]
    return np.where(t <= n, t, _FAR).astype(np.int64)


def gaps_without_doors(p1: np.ndarray, p2: np.ndarray, kept) -> np.ndarray:
    """Whether each gap (posts ``p1[i]``, ``p2[i]``, ``(K, 2)`` pixels) has its midpoint at least its
    own width from every segment of ``kept`` (``((r, c), (r, c))``): a doorway where a door is cut
    already needs no second cut (across a thick wall, two cuts a wall's thickness apart would leave
    a sliver between them). ``(K,)`` bool."""
    from .geometry import points_near_segments

    keep = np.ones(len(p1), bool)
    if len(p1) and len(kept):
        S = np.asarray(kept, float).reshape(-1, 2, 2)
        near, _ = points_near_segments((p1 + p2) / 2, np.hypot(*(p2 - p1).T), S[:, 0], S[:, 1])
        keep[near] = False
    return keep


def _near_any(mask: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Whether ``mask`` holds a cell within one cell (8-neighbourhood) of each point ``(K, 2)``."""
    H, W = mask.shape
    q = np.rint(pts).astype(np.int64)
    out = np.zeros(len(q), bool)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            out |= mask[np.clip(q[:, 0] + dr, 0, H - 1), np.clip(q[:, 1] + dc, 0, W - 1)]
    return out
