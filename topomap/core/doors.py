"""Doors: narrow passages of free space that meet protruding parts of walls.

Steps 2, 4 and 5 of the paper (Mora, Prados & Barber): clearance minima on the
free-space skeleton graph give candidate passages; rays perpendicular to each
passage give its intersection points (IP) with the walls; endpoints (EP) of
the occupied-space skeleton graphs mark protruding wall parts; the map's own
threshold (twice the mean wall half-thickness) decides which candidates are
doors.

All coordinates here are pixel ``(row, col)`` floats; metres come from the
grid's resolution.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from operator import itemgetter

import numpy as np

from .._fast import ranges
from .geometry import disk, points_near_segments
from .walls import across_walls_many, wall_faces

__all__ = ["Candidate", "Door", "passage_candidates", "intersection_points",
           "wall_threshold", "select_doors", "segment_crosses", "passage_minima",
           "nearest_wall_points", "protrusion", "protrusion_at", "occupied_skeleton_lines",
           "find_bottlenecks", "judge_doors", "suppress_duplicates", "opening_candidates", "across_corridor",
           "STATUSES"]

# --------------------------------------------------------------------------
# Candidate statuses: why a candidate was kept or refused (see the "How it
# works" page, which explains every one of them).
# --------------------------------------------------------------------------

#: Not judged yet.
CANDIDATE = "candidate"
#: Accepted as a door.
DOOR = "door"
#: A wall was found on at most one side of the passage.
NO_WALL_BOTH_SIDES = "no wall on both sides"
#: Paper: the occupied-space skeleton has no endpoint at all.
NO_ENDPOINTS = "no endpoints"
#: Paper: no occupied-skeleton endpoint within the threshold of an IP.
NO_PROTRUDING_WALL_NEAR = "no protruding wall near"
#: Paper: the centres of IP1-IP2 and EP1-EP2 are more than half the threshold apart.
CENTRES_APART = "centres apart"
#: Paper: IP1-IP2 or EP1-EP2 crosses an occupied-space skeleton.
CROSSES_WALL_SKELETON = "crosses a wall skeleton"
#: topomap: the posts are closer than ``min_door_width`` or farther than ``max_door_width``.
WIDTH_OUT_OF_RANGE = "width out of range"
#: topomap: the posts do not face each other across the bottleneck.
POSTS_NOT_FACING = "posts not facing"
#: topomap: the protrusion evidence of ``rule`` is missing.
NO_PROTRUDING_WALL = "no protruding wall"
#: topomap: a one-sided candidate (corridor mouth), not judged yet.
MOUTH = "mouth"
#: topomap: a corridor mouth whose walls do not protrude on both sides.
MOUTH_WITHOUT_PROTRUDING_WALLS = "mouth without protruding walls"
#: topomap: a narrower accepted door lies across it.
DUPLICATE = "duplicate"
#: topomap: wider than ``wide_opening`` and walls do not end at both posts.
WIDE_WITHOUT_WALL_ENDS = "wide opening without wall ends"
#: topomap: an opening between collinear pieces of a straight wall, cut as a door.
WALL_OPENING = "opening in a wall"
#: topomap: both posts stand out less than ``pillar_depth`` from the two long side walls of a corridor.
ACROSS_CORRIDOR = "across a corridor"
#: topomap: neither post is a laser hit (no occupied cell within ``frontier_post``): the edges of unexplored space.
UNEXPLORED_POSTS = "between unexplored edges"

#: topomap: a gap in a thin wall across the skeleton (``gaps``), cut as a door.
WALL_GAP = "gap in a thin wall"

#: Every status a candidate can end with or pass through.
STATUSES = (CANDIDATE, DOOR, NO_WALL_BOTH_SIDES, NO_ENDPOINTS, NO_PROTRUDING_WALL_NEAR, CENTRES_APART,
            CROSSES_WALL_SKELETON, WIDTH_OUT_OF_RANGE, POSTS_NOT_FACING, NO_PROTRUDING_WALL, MOUTH,
            MOUTH_WITHOUT_PROTRUDING_WALLS, DUPLICATE, WIDE_WITHOUT_WALL_ENDS, WALL_OPENING, ACROSS_CORRIDOR,
            UNEXPLORED_POSTS, WALL_GAP)


@dataclass
class Candidate:
    """A narrow passage on one free-space skeleton branch.

    Attributes
    ----------
    edge : tuple
        ``(u, v, key)`` of the branch in the free-space graph.
    centroid : (2,) ndarray
        Pixel ``(row, col)`` of the passage's centre.
    direction : (2,) ndarray
        Unit vector (rows, cols) along the skeleton at the passage.
    radius : float
        Clearance at the passage, pixels.
    ip1, ip2 : (2,) ndarray or None
        Intersection points with the walls on either side (pixels).
    status : str
        Why the candidate was kept or refused: one of :data:`STATUSES`.
    ep1, ep2 : (2,) ndarray or None
        Paper method: the occupied-skeleton endpoints nearest ``ip1``, ``ip2``.
    """

    edge: tuple
    centroid: np.ndarray
    direction: np.ndarray
    radius: float
    ip1: np.ndarray | None = None
    ip2: np.ndarray | None = None
    status: str = CANDIDATE
    ep1: np.ndarray | None = None
    ep2: np.ndarray | None = None


@dataclass
class Door:
    """A door: the segment between two wall points, in pixels and metres.

    Attributes
    ----------
    id : int
        Door index (0-based, deterministic).
    p1, p2 : tuple of float
        End points, pixel ``(row, col)``.
    xy1, xy2 : tuple of float
        End points in map-frame metres ``(x, y)``.
    width : float
        Door width, metres (distance between the end points).
    rooms : tuple of int
        The two room labels the door joins (``(0, 0)`` until rooms exist).
    """

    id: int
    p1: tuple
    p2: tuple
    xy1: tuple = (float("nan"), float("nan"))
    xy2: tuple = (float("nan"), float("nan"))
    width: float = float("nan")
    rooms: tuple = (0, 0)
    extra: dict = field(default_factory=dict)

    @property
    def midpoint(self):
        """Door midpoint in map-frame metres ``(x, y)``."""
        return ((self.xy1[0] + self.xy2[0]) / 2, (self.xy1[1] + self.xy2[1]) / 2)

    @property
    def segment(self):
        """``((r1, c1), (r2, c2))`` in pixels."""
        return (tuple(self.p1), tuple(self.p2))


def passage_candidates(G, *, min_branch_px: float = 10, margin_px: int = 2):
    """Clearance minima on every branch of the free-space skeleton graph.

    For each branch of at least ``min_branch_px`` pixels (the paper: 10), the
    pixels whose clearance equals the branch minimum are taken together with
    ``margin_px`` (2) neighbours on each side along the branch; each
    resulting run is one candidate, with its centroid and orientation (the
    principal axis of its pixels).

    Parameters
    ----------
    G : networkx.MultiGraph
        Free-space skeleton graph (:func:`topomap.core.skeleton.skeleton_graph`)
        with ``radius`` along edges.

    Returns
    -------
    list of Candidate
    """
    res = G.graph.get("resolution", 1.0)
    out = []
    for u, v, k, d in sorted(G.edges(keys=True, data=True), key=lambda e: (e[0], e[1], e[2])):
        path = d["path"]
        if path.shape[0] < min_branch_px:
            continue
        rad = d["radius"] / res
        # ignore the node pixels at both ends: a minimum there belongs to the junction
        inner = rad[1:-1] if rad.size > 2 else rad
        m = inner.min()
        hit = np.zeros(rad.size, bool)
        sel = np.flatnonzero(np.abs(rad - m) < 1e-6)
        sel = sel[(sel > 0) & (sel < rad.size - 1)] if rad.size > 2 else sel
        for off in range(-margin_px, margin_px + 1):
            j = np.clip(sel + off, 0, rad.size - 1)
            hit[j] = True
        # runs of consecutive selected pixels
        idx = np.flatnonzero(hit)
        runs = np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1)
        for run in runs:
            pts = path[run].astype(float)
            c = pts.mean(axis=0)
            out.append(Candidate(edge=(u, v, k), centroid=c, direction=_principal(pts, path, run),
                                 radius=float(rad[run].min())))
    return out


def _principal(pts, path, run):
    if pts.shape[0] >= 2:
        q = pts - pts.mean(axis=0)
        w, vec = np.linalg.eigh(q.T @ q)
        dvec = vec[:, -1]
        if w[-1] > 1e-9:
            return dvec / np.linalg.norm(dvec)
    # fall back on the neighbours along the path
    i = int(run[0])
    a = path[max(i - 2, 0)].astype(float)
    b = path[min(i + 2, path.shape[0] - 1)].astype(float)
    dvec = b - a
    n = np.linalg.norm(dvec)
    return dvec / n if n else np.array([1.0, 0.0])


def intersection_points(candidates, obstacle: np.ndarray, *, max_px: float):
    """Set ``ip1``, ``ip2``: the first obstacle cell along each perpendicular ray.

    Parameters
    ----------
    candidates : list of Candidate
    obstacle : (M, N) ndarray of bool
        Cells that stop a ray (occupied, and unknown: everything not free).
    max_px : float
        Longest ray, pixels. A ray that leaves the map or meets no obstacle
        within it leaves the candidate without intersection points.
    """
    H, W = obstacle.shape
    steps = np.arange(0.5, max_px, 0.5)
    for cand in candidates:
        nrm = np.array([-cand.direction[1], cand.direction[0]])
        ips = []
        for sgn in (1.0, -1.0):
            pts = cand.centroid[None, :] + sgn * steps[:, None] * nrm[None, :]
            rc = np.rint(pts).astype(int)
            inside = (rc[:, 0] >= 0) & (rc[:, 0] < H) & (rc[:, 1] >= 0) & (rc[:, 1] < W)
            stop = np.flatnonzero(~inside | obstacle[np.clip(rc[:, 0], 0, H - 1), np.clip(rc[:, 1], 0, W - 1)])
            if stop.size == 0 or not inside[stop[0]]:
                ips.append(None)
            else:
                ips.append(rc[stop[0]].astype(float))
        cand.ip1, cand.ip2 = ips
    return candidates


def wall_threshold(occ_dist: np.ndarray, occ_skeleton_pixels: np.ndarray) -> float:
    """The paper's map-dependent threshold, pixels: 2 × mean distance-to-free
    over the occupied-space skeleton pixels (the mean wall thickness)."""
    if occ_skeleton_pixels.shape[0] == 0:
        return 0.0
    vals = occ_dist[occ_skeleton_pixels[:, 0], occ_skeleton_pixels[:, 1]]
    return float(2.0 * vals.mean())


def segment_crosses(lines, p, q, *, trim_px: float = 1.5) -> bool:
    """Whether segment ``p``–``q`` (pixels), shortened by ``trim_px`` at both
    ends, intersects the shapely geometry ``lines`` (in (col, row) order)."""
    from shapely.geometry import LineString

    p = np.asarray(p, float)
    q = np.asarray(q, float)
    d = q - p
    n = np.linalg.norm(d)
    if n <= 2 * trim_px:
        return False
    a = p + d / n * trim_px
    b = q - d / n * trim_px
    seg = LineString([(a[1], a[0]), (b[1], b[0])])
    return bool(lines.intersects(seg))


def select_doors(candidates, endpoints: np.ndarray, threshold: float, occ_lines):
    """Apply the paper's door conditions; returns the accepted candidates.

    For each candidate with both intersection points, EP1 and EP2 are the
    endpoints nearest to IP1 and IP2. It is a door when
    ``d(IP1, EP1) <= thr``, ``d(IP2, EP2) <= thr``, the distance between the
    centres of IP1–IP2 and EP1–EP2 is ``<= thr / 2`` (the paper's Figure 8;
    its printed third condition repeats IP1/EP1), and neither segment crosses
    an occupied-space skeleton. Every candidate gets a ``status`` saying why
    it was kept or refused.
    """
    kept = []
    if endpoints.shape[0] == 0:
        for c in candidates:
            c.status = NO_ENDPOINTS
        return kept
    from scipy.spatial import cKDTree

    tree = cKDTree(endpoints)
    for c in candidates:
        if c.ip1 is None or c.ip2 is None:
            c.status = NO_WALL_BOTH_SIDES
            continue
        d1, i1 = tree.query(c.ip1)
        d2, i2 = tree.query(c.ip2)
        c.ep1, c.ep2 = endpoints[i1], endpoints[i2]
        if d1 > threshold or d2 > threshold:
            c.status = NO_PROTRUDING_WALL_NEAR
            continue
        ipc = (c.ip1 + c.ip2) / 2
        epc = (c.ep1 + c.ep2) / 2
        if np.linalg.norm(ipc - epc) > threshold / 2:
            c.status = CENTRES_APART
            continue
        if occ_lines is not None and (segment_crosses(occ_lines, c.ip1, c.ip2)
                                      or segment_crosses(occ_lines, c.ep1, c.ep2)):
            c.status = CROSSES_WALL_SKELETON
            continue
        c.status = DOOR
        kept.append(c)
    return kept


def passage_minima(G, *, window_px: float, rise_px: float, reach_px: float, min_branch_px: float = 3,
                   mouths: bool = False, min_run_px: float = 0.0, max_radius_px: float = np.inf):
    """Bottlenecks of free space: local clearance minima along skeleton branches.

    A pixel of a branch is a bottleneck when its clearance is the smallest
    within ``window_px`` along the branch and the clearance rises by at least
    ``rise_px`` on *both* sides within ``reach_px`` along the skeleton
    (continuing one branch past the end node): a door is a narrowing between
    two wider spaces, not a stretch of uniform corridor. A plateau of equal
    minima gives one candidate at its middle. Branches and minima with a
    clearance above ``max_radius_px`` are skipped: door posts at least 90°
    apart around such a point are more than ``max_radius_px * sqrt(2)``
    apart.

    All branches are searched at once (:class:`_Branches`): one minimum
    filter over their clearances laid end to end, each padded with its end
    values, and the clearance on either side of every minimum as a range
    maximum.

    Returns
    -------
    list of Candidate
        With ``centroid`` at the bottleneck pixel and ``direction`` along the
        branch there, branch by branch (in the order of their ``(u, v, key)``)
        and along each branch.
    """
    from scipy.ndimage import minimum_filter1d

    out = []
    branches = _Branches(G)
    if not branches.keys:
        return out
    R, n, start = branches.rad, branches.n, branches.start
    use = np.flatnonzero((n >= min_branch_px) & (branches.low <= max_radius_px))
    if use.size == 0:
        return out
    # the minimum filter of every used branch with its end values repeated ("nearest"):
    # the branches end to end, each padded with w copies of its end values
    w = max(int(round(window_px)), 1)
    cells = ranges(start[use], start[use] + n[use])
    at = np.cumsum(n[use] + 2 * w) - n[use] - w  # each branch's first cell in the padded array
    P = np.empty(cells.size + 2 * w * use.size)
    body = ranges(at, at + n[use])
    P[body] = R[cells]
    P[ranges(at - w, at)] = np.repeat(R[start[use]], w)
    P[ranges(at + n[use], at + n[use] + w)] = np.repeat(R[start[use] + n[use] - 1], w)
    is_min = np.zeros(R.size, bool)
    is_min[cells] = R[cells] <= minimum_filter1d(P, 2 * w + 1, mode="nearest")[body] + 1e-6
    idx = np.flatnonzero(is_min)
    if idx.size == 0:
        return out
    br = branches.branch
    brk = np.flatnonzero((np.diff(idx) > 1) | (np.diff(br[idx]) != 0)) + 1
    r_lo = idx[np.concatenate([[0], brk])]  # each run of minima: its first and last cell
    r_hi = idx[np.concatenate([brk - 1, [idx.size - 1]])]
    mid = r_lo + (r_hi - r_lo + 1) // 2
    ok = R[mid] <= max_radius_px
    r_lo, r_hi, mid = r_lo[ok], r_hi[ok], mid[ok]
    if mid.size == 0:
        return out
    e = br[mid]
    am, end = branches.arc[mid], branches.arc[start[e] + n[e] - 1]
    r = R[mid]
    # both sides' continuations past the end nodes in one call
    far = branches.beyond(np.r_[branches.u[e], branches.v[e]], np.r_[e, e],
                          np.r_[reach_px - am, reach_px - (end - am)])
    left = np.maximum(branches.range_max(branches.cell_at(e, am - reach_px, "left"), mid), far[:e.size])
    right = np.maximum(branches.range_max(mid + 1, branches.cell_at(e, am + reach_px, "right")), far[e.size:])
    door = (left >= r + rise_px) & (right >= r + rise_px)
    # every candidate's cell, in order: the bottleneck, or a corridor's mouths at its far
    # end then at its near end (all the runs' mouths at once, :func:`_mouths`, not one
    # call a run)
    cell = np.where(door, mid, -1)
    hi = lo = np.full(mid.size, -1)
    if mouths:
        m = np.flatnonzero(~door)
        hi, lo = hi.copy(), lo.copy()
        hi[m], lo[m] = _mouths(branches, e[m], r_lo[m], r_hi[m], reach_px, rise_px, min_run_px=min_run_px)
    cells = np.stack([cell, hi, lo], 1).ravel()
    status = np.tile(np.array([CANDIDATE, MOUTH, MOUTH], object), mid.size)
    on = cells >= 0
    return _candidates(branches, cells[on], status[on])


def _candidates(branches, cells, status):
    """The :class:`Candidate` at each cell of ``branches`` (:class:`_Branches`), with
    its status: centred on the cell's pixel, directed along its branch (the
    unit vector from the pixel 3 before it to the one 3 after, within the
    branch; ``(1, 0)`` where they coincide), all directions at once."""
    k = branches.branch[cells]
    s, n = branches.start[k], branches.n[k]
    i = cells - s
    P = branches.path
    # path differences are integers: the norms are exact, as np.linalg.norm's of each
    d = P[s + np.minimum(i + 3, n - 1)] - P[s + np.maximum(i - 3, 0)]
    norm = np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1])
    zero = norm == 0
    d[zero] = (1.0, 0.0)
    norm[zero] = 1.0
    direction = d / norm[:, None]
    centroid = P[cells]
    radius = branches.rad[cells].tolist()
    keys = branches.keys
    return [Candidate(edge=keys[kk], centroid=c, direction=dv, radius=r, status=st)
            for kk, c, dv, r, st in zip(k.tolist(), centroid, direction, radius, status)]


class _Branches:
    """The branches of a skeleton graph ``G`` laid end to end, in the order of
    their ``(u, v, key)``: clearance (px), arc length from the branch's start
    pixel and from its end pixel (px), the running maximum of the clearance
    from either end, the pixels ``path`` (floats); per branch its first cell
    ``start``, length ``n``, smallest clearance ``low`` and end nodes ``u``,
    ``v`` (as in its key, as indices into ``G.nodes``).

    Running sums are taken branch by branch in order (the branches padded
    into rows, :func:`_accumulate_runs`), and running maxima on ranks
    (:func:`_running_max`), so every value is the one :func:`numpy.cumsum` /
    :func:`numpy.maximum.accumulate` of the branch alone gives.
    """

    def __init__(self, G):
        res = G.graph.get("resolution", 1.0)
        # keys and data in one pass (not a G.edges[k] look-up per branch)
        edges = sorted(G.edges(keys=True, data=True), key=itemgetter(0, 1, 2))
        self.keys = [e[:3] for e in edges]
        self.data = [e[3] for e in edges]
        E = len(self.keys)
        self.n = n = np.array([d["radius"].size for d in self.data], np.intp)
        self.start = start = np.cumsum(n) - n
        if E == 0:
            return
        self.branch = np.repeat(np.arange(E), n)
        self.rad = R = np.concatenate([d["radius"] for d in self.data]) / res
        self.low = np.full(E, np.inf)
        has = n > 0
        self.low[has] = np.minimum.reduceat(R, start[has]) if R.size else np.inf
        self.path = P = np.concatenate([d["path"] for d in self.data]).astype(float)
        step = np.zeros(R.size)
        step[1:] = np.hypot(*np.diff(P, axis=0).T)
        step[start[has]] = 0.0
        self.arc = A = _accumulate_runs(np.add, step, n)
        last = np.repeat(start + n - 1, n)
        back = start[self.branch] + last - np.arange(R.size)  # the same cell counted from the branch's end
        self.arc_back = A[last] - A[back]
        self.pm, self.pm_back = _running_max(R, self.branch, back)
        # end nodes as indices into G.nodes, and every branch's incidences sorted by node
        # (node, branch, from its start?, a loop?), for :meth:`beyond`
        index = {x: i for i, x in enumerate(G.nodes)}
        self.u = u = np.array([index[k[0]] for k in self.keys], np.intp)
        self.v = v = np.array([index[k[1]] for k in self.keys], np.intp)
        at = np.array([index[d["start"]] if d["radius"].size else -1 for d in self.data], np.intp)
        i = np.flatnonzero(has)
        two = i[u[i] != v[i]]
        node, br = np.r_[u[i], v[two]], np.r_[i, two]
        fwd, loop = np.r_[at[i] == u[i], at[two] == v[two]], np.r_[u[i] == v[i], np.zeros(two.size, bool)]
        o = np.argsort(node, kind="stable")
        self._inc_b, self._inc_fwd, self._inc_loop = br[o], fwd[o], loop[o]
        self._inc_at = np.searchsorted(node[o], np.arange(len(index) + 1))
        self._key_f = self.branch + 1j * A
        # forward and backward arc lengths in one sorted key (backward branches numbered from E)
        self._key_fb = np.r_[self._key_f, (self.branch + E) + 1j * self.arc_back]
        self._pm_fb = np.r_[self.pm, self.pm_back]
        self._rad_end = np.append(R, 0.0)  # for range_max: every range's end an index of the array

    def cell_at(self, e, x, side):
        """First cell of each branch ``e`` whose arc length is >= ``x`` (``side="left"``) or > ``x``."""
        return np.searchsorted(self._key_f, e + 1j * np.asarray(x, float), side=side)

    def range_max(self, lo, hi):
        """Largest clearance over the cells ``lo..hi-1`` of each range; 0 for an empty one."""
        lo, hi = np.asarray(lo), np.asarray(hi)
        out = np.zeros(lo.shape)
        ok = hi > lo
        if ok.any():
            out[ok] = np.maximum.reduceat(self._rad_end, np.stack([lo[ok], hi[ok]], 1).ravel())[::2]
        return out

    def beyond(self, nodes, edges, rem):
        """Largest clearance within ``rem`` px past each node (an index into ``G.nodes``),
        along its branches other than branch ``edges`` (0 where ``rem <= 0`` or there is
        none): ``(m,)`` floats.

        All at once: every (query, incident branch) pair, one search of the
        arc lengths (not one Python look-up per pair); maxima are exact in any
        order.
        """
        rem = np.asarray(rem, float)
        out = np.zeros(rem.size)
        q = np.flatnonzero(rem > 0)
        if q.size == 0:
            return out
        nodes, edges = np.asarray(nodes)[q], np.asarray(edges)[q]
        lo, hi = self._inc_at[nodes], self._inc_at[nodes + 1]
        j = ranges(lo, hi)
        qq = np.repeat(q, hi - lo)
        b = self._inc_b[j]
        keep = (b != np.repeat(edges, hi - lo)) | self._inc_loop[j]
        j, qq, b = j[keep], qq[keep], b[keep]
        if j.size == 0:
            return out
        b = np.where(self._inc_fwd[j], b, b + len(self.keys))
        # the last cell within rem of the node: searchsorted(arc of the branch, rem, "right") - 1
        c = np.searchsorted(self._key_fb, b + 1j * rem[qq], side="right") - 1
        np.maximum.at(out, qq, self._pm_fb[c])
        return out


def _running_max(x, run, back):
    """The running maximum of each run of ``x`` (``run`` the run of every
    value, non-decreasing) from its start, and of ``x[back]`` (each run
    reversed, ``back`` a permutation within the runs).

    On ranks, whole array at once: every rank of a run offset past those of
    the runs before, so a maximum never carries over into the next run. A
    maximum is one of its values: the same as one ``np.maximum.accumulate``
    a run, and quicker than runs padded into rows.
    """
    order = np.argsort(x, kind="stable")
    rank = np.empty(x.size, np.intp)
    rank[order] = np.arange(x.size)
    off = run * x.size
    return (x[order[np.maximum.accumulate(off + rank) - off]],
            x[order[np.maximum.accumulate(off + rank[back]) - off]])


def _accumulate_runs(ufunc, x, n):
    """``ufunc.accumulate`` of each run of ``x`` (consecutive, lengths ``n``) on its own, as one array.

    The runs are grouped by length (up to twice the shortest in a group) into
    rows padded at their ends, accumulated along the rows: the same values,
    in the same order of operations, as one ``accumulate`` per run. When
    padding every run to the longest costs little, they make one group.
    """
    out = np.empty_like(x)
    start = np.cumsum(n) - n
    size = np.ceil(np.log2(np.maximum(n, 1))).astype(int)
    if n.size and n.size * int(n.max()) <= 4 * int(n.sum()) + 4096:
        size[:] = 0
    for s in np.unique(size[n > 0]):
        g = np.flatnonzero((size == s) & (n > 0))
        L = int(n[g].max())
        cols = ranges(np.zeros(g.size, np.intp), n[g])
        rows = np.repeat(np.arange(g.size), n[g])
        src = cols + np.repeat(start[g], n[g])
        M = np.zeros((g.size, L), x.dtype)
        M[rows, cols] = x[src]
        out[src] = ufunc.accumulate(M, axis=1)[rows, cols]
    return out


def protrusion_at(free: np.ndarray, points, radius_px: float, look_px: int) -> np.ndarray:
    """:func:`protrusion` evaluated only near ``points``: for each point, the
    largest protrusion of an obstacle cell within ``look_px`` (Chebyshev) of
    it, 0 where there is none. Same values as filtering the whole map, at the
    cost of a small window per point.

    Kernels are cut to the area they can reach (the map or the window, which
    lies outside only zeros), so memory stays within the map's size however
    large ``radius_px`` and ``look_px`` are (a long thin corridor)."""
    import cv2

    H, W = free.shape
    r = max(int(round(radius_px)), 1)

    def kernel(a, b):
        # disk(r) / its cell count, rows -a..a and columns -b..b only
        if a >= r and b >= r:
            k = disk(r, np.float32)
            k /= k.sum()
            return k
        count = sum(2 * math.isqrt(r * r - y * y) + 1 for y in range(-r, r + 1))  # cells of disk(r)
        y, x = np.ogrid[-a:a + 1, -b:b + 1]
        return (x * x + y * y <= r * r).astype(np.float32) / np.float32(count)

    out = np.zeros(len(points))
    pad = r + look_px
    if len(points) * (2 * pad + 1) ** 2 > free.size:
        # many posts: one filter over the whole map is cheaper than windows
        fr = cv2.filter2D(free.astype(np.float32), -1, kernel(min(r, H - 1), min(r, W - 1)),
                          borderType=cv2.BORDER_CONSTANT)
        la, lb = min(look_px, H - 1), min(look_px, W - 1)
        fr = cv2.dilate(np.where(free, 0, fr).astype(np.float32), np.ones((2 * la + 1, 2 * lb + 1), np.uint8))
        for n, p in enumerate(points):
            out[n] = fr[min(max(int(round(float(p[0]))), 0), H - 1), min(max(int(round(float(p[1]))), 0), W - 1)]
        return out
    kernels = {}
    seen = {}  # posts on the same cell share a window, hence a value
    inner = []  # posts whose window lies wholly inside the map: filtered together below
    same = []  # (post, the first post on its cell)
    for n, p in enumerate(points):
        pr, pc = int(round(float(p[0]))), int(round(float(p[1])))
        if (pr, pc) in seen:
            same.append((n, seen[pr, pc]))
            continue
        seen[pr, pc] = n
        if pad <= pr < H - pad and pad <= pc < W - pad:
            inner.append((n, pr, pc))
            continue
        ra, rb = max(pr - pad, 0), min(pr + pad + 1, H)
        ca, cb = max(pc - pad, 0), min(pc + pad + 1, W)
        win = free[ra:rb, ca:cb].astype(np.float32)
        a, b = min(r, rb - ra - 1), min(r, cb - ca - 1)
        k = kernels.get((a, b))
        if k is None:
            k = kernels[a, b] = kernel(a, b)
        # zero padding outside the map, as the whole-map filter does
        full = np.zeros((rb - ra + 2 * a, cb - ca + 2 * b), np.float32)
        full[a:a + rb - ra, b:b + cb - ca] = win
        fr = cv2.filter2D(full, -1, k, borderType=cv2.BORDER_CONSTANT)[a:a + rb - ra, b:b + cb - ca]
        # only cells near the post that are obstacles *and* whose disk lies
        # inside the window are exact; the look area is well inside
        la, lb = max(pr - look_px, 0) - ra, min(pr + look_px + 1, H) - ra
        lc, ld = max(pc - look_px, 0) - ca, min(pc + look_px + 1, W) - ca
        sub = np.where(win[la:lb, lc:ld] > 0, 0.0, fr[la:lb, lc:ld])
        out[n] = float(sub.max()) if sub.size else 0.0
    if inner:
        # the windows side by side, each with its own zero margin of r cells, in one filter
        side = 2 * pad + 1
        idx = np.array(inner)
        rr = idx[:, 1, None] + np.arange(-pad, pad + 1)  # (m, side) rows and columns of every window
        cc = idx[:, 2, None] + np.arange(-pad, pad + 1)
        wins = free[rr[:, :, None], cc[:, None, :]].astype(np.float32)  # (m, side, side)
        strip = np.zeros((side + 2 * r, len(inner), side + 2 * r), np.float32)
        strip[r:r + side, :, r:r + side] = wins.transpose(1, 0, 2)
        k = kernels.get((r, r))
        if k is None:
            k = kernels[r, r] = kernel(r, r)
        fr = cv2.filter2D(strip.reshape(side + 2 * r, -1), -1, k, borderType=cv2.BORDER_CONSTANT)
        fr = fr.reshape(side + 2 * r, len(inner), side + 2 * r)[r:r + side, :, r:r + side].transpose(1, 0, 2)
        look = slice(pad - look_px, pad + look_px + 1)  # the cells within look_px of the post
        sub = np.where(wins[:, look, look] > 0, 0.0, fr[:, look, look])
        out[idx[:, 0]] = sub.reshape(len(inner), -1).max(axis=1)
    for n, first in same:  # posts on a cell seen before take its value
        out[n] = out[first]
    return out


def _mouths(branches, k, r_lo, r_hi, reach_px, rise_px, tol_px: float = 1.0, min_run_px: float = 0.0):
    """One-sided bottlenecks at the ends of runs of minima (cells ``r_lo..r_hi``
    of ``branches``, :class:`_Branches`, on branches ``k``): where a passage of even
    width (a corridor, at least ``min_run_px`` long within ``tol_px``) opens
    into a wider space. The clearance rises by ``2 * rise_px`` on one side
    within ``reach_px`` and does not fall below the run's value minus
    ``tol_px`` on the other.

    All runs at once, on every cell of each run's branch (the same
    element-wise arithmetic as one branch at a time, and exact minima and
    maxima).

    Returns
    -------
    hi, lo : (m,) ndarray of int
        Per run, the cell of its mouth at the far end of its plateau and at
        the near end (the direction of the branch), or -1 where there is none.
    """
    R, A = branches.rad, branches.arc
    none = np.full(len(k), -1)
    if len(k) == 0:
        return none, none
    s, n = branches.start[k], branches.n[k]
    X = ranges(s, s + n)  # every cell of each run's branch
    Q = np.repeat(np.arange(len(k)), n)
    at = np.cumsum(n) - n  # each run's first entry in X
    RX, AX = R[X], A[X]
    # the plateau around the run: neighbours within ``tol_px`` of its minimum
    base = np.minimum.reduceat(branches._rad_end, np.stack([r_lo, r_hi + 1], 1).ravel())[::2]
    above = RX > (base + tol_px)[Q]
    lo = np.maximum.reduceat(np.where(above & (X < r_lo[Q]), X, (s - 1)[Q]), at) + 1
    hi = np.minimum.reduceat(np.where(above & (X > r_hi[Q]), X, (s + n)[Q]), at) - 1
    # too short a stretch of even width to be a corridor
    long = ~(A[hi] - A[lo] < min_run_px)
    end = A[s + n - 1]
    far = branches.beyond(np.r_[branches.v[k], branches.u[k]], np.r_[k, k],
                          np.r_[reach_px - (end - A[hi]), reach_px - A[lo]])
    out = []
    for j, (i, far_q) in enumerate(((hi, far[:len(k)]), (lo, far[len(k):]))):
        r = R[i]
        ai = A[i][Q]
        fw = (AX > ai) & (AX - ai <= reach_px)
        bw = (AX < ai) & (ai - AX <= reach_px)
        ahead, back = (fw, bw) if j == 0 else (bw, fw)
        up = np.maximum(np.maximum.reduceat(np.where(ahead, RX, -np.inf), at), 0.0)
        up = np.maximum(up, far_q)
        b_min = np.minimum.reduceat(np.where(back, RX, np.inf), at)
        b_max = np.maximum.reduceat(np.where(back, RX, -np.inf), at)
        b_any = np.add.reduceat(back, at) > 0
        ok = long & ~(up < r + 2 * rise_px) & b_any & ~(b_min < r - tol_px) & ~(b_max >= r + rise_px)
        out.append(np.where(ok, i, -1))
    return out[0], out[1]


def protrusion(obstacle_like_free: np.ndarray, radius_px: float) -> np.ndarray:
    """Fraction of free cells in a disk of ``radius_px`` around every cell.

    On an obstacle cell this measures how far the obstacle protrudes into
    free space: about 0.5 on a straight wall, 0.75 at a right-angled convex
    corner, close to 1 at the end of a thin wall, below 0.5 in a concave
    corner.
    """
    import cv2

    r = max(int(round(radius_px)), 1)
    k = disk(r, np.float32)
    k /= k.sum()
    return cv2.filter2D(obstacle_like_free.astype(np.float32), -1, k, borderType=cv2.BORDER_CONSTANT)


#: Pairs of cells :func:`nearest_wall_points` measures at once, at most (or one candidate's).
_PAIR_BLOCK = 1 << 20


def _window_cells(mask: np.ndarray, top: int, width: int, ra, rb, ca, cb):
    """The cells of ``mask`` in windows ``[ra:rb, ca:cb]``, all windows at once.

    Parameters
    ----------
    mask : (M, width) ndarray of bool
        Rows ``top`` to ``top + M`` of a map ``width`` columns wide.
    top, width : int
    ra, rb, ca, cb : (K,) ndarray of int
        Window bounds, inside the map's rows ``top`` to ``top + M``.

    Returns
    -------
    rows, cols, seg : ndarray of int
        The cells window after window, each window's in the order of
        :func:`numpy.nonzero` of its slice (row-major); ``seg`` the window of
        each cell.
    """
    lin = np.flatnonzero(mask) + top * width
    win = np.repeat(np.arange(len(ra)), rb - ra)
    row = ranges(ra, rb)
    lo = np.searchsorted(lin, row * width + ca[win])
    hi = np.searchsorted(lin, row * width + cb[win])
    n = hi - lo
    rows = np.repeat(row, n)
    return rows, lin[ranges(lo, hi)] - rows * width, np.repeat(win, n)


def _window_faces(obstacle: np.ndarray, ra, rb, ca, cb, faces=None):
    """:func:`~topomap.core.walls.wall_faces` of the windows ``[ra:rb, ca:cb]`` of
    ``obstacle`` (a cell outside its window is not free), all windows at once.

    From the map's faces over the rows the windows span, the cells on a
    window's edge checked again, when that is cheaper than one window at a
    time (windows far apart on a large map).

    Parameters
    ----------
    obstacle : (M, N) ndarray of bool
    ra, rb, ca, cb : (K,) ndarray of int
        Window bounds, inside the map.
    faces : (M, N) ndarray of bool, optional
        ``wall_faces(obstacle, ~obstacle)``, when the caller has them.

    Returns
    -------
    rows, cols, seg : ndarray of int
        As :func:`_window_cells`.
    """
    H, W = obstacle.shape
    top, bot = int(ra.min()), int(rb.max())
    area = int(((rb - ra) * (cb - ca)).sum())
    if (bot - top) * W > 4 * area + 4000 * len(ra):
        parts = []
        for k in range(len(ra)):
            win = obstacle[ra[k]:rb[k], ca[k]:cb[k]]
            r, c = np.nonzero(wall_faces(win, ~win))
            parts.append((r + ra[k], c + ca[k]))
        n = [p[0].size for p in parts]
        return (np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]),
                np.repeat(np.arange(len(ra)), n))
    if faces is None:
        band = obstacle[top:bot]
        faces = wall_faces(band, ~band)
    else:  # a cell's face state depends on its 4-neighbours only: the band's rows away from its edges
        faces = faces[top:bot]
    rr, cc, seg = _window_cells(faces, top, W, ra, rb, ca, cb)
    # on a window's edge, the free neighbour may lie outside the window
    edge = np.flatnonzero((rr == ra[seg]) | (rr == rb[seg] - 1) | (cc == ca[seg]) | (cc == cb[seg] - 1))
    er, ec, es = rr[edge], cc[edge], seg[edge]
    surf = np.zeros(edge.size, bool)
    for dr, dc in ((-1, 0), (1, 0), (0, -1), (0, 1)):
        rn, cn = er + dr, ec + dc
        inside = (rn >= ra[es]) & (rn < rb[es]) & (cn >= ca[es]) & (cn < cb[es])
        surf |= inside & ~obstacle[np.clip(rn, 0, H - 1), np.clip(cn, 0, W - 1)]
    on = np.ones(rr.size, bool)
    on[edge[~surf]] = False
    return rr[on], cc[on], seg[on]


def _strip_cells(u0, u1, r0, c0, ra, rb, ca, cb):
    """Per window, the cells ``x`` with ``-m < (x - p) . u <= 0`` (``p = (r0,
    c0)``, ``u`` a non-zero integer vector, ``m = max(|u0|, |u1|)``): one cell a
    row (``|u1| >= |u0|``) or a column, the edge of the half-plane
    ``(x - p) . u <= 0``.

    Returns
    -------
    rows, cols, seg : ndarray of int
        The cells inside their windows; ``seg`` the window of each.
    """
    by_row = np.abs(u1) >= np.abs(u0)
    # along the rows: t = -y u0, x u1 in (t - m, t]; along the columns the same, transposed
    lo, hi = np.where(by_row, ra - r0, ca - c0), np.where(by_row, rb - r0, cb - c0)
    seg = np.repeat(np.arange(len(ra)), hi - lo)
    y = ranges(lo, hi)
    a, b = np.where(by_row, u0, u1)[seg], np.where(by_row, u1, u0)[seg]
    t = -y * a
    x = np.where(b > 0, t // np.where(b == 0, 1, b), -((-t) // np.where(b == 0, 1, b)))
    rows = np.where(by_row[seg], y + r0[seg], x + r0[seg])
    cols = np.where(by_row[seg], x + c0[seg], y + c0[seg])
    dot = (rows - r0[seg]) * u0[seg] + (cols - c0[seg]) * u1[seg]
    m = np.maximum(np.abs(u0), np.abs(u1))[seg]
    ok = ((dot > -m) & (dot <= 0) & (rows >= ra[seg]) & (rows < rb[seg])
          & (cols >= ca[seg]) & (cols < cb[seg]))
    return rows[ok], cols[ok], seg[ok]


def _first_minima(x: np.ndarray, counts: np.ndarray):
    """Per segment of ``x`` (``counts[k]`` values each, one segment after
    the other): the smallest value (inf for an empty segment) and the index
    in ``x`` of its first occurrence (what :func:`numpy.argmin` gives; -1 for
    an empty segment)."""
    xmin = np.full(counts.size, np.inf)
    idx = np.full(counts.size, -1)
    has = counts > 0
    if x.size:
        starts = (np.cumsum(counts) - counts)[has]
        xmin[has] = np.minimum.reduceat(x, starts)
        pos = np.flatnonzero(x == np.repeat(xmin, counts))
        idx[has] = pos[np.searchsorted(pos, starts)]
    return xmin, idx


def _nearest_wall_points_one(c, obstacle: np.ndarray, max_px: float, depth_px: float) -> None:
    """:func:`nearest_wall_points` for one candidate, on its own window."""
    H, W = obstacle.shape
    R = int(np.ceil(min(c.radius * 1.5 + 3 + depth_px, max_px + depth_px)))
    r0, c0 = int(round(c.centroid[0])), int(round(c.centroid[1]))
    ra, rb = max(r0 - R, 0), min(r0 + R + 1, H)
    ca, cb = max(c0 - R, 0), min(c0 + R + 1, W)
    win = obstacle[ra:rb, ca:cb]
    rr, cc = np.nonzero(win)
    c.ip1 = c.ip2 = None
    if rr.size == 0:
        return
    q = np.stack([rr + ra, cc + ca], 1).astype(float)
    v = q - c.centroid
    d = np.hypot(v[:, 0], v[:, 1])
    i = int(np.argmin(d))
    if d[i] > max_px:
        return
    opp = (v @ v[i]) <= 0
    if not opp.any():
        c.ip1 = q[i]
        return
    j = np.flatnonzero(opp)[np.argmin(d[opp])]
    if d[j] > max_px:
        c.ip1 = q[i]
        return
    c.ip1, c.ip2 = q[i], q[j]
    if depth_px <= 0 or c.status == MOUTH:
        return
    # closest pairs of cells across a passage lie on the obstacles'
    # surface: only cells with a free 4-neighbour are paired (keeps the
    # pairing linear in the window's side, not in its area)
    on_surface = wall_faces(win, ~win)[rr, cc]
    a = q[(~opp) & (d <= d[i] + depth_px) & on_surface]
    b = q[opp & (d <= d[j] + depth_px) & on_surface]
    if a.size and b.size:
        D = np.hypot(a[:, None, 0] - b[None, :, 0], a[:, None, 1] - b[None, :, 1])
        ia, ib = np.nonzero(D <= D.min() + 0.75)
        c.ip1, c.ip2 = a[ia].mean(axis=0), b[ib].mean(axis=0)


def nearest_wall_points(candidates, obstacle: np.ndarray, *, max_px: float, depth_px: float = 0.0, faces=None):
    """Set ``ip1``, ``ip2``: the two door posts of each bottleneck.

    The nearest obstacle cell to the bottleneck and the nearest one on the
    opposite side (at least 90° apart, seen from the bottleneck) give the
    width of the passage; then, among the obstacle cells within
    ``depth_px`` of those distances, every pair (one cell per side) as close
    as the closest pair (within 0.75 px) is averaged. Where the passage has
    parallel faces, such as a gap between two wall ends, the door line thus
    runs through the middle of the wall's thickness, wherever along the
    passage the skeleton's minimum lies. Cells farther than ``max_px`` are
    not searched. ``faces``: :func:`~topomap.core.walls.wall_faces` of
    ``obstacle``, when the caller has them (else found here).

    Candidates centred on a free cell (all of :func:`passage_minima`'s)
    are handled all at once, on the surface cells of their windows (and
    the few cells on the edge of the opposite side that can be nearest
    there): every difference, dot product and sum is then exact in
    floating point, so the posts are bit for bit those of one window at a
    time; other candidates take one window each. Time and memory are linear
    in the map's rows spanned by the windows, plus the windows' cells.
    """
    H, W = obstacle.shape
    batch, cen = _free_centred(candidates, obstacle, max_px, depth_px)
    K = len(batch)
    if K == 0:
        return candidates
    R = np.array([int(np.ceil(min(c.radius * 1.5 + 3 + depth_px, max_px + depth_px))) for c in batch])
    r0, c0 = cen[:, 0].astype(int), cen[:, 1].astype(int)
    box = (np.maximum(r0 - R, 0), np.minimum(r0 + R + 1, H), np.maximum(c0 - R, 0), np.minimum(c0 + R + 1, W))
    # Only surface cells (an obstacle cell with a free 4-neighbour inside its
    # window) can be nearest to a free centre: the neighbour towards the
    # centre is nearer.
    rr, cc, seg = _window_faces(obstacle, *box, faces)
    if rr.size == 0:
        return candidates
    counts = np.bincount(seg, minlength=K)
    q0, q1 = rr.astype(float), cc.astype(float)
    v0, v1 = q0 - np.repeat(cen[:, 0], counts), q1 - np.repeat(cen[:, 1], counts)
    d = np.hypot(v0, v1)
    di, i = _first_minima(d, counts)
    # integers: the sign of v @ v[i] is exact whatever the order of the sums
    u0, u1 = v0[i].astype(int), v1[i].astype(int)
    dot = v0 * np.repeat(v0[i], counts) + v1 * np.repeat(v1[i], counts)
    opp = dot <= 0
    has = (counts > 0) & (di <= max_px)
    jr, jc, dj, firsts = _nearest_opposite(obstacle, cen, (rr[opp], cc[opp], seg[opp]), has, (u0, u1), (r0, c0), box)
    for k, c in enumerate(batch):
        if i[k] < 0 or di[k] > max_px:
            continue
        c.ip1 = np.array([q0[i[k]], q1[i[k]]])
        if firsts[k] >= 0 and dj[k] <= max_px:
            c.ip2 = np.array([float(jr[firsts[k]]), float(jc[firsts[k]])])
    if depth_px <= 0:
        return candidates
    pair = np.array([c.ip2 is not None and c.status != MOUTH for c in batch])
    sel = np.repeat(pair, counts) & np.where(opp, d <= np.repeat(dj, counts) + depth_px,
                                             d <= np.repeat(di, counts) + depth_px)
    keep = np.flatnonzero(sel)
    side = opp[keep]
    # each cell's distance to the line between the sides
    h = np.abs(dot) / np.repeat(np.hypot(u0, u1), counts)
    a, b = _pair_sides(keep[~side], keep[side], h, seg, q0[i], q1[i], q0, q1)
    _average_closest_pairs(batch, q0, q1, a, b, seg)
    return candidates


def _free_centred(candidates, obstacle: np.ndarray, max_px: float, depth_px: float):
    """``(batch, cen)``: the candidates centred on a free cell of ``obstacle`` and their centres
    ((K, 2) float), for :func:`nearest_wall_points` to handle at once; the posts of every candidate
    cleared, those of the others set one window each (:func:`_nearest_wall_points_one`)."""
    H, W = obstacle.shape
    cands = list(candidates)
    cen = np.array([c.centroid for c in cands], float).reshape(len(cands), 2)
    whole = np.all((cen == np.round(cen)) & (cen >= 0) & (cen < (H, W)), axis=1)
    whole[whole] = ~obstacle[cen[whole, 0].astype(int), cen[whole, 1].astype(int)]
    batch = [c for c, w in zip(cands, whole) if w]
    for c, w in zip(cands, whole):
        c.ip1 = c.ip2 = None
        if not w:
            _nearest_wall_points_one(c, obstacle, max_px, depth_px)
    return batch, cen[whole]


def _nearest_opposite(obstacle: np.ndarray, cen: np.ndarray, opposite, has: np.ndarray, u, centre, box):
    """``(jr, jc, dj, firsts)``: the nearest obstacle cell on the side opposite the nearest one, per
    candidate of :func:`nearest_wall_points`.

    ``opposite``: the windows' surface cells on that side ``(rows, cols, window)``; ``has``: the
    candidates with a nearest cell in reach; ``u``: the vectors ``(u0, u1)`` from each centre
    ``centre`` (``(r0, c0)``) to its nearest cell; ``box``: the windows ``(ra, rb, ca, cb)``.
    Returns the cells searched (``jr``, ``jc``), each candidate's smallest distance ``dj`` (inf:
    none) and the index in ``jr``/``jc`` of its nearest cell (-1: none).

    The nearest cell on the other side (v . u <= 0) is on the surface too,
    or its neighbour towards the centre lies on the near side: then it is
    on the half-plane's edge, -max(|u|) < v . u <= 0, one cell a row or a
    column; the first of the nearest in row-major order, as in one window.
    """
    K, W = len(cen), obstacle.shape[1]
    (u0, u1), (r0, c0), (ra, rb, ca, cb) = u, centre, box
    sr, sc, ss = _strip_cells(u0[has], u1[has], r0[has], c0[has], ra[has], rb[has], ca[has], cb[has])
    ss = np.flatnonzero(has)[ss]
    o = obstacle[sr, sc]
    sr, sc, ss = sr[o], sc[o], ss[o]
    jr, jc, js = np.r_[opposite[0], sr], np.r_[opposite[1], sc], np.r_[opposite[2], ss]
    order = np.argsort(js, kind="stable")
    jr, jc, js = jr[order], jc[order], js[order]
    jd = np.hypot(jr - cen[js, 0], jc - cen[js, 1])
    jn = np.bincount(js, minlength=K)
    dj, _ = _first_minima(jd, jn)
    at = np.flatnonzero(jd == np.repeat(dj, jn))
    lin = jr[at] * W + jc[at]
    firsts = np.full(K, -1)
    if at.size:
        # the smallest linear index of the nearest cells, per candidate
        o = np.lexsort((lin, js[at]))
        at = at[o][np.r_[True, js[at][o][1:] != js[at][o][:-1]]]
        firsts[js[at]] = at
    return jr, jc, dj, firsts


def _pair_sides(a: np.ndarray, b: np.ndarray, h: np.ndarray, seg: np.ndarray, near0: np.ndarray,
                near1: np.ndarray, q0: np.ndarray, q1: np.ndarray):
    """``(a, b)``: the cells of the near side ``a`` and the opposite side ``b`` (indices into the
    windows' cells ``q0``, ``q1``, of window ``seg``) that can be in a pair within 0.75 px of the
    closest pair of their window.

    A pair is at least as long as its cells' distances ``h`` to the line between
    the sides; the pair of the nearest cell (``near0``, ``near1``: per window) with its closest
    partner bounds the closest pair: cells that cannot be in a pair within
    0.75 px of the closest are left out (0.05 px to spare for rounding).
    """
    K = near0.size
    ub2 = np.full(K, np.inf)
    np.minimum.at(ub2, seg[b], (q0[b] - near0[seg[b]]) ** 2 + (q1[b] - near1[seg[b]]) ** 2)
    ha, hb = np.full(K, np.inf), np.full(K, np.inf)
    np.minimum.at(ha, seg[a], h[a])
    np.minimum.at(hb, seg[b], h[b])
    lim = np.sqrt(ub2) + 0.8
    return a[h[a] + hb[seg[a]] <= lim[seg[a]]], b[h[b] + ha[seg[b]] <= lim[seg[b]]]


def _average_closest_pairs(batch: list, q0: np.ndarray, q1: np.ndarray, a: np.ndarray, b: np.ndarray,
                           seg: np.ndarray) -> None:
    """Set the posts ``ip1``, ``ip2`` of each candidate of ``batch`` with cells on both sides
    (``a``, ``b``: :func:`_pair_sides`) to the means of the ends of its pairs of cells as close as
    its closest pair (within 0.75 px)."""
    K = len(batch)
    sa, sb = seg[a], seg[b]
    ks = np.arange(K)
    a_lo, na = np.searchsorted(sa, ks), np.bincount(sa, minlength=K)
    b_lo, nb = np.searchsorted(sb, ks), np.bincount(sb, minlength=K)
    ks = ks[(na > 0) & (nb > 0)]
    qa0, qa1, qb0, qb1 = q0[a], q1[a], q0[b], q1[b]
    # every pair of cells (one per side) of a candidate, a block of
    # candidates at a time (memory bounded by the largest candidate's pairs)
    npair = na[ks] * nb[ks]
    cum = np.cumsum(npair)
    start = 0
    while start < ks.size:
        stop = max(int(np.searchsorted(cum, cum[start] - npair[start] + _PAIR_BLOCK, "right")), start + 1)
        kk, nk = ks[start:stop], npair[start:stop]
        start = stop
        ai = ranges(a_lo[kk], a_lo[kk] + na[kk])
        rep = nb[sa[ai]]
        pb = ranges(b_lo[sa[ai]], b_lo[sa[ai]] + rep)
        # squared distances are exact integers: the closest pairs are found
        # on them, and only pairs that can be within 0.75 px of the closest
        # measured as the windowed search did (np.hypot)
        dr, dc = np.repeat(qa0[ai], rep) - qb0[pb], np.repeat(qa1[ai], rep) - qb1[pb]
        sq = dr * dr + dc * dc
        starts = np.cumsum(nk) - nk
        bound = (np.sqrt(np.minimum.reduceat(sq, starts)) + 0.76) ** 2
        near = np.flatnonzero(sq <= np.repeat(bound, nk))
        ps = np.repeat(kk, nk)[near]
        D = np.hypot(dr[near], dc[near])
        pos = np.searchsorted(near, starts)
        Dmin = np.empty(K)
        Dmin[kk] = np.minimum.reduceat(D, pos)
        ok = D <= Dmin[ps] + 0.75
        pa, pb, ps = np.repeat(ai, rep)[near[ok]], pb[near[ok]], ps[ok]
        n = np.bincount(ps, minlength=K)
        # integer coordinates: the sums are exact, the means those of numpy.mean
        sums = [np.bincount(ps, weights=x, minlength=K) for x in (qa0[pa], qa1[pa], qb0[pb], qb1[pb])]
        for k in kk:
            batch[k].ip1 = np.array([sums[0][k], sums[1][k]]) / n[k]
            batch[k].ip2 = np.array([sums[2][k], sums[3][k]]) / n[k]


# --------------------------------------------------------------------------
# The default method's door stages: bottlenecks, judging, duplicates
# --------------------------------------------------------------------------

def occupied_skeleton_lines(occupied_graph):
    """The occupied-space skeleton's branches as one shapely MultiLineString
    in ``(col, row)`` order (None when there is none), for
    :func:`select_doors`."""
    from shapely.geometry import MultiLineString

    paths = [d["path"][:, ::-1].astype(float) for _, _, d in occupied_graph.edges(data=True)
             if d["path"].shape[0] >= 2]
    return MultiLineString([p.tolist() for p in paths]) if paths else None


def find_bottlenecks(free_graph, obstacle: np.ndarray, opts, resolution: float, threshold_px: float, *,
                     faces=None) -> list:
    """Stage "bottlenecks" of the default method: candidate doors with their posts.

    Clearance minima along the free-space skeleton (and, with
    ``opts.mouths``, corridor mouths; :func:`passage_minima`), then the
    door posts of each at the nearest wall cells (:func:`nearest_wall_points`).

    Parameters
    ----------
    free_graph : networkx.MultiGraph
        Free-space skeleton graph with ``radius`` along edges.
    obstacle : (M, N) ndarray of bool
        Cells a door post can be on (every non-free cell of the map doors
        are searched in).
    opts : TopomapOptions
        With ``rise`` resolved.
    resolution : float
        m/px.
    threshold_px : float
        The map's wall-thickness threshold, pixels: posts are averaged over
        cells up to this deep into the wall (at least 2 px).
    faces : (M, N) ndarray of bool, optional
        :func:`~topomap.core.walls.wall_faces` of ``obstacle``, when the caller
        has them (the walls stage does).

    Returns
    -------
    list of Candidate
        Status :data:`CANDIDATE` or :data:`MOUTH`.
    """
    res = resolution
    cands = passage_minima(free_graph, window_px=opts.window / res, rise_px=opts.rise / res,
                           reach_px=opts.reach / res, mouths=opts.mouths, min_run_px=opts.corridor_length / res,
                           max_radius_px=opts.max_door_width / np.sqrt(2) / res)
    nearest_wall_points(cands, obstacle, max_px=opts.max_door_width / res, depth_px=max(threshold_px, 2.0),
                        faces=faces)
    return cands


def _posts_plausible(cands, opts, resolution: float) -> list:
    """``(width m, candidate)`` of the candidates with posts on both sides, a
    width in range and posts facing each other; the others get their status."""
    judged = []
    for c in cands:
        if c.ip1 is None or c.ip2 is None:
            c.status = NO_WALL_BOTH_SIDES
            continue
        width = np.linalg.norm(c.ip1 - c.ip2) * resolution
        if not (opts.min_door_width <= width <= opts.max_door_width):
            c.status = WIDTH_OUT_OF_RANGE
            continue
        if width < opts.facing * 2 * c.radius * resolution:
            # the posts do not face each other across the bottleneck: it
            # lies beside a corner, not in a doorway
            c.status = POSTS_NOT_FACING
            continue
        judged.append((width, c))
    return judged


def _rule_accepts(rule: str, e_ok: bool, f1: float, f2: float, protrusion_min: float, flat_min: float) -> bool:
    """Whether the protrusion evidence satisfies ``rule`` (see
    :class:`topomap.options.TopomapOptions`): ``e_ok`` the paper's endpoint
    test at both posts, ``f1``, ``f2`` the free fractions at the posts."""
    p1, p2 = f1 >= protrusion_min, f2 >= protrusion_min
    f_ok = p1 and p2
    if rule == "either":
        return e_ok or f_ok
    if rule == "ep":
        return e_ok
    if rule == "frac":
        return f_ok
    if rule == "one":
        return p1 or p2
    # "oneflat"
    return e_ok or f_ok or (max(f1, f2) >= protrusion_min and min(f1, f2) >= flat_min)


def judge_doors(cands, free: np.ndarray, endpoints: np.ndarray, threshold_px: float, opts,
                resolution: float) -> list:
    """Stage "door judging" of the default method: which bottlenecks are doors.

    A candidate needs posts on both sides, a width between
    ``opts.min_door_width`` and ``opts.max_door_width``, posts facing each
    other (``opts.facing``) and walls that protrude at the posts as
    ``opts.rule`` asks: the paper's endpoint evidence (an occupied-skeleton
    endpoint within the threshold of each post) and/or the convexity of the
    wall (:func:`protrusion_at`, the most protruding obstacle cell within
    half the wall thickness of each post). Corridor mouths need convexity
    at both posts. Every candidate gets its status.

    Parameters
    ----------
    cands : list of Candidate
        From :func:`find_bottlenecks`.
    free : (M, N) ndarray of bool
        Free cells of the map doors are searched in.
    endpoints : (K, 2) ndarray
        Occupied-skeleton endpoints, pixels.
    threshold_px : float
        The map's wall-thickness threshold, pixels.
    opts : TopomapOptions
    resolution : float
        m/px.

    Returns
    -------
    list of (float, Candidate)
        The accepted candidates (status :data:`DOOR`) with their width in
        metres, in candidate order.
    """
    from scipy.spatial import cKDTree

    tree = cKDTree(endpoints) if endpoints.shape[0] else None
    judged = _posts_plausible(cands, opts, resolution)
    posts = [p for _, c in judged for p in (c.ip1, c.ip2)]
    look = max(int(round(threshold_px / 2)), 1)
    pvals = protrusion_at(free, posts, max(threshold_px, 0.25 / resolution), look)
    ends_ok = _wall_ends_at_posts(tree, posts, threshold_px)
    accepted = []
    for n, (width, c) in enumerate(judged):
        f1, f2 = pvals[2 * n], pvals[2 * n + 1]
        e_ok = bool(ends_ok[n])
        if width > opts.wide_opening and not e_ok:
            # wider than any door leaf: only where walls end on both sides
            c.status = WIDE_WITHOUT_WALL_ENDS
            continue
        if c.status == MOUTH:
            # a corridor opening into a room: walls must end on both sides
            ok = f1 >= opts.protrusion_min and f2 >= opts.protrusion_min
            c.status = DOOR if ok else MOUTH_WITHOUT_PROTRUDING_WALLS
        else:
            ok = _rule_accepts(opts.rule, e_ok, f1, f2, opts.protrusion_min, opts.flat_min)
            c.status = DOOR if ok else NO_PROTRUDING_WALL
        if ok:
            accepted.append((width, c))
    return accepted


def _wall_ends_at_posts(tree, posts, threshold_px: float) -> np.ndarray:
    """The paper's endpoint evidence: for each pair of posts (``posts`` the two
    posts of every candidate in turn, ``(2 n, 2)``), whether an
    occupied-skeleton endpoint (the end of a wall) lies within
    ``threshold_px`` of both: ``(n,)`` bool."""
    n = len(posts) // 2
    if tree is None or n == 0:
        return np.zeros(n, bool)
    d, _ = tree.query(np.asarray(posts, float).reshape(-1, 2))
    return (d <= threshold_px).reshape(n, 2).all(axis=1)


def across_corridor(accepted, walls, depth_px: float) -> list:
    """Stage "door judging": the accepted ``(width, Candidate)`` whose posts
    do not both lie within ``depth_px`` of two long walls the door crosses
    (:func:`topomap.core.walls.across_walls`; ``walls`` a
    :class:`~topomap.core.walls.WallIndex` or a list of long walls); those get
    :data:`ACROSS_CORRIDOR`.

    A narrowing between two things that stand out of a corridor's side
    walls by less than that — pillars, wall columns, radiators, cupboards —
    is the corridor's own; a door across a corridor sits in a wall across
    it, which stands out farther. The corridor must also run on past the
    narrowing: one of the two walls goes on at least ``depth_px`` past its
    post both ways. Where both walls end at it, the narrowing is the
    corridor's mouth — a door from its end into the room ahead, which a
    laser map draws with posts a few centimetres proud of the walls — and
    stays a door."""
    if not accepted:
        return []
    across = across_walls_many(np.array([c.ip1 for _, c in accepted], float),
                               np.array([c.ip2 for _, c in accepted], float), walls, tol_px=depth_px,
                               past_px=depth_px)
    kept = []
    for (width, c), a in zip(accepted, across):
        if a:
            c.status = ACROSS_CORRIDOR
        else:
            kept.append((width, c))
    return kept


def seen_posts(accepted, seen: np.ndarray) -> list:
    """Stage "door judging": the accepted ``(width, Candidate)`` with at
    least one post on a cell of ``seen`` (the cells within ``frontier_post``
    of an occupied cell); the others get :data:`UNEXPLORED_POSTS`.

    On a map still being explored, free space often narrows between the
    edges of what the laser has seen (unknown cells on both sides, as where
    a room was glimpsed through its door); a door stands in a wall, which
    the laser hits."""
    if not accepted:
        return []
    H, W = seen.shape
    # every post at once (not np.clip on each post alone)
    posts = np.array([(c.ip1, c.ip2) for _, c in accepted], float).reshape(-1, 2)
    rc = np.clip(np.rint(posts).astype(int), 0, [H - 1, W - 1])
    hits = seen[rc[:, 0], rc[:, 1]].reshape(-1, 2).any(axis=1)
    kept = []
    for (width, c), hit in zip(accepted, hits.tolist()):
        if hit:
            kept.append((width, c))
        else:
            c.status = UNEXPLORED_POSTS
    return kept


def opening_candidates(openings, resolution: float, *, status: str = WALL_OPENING) -> list:
    """``(width m, Candidate)`` of wall openings (:func:`topomap.core.walls.wall_openings`), or of
    gaps in thin walls (``status`` :data:`WALL_GAP`), status :data:`WALL_OPENING` by default, for
    :func:`suppress_duplicates`."""
    openings = list(openings)
    if not openings:
        return []
    # all openings at once, the same element-wise arithmetic
    P = np.array([p for p, _ in openings], float).reshape(-1, 2)
    Q = np.array([q for _, q in openings], float).reshape(-1, 2)
    V = Q - P
    n = np.hypot(V[:, 0], V[:, 1])
    centre = (P + Q) / 2
    direction = V / np.maximum(n, 1e-9)[:, None]
    width, half = (n * resolution).tolist(), (n / 2).tolist()
    return [(w, Candidate(edge=None, centroid=c, direction=d, radius=h, ip1=p, ip2=q, status=status))
            for (p, q), w, c, d, h in zip(openings, width, centre, direction, half)]


def suppress_duplicates(accepted, resolution: float, *, kept=()) -> list:
    """Stage "duplicate suppression": keep the narrowest of doors lying across each other.

    Doors are taken from the narrowest up; one whose midpoint lies within
    half its width of a door kept before (or of a segment in ``kept``) is a
    :data:`DUPLICATE`.

    Parameters
    ----------
    accepted : list of (float, Candidate)
        From :func:`judge_doors` (width in metres), or wall openings
        (:func:`opening_candidates`).
    resolution : float
        m/px.
    kept : list of ((r1, c1), (r2, c2)), optional
        Segments kept before (doors, when openings are suppressed), which
        are not returned again.

    Returns
    -------
    list of ((r1, c1), (r2, c2))
        The door segments kept, pixels, narrowest first.
    """
    accepted = sorted(accepted, key=lambda t: t[0])
    n0, n = len(kept), len(accepted)
    if not n:
        return []
    A = np.array([p for p, _ in kept] + [c.ip1 for _, c in accepted], float).reshape(-1, 2)
    B = np.array([q for _, q in kept] + [c.ip2 for _, c in accepted], float).reshape(-1, 2)
    reach = 0.5 * np.array([w for w, _ in accepted], float) / resolution
    door, seg = points_near_segments((A[n0:] + B[n0:]) / 2, reach, A, B)  # in door order
    before = seg < n0 + door  # only the segments given and the doors taken before each door
    door, seg = door[before], seg[before]
    # a door near a segment given is a duplicate whatever the doors before it; the others
    # in turn, on Python lists (quicker than a numpy look-up a door)
    dup = np.zeros(n, bool)
    dup[door[seg < n0]] = True
    other = (seg >= n0) & ~dup[door]
    door, seg = door[other], seg[other] - n0
    keep = (~dup).tolist()  # the doors kept, final for every door before the one in turn
    if door.size:
        first = np.flatnonzero(np.r_[True, door[1:] != door[:-1]])
        seg = seg.tolist()
        for i, lo, hi in zip(door[first].tolist(), first.tolist(), np.r_[first[1:], door.size].tolist()):
            if any(keep[j] for j in seg[lo:hi]):
                keep[i] = False
    segs = []
    for (_, c), k in zip(accepted, keep):
        if k:
            segs.append((c.ip1, c.ip2))
        else:
            c.status = DUPLICATE
    return segs
