"""Editing rooms: merge two rooms, split one along a line, name a room, mark it no-go.

Each edit takes a :class:`~topomap.core.segmentation.Segmentation` and returns a
new one (a :class:`~topomap.core.identity.TrackedSegmentation`: room IDs need not
be ``1..N`` after an edit); the input is never changed. The labels, the doors
and the room graph of the result agree with each other, as those of a fresh
segmentation do:

* every free cell is in exactly one room or one fragment (fragments are not
  edited and still follow the largest room ID);
* every door joins two different rooms whose cells touch along it;
* the room graph is built again from the labels and the doors
  (:func:`topomap.core.roomgraph.room_graph`).

Room IDs
    A merge keeps the first room's ID (the second ID is no room any more). A
    split keeps the room's ID for the larger part and gives the other part a
    new ID, ``next_room_id``, so an ID is never given twice (as
    :mod:`topomap.core.identity` does when a map grows).

What the room graph says of an edit
    Node attributes that :func:`topomap.segment` with ``previous=`` carries to
    the next map of the same place: ``name`` (a string), ``no_go`` (``True``
    on a room a robot must not enter; absent elsewhere) and ``merged`` (the
    sorted IDs of the rooms a merged room was made of). A room whose pieces
    a later map finds again, each lying in the room (see :func:`keep_merges`),
    is merged again and keeps its ID and name.

An output folder of ``topomap segment`` is edited, as ``topomap edit OUT_DIR ...``
does, by :mod:`topomap.run.editing`.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
import unicodedata

import numpy as np
import networkx as nx
from scipy import ndimage

from ..errors import EditError
from ..options import TopomapOptions
from .doors import Door
from .geometry import line_pixels
from .result import Segmentation, TrackedSegmentation
from .rooms import NEIGHBOUR_COLS, NEIGHBOUR_ROWS, fill_unlabeled

log = logging.getLogger("topomap")

__all__ = ["merge", "split", "rename", "no_go", "apply_edits", "keep_merges", "merged_ids", "EDIT_ATTRIBUTES",
           "MAX_NAME_LENGTH"]

#: Node attributes an edit sets (and ``topomap.segment(..., previous=...)`` carries to the next map).
EDIT_ATTRIBUTES = ("name", "no_go", "merged")
#: Longest room name, in characters.
MAX_NAME_LENGTH = 200


# --------------------------------------------------------------------------
# Checks and the result
# --------------------------------------------------------------------------

def _fail(seg, problem: str) -> EditError:
    """An EditError naming ``seg``'s map; ``problem`` (the message without it) kept as ``exc.problem``."""
    exc = EditError(f"{seg.grid.name}: {problem}")
    exc.problem = problem
    return exc


def _room_ids(seg) -> list:
    """The IDs of the rooms of ``seg`` that hold cells (the room graph's nodes), ascending."""
    cnt = np.bincount(seg.room_labels.ravel())
    return [int(i) for i in np.flatnonzero(cnt) if i > 0]


def _id_text(ids) -> str:
    """``"1-4, 7, 9-12"``: the IDs as ranges, at most 12 of them."""
    parts, i = [], 0
    while i < len(ids):
        j = i
        while j + 1 < len(ids) and ids[j + 1] == ids[j] + 1:
            j += 1
        parts.append(str(ids[i]) if i == j else f"{ids[i]}-{ids[j]}")
        i = j + 1
    more = f", ... ({len(parts) - 12} more ranges)" if len(parts) > 12 else ""
    return ", ".join(parts[:12]) + more if parts else "none"


def _check_room(seg, ids, room, what: str = "room") -> int:
    if isinstance(room, (bool, np.bool_)) or not isinstance(room, (int, np.integer)):
        raise _fail(seg, f"{what} {room!r} is not a room ID (an integer)")
    if int(room) not in ids:
        raise _fail(seg, f"no room {room} (rooms: {_id_text(ids)})")
    return int(room)


def _next_id(seg, ids) -> int:
    nxt = getattr(seg, "next_room_id", None)
    top = max(ids, default=0) + 1
    return max(int(nxt), top) if isinstance(nxt, (int, np.integer)) else top


def _user_attributes(seg) -> dict:
    """``ID -> {name: value}``: the attributes of ``seg``'s rooms that topomap does not compute (names,
    no-go marks, merged IDs, a user's own), as :mod:`topomap.core.identity` carries them; copies."""
    return seg.user_attributes()


def merged_ids(value) -> list:
    """The room IDs of a ``merged`` node attribute as read from anywhere: a list, or the JSON text a
    GraphML or JSON file holds it as (``"[3, 5]"``); ``[]`` for none or an unreadable value."""
    if value is None or value == "":
        return []
    try:
        if isinstance(value, str):
            value = json.loads(value)
        out = sorted({int(v) for v in value if not isinstance(v, bool)})
    except (TypeError, ValueError):
        log.warning("merged = %r is not a list of room IDs: ignored", value)
        return []
    return out


def _result(seg, rooms, doors, next_id, attrs):
    """The TrackedSegmentation of room labels ``rooms`` (0 off the rooms; None: those of ``seg``),
    ``doors`` and user attributes ``attrs``; the fragments of ``seg`` follow the largest room ID."""

    if rooms is None:
        labels = seg.labels
        ids = _room_ids(seg)
    else:
        cnt = np.bincount(rooms.ravel())
        ids = [int(i) for i in np.flatnonzero(cnt) if i > 0]
        top, old = max(ids, default=0), seg.top_room_id
        labels = rooms.astype(np.int32, copy=True)
        frag = seg.labels > old
        if frag.any():
            labels[frag] = seg.labels[frag] - old + top
    keep = set(ids)
    base = {f.name: getattr(seg, f.name) for f in dataclasses.fields(Segmentation)}
    base.update(labels=labels, doors=sorted(doors, key=lambda d: d.id), room_count=None, _room_graph=None,
                timings=dict(seg.timings))
    return TrackedSegmentation(**base, room_ids=tuple(ids), next_room_id=int(max(next_id, max(ids, default=0) + 1)),
                               changes=getattr(seg, "changes", None),
                               room_attributes={r: a for r, a in attrs.items() if r in keep and a})


def _copied(doors) -> list:
    return [dataclasses.replace(d, extra=dict(d.extra)) for d in doors]


# --------------------------------------------------------------------------
# The edits
# --------------------------------------------------------------------------

def _touch(L: np.ndarray, a: int, b: int) -> bool:
    """Whether a cell of room ``a`` and one of room ``b`` are 4-neighbours."""
    ma, mb = L == a, L == b
    return bool((ma[:, :-1] & mb[:, 1:]).any() or (mb[:, :-1] & ma[:, 1:]).any()
                or (ma[:-1] & mb[1:]).any() or (mb[:-1] & ma[1:]).any())


def _merged_cells(rooms: np.ndarray, doors: list, a: int, b: int):
    """Room labels and doors with room ``b`` made part of room ``a``: the doors between them are gone."""
    out = []
    for d in doors:
        if set(d.rooms) == {a, b}:
            continue
        if b in d.rooms:
            d = dataclasses.replace(d, rooms=tuple(sorted(a if x == b else x for x in d.rooms)))
        out.append(d)
    return np.where(rooms == b, a, rooms), out


def merge(seg, a: int, b: int):
    """Merge room ``b`` into room ``a``.

    The merged room keeps ID ``a`` (its name, or ``b``'s when ``a`` has
    none) and is no-go when either room was. It records the rooms it was
    made of as the node attribute ``merged`` (sorted IDs, with those of
    earlier merges). The doors between the two rooms are gone; the other
    doors of ``b`` now lead into ``a``.

    Parameters
    ----------
    seg : Segmentation
    a, b : int
        Room IDs of two different rooms that share a door or touch.

    Returns
    -------
    TrackedSegmentation
        A new result; ``seg`` is not changed.

    Raises
    ------
    EditError
        An unknown room ID, ``a == b``, or rooms that neither share a
        door nor touch (a room is one place).
    """
    ids = _room_ids(seg)
    a, b = _check_room(seg, ids, a), _check_room(seg, ids, b)
    if a == b:
        raise _fail(seg, f"cannot merge room {a} with itself")
    L = seg.room_labels
    if not any(set(d.rooms) == {a, b} for d in seg.doors) and not _touch(L, a, b):
        raise _fail(seg, f"rooms {a} and {b} share no door and do not touch: only rooms side by side merge")
    rooms, doors = _merged_cells(L, _copied(seg.doors), a, b)
    attrs = _user_attributes(seg)
    A, B = attrs.get(a, {}), attrs.pop(b, {})
    new = {**B, **A}
    new["merged"] = sorted(set(merged_ids(A.get("merged")) or [a]) | set(merged_ids(B.get("merged")) or [b]))
    if A.get("no_go") or B.get("no_go"):
        new["no_go"] = True
    attrs[a] = new
    log.info("%s: room %d merged into room %d", seg.grid.name, b, a)
    return _result(seg, rooms, doors, _next_id(seg, ids), attrs)


def _point(seg, p, which: str) -> tuple:
    try:
        x, y = (float(v) for v in p)
    except (TypeError, ValueError):
        raise _fail(seg, f"split line {which} end {p!r} is not a point (x, y) in metres") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise _fail(seg, f"split line {which} end ({x}, {y}) is not a finite point")
    return x, y


def _extent_text(grid) -> str:
    H, W = grid.shape
    x, y = grid.pixel_to_world(np.array([-0.5, -0.5, H - 0.5, H - 0.5]), np.array([-0.5, W - 0.5, -0.5, W - 0.5]))
    return f"x {x.min():.2f}..{x.max():.2f} m, y {y.min():.2f}..{y.max():.2f} m"


def _neighbour_counts(rooms: np.ndarray, rr: np.ndarray, cc: np.ndarray, labels) -> list:
    """How many times each of ``labels`` is among the cells ``rr, cc`` and their 8-neighbours."""
    H, W = rooms.shape
    r = np.clip(np.r_[rr, (rr[:, None] + NEIGHBOUR_ROWS).ravel()], 0, H - 1)
    c = np.clip(np.r_[cc, (cc[:, None] + NEIGHBOUR_COLS).ravel()], 0, W - 1)
    v = rooms[r, c]
    return [int(np.count_nonzero(v == x)) for x in labels]


def split(seg, room: int, p1, p2, *, min_area: float | None = None):
    """Split a room in two along the line from ``p1`` to ``p2``.

    The line's cells cut the room; each of the two parts left must be at
    least ``min_area``. The larger part keeps the room's ID (and name), the
    other gets the ID ``next_room_id``; both keep a no-go mark. Where the
    line crosses the room — a passage between the two parts — it becomes a
    door between them, from wall to wall along the line. The cut cells, and
    pieces of the room smaller than ``min_area`` that the line cut off, go
    to the nearest part (as :func:`topomap.core.rooms.cut_rooms` gives them). The
    room's other doors lead into the part beside them. A merged room that
    is split is no longer recorded as merged.

    Parameters
    ----------
    seg : Segmentation
    room : int
        The room ID.
    p1, p2 : (float, float)
        The line's ends, map-frame metres; both on the map. Draw it from
        wall to wall: a line that ends inside the room cuts nothing.
    min_area : float, optional
        Smallest part, m². Default: the ``min_room_area`` of ``seg.options``
        (the smallest room of the default method), or of
        :class:`~topomap.options.TopomapOptions` for the other methods.

    Returns
    -------
    TrackedSegmentation
        A new result; ``seg`` is not changed.

    Raises
    ------
    EditError
        An unknown room ID, an end off the map, a line shorter than a cell
        or one that does not cross the room, or a line that does not cut it
        into exactly two parts of at least ``min_area``.
    """
    ids = _room_ids(seg)
    room = _check_room(seg, ids, room)
    grid = seg.grid
    min_area = _min_area(seg, min_area)
    line, rr, cc = _split_line(seg, p1, p2)
    on = seg.room_labels[rr, cc] == room
    if not on.any():
        raise _fail(seg, f"{line} does not cross room {room}")
    new_id = _next_id(seg, ids)
    rooms = _cut_in_two(seg, room, new_id, rr, cc, min_area, line)
    doors = _copied(seg.doors)
    new_doors = _doors_along(seg, rooms, room, new_id, rr, cc, on, max((d.id for d in doors), default=-1) + 1)
    if not new_doors:
        raise _fail(seg, f"{line} does not cross a passage between the two parts of room {room}")
    doors = _doors_beside(doors, rooms, room, new_id)
    attrs = _user_attributes(seg)
    kept = attrs.get(room, {})
    kept.pop("merged", None)
    attrs[room] = kept
    if kept.get("no_go"):
        attrs[new_id] = {"no_go": True}
    log.info("%s: room %d split along %s: room %d, new room %d, %d door(s)", grid.name, room, line, room, new_id,
             len(new_doors))
    return _result(seg, rooms, doors + new_doors, new_id + 1, attrs)


def _min_area(seg, min_area) -> float:
    """The smallest part of a split, m²: ``min_area``, by default the ``min_room_area`` of the options that
    ran (of :class:`~topomap.options.TopomapOptions` for the other methods); EditError unless an area > 0."""
    if min_area is None:
        opts = seg.options if isinstance(seg.options, TopomapOptions) else TopomapOptions()
        min_area = opts.min_room_area
    if isinstance(min_area, bool) or not isinstance(min_area, (int, float)) or not (0 < min_area < math.inf):
        raise _fail(seg, f"min_area must be an area > 0 (m²), got {min_area!r}")
    return min_area


def _split_line(seg, p1, p2):
    """``(text, rows, cols)``: the split line from map-frame points ``p1`` to ``p2`` as the words messages
    give it and its cells; EditError for an end off the map or a line shorter than a cell."""
    grid = seg.grid
    H, W = grid.shape
    (x1, y1), (x2, y2) = _point(seg, p1, "first"), _point(seg, p2, "second")
    ends = []
    for x, y in ((x1, y1), (x2, y2)):
        r, c = (float(v) for v in grid.world_to_pixel(x, y))
        if not (-0.5 <= r < H - 0.5 and -0.5 <= c < W - 0.5):
            raise _fail(seg, f"split line end ({x:g}, {y:g}) m is off the map ({_extent_text(grid)})")
        ends.append((r, c))
    if math.hypot(ends[0][0] - ends[1][0], ends[0][1] - ends[1][1]) < 1:
        raise _fail(seg, f"split line ({x1:g}, {y1:g})-({x2:g}, {y2:g}) m is shorter than a cell "
                         f"({grid.resolution:g} m)")
    rr, cc = line_pixels(ends[0], ends[1], (H, W))
    return f"split line ({x1:g}, {y1:g})-({x2:g}, {y2:g}) m", rr, cc


def _cut_in_two(seg, room: int, new_id: int, rr, cc, min_area: float, line: str) -> np.ndarray:
    """The room labels with ``room`` cut along the cells ``rr, cc``: the larger of the two parts of at
    least ``min_area`` keeps ``room``, the other becomes ``new_id``; the cut cells and small pieces go to
    the nearest part. EditError unless the line cuts exactly two such parts."""
    L = seg.room_labels
    H, W = L.shape
    res = seg.grid.resolution
    mask = L == room
    rows, cols = np.flatnonzero(mask.any(1)), np.flatnonzero(mask.any(0))
    r0, r1 = max(rows[0] - 1, 0), min(rows[-1] + 2, H)
    c0, c1 = max(cols[0] - 1, 0), min(cols[-1] + 2, W)
    m = mask[r0:r1, c0:c1]
    cut = np.zeros_like(m)
    inside = (rr >= r0) & (rr < r1) & (cc >= c0) & (cc < c1)
    cut[rr[inside] - r0, cc[inside] - c0] = True
    parts, n = ndimage.label(m & ~cut)  # 4-connected, as rooms are cut
    size = np.bincount(parts.ravel(), minlength=n + 1)
    size[0] = 0
    min_cells = math.ceil(min_area / res ** 2 - 1e-9)
    big = [int(k) for k in np.argsort(-size, kind="stable") if size[k] >= min_cells and k > 0]
    if len(big) != 2:
        areas = ", ".join(f"{s * res ** 2:.3g}" for s in sorted(size[1:], reverse=True)[:4]) or "none"
        what = "into no part" if not big else "into one part only" if len(big) == 1 else f"into {len(big)} parts"
        raise _fail(seg, f"{line} cuts room {room} {what} of at least {min_area:g} m² (the largest parts: {areas} m²); "
                         "draw a line from wall to wall that cuts it in two")
    a_part, b_part = big
    seeds = np.zeros(m.shape, np.int32)
    seeds[parts == a_part] = 1
    seeds[parts == b_part] = 2
    filled = fill_unlabeled(seeds, m)
    b_cell = tuple(np.argwhere(parts == b_part)[0])
    rooms = L.copy()
    rooms[r0:r1, c0:c1][filled == filled[b_cell]] = new_id
    return rooms


def _doors_along(seg, rooms: np.ndarray, room: int, new_id: int, rr, cc, on, next_door: int) -> list:
    """The new doors along the split line: each run of its cells in the room (``on``) that touches both
    parts, from the cell before it to the cell after it, numbered from ``next_door``."""
    grid = seg.grid
    res = grid.resolution
    runs = np.flatnonzero(np.diff(np.r_[0, on.view(np.int8), 0]))
    new_doors = []
    for i, j in zip(runs[0::2], runs[1::2] - 1):
        n_room, n_new = _neighbour_counts(rooms, rr[i:j + 1], cc[i:j + 1], (room, new_id))
        if not (n_room and n_new):
            continue
        a, b = (i - 1 if i > 0 else i), (j + 1 if j + 1 < rr.size else j)
        p, q = (float(rr[a]), float(cc[a])), (float(rr[b]), float(cc[b]))
        (xa, xb), (ya, yb) = (np.asarray(v, float).tolist() for v in grid.pixel_to_world([p[0], q[0]], [p[1], q[1]]))
        new_doors.append(Door(id=next_door, p1=p, p2=q, xy1=(xa, ya), xy2=(xb, yb),
                              width=math.hypot(p[0] - q[0], p[1] - q[1]) * res, rooms=(room, new_id),
                              extra={"edit": "split"}))
        next_door += 1
    return new_doors


def _doors_beside(doors: list, rooms: np.ndarray, room: int, new_id: int) -> list:
    """``doors`` with the split room's other doors leading into the part beside them (a new list)."""
    doors = list(doors)
    for k, d in enumerate(doors):
        if room in d.rooms and new_id not in d.rooms:
            lr, lc = line_pixels(d.p1, d.p2, rooms.shape)
            n_room, n_new = _neighbour_counts(rooms, lr, lc, (room, new_id))
            if n_new > n_room:
                other = d.rooms[0] if d.rooms[1] == room else d.rooms[1]
                doors[k] = dataclasses.replace(d, rooms=tuple(sorted((other, new_id))))
    return doors


def _check_name(seg, name) -> str:
    if not isinstance(name, str):
        raise _fail(seg, f"room name {name!r} is not text")
    text = name.strip()
    if not text:
        raise _fail(seg, f"room name {name!r} is empty")
    bad = [ch for ch in text if unicodedata.category(ch) in ("Cc", "Cs", "Zl", "Zp")]
    if bad:
        raise _fail(seg, f"room name {name!r} holds a control character ({bad[0]!r}): a name is one line of text")
    if len(text) > MAX_NAME_LENGTH:
        raise _fail(seg, f"room name {name[:40]!r}... has {len(text)} characters, more than {MAX_NAME_LENGTH}")
    return text


def rename(seg, room: int, name: str):
    """Name a room (the node attribute ``name``; a name it had is replaced).

    Parameters
    ----------
    seg : Segmentation
    room : int
        The room ID.
    name : str
        One line of text, at most :data:`MAX_NAME_LENGTH` characters;
        spaces at its ends are dropped. Two rooms may have the same name.

    Returns
    -------
    TrackedSegmentation
        A new result with the same labels and doors; ``seg`` is not changed.

    Raises
    ------
    EditError
        An unknown room ID, or a name that is not text, empty, too long or
        holds a line break or another control character.
    """
    ids = _room_ids(seg)
    room = _check_room(seg, ids, room)
    text = _check_name(seg, name)
    attrs = _user_attributes(seg)
    attrs.setdefault(room, {})["name"] = text
    return _result(seg, None, _copied(seg.doors), _next_id(seg, ids), attrs)


def no_go(seg, room: int, *, value: bool = True):
    """Mark a room as one a robot must not enter (the node attribute ``no_go``).

    Parameters
    ----------
    seg : Segmentation
    room : int
        The room ID.
    value : bool
        True marks the room (``no_go = True``); False takes the mark away
        (the attribute is then absent, as on every unmarked room).

    Returns
    -------
    TrackedSegmentation
        A new result with the same labels and doors; ``seg`` is not changed.

    Raises
    ------
    EditError
        An unknown room ID, or ``value`` not a bool.
    """
    ids = _room_ids(seg)
    room = _check_room(seg, ids, room)
    if not isinstance(value, (bool, np.bool_)):
        raise _fail(seg, f"no_go value must be True or False, got {value!r}")
    attrs = _user_attributes(seg)
    a = attrs.setdefault(room, {})
    if value:
        a["no_go"] = True
    else:
        a.pop("no_go", None)
    return _result(seg, None, _copied(seg.doors), _next_id(seg, ids), attrs)


#: Edit name -> (function, number of arguments after the segmentation).
_EDITS = {"merge": 2, "split": 5, "name": 2, "no_go": 1}


def _edit_text(kind, args) -> str:
    if kind == "split":
        r, x1, y1, x2, y2 = args
        return f"split {r} {x1:g} {y1:g} {x2:g} {y2:g}"
    if kind == "name":
        name = args[1]
        return f"name {args[0]} {name[:40] + '...' if isinstance(name, str) and len(name) > 40 else name!r}"
    return " ".join([kind.replace("_", "-"), *map(str, args)])


def apply_edits(seg, edits, *, source: str | None = None):
    """Apply edits in order.

    Parameters
    ----------
    seg : Segmentation
    edits : iterable of tuple
        Each one of ``("merge", a, b)``, ``("split", room, x1, y1, x2, y2)``,
        ``("name", room, name)``, ``("no_go", room)``: :func:`merge`,
        :func:`split`, :func:`rename`, :func:`no_go`, one after the other
        (room IDs are those after the edits before).
    source : str, optional
        What the error messages name (default the map's file).

    Returns
    -------
    seg : TrackedSegmentation
        The result of the last edit (``seg`` itself is not changed).
    records : list of dict
        One per edit, JSON-ready: ``{"edit": "merge", "rooms": [a, b]}``,
        ``{"edit": "split", "room": r, "line": [x1, y1, x2, y2], "new_room": n}``,
        ``{"edit": "name", "room": r, "name": name}``, ``{"edit": "no_go", "room": r}``.

    Raises
    ------
    EditError
        An edit that cannot be made (the message names it and says why);
        an unknown kind of edit or a wrong number of arguments.
    """
    records = []
    where = source if source is not None else seg.grid.name
    for k, e in enumerate(edits, 1):
        if not isinstance(e, (tuple, list)) or not e or e[0] not in _EDITS or len(e) != _EDITS[e[0]] + 1:
            raise EditError(f"{where}: edit {k}: {e!r} is not one of ('merge', a, b), ('split', room, x1, y1, x2, y2), "
                            "('name', room, name), ('no_go', room)")
        kind, args = e[0], tuple(e[1:])
        try:
            if kind == "merge":
                seg = merge(seg, *args)
                rec = {"edit": "merge", "rooms": [int(args[0]), int(args[1])]}
            elif kind == "split":
                new = _next_id(seg, _room_ids(seg))
                seg = split(seg, args[0], args[1:3], args[3:5])
                rec = {"edit": "split", "room": int(args[0]), "line": [float(v) for v in args[1:]], "new_room": new}
            elif kind == "name":
                seg = rename(seg, *args)
                rec = {"edit": "name", "room": int(args[0]), "name": seg.room_attributes[int(args[0])]["name"]}
            else:
                seg = no_go(seg, *args)
                rec = {"edit": "no_go", "room": int(args[0])}
        except EditError as exc:
            problem = getattr(exc, "problem", str(exc))
            raise EditError(f"{where}: {_edit_text(kind, args)}: {problem}") from None
        records.append(rec)
    return seg, records


# --------------------------------------------------------------------------
# Merges a later map keeps
# --------------------------------------------------------------------------

def keep_merges(previous, seg, *, min_overlap: float):
    """``seg`` with the rooms merged again that lie in one previous room a user had merged.

    :func:`topomap.core.identity.match_rooms` calls it before it matches rooms.
    A new room lies in previous room ``i`` when at least ``min_overlap`` of
    its part that the previous map knew is in ``i``; the new rooms that lie
    in a room with a ``merged`` attribute (two or more IDs) and are joined by
    doors among themselves become one room again — the door between the
    pieces is no door — so the matching gives it the merged room's ID, name
    and other attributes.

    Parameters
    ----------
    previous : object
        The previous rooms as :mod:`topomap.core.identity` reads them: ``attrs`` (ID -> user attributes),
        ``rooms_at(x, y)`` (their IDs at map-frame points) and ``name``.
    seg : Segmentation
        The new segmentation (not changed).
    min_overlap : float

    Returns
    -------
    Segmentation
        ``seg`` itself when nothing is merged, else a new result.
    """

    merged = [i for i, a in previous.attrs.items() if len(merged_ids(a.get("merged"))) >= 2]
    if not merged:
        return seg
    L = seg.room_labels
    rr, cc = np.nonzero(L)
    x, y = seg.grid.pixel_to_world(rr, cc)
    prev = previous.rooms_at(np.asarray(x, float), np.asarray(y, float))
    lab = L[rr, cc]
    top = int(L.max(initial=0))
    known = np.bincount(lab[prev > 0], minlength=top + 1)
    rooms, doors, joined = L, _copied(seg.doors), []
    for i in sorted(merged):
        inside = np.bincount(lab[prev == i], minlength=top + 1)
        group = {int(j) for j in np.flatnonzero(inside) if j > 0 and inside[j] >= min_overlap * known[j]}
        if len(group) < 2:
            continue
        G = nx.Graph()
        G.add_edges_from(d.rooms for d in doors if set(d.rooms) <= group and d.rooms[0] != d.rooms[1])
        for part in nx.connected_components(G):
            part = sorted(part)
            for j in part[1:]:
                rooms, doors = _merged_cells(rooms, doors, part[0], j)
            joined.append((i, part))
    if not joined:
        return seg
    for i, part in joined:
        log.info("%s: rooms %s lie in room %d of %s, which was merged: merged again", seg.grid.name,
                 ", ".join(map(str, part)), i, previous.name)
    ids = _room_ids(seg)
    return _result(seg, rooms, doors, _next_id(seg, ids), {})
