"""Small hand-drawn test maps with their known answers (skan style).

Every map is drawn with numpy only, at :data:`RES` = 0.05 m/px, and comes as
a :class:`TestMap`: the array (a bool free-space mask, or a uint8 gray image
with map_server's gray values), the expected room count and the expected
doors as centre points in metres, in the map frame of
``topomap.io.from_array(array)`` (origin ``(0, 0)`` at the lower-left corner
of the image, ``x`` to the right, ``y`` up).

Drawing convention: a map starts fully occupied (or unknown outside the
building for gray maps); room interiors are carved out as free rectangles
``(r0, r1, c0, c1)`` (half-open, pixels); a door is a free rectangle carved
through a wall.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

RES = 0.05  # m/px

GRAY_FREE, GRAY_OCCUPIED, GRAY_UNKNOWN = 254, 0, 205


@dataclass
class TestMap:
    """A test map and its known answer.

    Attributes
    ----------
    name : str
    array : (M, N) ndarray
        bool (True = free) or uint8 gray image.
    n_rooms : int
        Expected number of rooms.
    doors : list of (x, y)
        Expected door centres in metres (map frame of ``from_array``).
    door_widths : list of float
        Widths (m) of the door gaps, in the order of ``doors``.
    resolution : float
        Metres per pixel.
    """

    __test__ = False  # not a pytest test class

    name: str
    array: np.ndarray
    n_rooms: int
    doors: list = field(default_factory=list)
    door_widths: list = field(default_factory=list)
    resolution: float = RES

    @property
    def n_doors(self) -> int:
        return len(self.doors)

    @property
    def free(self) -> np.ndarray:
        a = self.array
        return a if a.dtype == bool else a == GRAY_FREE


def _centre_m(shape, r0, r1, c0, c1, res=RES):
    """Metric centre (x, y) of the half-open pixel rectangle in an image of ``shape``."""
    H = shape[0]
    rc = (r0 + r1 - 1) / 2.0
    cc = (c0 + c1 - 1) / 2.0
    return ((cc + 0.5) * res, (H - rc - 0.5) * res)


def _carve(a, rects, value=True):
    for r0, r1, c0, c1 in rects:
        a[r0:r1, c0:c1] = value
    return a


def _build(name, shape, rooms, doors, n_rooms, furniture=(), door_width_axis=None):
    """Bool map: occupied everywhere, ``rooms`` and ``doors`` carved free, ``furniture`` occupied."""
    a = np.zeros(shape, bool)
    _carve(a, rooms)
    _carve(a, doors)
    _carve(a, furniture, False)
    centres = [_centre_m(shape, *d) for d in doors]
    widths = [max(d[1] - d[0], d[3] - d[2]) * RES for d in doors]
    return TestMap(name, a, n_rooms, centres, widths)


def two_rooms() -> TestMap:
    """Two 3 m x 3 m rooms side by side, a 0.2 m wall between, one 0.9 m door.

    Outer walls 0.25 m (5 px), inner wall 0.2 m (4 px). 70 x 134 px.
    """
    rooms = [(5, 65, 5, 65), (5, 65, 69, 129)]
    doors = [(26, 44, 65, 69)]  # 18 px = 0.9 m, centred on the wall
    return _build("two_rooms", (70, 134), rooms, doors, 2)


def corridor_with_rooms() -> TestMap:
    """A 1.5 m corridor along the south with three 4 m x 3 m offices north of it.

    Doors of 0.8, 1.0 and 0.9 m, centred in the 0.2 m wall between each
    office and the corridor (so every door jamb is > 1 m of wall away from
    the next wall junction); 0.2 m walls between offices; 0.25 m outer
    walls. 104 x 258 px.
    """
    top, bot = 5, 65           # offices rows 5..64 (3 m)
    crow0, crow1 = 69, 99      # corridor rows 69..98 (1.5 m)
    cols = [(5, 85), (89, 169), (173, 253)]
    rooms = [(top, bot, c0, c1) for c0, c1 in cols] + [(crow0, crow1, 5, 253)]
    doors = [
        (bot, crow0, 37, 53),    # 0.8 m
        (bot, crow0, 119, 139),  # 1.0 m
        (bot, crow0, 204, 222),  # 0.9 m
    ]
    return _build("corridor_with_rooms", (104, 258), rooms, doors, 4)


def door_near_corner() -> TestMap:
    """:func:`corridor_with_rooms` drawn tighter: 3 m offices, doors 0.75-0.85 m from a corner.

    Same walls and doors as the corridor map, but the wall stubs beside the
    doors are only 15-17 px (0.75-0.85 m) long. 104 x 198 px.
    """
    top, bot = 5, 65
    crow0, crow1 = 69, 99
    cols = [(5, 65), (69, 129), (133, 193)]
    rooms = [(top, bot, c0, c1) for c0, c1 in cols] + [(crow0, crow1, 5, 193)]
    doors = [
        (bot, crow0, 20, 36),    # 0.8 m, 0.75 m from the west outer wall
        (bot, crow0, 85, 105),   # 1.0 m, 0.8 m from the wall between offices 1 and 2
        (bot, crow0, 160, 178),  # 0.9 m, 0.75 m from the east outer wall
    ]
    return _build("door_near_corner", (104, 198), rooms, doors, 4)


def room_with_furniture() -> TestMap:
    """One 5 m x 4 m room with a table, a chair, two cabinets and a column: no door.

    The furniture leaves passages of 0.7-1.2 m between itself and the walls,
    as narrow as doors, but it is free-standing (or against one wall), so no
    door must be found. 90 x 110 px.
    """
    rooms = [(5, 85, 5, 105)]
    furniture = [
        (30, 50, 40, 70),   # table 1.0 m x 1.5 m
        (55, 61, 52, 58),   # chair 0.3 m
        (5, 13, 20, 40),    # cabinet against the north wall
        (77, 85, 70, 95),   # cabinet against the south wall
        (40, 48, 85, 93),   # column 0.4 m
    ]
    return _build("room_with_furniture", (90, 110), rooms, [], 1, furniture)


def partition_of_blocks() -> TestMap:
    """Two rooms 9.2 m x 2.25 m apart by a partition drawn as a row of solid blocks.

    The 0.6 m thick partition runs from the west to the east wall: a 1.0 m
    stub on each outer wall and three free-standing blocks of 1.2 m x 0.6 m
    (each as bulky as a desk; more than half of the partition) between
    them, with four 0.9 m openings. On a drawn plan that is a wall with four
    doors, not a row of furniture. 112 x 194 px.
    """
    rooms = [(5, 107, 5, 189)]
    pieces = [(5, 25), (43, 67), (85, 109), (127, 151), (169, 189)]
    m = _build("partition_of_blocks", (112, 194), rooms, [], 2, [(50, 62, c0, c1) for c0, c1 in pieces])
    gaps = [(a[1], b[0]) for a, b in zip(pieces[:-1], pieces[1:])]
    m.doors = [_centre_m(m.array.shape, 50, 62, c0, c1) for c0, c1 in gaps]
    m.door_widths = [(c1 - c0) * RES for c0, c1 in gaps]
    return m


def l_shaped_room() -> TestMap:
    """One L-shaped room (legs 2.5 m wide, 5 m long), no door. 110 x 110 px."""
    rooms = [(5, 105, 5, 55), (55, 105, 5, 105)]
    return _build("l_shaped_room", (110, 110), rooms, [], 1)


def door_at_map_edge() -> TestMap:
    """Two rooms in a map cropped tight: the outer walls are the image border.

    The outer walls are 2 px (0.1 m) thick and lie on the image border, so
    the rooms' walls touch the edge of the map; a 0.9 m door is centred in
    the 0.2 m dividing wall, 1.3 m of wall on each side. 74 x 124 px.
    """
    rooms = [(2, 72, 2, 60), (2, 72, 64, 122)]
    doors = [(28, 46, 60, 64)]  # 18 px = 0.9 m
    return _build("door_at_map_edge", (74, 124), rooms, doors, 2)


def door_beside_wall() -> TestMap:
    """Two rooms joined by a 0.8 m door flush against the north outer wall.

    The door runs from the north wall to the end of the dividing wall: a
    wall end (protruding part) on one side only. 70 x 134 px.
    """
    rooms = [(5, 65, 5, 65), (5, 65, 69, 129)]
    doors = [(5, 21, 65, 69)]  # 16 px = 0.8 m
    return _build("door_beside_wall", (70, 134), rooms, doors, 2)


def gray_two_rooms_unknown_outside() -> TestMap:
    """:func:`two_rooms` as a gray image (254 free, 0 wall) inside unknown (205) surroundings.

    A 10 px unknown margin surrounds the building, as a SLAM map has. 90 x 154 px.
    """
    base = two_rooms()
    m = 10
    H, W = base.array.shape
    g = np.full((H + 2 * m, W + 2 * m), GRAY_UNKNOWN, np.uint8)
    g[m:m + H, m:m + W] = np.where(base.array, GRAY_FREE, GRAY_OCCUPIED)
    doors = [(x + m * RES, y + m * RES) for x, y in base.doors]
    return TestMap("gray_two_rooms_unknown_outside", g, 2, doors, base.door_widths)


def one_room() -> TestMap:
    """A single empty 4 m x 3 m rectangular room: one room, no door. 70 x 90 px."""
    return _build("one_room", (70, 90), [(5, 65, 5, 85)], [], 1)


def disconnected_regions() -> TestMap:
    """Three free regions with no connection at all (two rooms and a closed box).

    Each is a room of its own, no door. 60 x 150 px.
    """
    rooms = [(5, 55, 5, 55), (5, 55, 60, 110), (20, 40, 120, 140)]
    return _build("disconnected_regions", (60, 150), rooms, [], 3)


ALL = [two_rooms, corridor_with_rooms, door_near_corner, room_with_furniture, l_shaped_room,
       door_at_map_edge, door_beside_wall, gray_two_rooms_unknown_outside, one_room,
       disconnected_regions]


def gray(a: np.ndarray) -> np.ndarray:
    """map_server gray image of a bool free mask (254 free, 0 occupied)."""
    return np.where(a, GRAY_FREE, GRAY_OCCUPIED).astype(np.uint8)


# --------------------------------------------------------------------------
# Real-building features (issue 13): pillars, niches, desks, specks, noise.
# Not in ALL (whose maps other tests and docs/errors.md describe); listed in
# REAL_WORLD. Walls 0.2 m (4 px) unless said otherwise.
# --------------------------------------------------------------------------

def corridor_with_pillars() -> TestMap:
    """A 2 m x 20 m corridor with 0.35 m pillars on both sides, and one office off it.

    Pillars (7 px square) stand in opposite pairs every 3 m, alternately
    against the walls and 0.15 m (3 px) off them (free-standing), so the
    corridor narrows to 1.3 m and 1.0 m at the pairs: a pillar is not a
    wall, so none of these narrowings is a door. A 5 m x 4 m office north of
    the corridor is entered by a 0.9 m door in the 0.2 m wall, 0.7 m from
    the nearest pillar and 2 m of wall either side. 132 x 408 px.
    """
    crow0, crow1 = 88, 128                 # corridor rows (2 m)
    rooms = [(crow0, crow1, 4, 404),       # corridor 20 m
             (4, 84, 120, 220)]            # office 5 m x 4 m
    doors = [(84, 88, 161, 179)]           # 18 px = 0.9 m
    furniture = []
    for k, c in enumerate(range(20, 400, 60)):   # 7 pairs, 3 m apart
        off = 0 if k % 2 == 0 else 3             # against the wall / 0.15 m off it
        furniture.append((crow0 + off, crow0 + off + 7, c, c + 7))   # north pillar
        furniture.append((crow1 - off - 7, crow1 - off, c, c + 7))   # south pillar
    return _build("corridor_with_pillars", (132, 408), rooms, doors, 2, furniture)


def corridor_with_niches() -> TestMap:
    """A 2 m x 16 m corridor with five niches in its walls and doors into two offices.

    Niches (recesses 0.5-1.0 m deep, 1.2-2.0 m long) are cut into the solid
    parts of both corridor walls; they are part of the corridor, not rooms.
    Two 5 m x 4 m offices north of the corridor are entered by 0.9 m doors in
    the 0.2 m wall (3 rooms, 2 doors). 152 x 328 px.
    """
    crow0, crow1 = 88, 128                 # corridor rows (2 m)
    rooms = [(crow0, crow1, 4, 324),       # corridor 16 m
             (4, 84, 4, 104),              # office A 5 m x 4 m
             (4, 84, 170, 270)]            # office B 5 m x 4 m
    niches = [(72, crow0, 120, 150),       # north, 0.8 m deep, 1.5 m long (between the offices)
              (76, crow0, 290, 314),       # north, 0.6 m deep, 1.2 m long
              (crow1, crow1 + 16, 20, 50),     # south, 0.8 m deep, 1.5 m long
              (crow1, crow1 + 10, 140, 180),   # south, 0.5 m deep, 2.0 m long
              (crow1, crow1 + 20, 240, 270)]   # south, 1.0 m deep, 1.5 m long
    doors = [(84, crow0, 60, 78),          # office A, 0.9 m
             (84, crow0, 210, 228)]        # office B, 0.9 m
    return _build("corridor_with_niches", (152, 328), rooms + niches, doors, 3)


def room_with_desks() -> TestMap:
    """A 6 m x 5 m office with six 0.8 m x 1.6 m desks along three walls, and a second room.

    The desks (16 x 32 px) stand along the north, west and south walls,
    touching them or 0.1-0.3 m off them; neighbours along a wall are 0.2 m
    apart or 0.9 m apart (room for a chair: a door-wide gap between two
    desks). The east wall has a 0.9 m door into an empty 4 m x 5 m room.
    The slits behind the desks and the gaps between them are not doors:
    2 rooms, 1 door. 108 x 212 px.
    """
    rooms = [(4, 104, 4, 124),             # office 6 m x 5 m
             (4, 104, 128, 208)]           # second room 4 m x 5 m
    doors = [(50, 68, 124, 128)]           # 18 px = 0.9 m
    desks = [
        (4, 20, 10, 42),      # north wall, touching
        (6, 22, 60, 92),      # north wall, 0.1 m off, 0.9 m from the first
        (30, 62, 4, 20),      # west wall, touching
        (66, 98, 10, 26),     # west wall, 0.3 m off, 0.2 m from the first
        (88, 104, 36, 68),    # south wall, touching
        (85, 101, 86, 118),   # south wall, 0.15 m off, 0.9 m from the first, 0.3 m from the east wall
    ]
    return _build("room_with_desks", (108, 212), rooms, doors, 2, desks)


def specks_outside_building() -> TestMap:
    """:func:`two_rooms` as a gray SLAM-like map with free specks in the unknown outside.

    The building (two 3 m x 3 m rooms, a 0.9 m door) sits in a 1.5 m unknown
    (205) margin holding free cells no robot can reach, as laser beams
    through a window leave them: four single free cells, a 2-cell speck and
    an 11 x 11 px (0.55 m x 0.55 m = 0.30 m²) free patch with a few occupied
    cells on its far side. The specks are fragments, not rooms: 2 rooms, 1
    door. 130 x 194 px.
    """
    base = two_rooms()
    m = 30
    H, W = base.array.shape
    g = np.full((H + 2 * m, W + 2 * m), GRAY_UNKNOWN, np.uint8)
    g[m:m + H, m:m + W] = np.where(base.array, GRAY_FREE, GRAY_OCCUPIED)
    for r, c in [(8, 20), (15, 180), (120, 60), (112, 150)]:   # single free cells
        g[r, c] = GRAY_FREE
    g[60, 10:12] = GRAY_FREE                                    # 2-cell speck
    g[106:117, 10:21] = GRAY_FREE                               # 0.30 m² patch
    g[106:117, 8] = GRAY_OCCUPIED                               # its far side, partly seen
    g[108:112, 8] = GRAY_UNKNOWN
    doors = [(x + m * RES, y + m * RES) for x, y in base.doors]
    return TestMap("specks_outside_building", g, 2, doors, base.door_widths)



def free_strip_at_edge() -> TestMap:
    """:func:`specks_outside_building` with a strip of free cells two cells
    (0.1 m) wide along the top and left edges of the image (about 640
    cells, 1.6 m²: more than the smallest room), as a map's frame or a
    sensor artefact leaves it. No robot fits in it: a fragment, not a room;
    2 rooms, 1 door. 130 x 194 px.
    """
    base = specks_outside_building()
    g = base.array.copy()
    g[:2, :] = GRAY_FREE
    g[:, :2] = GRAY_FREE
    return TestMap("free_strip_at_edge", g, 2, base.doors, base.door_widths)

def noisy_corridor_with_pillars(seed: int = 13) -> TestMap:
    """:func:`corridor_with_pillars` with laser-style noise (seeded): 2 rooms, 1 door.

    * jagged wall edges: each free cell on an obstacle's face becomes
      occupied with probability 0.2, each obstacle cell on a face becomes
      free with probability 0.2 (±1 cell);
    * 8 gaps of 1-2 cells through the outer walls (the exterior is occupied,
      so they are dead-end slits, never a second way between rooms);
    * up to 40 isolated occupied cells in the free space (none at the door).

    The dividing wall, its door jambs and the door gap keep their drawn
    cells apart from the ±1 edge noise; free cells the noise cut off from
    the rest (if any) are filled, so the free space is one component.
    """
    import cv2

    base = corridor_with_pillars()
    a = base.array.copy()
    rng = np.random.default_rng(seed)
    H, W = a.shape
    occ = ~a
    pad = np.pad(a, 1)
    free_nb = pad[:-2, 1:-1] | pad[2:, 1:-1] | pad[1:-1, :-2] | pad[1:-1, 2:]
    padocc = np.pad(occ, 1, constant_values=True)
    occ_nb = padocc[:-2, 1:-1] | padocc[2:, 1:-1] | padocc[1:-1, :-2] | padocc[1:-1, 2:]
    grow = a & occ_nb & (rng.random(a.shape) < 0.2)       # free face cell -> occupied
    shrink = occ & free_nb & (rng.random(a.shape) < 0.2)  # wall face cell -> free
    keep = np.zeros_like(a)
    keep[84:88, 155:185] = True                           # door and its jambs stay as drawn
    a[grow & ~keep] = False
    a[shrink & ~keep] = True
    # gaps through the outer walls: south wall of the corridor, office's north wall
    for c in rng.choice(np.arange(10, 395), 6, replace=False):
        a[128:132, c:c + int(rng.integers(1, 3))] = True
    for c in rng.choice(np.arange(125, 215), 2, replace=False):
        a[0:4, c:c + int(rng.integers(1, 3))] = True
    # speckles in the free space, away from the door gap
    rr, cc = np.nonzero(base.array)
    idx = rng.choice(len(rr), 40, replace=False)
    for r, c in zip(rr[idx], cc[idx]):
        if not (80 <= r < 92 and 155 <= c < 185):
            a[r, c] = False
    # one free component: fill any pocket the noise cut off
    n, comp = cv2.connectedComponents(a.astype(np.uint8), connectivity=4)
    if n > 2:
        sizes = np.bincount(comp.ravel())
        sizes[0] = 0
        a &= comp == int(np.argmax(sizes))
    return TestMap("noisy_corridor_with_pillars", a, 2, base.doors, base.door_widths)


def partition_mapped_in_part(specks: bool = True) -> TestMap:
    """Two 4 m x 5 m rooms whose dividing wall the laser saw only in part.

    The 0.2 m partition stands on the south wall and is drawn 2.5 m long;
    on the remaining 2.5 m of its line to the north wall the laser saw only
    five single hits (0.05 m specks, 0.35-0.45 m apart), as a glass
    partition or a wall seen edge-on leaves them: a wall seen in pieces,
    the gap cut as the door between the rooms (2 rooms, 1 door).
    ``specks=False`` (:func:`partition_end_in_a_room`) leaves the line empty.
    108 x 172 px.
    """
    a = np.zeros((108, 172), bool)
    a[4:104, 4:168] = True
    a[54:104, 84:88] = False                       # partition, 2.5 m from the south wall
    if specks:
        for r in (14, 22, 31, 40, 47):
            a[r, 85] = False                       # laser hits on its line
    door = (4, 54, 84, 88)
    return TestMap("partition_mapped_in_part", a, 2, [_centre_m(a.shape, *door)], [2.5])


def partition_end_in_a_room() -> TestMap:
    """:func:`partition_mapped_in_part` with nothing seen past the wall's end.

    A wall that ends 2.5 m short of the wall across, with no laser hit on
    its line beyond: the way round its end in one U-shaped room (a cupboard
    row, a half-height divider), not a door: 1 room, 0 doors.
    """
    base = partition_mapped_in_part(specks=False)
    return TestMap("partition_end_in_a_room", base.array, 1)


REAL_WORLD = [corridor_with_pillars, corridor_with_niches, room_with_desks,
              specks_outside_building, free_strip_at_edge, noisy_corridor_with_pillars,
              partition_mapped_in_part, partition_end_in_a_room]
