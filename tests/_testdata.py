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
