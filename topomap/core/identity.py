"""Room identities that last across map updates.

A robot names its rooms, then keeps exploring or re-maps; a fresh
segmentation numbers rooms by a row-major scan of the new image, so "room 4"
may now be another room. :func:`match_rooms` gives the rooms of a new
segmentation the IDs of the rooms of a previous one (a
:class:`~topomap.core.segmentation.Segmentation`, a room graph, or a saved room
graph file) and says what changed; ``topomap.segment(grid, previous=...)``
calls it after the method has run.

Matching
--------
Every room cell of the new map is looked up in the previous rooms at the
same map-frame point (both maps' ``origin`` and ``resolution`` are used, so
the maps may differ in size, extent and cell size; a previous room graph is
read from its room polygons). The overlap of a new room ``j`` and a previous
room ``i`` (m²) is *significant* when it is at least ``min_overlap`` of the
smaller of the two rooms' parts the other map knows, and at least a tenth of
the smaller room or ``min_room_area`` (a sliver along a moved door is no
link; the doorway of a room just uncovered, which the previous map knew as
part of another room, is). Among the significant pairs a one-to-one
assignment of largest total overlap (:func:`scipy.optimize.linear_sum_assignment`)
decides which new room keeps which previous ID. Every other new room gets a
new ID, counted up from the previous ``next_room_id`` (one more than the
largest ID ever given), so an ID is never reused, not even the ID of a room
that vanished.

The change record (:class:`RoomChanges`) explains every ID that is not kept:
a previous room with two or more significant new rooms was *split* (the
piece of largest overlap keeps its ID), a new room with two or more
significant previous rooms is a *merge* (it keeps the ID of its largest
overlap), a previous room with no significant new room *vanished*, a new
room with no significant previous room is *new*.

Doors that last
---------------
Before the rooms are matched, ``topomap.segment(grid, previous=...)`` hands the
previous doors to the default method's door stage (:class:`DoorPrior`): a
previous door whose place is still a narrow passage is cut again unless a
new cut already closes it, and a new cut inside a previous room whose
surroundings did not change is dropped, so
that a door does not come and go between two versions of a map for reasons
measured far from it (the wall threshold, the clearance's noise).

Labels with stable IDs
----------------------
Room IDs are still the labels of the label image and the node keys of the
room graph, but they need not be ``1..N`` any more: IDs of vanished rooms
are gaps. Fragments follow the largest room ID (labels
``max(ID) + 1 ..``), so every free cell is still in exactly one room or one
fragment, and a label is a room exactly when it is a node of the room graph.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from typing import Optional

import numpy as np
import networkx as nx

from ..errors import ParameterError
from ..options import TopomapOptions, check_fraction
from .edit import keep_merges
from .geometry import line_pixels, point_segment_distances
from .roommap import RoomMap
from .result import MAX_ROOM_ID, ROOM_ATTRIBUTES, RoomChanges, Segmentation, TrackedSegmentation, check_room_ids

log = logging.getLogger("topomap")

__all__ = ["RoomChanges", "TrackedSegmentation", "DoorPrior", "match_rooms", "DEFAULT_MIN_OVERLAP"]

#: Default share of the smaller room two rooms must have in common to be the same room.
DEFAULT_MIN_OVERLAP = 0.5
#: Share of the smaller room an overlap must also reach (slivers along a moved door are no link).
_MIN_SHARE = 0.1


# --------------------------------------------------------------------------
# The previous rooms
# --------------------------------------------------------------------------

class _Previous:
    """Room IDs, areas (m²), user attributes and ``next_room_id`` of a previous result,
    and a lookup of its room at map-frame points."""

    def __init__(self, previous, within=None, source=None):
        if isinstance(previous, _Previous):
            self.__dict__.update(previous.__dict__)
            return
        self.offset = (0, 0)  # (row, col) of the previous frame's cell self.labels[0, 0] is
        self.name = "previous"
        if isinstance(previous, Segmentation):
            self.seg, self.G = previous, None
            self.name = previous.grid.name
            self.where = f"previous result {self.name}"
            L = self.labels = previous.room_labels
            self.grid = previous.grid
            cnt = np.bincount(L.ravel())
            ids = [int(i) for i in np.nonzero(cnt)[0] if i > 0]
            res2 = previous.grid.resolution ** 2
            self.area = {i: float(cnt[i]) * res2 for i in ids}
            self.attrs = previous.user_attributes()  # with the names a user put on the built graph
            nxt = getattr(previous, "next_room_id", None)
            self.doors = [(tuple(d.xy1), tuple(d.xy2)) for d in previous.doors]
            self.free = previous.grid.free
        elif isinstance(previous, nx.Graph):
            self.seg, self.G = None, previous
            self.name = str(previous.graph.get("map", "previous room graph"))
            self.where = source or f"previous room graph {self.name}"  # what messages name: the file, if any
            check_room_ids(previous, self.where)
            ids, self.area, self.attrs = [], {}, {}
            for r, d in previous.nodes(data=True):
                try:
                    r = int(r)
                except (TypeError, ValueError):
                    raise ParameterError(f"{self.where}: node {r!r} is not a room ID") from None
                poly = d.get("polygon")
                if poly is None or not hasattr(poly, "geom_type"):
                    raise ParameterError(f"{self.where}: room {r} has no polygon "
                                         "(build it with topomap.room_graph or load a file topomap segment wrote)")
                ids.append(r)
                self.area[r] = float(d.get("area", poly.area))
                extra = {k: v for k, v in d.items() if k not in ROOM_ATTRIBUTES}
                if extra:
                    self.attrs[r] = extra
            nxt = previous.graph.get("next_room_id")
            self.grid, self.labels, self.offset = _rasterised(previous, ids, within, self.where)
            self.doors = _graph_doors(previous)
            self.free = self.labels > 0  # a room graph knows its rooms' cells, not the map
        else:
            raise ParameterError("previous must be a Segmentation or a room graph (a saved one: "
                                 f"topomap.io.export.load_graph), got {type(previous).__name__}")
        self.ids = sorted(ids)
        top = max(self.ids, default=0) + 1
        try:
            self.next_id = max(int(nxt), top) if nxt not in (None, "") else top
        except (TypeError, ValueError):
            raise ParameterError(f"{self.where}: next_room_id {nxt!r} is not an integer") from None
        if self.ids and (self.ids[0] < 1 or self.ids[-1] > MAX_ROOM_ID) or not 1 <= self.next_id <= MAX_ROOM_ID + 1:
            raise ParameterError(f"{self.where}: room IDs {self.ids[0] if self.ids else '-'}.."
                                 f"{self.ids[-1] if self.ids else '-'} and next_room_id {self.next_id} must lie "
                                 f"in 1..{MAX_ROOM_ID} (next_room_id up to {MAX_ROOM_ID + 1})")

    def rooms_at(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Previous room ID at every map-frame point (0 = none)."""
        return self._at(self.labels, x, y)

    def free_at(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Whether the previous map was free at every map-frame point (outside it: not)."""
        return self._at(self.free, x, y)

    def _at(self, image: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """``image`` (of the previous map's cells) at every map-frame point (0 / False outside)."""
        out = np.zeros(x.shape, image.dtype)
        r, c = self.grid.world_to_pixel(x, y)
        r, c = np.rint(r).astype(np.int64) - self.offset[0], np.rint(c).astype(np.int64) - self.offset[1]
        H, W = image.shape
        ok = (r >= 0) & (r < H) & (c >= 0) & (c < W)
        out[ok] = image[r[ok], c[ok]]
        return out


#: A previous room graph is rasterised only where it overlaps the map being segmented; that window may
#: hold at most this many times the map's cells (plus :data:`PREVIOUS_WINDOW_SLACK`): a graph of a much
#: finer resolution, or whose frame is bogus, is refused before anything of its size is allocated.
PREVIOUS_WINDOW_RATIO = 16
PREVIOUS_WINDOW_SLACK = 1_000_000


def _window(ctx, within, name):
    """The half-open box ``(r0, r1, c0, c1)`` of ``ctx``'s frame that covers grid ``within`` (all of it
    when ``within`` is None); ParameterError when it holds too many cells for ``within``'s size."""
    H, W = ctx.shape
    if within is None:
        return 0, H, 0, W
    h, w = within.shape
    x, y = within.pixel_to_world(np.array([-1, -1, h, h]), np.array([-1, w, -1, w]))
    rows, cols = ctx.grid.world_to_pixel(np.asarray(x, float), np.asarray(y, float))
    if not (np.all(np.isfinite(rows)) and np.all(np.isfinite(cols))):
        return 0, 0, 0, 0
    r0, r1 = (int(min(max(v, 0), H)) for v in (np.floor(rows.min()) - 1, np.ceil(rows.max()) + 2))
    c0, c1 = (int(min(max(v, 0), W)) for v in (np.floor(cols.min()) - 1, np.ceil(cols.max()) + 2))
    cells = max(r1 - r0, 0) * max(c1 - c0, 0)
    if cells > PREVIOUS_WINDOW_RATIO * h * w + PREVIOUS_WINDOW_SLACK:
        raise ParameterError(f"{name}: its frame covers the map being segmented "
                             f"({w} x {h} cells) with {cells:,} cells of its own, more than "
                             f"{PREVIOUS_WINDOW_RATIO} times as many (another resolution, or a bogus frame)")
    return r0, max(r1, r0), c0, max(c1, c0)


def _rasterised(G, ids, within=None, name="previous room graph"):
    """The map frame of room graph ``G``, its label image where it overlaps grid ``within`` (all of the
    frame when None) and the ``(row, col)`` of the image's first cell in the frame, from the room
    polygons (which follow cell edges, so this is the label image it was built from; see
    :mod:`topomap.planning`). Time and memory are bounded by ``within``'s size, not the frame's."""
    ctx = RoomMap(G)
    w0, w1, v0, v1 = _window(ctx, within, name)
    labels = np.zeros((w1 - w0, v1 - v0), np.int32)
    for r in ids:
        box = ctx.room_bbox(r)
        if box is None:
            continue
        r0, r1, c0, c1 = max(box[0], w0), min(box[1], w1), max(box[2], v0), min(box[3], v1)
        if r0 >= r1 or c0 >= c1:
            continue
        win = ctx.window_labels([r], (r0, r1, c0, c1))
        part = labels[r0 - w0:r1 - w0, c0 - v0:c1 - v0]
        part[...] = np.where(win > 0, win, part)
    return ctx.grid, labels, (w0, v0)


# --------------------------------------------------------------------------
# Matching and relabelling
# --------------------------------------------------------------------------

def match_rooms(previous, seg: Segmentation, *, min_overlap: float = DEFAULT_MIN_OVERLAP,
                min_room_area: Optional[float] = None):
    """Give the rooms of ``seg`` the IDs of the matching rooms of ``previous``.

    Parameters
    ----------
    previous : Segmentation or networkx.MultiGraph
        The earlier result: a segmentation or its room graph (rooms need
        their ``polygon``; a graph loaded from a file ``topomap segment``
        wrote, :func:`topomap.io.export.load_graph`, has them).
    seg : Segmentation
        The new segmentation (not modified).
    min_overlap : float
        Share (0..1] of the smaller of two rooms they must have in common
        (in the map frame) to count as the same room, a split or a merge.
    min_room_area : float, optional
        An overlap (m²) of at least this area is no sliver, even when it is
        less than a tenth of the smaller room: the part of a room the robot
        has just uncovered that the previous map knew. Default: the
        ``min_room_area`` of ``seg.options`` (the smallest room), or of
        :class:`~topomap.options.TopomapOptions` for the other methods.

    Returns
    -------
    seg : TrackedSegmentation
        ``seg`` with its rooms relabelled: labels, doors' ``rooms`` and the
        room graph use the stable IDs; fragments follow the largest ID.
    changes : RoomChanges
        Kept, new, vanished, split and merged rooms (also ``seg.changes``).

    Raises
    ------
    ParameterError
        ``previous`` is not a segmentation or room graph, a previous room
        has no polygon, ``min_overlap`` is not in (0, 1] or ``min_room_area``
        is not an area > 0.
    """
    from scipy.optimize import linear_sum_assignment

    t0 = time.perf_counter()
    if check_fraction("min_overlap", min_overlap) == 0:
        raise ParameterError(f"min_overlap must be a share in (0, 1], got {min_overlap!r}")
    min_overlap = float(min_overlap)
    if min_room_area is None:
        opts = seg.options if isinstance(seg.options, TopomapOptions) else TopomapOptions()
        min_room_area = opts.min_room_area
    if not (isinstance(min_room_area, (int, float)) and np.isfinite(min_room_area) and min_room_area > 0):
        raise ParameterError(f"min_room_area must be an area > 0 (m²), got {min_room_area!r}")
    if not isinstance(seg, Segmentation):
        raise ParameterError(f"match_rooms() needs a Segmentation, got {type(seg).__name__}")
    prev = _Previous(previous, within=seg.grid)
    if any("merged" in a for a in prev.attrs.values()):  # rooms a user merged stay merged (topomap.core.edit)
        seg = keep_merges(prev, seg, min_overlap=min_overlap)
    grid = seg.grid
    res2 = grid.resolution ** 2
    L = seg.room_labels
    cnt = np.bincount(L.ravel())
    cur = [int(j) for j in np.nonzero(cnt)[0] if j > 0]  # the new rooms' labels
    area_cur = {j: float(cnt[j]) * res2 for j in cur}
    rr, cc = np.nonzero(L)
    x, y = grid.pixel_to_world(rr, cc)
    p = prev.rooms_at(np.asarray(x, float), np.asarray(y, float))
    pi = {i: k for k, i in enumerate(prev.ids)}
    # overlap (m²) of new room a (index into cur) and previous room b (index into prev.ids)
    lut_c = np.zeros(int(L.max(initial=0)) + 1, np.int64)
    lut_c[cur] = np.arange(len(cur))
    lut_p = np.full(int(p.max(initial=0)) + 1, len(prev.ids), np.int64)  # last column: no previous room
    lut_p[[i for i in prev.ids if i < lut_p.size]] = [pi[i] for i in prev.ids if i < lut_p.size]
    key = lut_c[L[rr, cc]] * (len(prev.ids) + 1) + lut_p[p]
    O = np.bincount(key, minlength=len(cur) * (len(prev.ids) + 1)).reshape(len(cur), len(prev.ids) + 1)
    O = O[:, :-1] * res2
    # rooms are compared on the part of the map both know: a room's overlap
    # with every room of the other map (the area of a room that was only
    # partly explored before, or is only partly in the new map, does not count)
    known = np.minimum.outer(O.sum(1), O.sum(0))
    whole = np.minimum.outer(np.array([area_cur[j] for j in cur], float).reshape(-1),
                             np.array([prev.area[i] for i in prev.ids], float).reshape(-1))
    # a sliver along a moved door is no link: an overlap must also be a tenth
    # of the smaller room, or at least a room's area (the part of a room just
    # uncovered that the previous map knew as part of another room)
    sig = (O > 0) & (O >= min_overlap * known) & ((O >= _MIN_SHARE * whole) | (O >= min_room_area))
    W = np.where(sig, O, 0.0)
    ids = {}
    if W.size and sig.any():
        rows, cols = linear_sum_assignment(W, maximize=True)
        for a, b in zip(rows, cols):
            if sig[a, b]:
                ids[cur[a]] = prev.ids[b]
    nxt = prev.next_id
    for j in cur:
        if j not in ids:
            ids[j] = nxt
            nxt += 1
    split = {}
    for b, i in enumerate(prev.ids):
        into = sorted(ids[cur[a]] for a in np.nonzero(sig[:, b])[0])
        if len(into) >= 2:
            split[i] = tuple(into)
    merged = {}
    for a, j in enumerate(cur):
        frm = sorted(prev.ids[b] for b in np.nonzero(sig[a])[0])
        if len(frm) >= 2:
            merged[ids[j]] = tuple(frm)
    kept_set = {i for i in ids.values() if i in pi}
    changes = RoomChanges(
        kept=tuple(sorted(kept_set)),
        new=tuple(sorted(ids[j] for a, j in enumerate(cur) if not sig[a].any())),
        vanished=tuple(sorted(i for b, i in enumerate(prev.ids) if not sig[:, b].any())),
        split=split, merged=merged, next_room_id=int(nxt))
    out = _relabelled(seg, ids, changes, {i: prev.attrs[i] for i in kept_set if i in prev.attrs})
    out.timings["match_rooms"] = time.perf_counter() - t0
    log.info("%s: room IDs follow %s: %s", grid.name, prev.name, changes.summary())
    return out, changes


def _relabelled(seg: Segmentation, ids: dict, changes: RoomChanges, attrs: dict) -> TrackedSegmentation:
    """``seg`` with room label ``j`` renamed ``ids[j]`` and fragments placed after the largest ID."""
    room_top = int(seg.room_labels.max()) if seg.labels.size else 0
    top = int(seg.labels.max()) if seg.labels.size else 0
    new_top = max(ids.values(), default=0)
    lut = np.zeros(top + 1, np.int64)
    for j, i in ids.items():
        lut[j] = i
    frag = np.arange(room_top + 1, top + 1)
    lut[frag] = new_top + np.arange(1, frag.size + 1)
    if lut.max(initial=0) > np.iinfo(np.int32).max:
        raise ParameterError(f"room IDs beyond {np.iinfo(np.int32).max}")
    labels = lut[seg.labels].astype(np.int32)
    doors = []
    for d in seg.doors:
        a, b = (int(lut[r]) for r in d.rooms)
        doors.append(dataclasses.replace(d, rooms=(min(a, b), max(a, b)), extra=dict(d.extra)))
    base = {f.name: getattr(seg, f.name) for f in dataclasses.fields(Segmentation)}
    base.update(labels=labels, doors=doors, room_count=None, _room_graph=None, timings=dict(seg.timings))
    return TrackedSegmentation(**base, room_ids=tuple(sorted(ids.values())), next_room_id=changes.next_room_id,
                               changes=changes, room_attributes=attrs)


# --------------------------------------------------------------------------
# Doors that last: the previous doors as a prior of the door stage
# --------------------------------------------------------------------------

def _graph_doors(G) -> list:
    """``[((x1, y1), (x2, y2))]``: the doors (edges) of room graph ``G`` in map-frame metres
    (an edge without its end points, as in a hand-built graph, is no door here)."""
    out = []
    for _, _, d in G.edges(data=True):
        try:
            out.append(((float(d["x1"]), float(d["y1"])), (float(d["x2"]), float(d["y2"]))))
        except (KeyError, TypeError, ValueError):
            continue
    return out


class DoorPrior:
    """The doors and free space of a previous result, as a prior of the door
    stage of a new run of the default method (``topomap.segment(grid,
    previous=...)`` makes one and hands it to
    :func:`~topomap.core.segmentation.segment_topomap`).

    A robot's map grows by a little between two versions, but the door
    decisions of a fresh run also depend on quantities measured over the
    whole map (the wall-thickness threshold, the clearance's noise), so a
    door found in one map may be missing from the next and back in the one
    after. :meth:`adjust` gives the cuts hysteresis:

    * a previous door whose place is still a narrow passage — along its
      line, a wall within ``prior_post_shift`` beyond each previous post or
      anywhere inside them (an opening that narrowed is the same door) — is
      cut again between the walls met (or a wall cell within
      ``prior_post_shift`` beside a post), across any wall now standing in
      the doorway, and from a post that is clutter on through it to the next
      wall (at most ``max_door_width`` in all), unless the new run's cuts already
      keep its two sides (``min_door_width / 2`` from its middle) apart
      within ``reach`` of it: a new cut that shares only a
      post with it, or stops short of a wall, leaves the rooms joined;
    * a new cut that lies inside a room the previous map had whole (the
      previous room on both sides of it, ``min_door_width / 2`` away, is the
      same), and that is not the same door as a previous one (each passes
      through the middle of the other, within ``min_door_width / 2``), is
      dropped when the map within ``reach`` of it did not change (at most
      ``prior_changed_area`` of cells free in one map and not in the
      other): the same walls give the same rooms.

    Parameters
    ----------
    previous : Segmentation or networkx.MultiGraph
        As for :func:`match_rooms`. From a room graph, doors are its edges'
        end points and the previous free space is its rooms' cells.
    within : OccupancyGrid, optional
        The map being segmented: a previous room graph is rasterised only
        where it overlaps it (a window of at most
        :data:`PREVIOUS_WINDOW_RATIO` times its cells), so the cost follows
        this map's size, not the frame the graph claims.
    source : str, optional
        The file ``previous`` was read from, named by the messages about it.
    """

    def __init__(self, previous, *, within=None, source=None):
        self.previous = _Previous(previous, within, source)
        d = np.asarray(self.previous.doors, float).reshape(-1, 2, 2)
        self.xy1, self.xy2 = d[:, 0], d[:, 1]

    def adjust(self, grid, segments, opts, *, walls: np.ndarray, space: np.ndarray) -> list:
        """The door segments of a new run with the previous doors taken into account.

        Parameters
        ----------
        grid : OccupancyGrid
            The map the rooms are cut from (its origin places it in the map frame).
        segments : list of ((r1, c1), (r2, c2))
            The new run's door segments, pixels of ``grid``.
        opts : TopomapOptions
            The options that ran (``prior_post_shift``, ``prior_changed_area``,
            ``reach``, ``min_door_width``, ``max_door_width``).
        walls : (M, N) ndarray of bool
            The cells door posts lie on (the non-free cells of the map doors
            are searched in, where free-standing clutter is looked through).
        space : (M, N) ndarray of bool
            The free cells rooms are cut from (clutter is not).

        Returns
        -------
        list of ((r1, c1), (r2, c2))
            ``segments`` without the dropped new cuts, then the previous
            doors cut again (those still a passage that no new cut closes).
        """
        res = grid.resolution
        K = self.xy1.shape[0]
        r1, c1 = grid.world_to_pixel(self.xy1[:, 0], self.xy1[:, 1])
        r2, c2 = grid.world_to_pixel(self.xy2[:, 0], self.xy2[:, 1])
        P, Q = np.stack([r1, c1], 1).reshape(K, 2), np.stack([r2, c2], 1).reshape(K, 2)
        S = np.asarray([np.r_[p, q] for p, q in segments], float).reshape(-1, 4)
        A, B = S[:, :2], S[:, 2:]
        same = _same_doors(A, B, P, Q, 0.5 * opts.min_door_width / res)
        kept = list(segments)
        if opts.prior_changed_area > 0:
            kept = [s for j, s in enumerate(segments) if same[j].any() or not self._unchanged_room(grid, s, opts)]
        again = []
        if opts.prior_post_shift > 0 and K:
            # the free cells rooms are cut from, with the new cuts taken out
            open_ = space.copy()
            for a, b in kept:
                open_[line_pixels(a, b, open_.shape)] = False
            for k in range(K):
                s = _passage_along(walls, space, P[k], Q[k], opts.prior_post_shift / res)
                if s is None:
                    continue
                s = _through_clutter(walls, s, opts.max_door_width / res)
                if not _closed(open_, s, opts.min_door_width / 2 / res, opts.reach / res):
                    again.append(s)
        if len(kept) < len(segments) or again:
            log.info("%s: %d doors of %s cut again, %d new cuts inside its unchanged rooms dropped", grid.name,
                     len(again), self.previous.name, len(segments) - len(kept))
        return kept + again

    def _unchanged_room(self, grid, seg, opts) -> bool:
        """Whether cut ``seg`` (pixels of ``grid``) lies inside one previous room
        and the map within ``opts.reach`` of it is the same in both maps."""
        res = grid.resolution
        found = _door_sides(seg, opts.min_door_width / 2 / res)
        if found is None:
            return False
        mid, sides = found
        x, y = grid.pixel_to_world(sides[:, 0], sides[:, 1])
        a, b = self.previous.rooms_at(np.asarray(x, float), np.asarray(y, float))
        if a == 0 or a != b:
            return False
        R = opts.reach / res
        H, W = grid.shape
        r0, r1 = max(int(np.floor(mid[0] - R)), 0), min(int(np.ceil(mid[0] + R)) + 1, H)
        c0, c1 = max(int(np.floor(mid[1] - R)), 0), min(int(np.ceil(mid[1] + R)) + 1, W)
        rr, cc = np.mgrid[r0:r1, c0:c1]
        inside = np.hypot(rr - mid[0], cc - mid[1]) <= R
        rr, cc = rr[inside], cc[inside]
        x, y = grid.pixel_to_world(rr, cc)
        changed = grid.free[rr, cc] != self.previous.free_at(np.asarray(x, float), np.asarray(y, float))
        return float(changed.sum()) * res ** 2 <= opts.prior_changed_area


def _same_doors(A, B, P, Q, tol_px: float) -> np.ndarray:
    """``(len(A), len(P))`` bool: new cut ``A[j]``-``B[j]`` and previous door
    ``P[k]``-``Q[k]`` (pixels) close the same opening.

    They do when each passes through the middle of the other: the midpoint of
    each lies within ``tol_px`` (half the narrowest door) of the other
    segment. Two different openings side by side in one wall are each at
    least a door wide, so the middle of one is more than half a door from
    the other; a cut that only shares one post with a previous door and
    runs off in another direction (across a corridor instead of along the
    doorway) closes another opening, and the previous door is then still
    to be cut.
    """
    if not (len(A) and len(P)):
        return np.zeros((len(A), len(P)), bool)
    mn, mp = (A + B) / 2, (P + Q) / 2
    return ((point_segment_distances(mn[:, None], P[None], Q[None]) <= tol_px)
            & (point_segment_distances(mp[None], A[:, None], B[:, None]) <= tol_px))


def _door_sides(s, side_px: float):
    """``(mid, sides)``: the middle of segment ``s`` (pixels) and the ``(2, 2)``
    points ``side_px`` either side of it, across it; None for a segment of no length."""
    p, q = np.asarray(s[0], float), np.asarray(s[1], float)
    v = q - p
    n = np.hypot(*v)
    if n == 0:
        return None
    mid, nrm = (p + q) / 2, np.array([-v[1], v[0]]) / n
    return mid, np.stack([mid + side_px * nrm, mid - side_px * nrm])


def _closed(open_: np.ndarray, s, side_px: float, reach_px: float) -> bool:
    """Whether door line ``s`` (pixels) is already closed in ``open_`` (the free
    cells with the new run's cuts taken out): the cells ``side_px`` either side
    of its midpoint are both open and not joined within ``reach_px`` of it
    (a new cut found the door and reaches its walls). A side that is not open
    (a wall, clutter, a cut) cannot show it, and the door counts as open."""
    from scipy import ndimage

    found = _door_sides(s, side_px)
    if found is None:
        return False
    mid, sides = found
    H, W = open_.shape
    R = int(np.ceil(reach_px + side_px)) + 1
    r0, c0 = max(int(mid[0]) - R, 0), max(int(mid[1]) - R, 0)
    r1, c1 = min(int(mid[0]) + R + 1, H), min(int(mid[1]) + R + 1, W)
    win = open_[r0:r1, c0:c1]
    rr, cc = np.ogrid[r0:r1, c0:c1]
    win = win & ((rr - mid[0]) ** 2 + (cc - mid[1]) ** 2 <= (reach_px + side_px) ** 2)
    ends = []
    for r, c in np.rint(sides).astype(int):
        if not (r0 <= r < r1 and c0 <= c < c1) or not win[r - r0, c - c0]:
            return False
        ends.append((r - r0, c - c0))
    lab, _ = ndimage.label(win)  # 4-connected, as rooms are cut
    return lab[ends[0]] != lab[ends[1]]


def _passage_along(walls: np.ndarray, space: np.ndarray, p, q, tol_px: float, *, moved: bool = False):
    """The door line between the walls met along ``p``–``q`` (pixels), or None.

    The line is sampled from ``tol_px`` before ``p`` to ``tol_px`` beyond
    ``q`` (plus half a cell's diagonal). A sample is *blocked* where it is a
    wall, or out of ``space`` (clutter) within ``tol_px`` of an end: clutter
    well inside the passage (a pillar in a wide opening) is looked through,
    as the door stage does. The door is still there when a blocked sample
    lies on each side of the middle (a wall met within ``tol_px`` beyond each
    post, or anywhere inside them: an opening that narrowed is still the
    same door) with free samples between them; it runs from the last blocked
    sample before the first free one to the first blocked sample after the
    last free one, across any wall in between (a wall piece now standing in
    the doorway leaves two openings, and both still join the rooms). Where
    no sample beyond a post is blocked, the nearest wall cell within
    ``tol_px`` of the post (a wall's end redrawn a cell beside the line) is
    the post, and the line is searched again to it (``moved``: once).

    Returns
    -------
    (a, b) or None
        The door's end points (pixels, the wall cells met), or None when a
        wall is gone (no wall within ``tol_px`` beyond a post) or the line is
        all wall.
    """
    p, q = np.asarray(p, float), np.asarray(q, float)
    v = q - p
    L = np.hypot(*v)
    if L == 0:
        return None
    H, W = walls.shape
    u = v / L
    reach = tol_px + np.sqrt(2) / 2
    t = np.arange(-reach, L + reach + 1e-9, 0.5)  # along the line from p
    rc = np.rint(p[None] + t[:, None] * u[None]).astype(np.int64)
    inside = (rc[:, 0] >= 0) & (rc[:, 0] < H) & (rc[:, 1] >= 0) & (rc[:, 1] < W)
    r, c = np.clip(rc[:, 0], 0, H - 1), np.clip(rc[:, 1], 0, W - 1)
    near = (t <= reach) | (t >= L - reach)
    blocked = ~inside | walls[r, c] | (near & ~space[r, c])
    half = t < L / 2
    ends = (blocked & half).any(), (blocked & ~half).any()
    if not all(ends):
        # no wall along the line beyond a post: a wall cell beside it (the
        # wall's end redrawn a cell off the line) is the post; none within
        # tol_px: the wall has moved away from the post
        if not moved:
            p2 = p if ends[0] else _nearest_wall(walls, p, reach)
            q2 = q if ends[1] else _nearest_wall(walls, q, reach)
            if p2 is not None and q2 is not None:
                return _passage_along(walls, space, p2, q2, tol_px, moved=True)
        return None
    first, last = np.flatnonzero(blocked & half)[0], np.flatnonzero(blocked & ~half)[-1]
    free = np.flatnonzero(~blocked[first:last + 1]) + first
    if free.size == 0:
        return None
    a, b = free[0] - 1, free[-1] + 1
    if not (inside[a] and inside[b]):
        return None
    return rc[a].astype(float), rc[b].astype(float)


def _through_clutter(walls: np.ndarray, s, max_px: float):
    """Door line ``s`` (pixels) carried on through clutter at its ends.

    A post that is not a wall is clutter (free-standing furniture, which the
    door stage looks through): now that the robot has seen more, free space
    may show beside it and the rooms join around it. From such a post the
    line goes on, straight, through the clutter and any free cells after it,
    to the next wall, as long as the door stays at most ``max_px`` long (the
    widest door); with no wall that near, the end stays on the clutter.
    """
    a, b = np.asarray(s[0], float), np.asarray(s[1], float)
    v = b - a
    n = np.hypot(*v)
    if n == 0:
        return s
    u = v / n
    H, W = walls.shape
    ends = [a, b]
    d = np.arange(0.5, max_px, 0.5)
    for k, sgn in ((0, -1.0), (1, 1.0)):
        e, other = ends[k], ends[1 - k]
        if walls[int(np.rint(e[0])), int(np.rint(e[1]))]:
            continue
        rc = np.rint(e[None] + sgn * d[:, None] * u[None]).astype(np.int64)
        ok = ((rc[:, 0] >= 0) & (rc[:, 0] < H) & (rc[:, 1] >= 0) & (rc[:, 1] < W)
              & (np.hypot(*(rc - other).T) <= max_px))
        n_ok = int(np.argmin(ok)) if not ok.all() else ok.size
        hit = np.flatnonzero(walls[rc[:n_ok, 0], rc[:n_ok, 1]])
        if hit.size:
            ends[k] = rc[hit[0]].astype(float)
    return ends[0], ends[1]


def _nearest_wall(walls: np.ndarray, p, radius: float):
    """The wall cell nearest to point ``p`` (pixels) within ``radius``, as floats; None if none."""
    H, W = walls.shape
    R = int(np.ceil(radius))
    r0, c0 = max(int(np.floor(p[0])) - R, 0), max(int(np.floor(p[1])) - R, 0)
    r1, c1 = min(int(np.ceil(p[0])) + R + 1, H), min(int(np.ceil(p[1])) + R + 1, W)
    if r0 >= r1 or c0 >= c1:
        return None
    rr, cc = np.nonzero(walls[r0:r1, c0:c1])
    if rr.size == 0:
        return None
    d = np.hypot(rr + r0 - p[0], cc + c0 - p[1])
    k = int(np.argmin(d))
    return None if d[k] > radius else np.array([rr[k] + r0, cc[k] + c0], float)
