"""Floor plans on a grid, with their ground truth: the input of the simulator.

A :class:`FloorPlan` is a home (or any building) drawn on an occupancy grid:
walls with a thickness, doors open, the outside of the building apart, and
the ground truth a room-segmentation benchmark needs (room labels with the
doors closed, the door segments, each room's kinds). It is what
:func:`read_plan` makes of one vector plan of the R2V / LIFULL data set and
what :mod:`topomap.bench.simulate` scans with a simulated robot.

Grid convention: the ROS one of :class:`topomap.io.OccupancyGrid`: row 0 is
the top of the image (largest y), ``origin`` is the world pose of the
lower-left corner of the grid, metres and radians.
"""

from __future__ import annotations

import logging
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._fast import label as _label
from ..core.geometry import point_segment_distances
from ..errors import MapError, MapFileError, MapTooLargeError, ParameterError, PlanFormatError, named
from ..grid import FREE, OCCUPIED, UNKNOWN, OccupancyGrid, cell_limit
from ..io.maps import save_map
from ..io.metadata import check_file, check_resolution
from ..options import check_area, check_length

__all__ = ["PlanDoor", "FloorPlan", "read_plan", "plan_grid", "ground_truth_problems", "ROOM_KINDS", "STORAGE_KINDS",
           "FIXTURE_KINDS"]

_log = logging.getLogger(__name__)

#: Categories of the plan files that name a room (their box is the room's label).
ROOM_KINDS = frozenset({"bedroom", "living_room", "kitchen", "bathroom", "restroom", "washing_room",
                        "corridor", "closet", "balcony", "entrance", "PS", "stairs"})
#: Room kinds that are storage, not rooms: such a space behind its own door belongs to the room it opens into.
STORAGE_KINDS = frozenset({"closet", "PS"})
#: Objects that make a small unlabelled space a room of its own (a toilet, a shower), not a nook.
FIXTURE_KINDS = frozenset({"toilet", "bathtub", "washing_basin", "cooking_counter"})
#: Categories that are neither rooms nor objects: skipped (wall junction points of some plans).
_SKIPPED = frozenset({"point"})

#: Defaults of :func:`read_plan` (metres, m²).
WALL_THICKNESS = 0.15
DOOR_WIDTH = 0.8
MARGIN = 1.0
MAX_GAP = 0.3
NOOK_AREA = 1.5
#: Door segments narrower than this are left out, the wall closed there (metres): narrower than
#: anyone walks through (as ``max_gap``); in the plans they are slips of the drawing.
MIN_DOOR_WIDTH = 0.3
#: A door segment this close to a wall line and parallel to it is moved onto it (metres).
DOOR_SNAP = 0.3
#: Sine of the largest angle between a door and the wall it is moved onto (10 degrees).
_SNAP_SIN = math.sin(math.radians(10.0))
#: Parts of the home apart from the largest (no door joins them) kept when at least this large (m²).
MIN_PART_AREA = 4.0
#: The area of the bounding box of a plan's walls that sets the scale of a plan with no doors (m²):
#: 62 m², the median over the R2V plans scaled by their doors (middle half 44-86 m²). A home's size
#: is the one physical cue left when there is no door; it gives the door-scaled plans' scale within
#: 20 % for half of them and within 50 % for nine in ten.
HOME_AREA = 62.0


@dataclass(frozen=True)
class PlanDoor:
    """One door of a plan.

    Parameters
    ----------
    p1, p2 : tuple of float
        End points of the door segment (on the wall's centre line), world
        metres ``(x, y)``.
    rooms : tuple of int
        The two ground-truth room labels the door joins, smaller first;
        0 stands for the outside of the home (an entrance, a balcony door
        onto an outside that is not a room). Both are the same label for
        the door of a closet that belongs to the room it opens into.
    width : float
        Length of the door segment, metres.
    """

    p1: tuple
    p2: tuple
    rooms: tuple
    width: float


@dataclass(frozen=True, eq=False)
class FloorPlan:
    """A plan drawn on a grid with its ground truth.

    Parameters
    ----------
    name : str
        The plan's name (its file stem).
    resolution : float
        Metres per cell.
    origin : tuple of float
        ``(x, y, yaw)`` of the grid's lower-left corner (ROS convention).
    walls : (M, N) ndarray of bool
        Wall cells, drawn with their thickness; doors are open (not walls).
    inside : (M, N) ndarray of bool
        Free cells inside the home (doors open, door cells included).
        Spaces closed all round with no door (pipe shafts, the slit between
        two wall lines drawn close together) are not inside: no robot gets
        there.
    rooms : (M, N) ndarray of uint16
        Ground-truth room labels on the same grid: 1..K inside the home with
        the doors closed (a closet behind its own door belongs to the room
        it opens into), 0 on walls and the outside. A door's cells belong to
        the rooms either side of its centre line, as a line drawn across the
        doorway splits them in a ground-truth image (all of them to the room
        when the other side is the outside), so ``rooms > 0`` is exactly
        ``inside``.
    doors : tuple of PlanDoor
        The doors of the plan.
    kinds : dict
        Room label -> tuple of kind names from the plan's label boxes
        (``"bedroom"``, ``"corridor"``, ...) in the order of the file, one
        per box; ``()`` for a room with none. Every label 1..K is a key.
    outer_walls : (M, N) ndarray of bool
        The wall cells that face the outside (the facade): where glass may
        let laser rays through.
    objects : tuple
        Object boxes of the plan (fixtures, furniture) as
        ``(kind, x1, y1, x2, y2)`` in world metres, ``x1 <= x2``, ``y1 <= y2``.
    scale : float
        Metres per unit of the plan's own coordinates.
    quirks : dict
        Counts of what the reader mended or left out (see :func:`read_plan`).
    """

    name: str
    resolution: float
    origin: tuple
    walls: np.ndarray
    inside: np.ndarray
    rooms: np.ndarray
    doors: tuple = ()
    kinds: dict = field(default_factory=dict)
    outer_walls: np.ndarray = None
    objects: tuple = ()
    scale: float = 1.0
    quirks: dict = field(default_factory=dict)

    @property
    def shape(self) -> tuple:
        return self.walls.shape

    @property
    def n_rooms(self) -> int:
        """Number of ground-truth rooms K."""
        return len(self.kinds)

    @property
    def area(self) -> float:
        """Area of the home's free space (``inside``), m²."""
        return float(np.count_nonzero(self.inside)) * self.resolution ** 2

    def room_areas(self) -> dict:
        """Room label -> area in m² (door cells counted with their room)."""
        counts = np.bincount(self.rooms.ravel(), minlength=self.n_rooms + 1)
        return {k: float(counts[k]) * self.resolution ** 2 for k in range(1, self.n_rooms + 1)}

    def grid(self) -> OccupancyGrid:
        """The plan as a map a user would draw: see :func:`plan_grid`."""
        return plan_grid(self)

    def save(self, path_stem):
        """Write :meth:`grid` as a map_server PGM + YAML pair (0 wall, 254 free, 205 unknown).

        Returns the YAML path (:func:`topomap.io.save_map`).
        """
        return save_map(self.grid(), path_stem)


def plan_grid(plan: FloorPlan) -> OccupancyGrid:
    """The drawn map of a plan: walls OCCUPIED, the home FREE, everything else UNKNOWN.

    Parameters
    ----------
    plan : FloorPlan

    Returns
    -------
    OccupancyGrid
        On the plan's resolution and origin, ``source`` the plan's name. The
        outside and the closed spaces no door leads into are unknown.
    """
    cells = np.full(plan.shape, UNKNOWN, np.int8)
    cells[plan.inside] = FREE
    cells[plan.walls] = OCCUPIED
    return OccupancyGrid(cells, resolution=plan.resolution, origin=plan.origin, source=plan.name)


# --------------------------------------------------------------------------
# reading the file
# --------------------------------------------------------------------------

def _parse(path: Path, name: str):
    """Walls (n, 4), doors (m, 4) and boxes ``[(category, x1, y1, x2, y2)]`` in plan units."""
    try:
        check_file(name, path, what="plan file")
    except PlanFormatError:
        raise
    except MapError as exc:  # empty file
        raise PlanFormatError(str(exc)) from None
    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as exc:
        raise PlanFormatError(named(name, f"not a text plan file (not UTF-8 at byte {exc.start})")) from None
    except OSError as exc:
        raise MapFileError(named(name, f"cannot read plan file: {exc.strerror or exc}")) from None
    walls, doors, boxes = [], [], []
    n = 0
    for i, line in enumerate(text.splitlines(), 1):
        f = line.split()
        if not f:
            continue
        if not 5 <= len(f) <= 7:
            raise PlanFormatError(named(name, f"line {i}: expected 'x1 y1 x2 y2 category [a b]' "
                                              f"(5 to 7 fields), got {len(f)} fields: {line.strip()!r}"))
        try:
            xy = [float(v) for v in f[:4]]
        except ValueError:
            bad = next(v for v in f[:4] if not _is_number(v))
            raise PlanFormatError(named(name, f"line {i}: coordinate {bad!r} is not a number")) from None
        if not all(math.isfinite(v) for v in xy):
            raise PlanFormatError(named(name, f"line {i}: coordinates must be finite, got {f[:4]}"))
        cat = f[4]
        if not cat[0].isalpha():
            raise PlanFormatError(named(name, f"line {i}: category {cat!r} is not a name (wall, door, bedroom, ...)"))
        n += 1
        if cat == "wall":
            walls.append(xy)
        elif cat == "door":
            doors.append(xy)
        elif cat not in _SKIPPED:
            boxes.append((cat, *xy))
    if n == 0:
        raise PlanFormatError(named(name, "plan file has no elements (blank)"))
    walls = np.array(walls, float).reshape(-1, 4)
    doors = np.array(doors, float).reshape(-1, 4)
    if not np.any(_lengths(walls) > 0):
        raise PlanFormatError(named(name, "plan has no walls"))
    return walls, doors, boxes


def _is_number(v: str) -> bool:
    try:
        float(v)
    except ValueError:
        return False
    return True


def _lengths(seg: np.ndarray) -> np.ndarray:
    return np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])


# --------------------------------------------------------------------------
# mending the geometry (world metres)
# --------------------------------------------------------------------------

def _cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _dedupe(walls: np.ndarray):
    """Walls without the zero-length ones and exact duplicates (either direction); counts of both."""
    keep = _lengths(walls) > 1e-9
    n_zero = int((~keep).sum())
    w = walls[keep]
    ends = np.concatenate([w[:, :2], w[:, 2:]], axis=1)
    flip = (w[:, 0] > w[:, 2]) | ((w[:, 0] == w[:, 2]) & (w[:, 1] > w[:, 3]))
    ends[flip] = w[flip][:, [2, 3, 0, 1]]
    _, first = np.unique(ends, axis=0, return_index=True)
    first.sort()
    return w[first], n_zero, int(len(w) - len(first))


def _snap_doors(doors: np.ndarray, walls: np.ndarray, snap: float):
    """Doors moved onto the centre line of the nearest parallel wall within ``snap`` metres.

    Returns the doors, how many moved more than 1 cm, and how many have no
    such wall (left where they are: the door, closed, is then the wall).
    """
    out = doors.copy()
    if len(doors) == 0:
        return out, 0, 0
    a, b = walls[:, :2], walls[:, 2:]
    uw = (b - a) / _lengths(walls)[:, None]
    moved = floating = 0
    for k, d in enumerate(doors):
        p, q = d[:2], d[2:]
        ud = (q - p) / np.hypot(*(q - p))
        dist = point_segment_distances((p + q) / 2, a, b)
        ok = (np.abs(_cross(uw, ud)) < _SNAP_SIN) & (dist <= snap)
        if not ok.any():
            floating += 1
            continue
        j = int(np.flatnonzero(ok)[np.argmin(dist[ok])])
        pa, u = a[j], uw[j]
        p2 = pa + np.dot(p - pa, u) * u
        q2 = pa + np.dot(q - pa, u) * u
        if max(np.hypot(*(p2 - p)), np.hypot(*(q2 - q))) > 0.01:
            moved += 1
        out[k] = [*p2, *q2]
    return out, moved, floating


def _close_gaps(walls: np.ndarray, doors: np.ndarray, thickness: float, max_gap: float):
    """Walls whose ends stop short of another wall (or door) by at most ``max_gap`` metres, mended.

    An end is first extended straight on to the first wall or door line it
    meets within ``max_gap``; an end that meets none is bridged to the
    nearest point of the nearest other segment when that is within
    ``max_gap`` and farther than ``thickness`` (nearer, the drawn thickness
    closes it). Returns the walls, the bridge segments (k, 4) and the
    counts of ends extended across a gap wider than ``thickness`` and of
    ends bridged.
    """
    n = len(walls)
    segs = np.concatenate([walls, doors]) if len(doors) else walls
    p, q = segs[:, :2], segs[:, 2:]
    r = q - p
    rl = np.hypot(r[:, 0], r[:, 1])
    ok_seg = rl > 1e-9
    ends = np.concatenate([walls[:, :2], walls[:, 2:]])          # (2n, 2)
    other = np.concatenate([walls[:, 2:], walls[:, :2]])
    own = np.concatenate([np.arange(n), np.arange(n)])
    u = ends - other
    u /= np.hypot(u[:, 0], u[:, 1])[:, None]
    near = point_segment_distances(ends[:, None, :], p[None], q[None])   # (2n, S)
    near[np.arange(2 * n), own] = np.inf
    near[:, ~ok_seg] = np.inf
    d_near = near.min(axis=1)
    # straight on: e + t u = p + s r
    w = p[None] - ends[:, None, :]
    den = _cross(u[:, None, :], r[None])
    with np.errstate(divide="ignore", invalid="ignore"):
        t = _cross(w, r[None]) / den
        s = _cross(w, u[:, None, :]) / den
    tol = (thickness / 2) / np.where(ok_seg, rl, 1.0)
    hit = (np.abs(den) > 1e-12) & (t > 1e-9) & (s >= -tol) & (s <= 1 + tol)
    t_hit = np.where(hit, t, np.inf)
    # collinear segments straight on (a wall drawn in two pieces with a gap)
    par = (np.abs(den) <= 1e-12 * np.maximum(rl, 1.0)[None]) & ok_seg[None]
    off = np.abs(_cross(w, u[:, None, :]))
    tp = (w * u[:, None, :]).sum(-1)
    tq = ((q[None] - ends[:, None, :]) * u[:, None, :]).sum(-1)
    tc = np.where(tp > 1e-9, tp, np.inf)
    tc = np.minimum(tc, np.where(tq > 1e-9, tq, np.inf))
    t_hit = np.minimum(t_hit, np.where(par & (off <= thickness / 2), tc, np.inf))
    t_hit[np.arange(2 * n), own] = np.inf
    t_min = t_hit.min(axis=1)
    walls = walls.copy()
    bridges = []
    extended = bridged = 0
    for e in range(2 * n):
        if d_near[e] <= 1e-9:
            continue
        if t_min[e] <= max_gap:
            i = own[e]
            end = ends[e] + t_min[e] * u[e]
            if e < n:
                walls[i, :2] = end
            else:
                walls[i, 2:] = end
            extended += int(d_near[e] >= thickness)
        elif thickness <= d_near[e] <= max_gap:
            j = int(np.argmin(near[e]))
            ab = r[j]
            tt = np.clip(np.dot(ends[e] - p[j], ab) / np.dot(ab, ab), 0.0, 1.0)
            bridges.append([*ends[e], *(p[j] + tt * ab)])
            bridged += 1
    return walls, np.array(bridges, float).reshape(-1, 4), extended, bridged


# --------------------------------------------------------------------------
# rasterising (cells, fractional (row, col))
# --------------------------------------------------------------------------

def _box(shape, a, b, half):
    """Bounding box ``(r0, r1, c0, c1)`` of the cells within ``half`` of segment a-b, clipped."""
    H, W = shape
    r0 = max(int(math.floor(min(a[0], b[0]) - half)), 0)
    r1 = min(int(math.ceil(max(a[0], b[0]) + half)) + 1, H)
    c0 = max(int(math.floor(min(a[1], b[1]) - half)), 0)
    c1 = min(int(math.ceil(max(a[1], b[1]) + half)) + 1, W)
    return r0, max(r1, r0), c0, max(c1, c0)


def _band(box, a, b, half):
    """Cells of ``box`` whose centre is within ``half`` cells of segment a-b (round ends)."""
    r0, r1, c0, c1 = box
    rr, cc = np.meshgrid(np.arange(r0, r1, dtype=float), np.arange(c0, c1, dtype=float), indexing="ij")
    d = point_segment_distances(np.stack([rr, cc], -1), a, b)
    return d <= half + 1e-9


def _signed(rows, cols, a, b):
    """Position along segment a-b (cells from ``a``) and signed distance from its line of cells
    ``(rows, cols)`` (broadcast)."""
    rr = np.asarray(rows, float) - a[0]
    cc = np.asarray(cols, float) - a[1]
    d = np.asarray(b, float) - a
    L = math.hypot(d[0], d[1])
    return (rr * d[0] + cc * d[1]) / L, (rr * d[1] - cc * d[0]) / L


def _rect(box, a, b, half):
    """Cells of ``box`` over segment a-b (projection within it) within ``half`` cells of its line (square ends),
    and their signed distances from the line."""
    r0, r1, c0, c1 = box
    t, side = _signed(np.arange(r0, r1)[:, None], np.arange(c0, c1)[None, :], a, b)
    L = math.hypot(b[0] - a[0], b[1] - a[1])
    return (t >= -1e-9) & (t <= L + 1e-9) & (np.abs(side) <= half + 1e-9), side


_CROSS = np.array([[0, 1, 0], [1, 1, 1], [0, 1, 0]], np.uint8)
_SQUARE = np.ones((3, 3), np.uint8)


def _dilate(mask, kernel):
    import cv2

    return cv2.dilate(mask.view(np.uint8), kernel).astype(bool)


def _stamp(mask, a, b, half):
    box = _box(mask.shape, a, b, half)
    r0, r1, c0, c1 = box
    if r1 > r0 and c1 > c0:
        mask[r0:r1, c0:c1] |= _band(box, a, b, half)


def _mode(values: np.ndarray) -> int:
    """The most common value (the smallest of the most common), -1 when there is none."""
    if values.size == 0:
        return -1
    vals, counts = np.unique(values, return_counts=True)
    return int(vals[np.argmax(counts)])


# --------------------------------------------------------------------------
# the reader
# --------------------------------------------------------------------------

def read_plan(path, *, resolution: float = 0.05, wall_thickness: float = WALL_THICKNESS,
              door_width: float = DOOR_WIDTH, margin: float = MARGIN, scale=None,
              max_gap: float = MAX_GAP, nook_area: float = NOOK_AREA,
              home_area: float = HOME_AREA) -> FloorPlan:
    """Read one vector floor plan (R2V / LIFULL text format) into a :class:`FloorPlan`.

    Parameters
    ----------
    path : str or os.PathLike
        The plan file: one element a line, ``x1 y1 x2 y2 category [a b]``
        (tab or space separated) in the plan's own units; ``wall`` lines
        are wall centre lines, ``door`` lines door openings on them, the
        rest label boxes (:data:`ROOM_KINDS`) or object boxes.
    resolution : float, optional
        Metres per cell of the grid (0.05: the usual resolution of robot
        maps, and of the room-segmentation benchmarks).
    wall_thickness : float, optional
        Thickness the wall lines are drawn with, metres (0.15: the middle
        of the 0.1-0.2 m of the walls of homes). At least ``resolution``.
    door_width : float, optional
        The real width the plan's 25th-percentile door segment is scaled to,
        metres (0.8: a common interior door; the median would be pulled wide
        by the sliding doors onto balconies). Ignored when ``scale`` is given.
    margin : float, optional
        Free space around the home, metres (1.0: room for laser rays to
        leave the building and for a robot's start outside).
    scale : float, optional
        Metres per plan unit, instead of the scale from the doors (or, for
        a plan with no doors, from ``home_area``).
    max_gap : float, optional
        Wall ends that stop at most this far short of another wall (or
        door) are joined to it, metres (0.3: narrower than anyone walks
        through, so a gap that narrow in a drawn plan is a slip of the
        drawing, and leaving it open lets rooms run into each other or the
        outside).
    nook_area : float, optional
        An unlabelled space behind its own door smaller than this, with no
        fixture (toilet, bath, basin, counter) in it, is a nook of the room
        it opens into, m² (1.5: smaller than any room of a home -- a
        Japanese toilet room, the smallest, is about 1.5-2 m² and has a
        toilet in it -- and larger than the usual built-in cupboard of
        0.5-1 m²).
    home_area : float, optional
        A plan with no door segment (nothing to take the scale from) is
        scaled so that the bounding box of its walls covers this area, m²
        (:data:`HOME_AREA`, 62: the median of the plans scaled by their
        doors). Ignored when the plan has doors or ``scale`` is given.

    Returns
    -------
    FloorPlan
        ``origin`` ``(0, 0, 0)``; the plan's y axis (down the image) points
        down the grid. ``quirks`` counts: ``zero_walls``,
        ``duplicate_walls`` (left out), ``gaps_extended``,
        ``gaps_bridged`` (wall ends joined across more than the wall
        thickness), ``doors_snapped`` (moved onto their wall's line),
        ``doors_floating`` (no wall under them), ``doors_narrow`` (narrower
        than :data:`MIN_DOOR_WIDTH`, left out: the wall is closed there),
        ``doors_dropped`` (no room on either side, or of zero length),
        ``closets_merged``, ``closed_spaces`` (no door into them: not part
        of the home), ``parts`` (pieces of the home no door joins),
        ``scale_from_area`` (1 when the scale came from ``home_area``).

    Raises
    ------
    MapFileNotFoundError, MapFileError
        No such file, a directory, unreadable.
    PlanFormatError
        Empty file, a bad line (the message names the line), or no walls.
    ParameterError
        A bad option.
    MapTooLargeError
        The grid would have more than :func:`topomap.io.cell_limit` cells.

    Notes
    -----
    Walls are the cells whose centre is within half the thickness of a
    wall line. With the doors closed (each door drawn as a wall), the free
    cells connected to the border of the grid are the outside; the other
    free cells form the rooms (4-connected). Each door then opens its
    wall: the cells over the door segment within half a thickness of its
    line, except the cells of the other walls that meet it there. A room
    whose label boxes are all storage (:data:`STORAGE_KINDS`), or an
    unlabelled nook (``nook_area``), belongs to the room its doors lead
    into (the widest door, then the largest room).
    """
    name = os.fspath(path)
    res = check_resolution(resolution, name="resolution")
    th = check_length("wall_thickness", wall_thickness)
    if th < res:
        raise ParameterError(f"wall_thickness must be at least the resolution ({res} m), got {wall_thickness!r}")
    dw = check_length("door_width", door_width)
    if dw <= 0:
        raise ParameterError(f"door_width must be a length > 0 m, got {door_width!r}")
    margin = check_length("margin", margin)
    max_gap = check_length("max_gap", max_gap)
    nook_area = check_area("nook_area", nook_area)
    home_area = check_area("home_area", home_area)
    if home_area <= 0:
        raise ParameterError(f"home_area must be an area > 0 m², got {home_area!r}")
    if scale is not None:
        scale = check_length("scale", scale)
        if scale <= 0:
            raise ParameterError(f"scale must be > 0 m per plan unit, got {scale!r}")
    walls_u, doors_u, boxes_u = _parse(Path(name), name)
    dl = _lengths(doors_u)
    from_area = scale is None and not np.any(dl > 0)
    if from_area:
        pts = walls_u.reshape(-1, 2)
        box = float(np.prod(pts.max(axis=0) - pts.min(axis=0)))
        if box <= 0:
            raise PlanFormatError(named(name, "plan has no doors and its walls span no area: no scale "
                                              "(give scale= in metres per plan unit)"))
        scale = math.sqrt(home_area / box)
        _log.info("%s: no doors: scaled so that its walls' bounding box is %g m² (%.4g m per unit)",
                  name, home_area, scale)
    elif scale is None:
        scale = dw / float(np.percentile(dl[dl > 0], 25))
    narrow = dl * scale < MIN_DOOR_WIDTH
    quirks = {"doors_dropped": int((dl <= 0).sum()), "doors_narrow": int((narrow & (dl > 0)).sum()),
              "scale_from_area": int(from_area)}
    doors_u = doors_u[~narrow]
    stem = Path(name).stem
    return _build(stem, walls_u, doors_u, boxes_u, scale=scale, res=res, th=th, margin=margin,
                  max_gap=max_gap, nook_area=nook_area, quirks=quirks)


@dataclass(frozen=True)
class _Frame:
    """Where a plan lies on its grid: plan units -> world metres (x right, y up; the plan's y runs
    down the image) -> fractional grid cells ``(row, col)``."""

    umin: float   # the plan's smallest x (plan units)
    vmax: float   # the plan's largest y (plan units)
    scale: float  # metres per plan unit
    pad: float    # metres between the plan's extent and the border of the grid
    res: float    # metres per cell
    shape: tuple  # (rows, cols) of the grid

    def world(self, seg: np.ndarray) -> np.ndarray:
        """Plan segments (k, 4) ``x1 y1 x2 y2`` in world metres."""
        out = np.empty_like(seg, dtype=float)
        out[:, 0::2] = (seg[:, 0::2] - self.umin) * self.scale + self.pad
        out[:, 1::2] = (self.vmax - seg[:, 1::2]) * self.scale + self.pad
        return out

    def px(self, xy) -> np.ndarray:
        """World ``(x, y)`` as fractional ``(row, col)``."""
        return np.array([self.shape[0] - xy[1] / self.res - 0.5, xy[0] / self.res - 0.5])

    def world_box(self, xy) -> tuple:
        """Plan box ``(x1, y1, x2, y2)`` in world metres, ``x1 <= x2``, ``y1 <= y2``."""
        x1, x2 = sorted(((xy[0] - self.umin) * self.scale + self.pad, (xy[2] - self.umin) * self.scale + self.pad))
        y1, y2 = sorted(((self.vmax - xy[1]) * self.scale + self.pad, (self.vmax - xy[3]) * self.scale + self.pad))
        return x1, y1, x2, y2


def _build(name, walls_u, doors_u, boxes_u, *, scale, res, th, margin, max_gap, nook_area, quirks):
    """The :class:`FloorPlan` of a parsed plan (walls, doors and boxes in plan units, ``scale`` metres
    per unit); ``quirks`` gets the counts of what was mended (see :func:`read_plan`)."""
    frame = _plan_frame(name, walls_u, doors_u, scale=scale, res=res, th=th, margin=margin)
    walls, doors = _mend(frame, walls_u, doors_u, th, max_gap, quirks)
    half = th / 2 / res
    closed = _closed_walls(frame, walls, doors, half)
    opened, walls_open = _open_doors(frame, walls, doors, closed, th, half)
    outside, raw, is_out = _outside(closed)
    inside, room_kept, raw = _home(walls_open, outside, raw, is_out, res, quirks)
    door_sides = _door_sides(frame, opened, doors, raw, outside, closed)
    box_room = [_box_label(raw, frame, b[1:]) for b in boxes_u]
    area = np.bincount(raw.ravel(), minlength=len(is_out)) * res * res
    storage = _storage_rooms(room_kept, area, boxes_u, box_room, nook_area)
    parent = _storage_parents(storage, area, door_sides, doors)
    quirks["closets_merged"] = len(parent)
    merged, final, rooms = _room_numbers(parent, raw, len(is_out) - 1)
    plan_doors, dropped = _door_truth(opened, door_sides, doors, merged, final, rooms)
    quirks["doors_dropped"] += dropped
    _assign_loose_cells(rooms, inside, quirks)
    kinds, objects = _kinds_and_objects(frame, boxes_u, box_room, merged, final)
    outer = walls_open & _dilate(outside, _SQUARE)
    plan = FloorPlan(name=name, resolution=res, origin=(0.0, 0.0, 0.0), walls=walls_open, inside=inside,
                     rooms=rooms.astype(np.uint16), doors=tuple(plan_doors), kinds=kinds, outer_walls=outer,
                     objects=tuple(objects), scale=float(scale), quirks=quirks)
    H, W = frame.shape
    _log.debug("%s: %d x %d cells, %.1f m², %d rooms, %d doors, %s", name, W, H, plan.area, len(kinds),
               len(plan_doors), quirks)
    return plan


def _plan_frame(name, walls_u, doors_u, *, scale, res, th, margin) -> _Frame:
    """The :class:`_Frame` of a plan: its extent with ``margin``, half a wall and a cell around it.

    Raises MapTooLargeError when the grid would have more than :func:`cell_limit` cells.
    """
    pts = np.concatenate([walls_u.reshape(-1, 2), doors_u.reshape(-1, 2)])
    umin, vmax = pts[:, 0].min(), pts[:, 1].max()
    ext = (pts.max(axis=0) - pts.min(axis=0)) * scale
    pad = margin + th / 2 + res
    W = int(math.ceil((ext[0] + 2 * pad) / res))
    H = int(math.ceil((ext[1] + 2 * pad) / res))
    limit, why = cell_limit()
    if H * W > limit:
        raise MapTooLargeError(named(name, f"plan would be {W} x {H} cells = {H * W:,} at {res} m, more than {why}"))
    return _Frame(umin, vmax, scale, pad, res, (H, W))


def _mend(frame: _Frame, walls_u, doors_u, th, max_gap, quirks) -> tuple:
    """``(walls, doors)`` (k, 4) in world metres, mended: zero-length and duplicate walls out, doors
    moved onto their walls, gaps between wall ends closed (the bridges added to the walls); the
    counts in ``quirks``."""
    walls, quirks["zero_walls"], quirks["duplicate_walls"] = _dedupe(frame.world(walls_u))
    doors, quirks["doors_snapped"], quirks["doors_floating"] = _snap_doors(frame.world(doors_u), walls, DOOR_SNAP)
    walls, bridges, quirks["gaps_extended"], quirks["gaps_bridged"] = _close_gaps(walls, doors, th, max_gap)
    return np.concatenate([walls, bridges]), doors


def _closed_walls(frame: _Frame, walls, doors, half) -> np.ndarray:
    """The wall cells (bool) with every door drawn as a wall, ``half`` cells either side of its line."""
    closed = np.zeros(frame.shape, bool)
    for w in np.concatenate([walls, doors]):
        _stamp(closed, frame.px(w[:2]), frame.px(w[2:]), half)
    return closed


def _open_doors(frame: _Frame, walls, doors, closed, th, half) -> tuple:
    """``(opened, walls_open)``: per door ``(box, cells, signed side)`` of the cells it opens (the
    rectangle over it, less the other walls that meet it), and the wall cells with the doors open."""
    px = frame.px
    a_w, b_w = walls[:, :2], walls[:, 2:]
    uw = (b_w - a_w) / _lengths(walls)[:, None]
    lo = np.minimum(a_w, b_w) - th
    hi = np.maximum(a_w, b_w) + th
    opened = []
    is_open = np.zeros(frame.shape, bool)
    for d in doors:
        p, q = px(d[:2]), px(d[2:])
        ud = (d[2:] - d[:2]) / math.hypot(*(d[2:] - d[:2]))
        # the walls the door opens: along its line, or doubled beside it closer than a wall thickness
        off = np.maximum(np.abs(_cross(d[:2] - a_w, uw)), np.abs(_cross(d[2:] - a_w, uw)))
        host = (np.abs(_cross(uw, ud)) < 0.02) & (off <= th)
        cut_half = (max(float(off[host].max()), 0.0) if host.any() else 0.0) / frame.res + half + 0.5
        box = _box(frame.shape, p, q, cut_half)
        r0, r1, c0, c1 = box
        cells, side = _rect(box, p, q, cut_half)
        dlo, dhi = np.minimum(d[:2], d[2:]) - th, np.maximum(d[:2], d[2:]) + th
        near = ~host & np.all(lo <= dhi, axis=1) & np.all(hi >= dlo, axis=1)
        for j in np.flatnonzero(near):
            cells &= ~_band(box, px(walls[j, :2]), px(walls[j, 2:]), half)
        cells &= closed[r0:r1, c0:c1]
        is_open[r0:r1, c0:c1] |= cells
        opened.append((box, cells, side))
    return opened, closed & ~is_open


def _outside(closed) -> tuple:
    """``(outside, raw, is_out)`` with the doors closed: the free cells joined to the border of the
    grid (bool), the labels of the 4-connected free regions (0 outside), and which labels are outside
    (bool, one per label and 0)."""
    lab, n = _label(~closed, 4)
    border = np.unique(np.concatenate([lab[0], lab[-1], lab[:, 0], lab[:, -1]]))
    is_out = np.zeros(n + 1, bool)
    is_out[border] = True
    is_out[0] = False
    outside = is_out[lab]
    return outside, np.where(outside, 0, lab), is_out


def _home(walls_open, outside, raw, is_out, res, quirks) -> tuple:
    """``(inside, room_kept, raw)``: the home is the largest piece the open doors join, and every
    other piece of at least :data:`MIN_PART_AREA`; closed spaces and smaller pieces are not in it.
    ``inside`` its cells, ``room_kept`` which raw labels are in it, ``raw`` with the others 0; the
    counts in ``quirks``."""
    parts, n_parts = _label(~walls_open & ~outside, 4)
    part_area = np.bincount(parts.ravel(), minlength=n_parts + 1) * res * res
    part_area[0] = 0
    keep_part = np.zeros(n_parts + 1, bool)
    if n_parts:
        keep_part[int(np.argmax(part_area))] = True
        keep_part |= part_area >= MIN_PART_AREA
        keep_part[0] = False
    inside = keep_part[parts]
    room_part = np.zeros(len(is_out), np.int64)
    room_part[raw.ravel()] = parts.ravel()
    room_kept = keep_part[room_part]
    room_kept[0] = False
    room_kept &= ~is_out
    quirks["closed_spaces"] = int(np.count_nonzero(~keep_part[1:]))
    quirks["parts"] = int(np.count_nonzero(keep_part))
    return inside, room_kept, np.where(room_kept[raw], raw, 0)


def _door_sides(frame: _Frame, opened, doors, raw, outside, closed) -> list:
    """Per door ``(room on its positive side, room on its negative side, ring)``: the most common raw
    label just beyond its cells on either side of its line (0 the outside, -1 none), and ``ring``
    ``(rows, cols, on the positive side, labels)`` of those cells beyond it."""
    H, W = frame.shape
    door_sides = []
    for (box, cells, side), d in zip(opened, doors):
        segment = (frame.px(d[:2]), frame.px(d[2:]))
        r0, r1, c0, c1 = box
        g0, g1, h0, h1 = max(r0 - 1, 0), min(r1 + 1, H), max(c0 - 1, 0), min(c1 + 1, W)
        grown = np.zeros((g1 - g0, h1 - h0), bool)
        grown[r0 - g0:r1 - g0, c0 - h0:c1 - h0] = cells
        ring = _dilate(grown, _CROSS) & ~grown & ~closed[g0:g1, h0:h1]
        rr, cc = np.nonzero(ring)
        _, s = _signed(rr + g0, cc + h0, *segment)
        vals = raw[g0:g1, h0:h1][rr, cc]
        outs = outside[g0:g1, h0:h1][rr, cc]
        vals = np.where(outs, 0, vals)
        door_sides.append((_mode(vals[s >= 0]), _mode(vals[s < 0]), (rr + g0, cc + h0, s >= 0, vals)))
    return door_sides


def _storage_rooms(room_kept, area, boxes_u, box_room, nook_area) -> set:
    """Raw labels of the rooms that join the room they open into: those whose label boxes are all
    storage (:data:`STORAGE_KINDS`), and unlabelled nooks (smaller than ``nook_area`` m², no fixture)."""
    kinds_raw = {}
    fixture = np.zeros(len(room_kept), bool)
    for (cat, *_), k in zip(boxes_u, box_room):
        if k <= 0:
            continue
        if cat in ROOM_KINDS:
            kinds_raw.setdefault(k, []).append(cat)
        elif cat in FIXTURE_KINDS:
            fixture[k] = True
    storage = set()
    for k in np.flatnonzero(room_kept):
        ks = kinds_raw.get(int(k), [])
        if (ks and all(c in STORAGE_KINDS for c in ks)) or (not ks and not fixture[k] and area[k] < nook_area):
            storage.add(int(k))
    return storage


def _storage_parents(storage: set, area, door_sides, doors) -> dict:
    """Raw label of each storage room -> the room it joins: of the rooms its doors lead into, the one
    of the widest doors, then the largest (a storage room only into another that joins a room)."""
    widths = {}
    for (pos, neg, _), d in zip(door_sides, doors):
        if pos > 0 and neg > 0 and pos != neg:
            wd = math.hypot(*(d[2:] - d[:2]))
            for x, y in ((pos, neg), (neg, pos)):
                widths[(x, y)] = widths.get((x, y), 0.0) + wd
    parent = {}
    changed = True
    while changed:
        changed = False
        for k in sorted(storage - set(parent)):
            cand = [(wd, area[y], -y, y) for (x, y), wd in widths.items()
                    if x == k and (y not in storage or y in parent)]
            if cand:
                parent[k] = max(cand)[3]
                changed = True
    return parent


def _room_numbers(parent: dict, raw, n: int) -> tuple:
    """``(merged, final, rooms)``: raw label (1..n) -> the raw label of the room it joins
    (``parent`` followed to its end), that label -> room number 1..K in raster order of each room's
    first cell (0 for none), and the image of the room numbers."""
    def root(k):
        while k in parent:
            k = parent[k]
        return k

    merged = np.arange(n + 1)
    for k in parent:
        merged[k] = root(k)
    merged[0] = 0
    lab2 = merged[raw]
    ids, first = np.unique(lab2.ravel(), return_index=True)
    order = ids[ids > 0][np.argsort(first[ids > 0])]
    final = np.zeros(n + 1, np.int64)
    final[order] = np.arange(1, order.size + 1)
    return merged, final, final[lab2]


def _door_truth(opened, door_sides, doors, merged, final, rooms) -> tuple:
    """``(plan doors, how many dropped)``: a :class:`PlanDoor` per door with a room on either side
    (the others are dropped); each door cell of ``rooms`` set to the room of the nearest cell beside
    the door on its side of the line (on the other side when its own is the outside): a door may run
    past several rooms."""
    plan_doors = []
    dropped = 0
    for (box, cells, side), (pos, neg, ring), d in zip(opened, door_sides, doors):
        fp = final[merged[pos]] if pos > 0 else 0
        fn = final[merged[neg]] if neg > 0 else 0
        if fp == 0 and fn == 0:
            dropped += 1
            continue
        r0, r1, c0, c1 = box
        ring_r, ring_c, ring_pos, ring_lab = ring
        ring_lab = final[merged[ring_lab]]
        rr, cc = np.nonzero(cells)
        cell_pos = side[rr, cc] >= 0
        dist = (rr[:, None] + r0 - ring_r[None]) ** 2 + (cc[:, None] + c0 - ring_c[None]) ** 2
        dist = dist + np.where(cell_pos[:, None] == ring_pos[None], 0, 1 << 40)
        dist = np.where(ring_lab[None] > 0, dist, np.iinfo(np.int64).max)
        rooms[rr + r0, cc + c0] = ring_lab[np.argmin(dist, axis=1)]
        plan_doors.append(PlanDoor(p1=(float(d[0]), float(d[1])), p2=(float(d[2]), float(d[3])),
                                   rooms=tuple(sorted((int(fp), int(fn)))),
                                   width=float(math.hypot(d[2] - d[0], d[3] - d[1]))))
    return plan_doors, dropped


def _assign_loose_cells(rooms, inside, quirks) -> None:
    """``rooms`` 0 outside the home, and its door cells beside no room of their own given the nearest
    room; their count in ``quirks``."""
    rooms[~inside] = 0
    loose = inside & (rooms == 0)
    quirks["cells_unassigned"] = int(np.count_nonzero(loose))
    if loose.any():
        from scipy import ndimage as ndi  # scipy only for the plans that have such cells

        idx = ndi.distance_transform_edt(rooms == 0, return_distances=False, return_indices=True)
        rooms[loose] = rooms[idx[0][loose], idx[1][loose]]


def _kinds_and_objects(frame: _Frame, boxes_u, box_room, merged, final) -> tuple:
    """``(kinds, objects)``: room number -> the kinds of its label boxes (see :class:`FloorPlan`), and
    the object boxes ``(kind, x1, y1, x2, y2)`` in world metres."""
    kinds = {k: [] for k in range(1, int(final.max(initial=0)) + 1)}
    objects = []
    for (cat, *xy), k in zip(boxes_u, box_room):
        if cat in ROOM_KINDS:
            if k > 0 and final[merged[k]] > 0:
                kinds[int(final[merged[k]])].append(cat)
        else:
            x1, y1, x2, y2 = frame.world_box(xy)
            objects.append((cat, float(x1), float(y1), float(x2), float(y2)))
    return {k: tuple(v) for k, v in kinds.items()}, objects


def _box_label(raw, frame: _Frame, xy):
    """Raw room label of a label box: the cell under its centre, else the most common label in it."""
    x1, y1, x2, y2 = frame.world_box(xy)
    px = frame.px
    H, W = raw.shape
    r, c = px(((x1 + x2) / 2, (y1 + y2) / 2))
    r, c = int(round(r)), int(round(c))
    if 0 <= r < H and 0 <= c < W and raw[r, c] > 0:
        return int(raw[r, c])
    (ra, ca), (rb, cb) = px((x1, y2)), px((x2, y1))
    ra, rb = max(int(round(ra)), 0), min(int(round(rb)) + 1, H)
    ca, cb = max(int(round(ca)), 0), min(int(round(cb)) + 1, W)
    if ra >= rb or ca >= cb:
        return 0
    vals = raw[ra:rb, ca:cb]
    return max(_mode(vals[vals > 0]), 0)


def ground_truth_problems(plan: FloorPlan) -> list:
    """What is wrong with a plan's ground truth: the invariants :func:`read_plan` keeps.

    Parameters
    ----------
    plan : FloorPlan

    Returns
    -------
    list of str
        One line per broken invariant (empty when all hold): the rooms are
        exactly the inside, each room one 4-connected piece; the inside
        touches neither a wall nor the border of the grid; the facade is
        wall; the labels are 1..K with a ``kinds`` entry each; every door
        lies in the grid, at least half of it on free cells of the home,
        and joins two labels of ``0..K`` (not both 0) found beside it.
    """
    out = []
    rooms, inside, walls = plan.rooms, plan.inside, plan.walls
    K = plan.n_rooms
    if not np.array_equal(rooms > 0, inside):
        out.append(f"{np.count_nonzero((rooms > 0) != inside)} cells where rooms > 0 is not inside")
    if np.any(inside & walls):
        out.append(f"{np.count_nonzero(inside & walls)} inside cells are walls")
    if inside[0].any() or inside[-1].any() or inside[:, 0].any() or inside[:, -1].any():
        out.append("the inside touches the border of the grid")
    if plan.outer_walls is not None and np.any(plan.outer_walls & ~walls):
        out.append("outer_walls holds cells that are not walls")
    present = np.unique(rooms[rooms > 0])
    if not np.array_equal(present, np.arange(1, K + 1)) or set(plan.kinds) != set(range(1, K + 1)):
        out.append(f"labels {present.tolist()[:10]}... are not 1..{K} with a kinds entry each")
    if K:
        lab, n = _label(rooms > 0, 4)
        pieces = np.zeros(K + 1, np.int64)
        pairs = np.unique(np.stack([rooms[lab > 0], lab[lab > 0]]), axis=1)
        np.add.at(pieces, pairs[0], 1)
        split = np.flatnonzero(pieces > 1)
        if split.size:
            out.append(f"rooms {split.tolist()} are in more than one piece")
    H, W = plan.shape
    res = plan.resolution
    for i, d in enumerate(plan.doors):
        a, b = sorted(d.rooms)
        if tuple(d.rooms) != (a, b) or not (0 <= a <= K and 0 < b <= K):
            out.append(f"door {i} joins rooms {d.rooms} (labels 1..{K}, 0 the outside, not both)")
            continue
        p, q = np.array(d.p1), np.array(d.p2)
        if abs(math.hypot(*(q - p)) - d.width) > 1e-6:
            out.append(f"door {i}: width {d.width} is not its length")
        # the cells along the door: mostly free cells of the home (a wall meeting it may cross it)
        n_s = max(int(math.ceil(d.width / res)) + 1, 2)
        xy = p[None] + np.linspace(0.0, 1.0, n_s)[:, None] * (q - p)[None]
        rows = np.rint(H - xy[:, 1] / res - 0.5).astype(int)
        cols = np.rint(xy[:, 0] / res - 0.5).astype(int)
        if rows.min() < 0 or cols.min() < 0 or rows.max() >= H or cols.max() >= W:
            out.append(f"door {i}: not inside the grid")
            continue
        free = inside[rows, cols]
        if free.mean() < 0.5:
            out.append(f"door {i}: {np.count_nonzero(~free)} of its {n_s} cells are not free cells of the home")
            continue
        # its rooms are the labels of its own cells and of those within a wall thickness of them
        k = max(int(math.ceil(0.3 / res)), 2)
        near = set()
        for r, c in zip(rows[free], cols[free]):
            near |= set(np.unique(rooms[max(r - k, 0):r + k + 1, max(c - k, 0):c + k + 1]).tolist())
        if not {a, b} <= (near | {0}):
            out.append(f"door {i}: rooms {d.rooms} are not beside it (near: {sorted(near)})")
    return out
