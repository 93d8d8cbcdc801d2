"""Synthetic example office map with ground truth.

The map is drawn with numpy only (no randomness), at 0.05 m/px, 400 x 280 px
(20 m x 14 m): a 2 m wide east-west corridor with three rooms north of it,
two rooms, an L-shaped room and a closet south of it. Walls are 0.15-0.25 m
thick, doors are gaps of 0.7-1.2 m, one room opens onto the corridor through
a 1.6 m wide opening, and there is some furniture (a table, a chair,
cabinets along walls, a round plant, a desk).

Run ``python -m topomap.io.example`` to rewrite the shipped files
``topomap/data/example_office.pgm`` and ``example_office.yaml``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .files import write_bytes
from .maps import GRAY_FREE, GRAY_OCCUPIED, GRAY_UNKNOWN, pgm_bytes, yaml_text

__all__ = ["ExampleMap", "make_example_office", "example_map_path", "write_example_files",
           "ROOM_NAMES", "EXAMPLE_STEM"]

EXAMPLE_STEM = "example_office"
RESOLUTION = 0.05
ORIGIN = [-10.0, -7.0, 0.0]
SHAPE = (280, 400)  # rows, cols

#: Room label -> name in the ground-truth label image.
ROOM_NAMES = {
    1: "north-west office",
    2: "meeting room",
    3: "north-east office",
    4: "south-west office",
    5: "lab",
    6: "L-shaped office",
    7: "closet",
    8: "corridor",
}

# Free interiors per room: list of (r0, r1, c0, c1) half-open rectangles.
# Outer walls are 5 px (0.25 m), inner walls 4 px (0.2 m), closet walls 3 px
# (0.15 m); walls are whatever is not carved out of the building block.
_BUILDING = (10, 270, 10, 390)
_ROOMS = {
    1: [(15, 116, 15, 134)],
    2: [(15, 116, 138, 258)],
    3: [(15, 116, 262, 385)],
    4: [(164, 265, 15, 120)],
    5: [(164, 265, 124, 250)],
    6: [(213, 265, 254, 385), (164, 213, 254, 323)],  # L shape
    7: [(164, 210, 326, 385)],
    8: [(120, 160, 15, 385)],
}

# Doors: (r0, r1, c0, c1) gap carved through a wall, and the two rooms joined.
_DOORS = [
    ((116, 120, 60, 78), (1, 8)),     # 0.9 m
    ((116, 120, 182, 214), (2, 8)),   # 1.6 m wide opening
    ((116, 120, 300, 314), (3, 8)),   # 0.7 m
    ((40, 60, 134, 138), (1, 2)),     # 1.0 m, room to room
    ((160, 164, 40, 64), (4, 8)),     # 1.2 m
    ((160, 164, 160, 176), (5, 8)),   # 0.8 m
    ((160, 164, 270, 292), (6, 8)),   # 1.1 m
    ((180, 196, 323, 326), (7, 6)),   # 0.8 m, closet, thin wall
]

# Furniture: occupied rectangles (r0, r1, c0, c1) and disks (r, c, radius).
_FURNITURE_RECTS = [
    (50, 66, 186, 206),    # meeting table 0.8 m x 1.0 m
    (70, 76, 90, 96),      # chair 0.3 m
    (257, 265, 30, 46),    # cabinet 0.8 m x 0.4 m against the south wall
    (257, 265, 50, 66),    # cabinet
    (15, 23, 330, 348),    # cabinet 0.9 m x 0.4 m against the north wall
    (15, 23, 352, 370),    # cabinet
    (240, 252, 290, 310),  # desk 0.6 m x 1.0 m
]
_FURNITURE_DISKS = [
    (215, 190, 7),         # plant / round table, 0.75 m across
]


@dataclass(frozen=True, eq=False)
class ExampleMap:
    """The example office map and its ground truth.

    Iterating yields ``(gray, yaml)``, so ``gray, meta = make_example_office()``
    works.

    Attributes
    ----------
    gray : (280, 400) ndarray of uint8
        Map image: 0 occupied (walls, furniture), 254 free, 205 unknown
        (outside the building).
    yaml : dict
        map_server metadata (``image``, ``resolution`` 0.05 m/px, ``origin``
        ``[-10, -7, 0]``, ``negate``, ``occupied_thresh``, ``free_thresh``).
    rooms : (280, 400) ndarray of int32
        True room of every free cell (labels 1..8, see :data:`ROOM_NAMES`,
        8 = corridor); 0 on walls, furniture, outside and door gaps.
    doors : list of ((int, int), (int, int))
        Each door as a pixel segment ``((r0, c0), (r1, c1))`` (inclusive
        end points) across the gap, along the middle of the wall.
    door_rooms : list of (int, int)
        The two room labels each door joins, parallel to ``doors``.
    door_widths : list of float
        Clear width of each door in metres.
    """

    gray: np.ndarray
    yaml: dict
    rooms: np.ndarray
    doors: list
    door_rooms: list
    door_widths: list

    def __iter__(self):
        return iter((self.gray, self.yaml))


def _disk(shape, r, c, radius):
    rr, cc = np.ogrid[:shape[0], :shape[1]]
    return (rr - r) ** 2 + (cc - c) ** 2 <= radius ** 2


def make_example_office() -> ExampleMap:
    """Draw the example office map (deterministic).

    Returns
    -------
    ExampleMap
        ``gray`` (280, 400) uint8 image at 0.05 m/px, ``yaml`` dict,
        ``rooms`` (280, 400) int32 truth labels, ``doors`` pixel segments.
    """
    gray = np.full(SHAPE, GRAY_UNKNOWN, np.uint8)
    r0, r1, c0, c1 = _BUILDING
    gray[r0:r1, c0:c1] = GRAY_OCCUPIED
    rooms = np.zeros(SHAPE, np.int32)
    for label, rects in _ROOMS.items():
        for (a, b, c, d) in rects:
            gray[a:b, c:d] = GRAY_FREE
            rooms[a:b, c:d] = label
    doors, door_rooms, widths = [], [], []
    for (a, b, c, d), joined in _DOORS:
        gray[a:b, c:d] = GRAY_FREE
        if b - a < d - c:  # gap in a horizontal wall
            mid = (a + b) // 2
            doors.append(((mid, c), (mid, d - 1)))
            widths.append(round((d - c) * RESOLUTION, 6))
        else:
            mid = (c + d) // 2
            doors.append(((a, mid), (b - 1, mid)))
            widths.append(round((b - a) * RESOLUTION, 6))
        door_rooms.append(joined)
    furniture = np.zeros(SHAPE, bool)
    for (a, b, c, d) in _FURNITURE_RECTS:
        furniture[a:b, c:d] = True
    for (r, c, rad) in _FURNITURE_DISKS:
        furniture |= _disk(SHAPE, r, c, rad)
    gray[furniture] = GRAY_OCCUPIED
    rooms[gray != GRAY_FREE] = 0
    meta = {
        "image": f"{EXAMPLE_STEM}.pgm",
        "resolution": RESOLUTION,
        "origin": list(ORIGIN),
        "negate": 0,
        "occupied_thresh": 0.65,
        "free_thresh": 0.196,
    }
    return ExampleMap(gray, meta, rooms, doors, door_rooms, widths)


def _data_dir() -> Path:
    return Path(__file__).parent.parent / "data"


def example_map_path() -> Path:
    """Path of the shipped example map YAML (``topomap/data/example_office.yaml``).

    Returns
    -------
    pathlib.Path
        Pass it to :func:`topomap.io.load_map`.
    """
    return _data_dir() / f"{EXAMPLE_STEM}.yaml"


def example_file_bytes() -> dict:
    """Exact bytes of the shipped files, keyed by file name."""
    ex = make_example_office()
    return {
        f"{EXAMPLE_STEM}.pgm": pgm_bytes(ex.gray),
        f"{EXAMPLE_STEM}.yaml": yaml_text(ex.yaml).encode(),
    }


def write_example_files(directory=None) -> Path:
    """Write the example PGM + YAML into ``directory`` (default: the package data).

    Returns
    -------
    pathlib.Path
        The YAML file written.
    """
    d = Path(directory) if directory is not None else _data_dir()
    d.mkdir(parents=True, exist_ok=True)
    for fname, data in example_file_bytes().items():
        write_bytes(d / fname, data)
    return d / f"{EXAMPLE_STEM}.yaml"


if __name__ == "__main__":  # pragma: no cover
    print(write_example_files())
