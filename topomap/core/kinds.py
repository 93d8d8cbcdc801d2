"""What kind of space each room is: corridor, room, hall or doorway, from its shape and its place in the room graph.

:func:`room_shape` measures a room from its cells alone; :func:`room_kind` turns
the measures, the room's number of doors and its place in the room graph
into a kind; :func:`annotate_kinds` puts both on every node of a room graph
(:func:`topomap.core.roomgraph.room_graph` calls it). Every threshold is a
physical quantity (m, m²), a ratio of lengths or a count of doors; the
"Graph attributes" page of the documentation gives the reason of each.

The measures of the shape
-------------------------
``width`` (m)
    The room's mean width from its distance transform: each cell's distance
    to the nearest cell outside the room, averaged over the room, times four
    (a strip of width ``w`` has mean distance ``w / 4`` to its long sides;
    one cell is taken off for the cell-centre distances; enclosed patches of
    furniture up to :data:`FURNITURE_MAX_AREA` count as floor). A long strip gives
    its width, a square of side ``s`` ``2 s / 3``, an ``a`` × ``b`` rectangle
    ``a - a² / (3 b)``.
``length`` (m)
    ``area / width``: the length of the strip of that width and area — the
    length of the room's skeleton for a strip, however it bends.
``elongation``
    ``length / width`` (``area / width²``): about the ratio of the sides plus
    0.8 for a rectangle, 2.25 for a square, the length over the width for a
    long corridor.

The measures of the place in the graph
--------------------------------------
``doors``
    The room's doors (its degree in the room graph; two doors to the same
    room count twice).
``cut``
    Whether the room is a *cut vertex* of the room graph: taking it away
    leaves some rooms with no route to the others, so every route between
    them passes through it.
``dead_ends``
    How many of the rooms it opens onto open onto no other room (a bathroom,
    a closet, a bedroom with one door).

The width of the room's own medial axis (twice the clearance along its
skeleton, its median or its largest value) was measured as well: on the
drawn plans it separates corridors from the narrow rooms of homes no better
than the mean width, so the mean width stays.
"""

from __future__ import annotations

import networkx as nx
import numpy as np
from scipy import ndimage as ndi

from .._fast import edt, label

__all__ = ["KINDS", "CORRIDOR_MAX_WIDTH", "CORRIDOR_MIN_WIDTH", "CORRIDOR_MIN_ELONGATION", "CORRIDOR_MIN_LENGTH", "CORRIDOR_MIN_DOORS",
           "HALLWAY_MIN_DOORS", "SIDE_DOOR_MIN_RATIO", "WIDE_CORRIDOR_MAX_WIDTH", "WIDE_CORRIDOR_MIN_ELONGATION",
           "FURNITURE_MAX_AREA", "DOORWAY_MAX_AREA", "DOORWAY_MAX_WIDTH", "HALL_MIN_AREA", "HALL_MIN_WIDTH",
           "room_shape", "room_kind", "graph_place", "annotate_kinds"]

#: The kinds :func:`room_kind` gives.
KINDS = ("corridor", "room", "hall", "doorway")

#: A corridor is at most this wide (m, mean width): hallways of homes are 0.9 to 1.2 m wide (a
#: wheelchair needs 0.9 m, two people pass in 1.2 m); a strip wider than that is a room (a long
#: kitchen, a gallery). Small rooms of homes (a washroom, a toilet, a balcony) are as narrow on this
#: measure (0.8 to 1.3 m): their place in the room graph tells them apart, not their width.
CORRIDOR_MAX_WIDTH = 1.2
#: ... and at least this wide (m, mean width): a person's shoulders take about 0.5 m, so a strip
#: narrower than this is a gap between walls or furniture that nobody walks along, not a corridor.
CORRIDOR_MIN_WIDTH = 0.6
#: ... and a corridor with two doors is at least this many widths long (length / width): a square
#: has 2.25 and a 2:1 rectangle 2.9 on this measure; a passage longer than about three times its
#: width is a corridor.
CORRIDOR_MIN_ELONGATION = 3.0
#: ... and at least this long (m): a shorter strip is the space of a door or a niche.
CORRIDOR_MIN_LENGTH = 2.0
#: A wider corridor, up to this width (m): office and public corridors are 1.5 to 2.4 m wide ...
WIDE_CORRIDOR_MAX_WIDTH = 2.5
#: ... counts when it is at least this many widths long: a long corridor with rooms along it, not a
#: wide room of a home (which reaches about 4 widths). A strip this long with two doors is a
#: corridor even when one of its doors leads to a dead end (the end of a corridor).
WIDE_CORRIDOR_MIN_ELONGATION = 6.0
#: A corridor-shaped room with this many doors is a passage: with two doors, it is a corridor when
#: every route between the rooms at its two ends passes through it (a *cut vertex* of the room
#: graph) and neither of them is a dead end. A narrow space with two doors of which one leads to a
#: room with no other door is that room's anteroom (the washroom before a bath, the lobby of a
#: closet), and one whose two ends are joined by another route as well, through doors much wider
#: than itself (:data:`SIDE_DOOR_MIN_RATIO`), is a space beside the rooms (a balcony along two
#: bedrooms); with one door it is a closet, a washroom or a dead end.
CORRIDOR_MIN_DOORS = 2
#: A narrow room (at most :data:`CORRIDOR_MAX_WIDTH`, or a long wide strip) with at least this many
#: doors is a hallway, however short: three rooms or more open onto it (the small hall of a flat
#: between its entrance, its toilet, its bath and its rooms). Rooms this narrow with that many
#: doors are hallways in homes; washrooms with a third door (to a kitchen) are the exception.
HALLWAY_MIN_DOORS = 3
#: A corridor-shaped room with two doors whose widest door is at least this many times its width,
#: and whose two neighbours are joined by another route as well (not a cut vertex), opens along
#: its long side onto the rooms beside it: a balcony or a loggia behind the glass doors of two
#: rooms (doors of 1.6 to 2.5 m on a strip 0.8 to 1.2 m wide). A corridor's doors are at its ends,
#: as wide as it is, or are the doors of the rooms along it, narrower than it. (On the training
#: plans: 1.9 or more for nine balconies in ten, 1.4 or less for nine such corridors in ten.)
SIDE_DOOR_MIN_RATIO = 1.6
#: A doorway area (a small space between two doors: a draught lobby, the passage through a thick
#: wall, the short stub of hallway a segmentation cuts between two doors) is at most this large (m²).
DOORWAY_MAX_AREA = 2.5
#: ... and at most this wide (m): as wide as a door and its frame.
DOORWAY_MAX_WIDTH = 1.5
#: Patches of furniture (desks, tables, pillars: cells of no room enclosed by one room) up to this
#: area (m²) count as the room's floor for its width and length: a desk makes an office no narrower.
#: Larger enclosed patches (a block of walls, a court) are kept out.
FURNITURE_MAX_AREA = 4.0
#: A hall is at least this large (m²) ...
HALL_MIN_AREA = 40.0
#: ... and this wide (m): a large open space (a lobby, an open-plan floor), not a long corridor.
HALL_MIN_WIDTH = 3.0


def room_shape(mask: np.ndarray, resolution: float) -> dict:
    """Shape measures of one room.

    Parameters
    ----------
    mask : (M, N) ndarray of bool
        The room's cells (any box around them).
    resolution : float
        Metres per cell.

    Returns
    -------
    dict
        ``area`` (m²), ``width`` (m, mean width), ``length`` (m, ``area / width``) and
        ``elongation`` (``length / width``), as the module docstring defines them.
    """
    mask = np.asarray(mask, bool)
    m = np.zeros((mask.shape[0] + 2, mask.shape[1] + 2), bool)
    m[1:-1, 1:-1] = mask
    n = int(np.count_nonzero(m))
    if n == 0:
        return {"area": 0.0, "width": 0.0, "length": 0.0, "elongation": 0.0}
    # OpenCV's 5 x 5 chamfer distances: a sequential two-pass transform, the same values whatever
    # the number of threads (its "precise" transform is parallel, and its float32 values change
    # with the threads), much faster than scipy's exact one, the mean within a fraction of a
    # percent of it
    dt = edt(m, exact=False)
    mean = float(dt[m].mean())
    width = max(4.0 * mean - 2.0, 1.0) * resolution  # cell-centre distances: a strip of k cells has mean (k + 2) / 4
    area = n * resolution ** 2
    length = area / width
    return {"area": area, "width": width, "length": length, "elongation": length / width}


def room_kind(area: float, width: float, length: float, doors: int, *, cut: bool = True,
              dead_ends: int = 0, widest_door: float = 0.0) -> str:
    """The kind of a room of these measures (:func:`room_shape`), number of doors and place in the
    room graph.

    Parameters
    ----------
    area : float
        m².
    width, length : float
        m.
    doors : int
        Number of the room's doors.
    cut : bool, optional
        Whether the room is a cut vertex of the room graph (every route between some of the rooms
        passes through it); true when not known.
    dead_ends : int, optional
        How many of the rooms it opens onto open onto no other room; 0 when not known.
    widest_door : float, optional
        Width of its widest door (m); 0 when not known.

    Returns
    -------
    str
        ``"corridor"``, ``"doorway"``, ``"hall"`` or ``"room"``, tested in that order:

        - ``"corridor"``: *corridor-shaped* — at least :data:`CORRIDOR_MIN_WIDTH` m wide and at
          most :data:`CORRIDOR_MAX_WIDTH` m, or a *long strip* (at most
          :data:`WIDE_CORRIDOR_MAX_WIDTH` m wide, :data:`WIDE_CORRIDOR_MIN_ELONGATION` widths and
          :data:`CORRIDOR_MIN_LENGTH` m long) — and a *hallway* (at least
          :data:`HALLWAY_MIN_DOORS` doors), a *passage* (:data:`CORRIDOR_MIN_DOORS` doors, at
          least :data:`CORRIDOR_MIN_LENGTH` m and :data:`CORRIDOR_MIN_ELONGATION` widths long,
          not the anteroom of a dead end among its two neighbours unless it is a long strip, and
          not, when those two are joined another way too, opening onto them through a door at
          least :data:`SIDE_DOOR_MIN_RATIO` times its width) or *alone* (no door, at least :data:`CORRIDOR_MIN_LENGTH` m and
          :data:`CORRIDOR_MIN_ELONGATION` widths long: a stair hall or an entrance the map joins to
          no room);
        - ``"doorway"``: at most :data:`DOORWAY_MAX_AREA` m² and :data:`DOORWAY_MAX_WIDTH` m
          wide, two doors or more;
        - ``"hall"``: at least :data:`HALL_MIN_AREA` m² and :data:`HALL_MIN_WIDTH` m wide;
        - ``"room"``: everything else.
    """
    if _corridor(width, length, doors, cut, dead_ends, widest_door):
        return "corridor"
    if doors >= 2 and area <= DOORWAY_MAX_AREA and width <= DOORWAY_MAX_WIDTH:
        return "doorway"
    if area >= HALL_MIN_AREA and width >= HALL_MIN_WIDTH:
        return "hall"
    return "room"


def _corridor(width, length, doors, cut, dead_ends, widest_door) -> bool:
    """Whether a room is a corridor: the first rule of :func:`room_kind`."""
    elongation = length / width if width > 0 else 0.0
    long_strip = (width <= WIDE_CORRIDOR_MAX_WIDTH and elongation >= WIDE_CORRIDOR_MIN_ELONGATION
                  and length >= CORRIDOR_MIN_LENGTH)
    if width < CORRIDOR_MIN_WIDTH or not (width <= CORRIDOR_MAX_WIDTH or long_strip):
        return False
    if doors >= HALLWAY_MIN_DOORS:
        return True
    strip = length >= CORRIDOR_MIN_LENGTH and elongation >= CORRIDOR_MIN_ELONGATION
    if doors == CORRIDOR_MIN_DOORS:
        anteroom = dead_ends > 0 and not long_strip
        beside = not cut and widest_door >= SIDE_DOOR_MIN_RATIO * width
        return strip and not anteroom and not beside
    return doors == 0 and strip


def _without_furniture(L, n, resolution):
    """The cells of room ``n`` in its box of labels ``L``, with the enclosed patches of no room's cells
    (furniture, pillars) of at most :data:`FURNITURE_MAX_AREA` m² filled in."""
    m = L == n
    holes, k = label(~m, 4)
    fill = np.ones(k + 1, bool)
    fill[0] = False
    fill[np.concatenate([holes[0], holes[-1], holes[:, 0], holes[:, -1]])] = False  # reach the box's border
    if fill.any():  # enclosed patches: only those small enough and holding no other room's cells
        fill &= np.bincount(holes.ravel(), minlength=k + 1) * resolution ** 2 <= FURNITURE_MAX_AREA
    if fill.any():
        fill[holes[(L != 0) & ~m]] = False
    if not fill.any():
        return m
    return m | fill[holes]


def graph_place(G) -> tuple:
    """Each room's place in the room graph ``G``: the set of its cut vertices and, per room, the
    number of its neighbours that have no other neighbour (dead ends).

    Linear in the rooms and doors (:func:`networkx.articulation_points`). A door from a room to
    itself is no route and counts for neither.
    """
    S = nx.Graph()
    S.add_nodes_from(G)
    S.add_edges_from((a, b) for a, b in G.edges() if a != b)
    cut = set(nx.articulation_points(S))
    adj = {n: list(nbrs) for n, nbrs in S.adjacency()}
    dead = {n: sum(1 for m in adj[n] if len(adj[m]) == 1) for n in adj}  # no self-loops: the degree
    return cut, dead


def annotate_kinds(G, labels: np.ndarray, resolution: float, *, boxes=None) -> None:
    """Put ``room_kind``, ``width`` and ``length`` on every room node of ``G``.

    Parameters
    ----------
    G : networkx.MultiGraph
        Room graph: its nodes are labels of ``labels``, its edges doors.
    labels : (M, N) ndarray of int
        The room labels.
    resolution : float
        Metres per cell.
    boxes : list of tuple of slice, optional
        ``ndi.find_objects(labels)``: the box of label ``i`` at ``boxes[i - 1]`` (found when not given).
    """
    if G.number_of_nodes() == 0:
        return
    if boxes is None:
        boxes = ndi.find_objects(labels, max_label=max(G.nodes))
    cut, dead = graph_place(G)
    widest = {}
    for a, b, w in G.edges(data="width", default=0.0):
        widest[a] = max(widest.get(a, 0.0), w)
        widest[b] = max(widest.get(b, 0.0), w)
    for n in G.nodes:
        sl = boxes[n - 1] if 0 < n <= len(boxes) else None
        if sl is None:
            continue
        s = room_shape(_without_furniture(labels[sl], n, resolution), resolution)
        G.nodes[n]["room_kind"] = room_kind(s["area"], s["width"], s["length"], G.degree(n),
                                            cut=n in cut, dead_ends=dead[n], widest_door=widest.get(n, 0.0))
        G.nodes[n]["width"] = s["width"]
        G.nodes[n]["length"] = s["length"]
