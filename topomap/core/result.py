"""The result of a segmentation: :class:`Segmentation` (rooms, doors, skeleton graphs, timings) and the
:class:`Intermediates` it was computed from."""

from __future__ import annotations

import numbers
import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from ..errors import GraphFormatError, one_line
from ..grid import OccupancyGrid

__all__ = ["Segmentation", "TrackedSegmentation", "RoomChanges", "Intermediates", "StageTimer", "paste",
           "ROOM_ATTRIBUTES", "MAX_FILE_LABEL", "MAX_ROOM_ID", "check_room_ids"]

#: The room (node) attributes topomap computes (:func:`topomap.core.roomgraph.room_graph`, and
#: ``door_distances``, which ``topomap segment`` adds from the travel graph); any other attribute of a
#: room is a user's (a name, a no-go mark, merged IDs, ...) and is carried to the next map of the place.
ROOM_ATTRIBUTES = ("area", "cells", "x", "y", "row", "col", "interior_x", "interior_y", "interior_row",
                   "interior_col", "polygon", "door_distances", "room_kind", "width", "length")

#: Largest label a label file holds (16 bits).
MAX_FILE_LABEL = 65535
#: Largest room ID: the label files hold room IDs up to 65534 with the fragments' label after them. A room
#: graph read from a file (a ``--previous`` or a ``plan`` / ``tour`` graph) must have whole-number room IDs
#: in 1..MAX_ROOM_ID and a ``next_room_id`` of at most MAX_ROOM_ID + 1, so what is built from its IDs is
#: bounded by the number of its rooms.
MAX_ROOM_ID = MAX_FILE_LABEL - 1


def check_room_ids(G, name) -> None:
    """GraphFormatError naming ``name`` unless every room ID of ``G`` is an ``int`` in 1..:data:`MAX_ROOM_ID`
    and its ``next_room_id`` (when it has one) an integer in 1..MAX_ROOM_ID + 1."""

    def whole(v, top):
        return isinstance(v, numbers.Integral) and not isinstance(v, bool) and 1 <= int(v) <= top

    for r in G.nodes:
        if not whole(r, MAX_ROOM_ID):
            raise GraphFormatError(f"{name}: room ID {one_line(repr(r))[:40]} is not a whole number from 1 to "
                                   f"{MAX_ROOM_ID} (room IDs are the labels of the 16-bit label files)")
    nxt = G.graph.get("next_room_id")
    if nxt not in (None, ""):
        if isinstance(nxt, str) and nxt.strip().isdigit():
            nxt = int(nxt)
        if not whole(nxt, MAX_ROOM_ID + 1):
            raise GraphFormatError(f"{name}: next_room_id {one_line(repr(nxt))[:40]} is not a whole number from 1 "
                                   f"to {MAX_ROOM_ID + 1}")

def paste(a, shape, box):
    """``a`` (a crop ``box`` of an image) placed on zeros of ``shape``."""
    if a is None:
        return None
    r0, r1, c0, c1 = box
    out = np.zeros(shape, a.dtype)
    out[r0:r1, c0:c1] = a
    return out


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
        value = paste(crops.pop(name), shape, box)
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
            from .roomgraph import room_graph  # here: shapely is imported only when a graph is built

            t = time.perf_counter()
            self._room_graph = room_graph(self)
            self.timings["room_graph"] = time.perf_counter() - t
        return self._room_graph

    def user_attributes(self) -> dict:
        """``ID -> {name: value}``: the attributes of the rooms that topomap does not compute (names, no-go
        marks, merged IDs, a user's own; not :data:`ROOM_ATTRIBUTES`): those carried from a previous map
        (``room_attributes``) and those put on the built :attr:`room_graph`; copies."""
        attrs = {int(r): dict(a) for r, a in getattr(self, "room_attributes", {}).items()}
        if self._room_graph is not None:
            for r, d in self._room_graph.nodes(data=True):
                extra = {k: v for k, v in d.items() if k not in ROOM_ATTRIBUTES}
                if extra:
                    attrs[int(r)] = {**attrs.get(int(r), {}), **extra}
        return attrs

    def room_at(self, x: float, y: float) -> int:
        """Room label at map-frame point ``(x, y)`` metres (0 = not in a room)."""
        r, c = self.grid.world_to_pixel(x, y)
        r, c = int(np.rint(r)), int(np.rint(c))
        if 0 <= r < self.labels.shape[0] and 0 <= c < self.labels.shape[1]:
            return int(self.labels[r, c])
        return 0


class StageTimer:
    """Seconds per named stage: ``with timer("walls"): ...`` adds the time spent to ``timer.t["walls"]``."""

    def __init__(self):
        self.t = {}

    @contextmanager
    def __call__(self, name):
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.t[name] = self.t.get(name, 0.0) + time.perf_counter() - t0


@dataclass(frozen=True)
class RoomChanges:
    """What happened to the rooms between a previous and a new segmentation.

    Attributes
    ----------
    kept : tuple of int
        IDs present in both (the new room took the previous room's ID).
    new : tuple of int
        IDs of new rooms that overlap no previous room significantly.
    vanished : tuple of int
        Previous IDs whose room overlaps no new room significantly.
    split : dict
        ``previous ID -> tuple of new IDs``: a previous room now covered by
        two or more new rooms (its own ID, when kept, is among them).
    merged : dict
        ``new ID -> tuple of previous IDs``: a new room covering two or more
        previous rooms (it keeps one of their IDs).
    next_room_id : int
        The ID the next new room will get (one more than every ID given so far).
    """

    kept: tuple = ()
    new: tuple = ()
    vanished: tuple = ()
    split: dict = field(default_factory=dict)
    merged: dict = field(default_factory=dict)
    next_room_id: int = 1

    def explains(self, old: int, new: int) -> bool:
        """True when the record links previous room ``old`` to new room ``new``:
        the same ID kept, a split of ``old`` into ``new``, or a merge of
        ``old`` into ``new``."""
        old, new = int(old), int(new)
        if old == new:
            return old in self.kept
        return new in self.split.get(old, ()) or old in self.merged.get(new, ())

    def as_dict(self) -> dict:
        """Plain JSON-ready form (dict keys as strings)."""
        return {"kept": list(self.kept), "new": list(self.new), "vanished": list(self.vanished),
                "split": {str(k): list(v) for k, v in self.split.items()},
                "merged": {str(k): list(v) for k, v in self.merged.items()},
                "next_room_id": int(self.next_room_id)}

    @classmethod
    def from_dict(cls, d: dict) -> "RoomChanges":
        """The record of :meth:`as_dict` (``changes.json``) back as a :class:`RoomChanges`."""
        return cls(kept=tuple(d["kept"]), new=tuple(d["new"]), vanished=tuple(d["vanished"]),
                   split={int(k): tuple(v) for k, v in d["split"].items()},
                   merged={int(k): tuple(v) for k, v in d["merged"].items()},
                   next_room_id=int(d["next_room_id"]))

    def summary(self) -> str:
        """One line, e.g. ``"9 kept, 1 new, 0 vanished, 1 split, 0 merged"``."""
        return (f"{len(self.kept)} kept, {len(self.new)} new, {len(self.vanished)} vanished, "
                f"{len(self.split)} split, {len(self.merged)} merged")


@dataclass
class TrackedSegmentation(Segmentation):
    """A :class:`~topomap.core.segmentation.Segmentation` whose room IDs follow a
    previous one (returned by :func:`match_rooms`).

    Room IDs are the labels of ``labels`` and need not be contiguous;
    fragments are the labels above the largest room ID.

    Attributes
    ----------
    room_ids : tuple of int
        The room IDs, ascending (the room graph's nodes).
    next_room_id : int
        The ID the next new room will get; saved as the room graph's graph
        attribute ``next_room_id``.
    changes : RoomChanges
        What changed against the previous segmentation.
    room_attributes : dict
        ``ID -> {name: value}``: attributes a user had added to the previous
        rooms (``name``, ...), put on the matched nodes of :attr:`room_graph`.
    """

    room_ids: tuple = ()
    next_room_id: int = 1
    changes: Optional[RoomChanges] = None
    room_attributes: dict = field(default_factory=dict, repr=False)

    @property
    def n_rooms(self) -> int:
        """Number of rooms (``len(room_ids)``)."""
        return len(self.room_ids)

    @property
    def top_room_id(self) -> int:
        """The largest room ID (0 without rooms): labels above it are fragments."""
        return max(self.room_ids, default=0)

    @property
    def room_graph(self):
        """The room–door graph, with ``next_room_id`` and the carried user attributes."""
        if self._room_graph is None:
            G = Segmentation.room_graph.fget(self)
            G.graph["next_room_id"] = int(self.next_room_id)
            for r, attrs in self.room_attributes.items():
                if r in G:
                    for k, v in attrs.items():
                        G.nodes[r].setdefault(k, v)
        return self._room_graph
