"""A robot's laser SLAM map of a floor plan, simulated.

:func:`simulate_scan` drives a simulated robot with a 2-D laser scanner
through a :class:`~topomap.bench.floorplan.FloorPlan` and builds the occupancy grid
a SLAM package (gmapping, slam_toolbox) would publish and ``map_saver``
would write: free where the beams passed, occupied where they ended,
unknown where no beam reached. The map lies on the plan's own grid (same
shape, resolution and origin), so the plan's ground truth (rooms, doors)
scores a segmentation of the simulated map directly.

The stages, each a function of its own:

1. :class:`ScanOptions`: the laser, the path, the occupancy update and the
   faults, every one a physical quantity with its default's reason.
2. :func:`build_world`: what the laser sees: the plan's walls, the doors
   left closed, furniture (the plan's object boxes and random tables, beds,
   shelves), and the glass of the facade (windows rays pass through).
3. :func:`robot_path`: the robot's path through the rooms it visits, door
   to door, kept ``clearance`` away from every obstacle.
4. :func:`scan_poses`: poses along the path every ``pose_spacing`` metres,
   and the poses the SLAM believes (a small bounded error of position and
   heading that wanders along the path, the SLAM's residual drift).
5. :func:`cast_rays`: one laser scan per pose, ray cast on the grid against
   the world and the people walking by, with range noise and beams that
   return nothing.
6. :func:`integrate`: the log-odds occupancy update along every beam (cells
   before the end point freer, the end point cell more occupied) at the
   believed poses: with drift the map shows the SLAM error (doubled,
   slightly bent walls).
7. :func:`to_grid`: the trinary map (``map_saver``'s thresholds) as a
   :class:`~topomap.io.OccupancyGrid`; :func:`topomap.io.save_map` writes it
   as the PGM + YAML pair ``map_saver`` writes.

What is simulated: beams of a planar laser with a finite range, angular
step and field of view, Gaussian range noise, no-return beams; glass in the
facade (beams pass, so rays fan out of the building through the windows,
as in real maps); closed doors; furniture seen only where the path lets the
laser see it (tables only by their legs); people walking by, left in the
map as specks where no later beam cleared them; rooms the robot never
entered, unknown except what was seen through their doors; the odometry
error a SLAM leaves after scan matching and loop closure (a few
centimetres, half a degree).

What is not, so the simulated maps are cleaner than real ones: beams are
rays of zero width on the grid (no beam divergence, no mixed pixels at
edges, no multipath); each cell is updated at most once per scan, by the
beam nearest its direction (far cells between two beams are filled in, where
a real scan leaves a moire of gaps); glass is fully transparent (no
reflections off windows, no frames); mirrors, black surfaces at grazing
angles and sun light are not modelled beyond the random no-return share;
the robot follows its path exactly and the SLAM's error is one smooth,
bounded wander (no scan matching, no loop closures that jump the map); the world is static
but for the people; poses are the centres of cells.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..core.geometry import point_segment_distances
from ..errors import ParameterError
from ..grid import FREE, OCCUPIED, UNKNOWN, OccupancyGrid
from ..io.maps import FREE_THRESH, OCCUPIED_THRESH
from ..io.metadata import check_resolution
from ..options import CheckedOptions, check_area, option
from .floorplan import FloorPlan

__all__ = ["ScanOptions", "ScanResult", "World", "build_world", "robot_path", "scan_poses",
           "cast_rays", "integrate", "to_grid", "simulate_scan", "SHOWN_AREA", "shown_rooms", "shown_doors"]

log = logging.getLogger(__name__)

#: Random furniture: kind, (width, depth) in metres, drawn as its legs only.
#: A bed (1.4 m x 2.0 m, a double bed) and a shelf (1.0 m x 0.4 m) stand on the floor with closed
# sides the laser (at 0.2-0.3 m height) sees; a table (1.2 m x 0.8 m) shows only its four legs.
_FURNITURE = (("table", (1.2, 0.8), True), ("bed", (1.4, 2.0), False), ("shelf", (1.0, 0.4), False))
_LEGS_ONLY = dict({kind: legs for kind, _size, legs in _FURNITURE}, chair=True)
#: A table stands with its chairs: four (two along each long side), each 0.45 m square (a dining
#: chair's seat), seen by its four legs, its centre this far out from the table's edge (pulled half
#: under the table), metres.
_CHAIR = 0.45
_CHAIR_OUT = 0.1
#: Side of a table leg, metres (a wooden table leg, 4-5 cm).
_LEG = 0.05
#: Furniture keeps this far from the door cells, metres (a door leaf swings ~0.8 m into a room).
_DOOR_KEEPOUT = 0.8


def _logit(p: float) -> float:
    return math.log(p / (1.0 - p))


@dataclass(frozen=True)
class ScanOptions(CheckedOptions):
    """Options of :func:`simulate_scan`: the laser, the path, the occupancy update and the faults.

    Every fault is switched off by a zero (``glass_share``, ``drift_xy`` and
    ``drift_yaw``, ``furniture_density`` and ``plan_furniture=False``,
    ``closed_doors``, ``people_per_metre``, ``no_return_share``,
    ``range_sigma``) and unexplored rooms by ``explore=1``.

    Attributes
    ----------
    range_max : float
        Largest range of the laser, m: 10 m, a common indoor 2-D lidar
        (Hokuyo URG-04LX 5.6 m, RPLIDAR A2 12-16 m, Hokuyo UTM-30LX 30 m).
        Beams with nothing within it clear the cells along their whole length
        and mark no end point (gmapping's ``maxUrange``).
    angle_step : float
        Angle between two beams, degrees: 0.5 deg (SICK LMS, RPLIDAR
        0.45-0.9 deg, Hokuyo 0.25-0.36 deg). Rounded so that 360 deg holds a
        whole number of beams.
    field_of_view : float
        Angle the beams span, degrees, centred on the heading, in
        (0, 360]: 270 deg, the Hokuyo and SICK TiM scanners; 360 for a
        spinning lidar.
    range_sigma : float
        Standard deviation of the range noise, m: 0.02 m, a typical
        scanner's accuracy (Hokuyo UTM-30LX +-30 mm, RPLIDAR ~1 %).
    no_return_share : float
        Share of beams that return nothing (dark or shiny surfaces,
        grazing angles), in [0, 1]: 0.02. They are dropped as gmapping and
        slam_toolbox drop invalid readings, leaving gaps in the walls.
    explore : float
        Share of the plan's rooms the robot enters, in [0, 1]: 1 (a full
        exploration). At least one room is entered; the rooms are taken in
        a walk over the room-door graph from the start room, so the visited
        ones hang together; the others stay unknown but for what is seen
        through their doors.
    pose_spacing : float
        Distance between two scans along the path, m: 0.3 m (gmapping's
        ``linearUpdate`` is 1 m, slam_toolbox's ``minimum_travel_distance``
        0.5 m; the laser runs at 10-40 Hz, so a SLAM sees many more scans
        than it keys).
    clearance : float
        Least distance from the robot's centre to any wall or obstacle,
        m: 0.2 m, the radius of a TurtleBot / Kobuki base (0.18 m) and a
        little margin. Doors narrower than twice this stop the robot.
    room_coverage : float
        The robot visits waypoints in every room it enters until each free
        cell of the room is within this distance of one, m: 2.5 m (an
        exploration that goes near every part of a room rather than scanning
        it from the door).
    hit_probability, miss_probability : float
        Occupancy probability of one beam ending in a cell / passing
        through it, in (0.5, 1) / (0, 0.5): 0.7 and 0.4, the log-odds
        inverse sensor model of OctoMap (and of the ROS occupancy grid
        mappers built on it); gmapping and slam_toolbox count hits over
        visits, which the same update with these weights approaches.
    clamp_min, clamp_max : float
        Bounds of a cell's occupancy probability, in (0, 1): 0.12 and 0.97
        (OctoMap's), so a cell that was free can become occupied after a few
        hits (a door closed, a person) and the other way round.
    occupied_thresh, free_thresh : float
        ``map_saver``'s thresholds on the probability: occupied from 0.65,
        free up to 0.196, unknown in between (ROS defaults).
    glass_share : float
        Share of the facade (the plan's outer walls) that is glass, in
        [0, 1]: 0.15, windows of a home. Beams pass glass; rays fan out of
        the building through the windows, as in real maps.
    window_width : float
        Width of one window, m: 1.2 m (a two-leaf window).
    drift_xy : float
        The SLAM's residual position error, m (standard deviation along x
        and along y): 0.03. What remains after scan matching and loop
        closure: a wall seen twice from poses far apart on the path comes
        out doubled or thickened by a few centimetres, never shifted by a
        room. The error is bounded (it reverts to zero over
        ``drift_length``), not a random walk that grows with the path: a
        SLAM closes its loops, dead reckoning does not.
    drift_yaw : float
        The SLAM's residual heading error, degrees (standard deviation):
        0.5 (a wall 5 m away moves by about 4 cm: slightly bent walls).
    drift_length : float
        Path length over which the error changes, m: 5.0 (about a room: the
        scans of one room agree with each other better than with the scans
        of a room visited much later).
    plan_furniture : bool
        Draw the plan's object boxes (fixtures, furniture) as obstacles:
        True (a home is furnished).
    furniture_density : float
        Random furniture pieces (tables, beds, shelves) per m² of room,
        placed inside the rooms away from the doors: 0.05 (a 12 m² bedroom
        gets about one piece beyond its plan's own objects). A piece never
        cuts the floor of its room the robot drives on into pieces (people
        walk through every part of a room); where it would, it goes
        elsewhere or is left out.
    closed_doors : float
        Share of the doors that are closed, in [0, 1]: 0.1, drawn among the
        doors of dead-end rooms only (a bedroom, a bathroom, a closet off
        the robot's way; a door on its way between rooms would have been
        opened for the mapping run). A closed door is a wall to the laser
        and to the robot, and the room behind it stays unknown.
    people_per_metre : float
        People the robot meets per metre of its path: 0.02 (one every 50 m).
        Each stands near the path while the robot passes and leaves a speck
        in the map where no later beam clears it.
    person_width : float
        Width of a person at the laser's height (the legs), m: 0.3.
    person_seen_for : float
        Distance the robot travels while a person stands in view, m: 2.0
        (a person walks on after a few seconds).
    """

    range_max: float = option(10.0, "length")
    angle_step: float = option(0.5, "ratio")
    field_of_view: float = option(270.0, "ratio")
    range_sigma: float = option(0.02, "length")
    no_return_share: float = option(0.02, "fraction")
    explore: float = option(1.0, "fraction")
    pose_spacing: float = option(0.3, "length")
    clearance: float = option(0.2, "length")
    room_coverage: float = option(2.5, "length")
    hit_probability: float = option(0.7, "fraction")
    miss_probability: float = option(0.4, "fraction")
    clamp_min: float = option(0.12, "fraction")
    clamp_max: float = option(0.97, "fraction")
    occupied_thresh: float = option(OCCUPIED_THRESH, "fraction")
    free_thresh: float = option(FREE_THRESH, "fraction")
    glass_share: float = option(0.15, "fraction")
    window_width: float = option(1.2, "length")
    drift_xy: float = option(0.03, "length")
    drift_yaw: float = option(0.5, "ratio")
    drift_length: float = option(5.0, "length")
    plan_furniture: bool = option(True, "bool")
    furniture_density: float = option(0.05, "ratio")
    closed_doors: float = option(0.1, "fraction")
    people_per_metre: float = option(0.02, "ratio")
    person_width: float = option(0.3, "length")
    person_seen_for: float = option(2.0, "length")

    def __post_init__(self):
        super().__post_init__()
        for name in ("range_max", "angle_step", "pose_spacing", "room_coverage", "window_width",
                     "person_width", "drift_length"):
            if getattr(self, name) <= 0:
                raise ParameterError(f"{name} must be > 0, got {getattr(self, name)!r}")
        if self.field_of_view <= 0 or self.field_of_view > 360:
            raise ParameterError(f"field_of_view must be in (0, 360] degrees, got {self.field_of_view!r}")
        if self.angle_step > min(self.field_of_view, 90.0):
            raise ParameterError(f"angle_step must be at most the field of view and 90 degrees, "
                                 f"got {self.angle_step!r}")
        if not 0.5 < self.hit_probability < 1:
            raise ParameterError(f"hit_probability must be in (0.5, 1), got {self.hit_probability!r}")
        if not 0 < self.miss_probability < 0.5:
            raise ParameterError(f"miss_probability must be in (0, 0.5), got {self.miss_probability!r}")
        if not 0 < self.clamp_min < self.free_thresh:
            raise ParameterError(f"clamp_min must be in (0, free_thresh = {self.free_thresh!r}), "
                                 f"got {self.clamp_min!r}")
        if not self.free_thresh < self.occupied_thresh:
            raise ParameterError(f"free_thresh must be below occupied_thresh = {self.occupied_thresh!r}, "
                                 f"got {self.free_thresh!r}")
        if not self.occupied_thresh <= self.clamp_max < 1:
            raise ParameterError(f"clamp_max must be in [occupied_thresh = {self.occupied_thresh!r}, 1), "
                                 f"got {self.clamp_max!r}")

    @property
    def beams_per_turn(self) -> int:
        """Beams in a full turn: ``360 / angle_step`` rounded (at least 4)."""
        return max(int(round(360.0 / self.angle_step)), 4)


@dataclass(frozen=True, eq=False)
class World:
    """What the laser and the robot meet (:func:`build_world`), on the plan's grid.

    Attributes
    ----------
    opaque : (M, N) ndarray of bool
        Cells that stop a beam: walls but glass, closed doors, furniture.
    blocked : (M, N) ndarray of bool
        Obstacles beyond the plan's walls: closed doors and furniture.
    glass : (M, N) ndarray of bool
        Outer-wall cells that are glass.
    closed_doors : tuple of int
        Indices into ``plan.doors`` of the closed doors.
    furniture : tuple
        The random furniture added, ``(kind, x1, y1, x2, y2)`` in world metres
        (the plan's own objects are in ``plan.objects``).
    """

    opaque: np.ndarray
    blocked: np.ndarray
    glass: np.ndarray
    closed_doors: tuple
    furniture: tuple


@dataclass(frozen=True, eq=False)
class ScanResult:
    """A simulated scan and its intermediates (:func:`simulate_scan`).

    Attributes
    ----------
    grid : OccupancyGrid
        The map: the plan's shape, resolution and origin.
    path : (L, 2) ndarray of float
        The robot's path, world metres ``(x, y)``, cell centre to cell centre.
    poses : (K, 3) ndarray of float
        Where the scans were taken: world ``(x, y, yaw)``, metres and radians.
    map_poses : (K, 3) ndarray of float
        Where the SLAM believed them taken (with the pose drift), where the
        map is drawn; equal to ``poses`` without drift.
    visited : tuple of int
        Room labels the robot entered, in visiting order.
    world : World
        Glass, closed doors, furniture.
    people : (P, 2) ndarray of float
        Where the people stood, world metres.
    logodds : (M, N) ndarray of float32
        The occupancy log-odds the grid was thresholded from (0: never seen).
    """

    grid: OccupancyGrid
    path: np.ndarray
    poses: np.ndarray
    map_poses: np.ndarray
    visited: tuple
    world: World
    people: np.ndarray
    logodds: np.ndarray

    @property
    def glass(self) -> np.ndarray:
        """(M, N) ndarray of bool: the outer-wall cells that were glass."""
        return self.world.glass

    @property
    def closed_doors(self) -> tuple:
        """Indices into ``plan.doors`` of the doors that were closed."""
        return self.world.closed_doors

    @property
    def furniture(self) -> tuple:
        """The random furniture boxes added, ``(kind, x1, y1, x2, y2)`` metres."""
        return self.world.furniture


# --------------------------------------------------------------------------
# Frames: the plan's grid
# --------------------------------------------------------------------------

def _frame(plan: FloorPlan) -> OccupancyGrid:
    """An empty grid of the plan's shape and frame (a zero-strided view), for its
    :meth:`~topomap.io.OccupancyGrid.pixel_to_world` and ``world_to_pixel``."""
    return OccupancyGrid(np.broadcast_to(np.int8(UNKNOWN), plan.shape), resolution=plan.resolution,
                         origin=plan.origin)


def _to_world(plan: FloorPlan, rc) -> np.ndarray:
    """(K, 2) pixel ``(row, col)`` -> (K, 2) world ``(x, y)`` on the plan's grid."""
    rc = np.asarray(rc, float).reshape(-1, 2)
    x, y = _frame(plan).pixel_to_world(rc[:, 0], rc[:, 1])
    return np.stack([x, y], axis=1)


def _to_pixel(plan: FloorPlan, xy) -> np.ndarray:
    """(K, 2) world ``(x, y)`` -> (K, 2) fractional pixel ``(row, col)`` on the plan's grid."""
    xy = np.asarray(xy, float).reshape(-1, 2)
    r, c = _frame(plan).world_to_pixel(xy[:, 0], xy[:, 1])
    return np.stack([r, c], axis=1)


def _check_plan(plan) -> None:
    if not isinstance(plan, FloorPlan):
        raise ParameterError(f"plan must be a FloorPlan, got {type(plan).__name__}")
    shape = getattr(plan.walls, "shape", None)
    for key in ("walls", "inside", "rooms", "outer_walls"):
        a = getattr(plan, key)
        if a is None and key == "outer_walls":
            continue
        if not isinstance(a, np.ndarray) or a.ndim != 2 or a.shape != shape or 0 in a.shape:
            raise ParameterError(f"{plan.name}: plan.{key} must be a 2-D array of the walls' shape "
                                 f"{shape}, got {getattr(a, 'shape', type(a).__name__)}")
        if key != "rooms" and a.dtype != bool:
            raise ParameterError(f"{plan.name}: plan.{key} must be a bool array, got dtype {a.dtype}")
    if not np.issubdtype(plan.rooms.dtype, np.integer):
        raise ParameterError(f"{plan.name}: plan.rooms must be integer labels, got dtype {plan.rooms.dtype}")


# --------------------------------------------------------------------------
# Stage 2: the world
# --------------------------------------------------------------------------

def _outer_walls(plan: FloorPlan) -> np.ndarray:
    """The facade: ``plan.outer_walls``, else the wall cells within 0.35 m (an outer wall's
    thickness) of the outside."""
    if plan.outer_walls is not None:
        return np.asarray(plan.outer_walls, bool) & plan.walls
    from scipy import ndimage as ndi
    outside = ~plan.walls & ~plan.inside
    if not outside.any():
        return np.zeros(plan.shape, bool)
    d = ndi.distance_transform_edt(~outside) * plan.resolution
    return plan.walls & (d <= 0.35)


def _glass(plan: FloorPlan, options: ScanOptions, rng) -> np.ndarray:
    """Windows: disks of ``window_width`` on the facade until ``glass_share`` of it is glass."""
    outer = _outer_walls(plan)
    glass = np.zeros(plan.shape, bool)
    n_outer = int(outer.sum())
    if options.glass_share <= 0 or n_outer == 0:
        return glass
    target = options.glass_share * n_outer
    cells = np.argwhere(outer)
    r = max(options.window_width / 2 / plan.resolution, 0.5)
    ri = int(math.ceil(r))
    yy, xx = np.mgrid[-ri:ri + 1, -ri:ri + 1]
    disk = yy * yy + xx * xx <= r * r
    H, W = plan.shape
    n_glass = 0
    order = rng.permutation(len(cells))
    for i in order:
        if n_glass >= target:
            break
        r0, c0 = cells[i]
        if glass[r0, c0]:
            continue
        a0, a1, b0, b1 = max(r0 - ri, 0), min(r0 + ri + 1, H), max(c0 - ri, 0), min(c0 + ri + 1, W)
        d = disk[a0 - r0 + ri:a1 - r0 + ri, b0 - c0 + ri:b1 - c0 + ri]
        new = d & outer[a0:a1, b0:b1] & ~glass[a0:a1, b0:b1]
        glass[a0:a1, b0:b1] |= new
        n_glass += int(new.sum())
    return glass


def _segment_cells(plan: FloorPlan, p1, p2, half_width: float) -> tuple:
    """Cells (rows, cols) within ``half_width`` metres of the world segment p1-p2."""
    a, b = _to_pixel(plan, [p1, p2])
    hw = half_width / plan.resolution
    H, W = plan.shape
    r0, r1 = int(max(min(a[0], b[0]) - hw - 1, 0)), int(min(max(a[0], b[0]) + hw + 2, H))
    c0, c1 = int(max(min(a[1], b[1]) - hw - 1, 0)), int(min(max(a[1], b[1]) + hw + 2, W))
    if r0 >= r1 or c0 >= c1:
        return np.zeros(0, int), np.zeros(0, int)
    rr, cc = np.mgrid[r0:r1, c0:c1]
    p = np.stack([rr.ravel(), cc.ravel()], axis=1).astype(float)
    near = point_segment_distances(p, a, b) <= hw
    return rr.ravel()[near], cc.ravel()[near]


def _box_cells(plan: FloorPlan, x1, y1, x2, y2) -> tuple:
    """Slices (rows, cols) of the cells whose centres lie in the world box."""
    (ra, ca), (rb, cb) = _to_pixel(plan, [(min(x1, x2), min(y1, y2)), (max(x1, x2), max(y1, y2))])
    H, W = plan.shape
    r0, r1 = max(int(math.ceil(min(ra, rb) - 0.5)), 0), min(int(math.floor(max(ra, rb) + 0.5)) + 1, H)
    c0, c1 = max(int(math.ceil(min(ca, cb) - 0.5)), 0), min(int(math.floor(max(ca, cb) + 0.5)) + 1, W)
    return slice(r0, max(r1, r0)), slice(c0, max(c1, c0))


def _draw_piece(plan, mask, kind_legs, box) -> None:
    """Draw one furniture box into ``mask``: the whole box, or its four legs only."""
    x1, y1, x2, y2 = box
    if not kind_legs:
        mask[_box_cells(plan, x1, y1, x2, y2)] = True
        return
    leg = _LEG
    for lx, ly in ((x1, y1), (x2 - leg, y1), (x1, y2 - leg), (x2 - leg, y2 - leg)):
        rs, cs = _box_cells(plan, lx, ly, lx + leg, ly + leg)
        if rs.stop <= rs.start or cs.stop <= cs.start:  # a leg thinner than a cell: its nearest cell
            (r, c), = np.rint(_to_pixel(plan, [(lx + leg / 2, ly + leg / 2)])).astype(int)
            if 0 <= r < plan.shape[0] and 0 <= c < plan.shape[1]:
                mask[r, c] = True
        else:
            mask[rs, cs] = True


#: A piece of a room's floor a robot (or a person) walks into, m²: smaller pockets (under a table
#: ringed by its chairs, behind a bed's foot) are not a part of the room the furniture cut off.
_FLOOR_PART = 0.5


def _walkable_parts(space: np.ndarray, clearance_px: float, min_cells: float) -> int:
    """Number of 8-connected pieces, of more than ``min_cells`` cells, of the cells of ``space``
    farther than ``clearance_px`` from every cell that is not (the border of the array counts as not)."""
    from scipy import ndimage as ndi

    walk = ndi.distance_transform_edt(np.pad(space, 1)) > clearance_px
    lab, n = ndi.label(walk, structure=np.ones((3, 3), bool))
    return int((np.bincount(lab.ravel())[1:] > min_cells).sum()) if n else 0


def _random_furniture(plan: FloorPlan, options: ScanOptions, rng, keep_free: np.ndarray) -> tuple:
    """Random tables, beds and shelves inside the rooms: ``(kind, x1, y1, x2, y2)`` boxes that lie
    wholly in one room, clear of the door cells by :data:`_DOOR_KEEPOUT` and of ``keep_free``.

    A piece stands where it leaves a way round it: people walk through every part of a room, so
    furniture never cuts the room's floor (for the robot: the cells ``clearance`` from every
    obstacle) into more pieces than it had. A piece that would is placed elsewhere, or left out.
    """
    if options.furniture_density <= 0:
        return ()
    from scipy import ndimage as ndi
    res = plan.resolution
    doors = plan.inside & ~plan.walls & (plan.rooms == 0)
    near_door = ndi.distance_transform_edt(~doors) * res < _DOOR_KEEPOUT if doors.any() else \
        np.zeros(plan.shape, bool)
    labels = plan.rooms
    n_labels = int(labels.max()) if labels.size else 0
    if n_labels == 0:
        return ()
    objs = ndi.find_objects(labels)
    pieces = []
    for lab in range(1, n_labels + 1):
        sl = objs[lab - 1]
        if sl is None:
            continue
        room = labels[sl] == lab
        area = float(room.sum()) * res * res
        n = int(rng.poisson(options.furniture_density * area))
        ok = room & ~near_door[sl] & ~keep_free[sl]
        cand = np.argwhere(ok)
        if n == 0 or len(cand) == 0:
            continue
        floor = room & ~keep_free[sl]  # the room's floor the pieces placed so far leave
        clear_px = options.clearance / res
        part_px = _FLOOR_PART / res ** 2
        parts = _walkable_parts(floor, clear_px, part_px)

        def place(kind, legs, a0, a1, b0, b1, free_here):
            """Put a piece on the slice's cells a0..a1 x b0..b1 if they are all ``free_here`` and it
            leaves a way round it; its box, or None."""
            nonlocal floor
            if a0 < 0 or b0 < 0 or a1 >= room.shape[0] or b1 >= room.shape[1]:
                return None
            if not free_here[a0:a1 + 1, b0:b1 + 1].all():
                return None
            (xa, ya), (xb, yb) = _to_world(plan, np.array([[a1 + sl[0].start + 0.5, b0 + sl[1].start - 0.5],
                                                          [a0 + sl[0].start - 0.5, b1 + sl[1].start + 0.5]]))
            box = (float(xa), float(ya), float(xb), float(yb))
            drawn = np.zeros(plan.shape, bool)
            _draw_piece(plan, drawn, legs, box)
            after = floor & ~drawn[sl]
            if _walkable_parts(after, clear_px, part_px) > parts:
                return None  # it would cut the room's floor in two
            floor = after
            pieces.append((kind, *box))
            return box

        for _ in range(n):
            kind, (w, d), legs = _FURNITURE[int(rng.integers(len(_FURNITURE)))]
            if rng.random() < 0.5:
                w, d = d, w
            for _try in range(20):
                r, c = cand[int(rng.integers(len(cand)))]
                hr, hc = d / res / 2, w / res / 2  # rows along y (depth), cols along x (width)
                a0, a1 = int(round(r - hr)), int(round(r + hr))
                b0, b1 = int(round(c - hc)), int(round(c + hc))
                before = ok.copy()
                if place(kind, legs, a0, a1, b0, b1, ok) is None:
                    continue
                ok[max(a0 - 2, 0):a1 + 3, max(b0 - 2, 0):b1 + 3] = False  # no overlaps
                if kind == "table":  # its chairs, two along each long side, pulled half under it
                    under = before.copy()
                    under[a0:a1 + 1, b0:b1 + 1] = True
                    half = _CHAIR / res / 2
                    out = _CHAIR_OUT / res
                    along_cols = (b1 - b0) >= (a1 - a0)
                    lo, hi = (b0, b1) if along_cols else (a0, a1)
                    for side in ((a0 - out, a1 + out) if along_cols else (b0 - out, b1 + out)):
                        for frac in (0.25, 0.75):
                            u = lo + frac * (hi - lo)
                            cr, cc = (side, u) if along_cols else (u, side)
                            ca0, ca1 = int(round(cr - half)), int(round(cr + half))
                            cb0, cb1 = int(round(cc - half)), int(round(cc + half))
                            if place("chair", True, ca0, ca1, cb0, cb1, under) is not None:
                                ok[max(ca0 - 1, 0):ca1 + 2, max(cb0 - 1, 0):cb1 + 2] = False
                break
    return tuple(pieces)


def build_world(plan: FloorPlan, options: Optional[ScanOptions] = None, rng=None) -> World:
    """What the laser and the robot meet: walls, closed doors, furniture, glass.

    Parameters
    ----------
    plan : FloorPlan
    options : ScanOptions, optional
    rng : numpy.random.Generator, optional

    Returns
    -------
    World
        Doors closed: ``round(closed_doors * len(plan.doors))`` of them, at
        random among the doors :func:`_closable_doors` allows (at most
        all of those); each is drawn as a leaf 3 cells (at least 0.1 m) thick
        along its segment. Furniture: the plan's object boxes (whole boxes)
        with ``plan_furniture``, and random pieces at ``furniture_density``
        per m² of room. Glass: windows of ``window_width`` on the facade.
    """
    options = options or ScanOptions()
    rng = rng if rng is not None else np.random.default_rng(0)
    _check_plan(plan)
    res = plan.resolution
    blocked = np.zeros(plan.shape, bool)
    n_doors = len(plan.doors)
    closable = _closable_doors(plan)
    n_closed = min(int(round(options.closed_doors * n_doors)), len(closable))
    closed = tuple(sorted(int(closable[i]) for i in rng.choice(len(closable), size=n_closed, replace=False))) \
        if n_closed else ()
    leaf = max(1.5 * res, 0.05)
    for i in closed:
        d = plan.doors[i]
        rr, cc = _segment_cells(plan, d.p1, d.p2, leaf)
        blocked[rr, cc] = True
    blocked &= ~plan.walls
    if options.plan_furniture:
        for obj in plan.objects:
            _kind, x1, y1, x2, y2 = obj
            blocked[_box_cells(plan, x1, y1, x2, y2)] = True
    furniture = _random_furniture(plan, options, rng, blocked | plan.walls | ~plan.inside)
    for kind, x1, y1, x2, y2 in furniture:
        _draw_piece(plan, blocked, _LEGS_ONLY[kind], (x1, y1, x2, y2))
    blocked &= ~plan.walls
    glass = _glass(plan, options, rng)
    opaque = (plan.walls & ~glass) | blocked
    log.debug("%s: %d closed doors, %d furniture pieces, %d glass cells", plan.name, len(closed),
              len(furniture), int(glass.sum()))
    return World(opaque=opaque, blocked=blocked, glass=glass, closed_doors=closed, furniture=furniture)


# --------------------------------------------------------------------------
# Stage 3: the path
# --------------------------------------------------------------------------

def _room_graph(plan: FloorPlan, closed: tuple) -> dict:
    """Room label -> set of neighbour labels: the open doors between two rooms, and rooms whose
    cells touch (an opening with no door)."""
    adj = {}
    for i, d in enumerate(plan.doors):
        a, b = (int(v) for v in d.rooms)
        if i in closed or a <= 0 or b <= 0 or a == b:
            continue
        adj.setdefault(a, set()).add(b)
        adj.setdefault(b, set()).add(a)
    L = plan.rooms
    for x, y in ((L[1:], L[:-1]), (L[:, 1:], L[:, :-1])):
        m = (x != y) & (x > 0) & (y > 0)
        for a, b in set(zip(x[m].tolist(), y[m].tolist())):
            adj.setdefault(a, set()).add(b)
            adj.setdefault(b, set()).add(a)
    return adj


def _closable_doors(plan: FloorPlan) -> list:
    """Indices of the doors that may be closed: the doors of dead-end rooms.

    A robot that maps a home passes every door on its way between rooms (a
    closed one there would be opened, or the map is not of the home); it
    finds closed the doors of rooms off its way: a bedroom, a bathroom, a
    closet. So a door may be closed only where one of its two rooms is
    reached through no other room (one neighbour in the room graph) and has
    no door to the outside (the robot comes in there).
    """
    adj = _room_graph(plan, ())
    entered = {r for d in plan.doors if 0 in d.rooms for r in d.rooms}
    out = []
    for i, d in enumerate(plan.doors):
        a, b = (int(v) for v in d.rooms)
        if a <= 0 or b <= 0 or a == b:
            continue
        if any(len(adj.get(r, ())) == 1 and r not in entered for r in (a, b)):
            out.append(i)
    return out


def _largest_part(adj: dict, area: np.ndarray) -> set:
    """The rooms (labels with ``area > 0``) of the connected part of the room graph ``adj`` with the
    largest area."""
    rooms = [r for r in range(1, len(area)) if area[r] > 0]
    best, best_area, seen = set(), -1, set()
    for r in rooms:
        if r in seen:
            continue
        part, stack = {r}, [r]
        while stack:
            for b in adj.get(stack.pop(), ()):
                if b not in part and 0 < b < len(area) and area[b] > 0:
                    part.add(b)
                    stack.append(b)
        seen |= part
        total = int(sum(area[k] for k in part))
        if total > best_area:
            best, best_area = part, total
    return best


def _room_order(plan, reach_labels, adj, start, rng) -> list:
    """A depth-first walk over the room graph from ``start`` (neighbours in random order), then
    any reachable room the graph misses."""
    order, seen, stack = [], {start}, [start]
    while stack:
        a = stack.pop()
        order.append(a)
        nb = [b for b in sorted(adj.get(a, ())) if b in reach_labels and b not in seen]
        rng.shuffle(nb)
        for b in nb:
            seen.add(b)
        stack.extend(nb)
    order += [b for b in sorted(reach_labels) if b not in seen]
    return order


def _waypoints(room_cells: np.ndarray, dist: np.ndarray, coverage_px: float) -> np.ndarray:
    """Farthest-point waypoints of one room's cells (K, 2): the most open cell first, then the
    cell farthest from every waypoint until each cell is within ``coverage_px`` of one."""
    first = int(np.argmax(dist[room_cells[:, 0], room_cells[:, 1]]))
    pts = [first]
    d = np.hypot(*(room_cells - room_cells[first]).T)
    while True:
        far = int(np.argmax(d))
        if d[far] <= coverage_px:
            break
        pts.append(far)
        d = np.minimum(d, np.hypot(*(room_cells - room_cells[far]).T))
    return room_cells[pts]


def robot_path(plan: FloorPlan, options: Optional[ScanOptions] = None, rng=None, *,
               world: Optional[World] = None):
    """The robot's path through the rooms it visits.

    The robot moves on the free cells inside the home (doors included)
    farther than ``clearance`` from every wall and obstacle. It starts in a
    room with a door to the outside (or the room with most neighbours) of
    the largest part of the home the room graph joins (a plan may hold two
    flats, or a stair hall no door joins to the rest: a robot maps one),
    in the largest piece of the space it can drive on there (fixtures may
    leave a room by the door a pocket cut off from the rest of the home),
    takes the rooms in a depth-first walk over the room-door graph, the
    first ``max(1, round(explore * rooms))`` of those it can reach, and in
    each room visits waypoints (the most open point first, then farthest
    points, until every cell of the room it can reach lies within
    ``room_coverage`` of one), nearest first. Consecutive waypoints are
    joined by a shortest 8-connected path (:class:`skimage.graph.MCP_Geometric`).

    Parameters
    ----------
    plan : FloorPlan
    options : ScanOptions, optional
    rng : numpy.random.Generator, optional
    world : World, optional
        Obstacles beyond the walls (:func:`build_world`); none when omitted.

    Returns
    -------
    path : (L, 2) ndarray of int
        Pixel ``(row, col)`` of the path's cells, in order (empty when the
        robot has nowhere to stand).
    visited : tuple of int
        Room labels entered, in order.
    """
    from scipy import ndimage as ndi
    from skimage.graph import MCP_Geometric

    options = options or ScanOptions()
    rng = rng if rng is not None else np.random.default_rng(0)
    _check_plan(plan)
    res = plan.resolution
    blocked = world.blocked if world is not None else np.zeros(plan.shape, bool)
    space = plan.inside & ~plan.walls & ~blocked
    dist = ndi.distance_transform_edt(space)
    robot = dist * res > options.clearance
    empty = np.zeros((0, 2), int), ()
    if not robot.any():
        log.warning("%s: no cell is %.2f m from every wall: the robot cannot stand", plan.name,
                    options.clearance)
        return empty
    comp, _n = ndi.label(robot, structure=np.ones((3, 3), bool))
    labels = np.where(robot, plan.rooms, 0)
    n_rooms = int(plan.rooms.max())
    if n_rooms == 0:
        return empty
    area = np.bincount(labels.ravel(), minlength=n_rooms + 1)
    adj = _room_graph(plan, world.closed_doors if world is not None else ())
    entrance = sorted({max(int(v) for v in d.rooms) for i, d in enumerate(plan.doors)
                       if min(int(v) for v in d.rooms) == 0 and
                       (world is None or i not in world.closed_doors)})
    home = _largest_part(adj, area)
    if not home:
        return empty
    # the robot is set down in the largest piece of robot space of that part (fixtures and
    # furniture may leave a room with an outside door only a pocket cut off from the rest)
    in_home = np.isin(labels, sorted(home))
    piece = int(np.argmax(np.bincount(comp[in_home].ravel(), minlength=2)[1:])) + 1
    reach = (comp == piece)
    in_piece = set(np.unique(labels[reach]).tolist()) - {0}
    entrance = [r for r in entrance if r in home and r in in_piece]
    if entrance:
        start = entrance[int(rng.integers(len(entrance)))]
    else:
        start = max(sorted(home & in_piece) or sorted(home), key=lambda r: (len(adj.get(r, ())), area[r], -r))
    reach_area = np.bincount(labels[reach].ravel(), minlength=n_rooms + 1)
    reach_labels = {r for r in range(1, n_rooms + 1) if reach_area[r] > 0}
    order = _room_order(plan, reach_labels, adj, start, rng)
    n_visit = min(max(1, int(round(options.explore * n_rooms))), len(order))
    visited = tuple(int(r) for r in order[:n_visit])
    cost = np.where(reach, 1.0, np.inf)
    mcp = MCP_Geometric(cost, fully_connected=True)
    here = None
    pieces = []
    for r in visited:
        cells = np.argwhere(reach & (labels == r))
        todo = [tuple(p) for p in _waypoints(cells, dist, options.room_coverage / res)]
        while todo:
            if here is None:
                nxt = todo.pop(0)
                pieces.append(np.array([nxt]))
                here = nxt
                continue
            k = int(np.argmin([math.hypot(p[0] - here[0], p[1] - here[1]) for p in todo]))
            nxt = todo.pop(k)
            mcp.find_costs([here], [nxt], find_all_ends=False)
            pieces.append(np.array(mcp.traceback(nxt))[1:])
            here = nxt
    path = np.concatenate(pieces).astype(int) if pieces else np.zeros((0, 2), int)
    log.debug("%s: path of %d cells through %d of %d rooms", plan.name, len(path), len(visited),
              n_rooms)
    return path, visited


# --------------------------------------------------------------------------
# Stage 4: poses and drift
# --------------------------------------------------------------------------

def scan_poses(path: np.ndarray, resolution: float, options: Optional[ScanOptions] = None, rng=None):
    """Scan poses along a pixel path, and the poses the SLAM believes.

    Parameters
    ----------
    path : (L, 2) ndarray
        Pixel ``(row, col)`` path (:func:`robot_path`).
    resolution : float
        Metres per cell.
    options : ScanOptions, optional
    rng : numpy.random.Generator, optional

    Returns
    -------
    true, believed : (K, 3) ndarray of float
        Pixel ``(row, col, heading)``: the cell centre of each scan and the
        heading (radians, counter-clockwise from the grid's +x, i.e. the
        image's columns). One pose every ``pose_spacing`` metres of the
        path (and at its two ends). ``believed`` adds the SLAM's residual
        error: position and heading errors that wander along the path as an
        Ornstein-Uhlenbeck process (standard deviations ``drift_xy`` m and
        ``drift_yaw`` degrees, correlation length ``drift_length`` m),
        starting at zero where the map starts; positions rounded to cells.
    """
    options = options or ScanOptions()
    rng = rng if rng is not None else np.random.default_rng(0)
    path = np.asarray(path, float).reshape(-1, 2)
    if len(path) == 0:
        return np.zeros((0, 3)), np.zeros((0, 3))
    seg = np.hypot(*np.diff(path, axis=0).T) * resolution
    s = np.concatenate([[0.0], np.cumsum(seg)])
    total = s[-1]
    n = max(int(math.floor(total / options.pose_spacing)) + 1, 1)
    at = np.linspace(0.0, n - 1, n) * options.pose_spacing
    if total - at[-1] > 1e-9:
        at = np.append(at, total)
    rows = np.interp(at, s, path[:, 0])
    cols = np.interp(at, s, path[:, 1])
    # heading: direction of travel over +-0.5 m of path (a robot turns smoothly)
    ahead = np.interp(np.minimum(at + 0.5, total), s, path[:, 0]), np.interp(np.minimum(at + 0.5, total), s, path[:, 1])
    behind = np.interp(np.maximum(at - 0.5, 0), s, path[:, 0]), np.interp(np.maximum(at - 0.5, 0), s, path[:, 1])
    dr, dc = ahead[0] - behind[0], ahead[1] - behind[1]
    heading = np.arctan2(-dr, dc)
    true = np.stack([np.rint(rows), np.rint(cols), heading], axis=1)
    step = np.diff(at, prepend=0.0)  # metres since the previous pose
    noise = rng.normal(0.0, 1.0, (len(at), 3))
    err = _wander(noise, step, options.drift_length)
    e_yaw = err[:, 2] * math.radians(options.drift_yaw)
    e_xy = err[:, :2] * (options.drift_xy / resolution)
    believed = np.stack([np.rint(rows + e_xy[:, 0]), np.rint(cols + e_xy[:, 1]), heading + e_yaw], axis=1)
    return true, believed


def _wander(noise: np.ndarray, step: np.ndarray, length: float) -> np.ndarray:
    """A unit-variance Ornstein-Uhlenbeck process along the path, zero at its start.

    ``noise`` (K, C) standard normal draws, ``step`` (K,) metres since the previous sample,
    ``length`` the correlation length in metres: x_k = a x_{k-1} + sqrt(1 - a^2) n_k with
    a = exp(-step_k / length), so the error stays bounded (standard deviation 1 far from the
    start) however long the path.
    """
    a = np.exp(-np.asarray(step, float) / length)
    b = np.sqrt(1.0 - a * a)
    out = np.zeros_like(noise, dtype=float)
    x = np.zeros(noise.shape[1])
    for k in range(len(a)):
        x = a[k] * x + b[k] * noise[k]
        out[k] = x
    return out


# --------------------------------------------------------------------------
# Stage 5: rays
# --------------------------------------------------------------------------

def _beams(options: ScanOptions):
    """Beam angles relative to the heading (radians), their indices in a full turn, the radial
    sample step (cells) and the sample radii (cells)."""
    n360 = options.beams_per_turn
    dth = 2 * math.pi / n360
    half = int(math.floor(math.radians(options.field_of_view) / 2 / dth + 1e-9))
    idx = np.arange(-half, half + 1)
    if len(idx) > n360:  # a full turn: no beam twice
        idx = idx[:n360]
    return idx * dth, idx, n360


def cast_rays(opaque: np.ndarray, poses: np.ndarray, resolution: float,
              options: Optional[ScanOptions] = None, rng=None, *, people=None) -> np.ndarray:
    """One laser scan per pose: the range of each beam.

    Every beam is sampled every half cell out to ``range_max`` (nearest
    cell, :func:`cv2.remap`); its range is that of its first opaque sample
    less half a sample, plus Gaussian noise of ``range_sigma``. Cells off
    the grid are empty space.

    Parameters
    ----------
    opaque : (M, N) ndarray of bool
        Cells that stop a beam.
    poses : (K, 3) ndarray
        Pixel ``(row, col, heading)`` (:func:`scan_poses`).
    resolution : float
        Metres per cell.
    options : ScanOptions, optional
    rng : numpy.random.Generator, optional
    people : list of (row, col, radius, first, last), optional
        Discs (pixels) that are opaque for the scans ``first..last``.

    Returns
    -------
    (K, B) ndarray of float32
        Range per beam in metres (beams in the order of ``_beams``: from
        ``-field_of_view / 2`` to ``+field_of_view / 2`` about the
        heading); ``inf`` where nothing lies within ``range_max``; ``nan``
        for the beams that returned nothing (``no_return_share``).
    """
    import cv2

    options = options or ScanOptions()
    rng = rng if rng is not None else np.random.default_rng(0)
    rel, _idx, _n = _beams(options)
    step = 0.5  # cells between two samples of a beam
    n_rad = int(math.ceil(options.range_max / resolution / step)) + 1
    rho = (np.arange(n_rad, dtype=np.float32) * step)
    img = np.ascontiguousarray(opaque, dtype=np.uint8)
    K, B = len(poses), len(rel)
    out = np.full((K, B), np.inf, np.float32)
    people = list(people or ())
    H, W = img.shape
    for k in range(K):
        r0, c0, th = poses[k]
        saved = []
        for pr, pc, prad, first, last in people:
            if first <= k <= last:
                a0, a1 = max(int(pr - prad - 1), 0), min(int(pr + prad + 2), H)
                b0, b1 = max(int(pc - prad - 1), 0), min(int(pc + prad + 2), W)
                if a0 < a1 and b0 < b1:
                    saved.append((a0, a1, b0, b1, img[a0:a1, b0:b1].copy()))
                    yy, xx = np.ogrid[a0:a1, b0:b1]
                    img[a0:a1, b0:b1] |= ((yy - pr) ** 2 + (xx - pc) ** 2 <= prad * prad).astype(np.uint8)
        ang = rel + th
        cx = (np.cos(ang).astype(np.float32)[:, None] * rho[None, :]) + np.float32(c0)
        cy = (-np.sin(ang).astype(np.float32)[:, None] * rho[None, :]) + np.float32(r0)
        samp = cv2.remap(img, cx, cy, cv2.INTER_NEAREST, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
        hit = samp.argmax(axis=1)
        has = samp[np.arange(B), hit] > 0
        out[k, has] = (np.maximum(hit[has] * step - step / 2, 0.0)) * resolution
        for a0, a1, b0, b1, patch in saved:
            img[a0:a1, b0:b1] = patch
    if options.range_sigma > 0:
        fin = np.isfinite(out)
        out[fin] += rng.normal(0.0, options.range_sigma, int(fin.sum())).astype(np.float32)
        np.maximum(out, 0.0, out=out)
    if options.no_return_share > 0:
        out[rng.random(out.shape) < options.no_return_share] = np.nan
    out[np.isfinite(out) & (out > options.range_max)] = np.inf
    return out


# --------------------------------------------------------------------------
# Stage 6: occupancy update
# --------------------------------------------------------------------------

def integrate(shape: tuple, poses: np.ndarray, ranges: np.ndarray, resolution: float,
              options: Optional[ScanOptions] = None) -> np.ndarray:
    """Log-odds occupancy update of every scan, drawn at ``poses``.

    For each scan, every cell within ``range_max`` of the pose takes the
    beam nearest its direction: a cell before the beam's end (by more than
    half a cell) gains ``logit(miss_probability)``, the cell at its end
    ``logit(hit_probability)``; a beam with no end (``inf``) frees its
    whole length, a dropped beam (``nan``) and cells outside the field of
    view are left alone. The log-odds are clamped after each scan.

    Parameters
    ----------
    shape : tuple
        ``(M, N)`` of the grid.
    poses : (K, 3) ndarray
        Pixel ``(row, col, heading)`` where the map is drawn (the believed
        poses of :func:`scan_poses`).
    ranges : (K, B) ndarray
        :func:`cast_rays`.
    resolution : float
    options : ScanOptions, optional

    Returns
    -------
    (M, N) ndarray of float32
        Log-odds of occupancy; 0 where no beam reached.
    """
    import cv2

    options = options or ScanOptions()
    rel, idx, n360 = _beams(options)
    dth = 2 * math.pi / n360
    step = 0.5
    n_rad = int(math.ceil(options.range_max / resolution / step)) + 1
    R = int(math.ceil(options.range_max / resolution))
    yy, xx = np.mgrid[-R:R + 1, -R:R + 1].astype(np.float32)
    rad_px = np.hypot(yy, xx)
    mapx = (rad_px / step).astype(np.float32)
    mapx[rad_px * resolution > options.range_max] = -10.0  # off the polar image: no update
    ang_base = np.mod(np.arctan2(-yy, xx) / dth, n360).astype(np.float32)  # beams, counter-clockwise
    rho = np.arange(n_rad, dtype=np.float32) * step * resolution
    half = np.float32(resolution / 2)
    lut = np.array([0.0, _logit(options.miss_probability), _logit(options.hit_probability)], np.float32)
    lo, hi = np.float32(_logit(options.clamp_min)), np.float32(_logit(options.clamp_max))
    L = np.zeros(shape, np.float32)
    H, W = shape
    rows = (idx % n360)
    for k in range(len(poses)):
        r0, c0, th = poses[k]
        r0, c0 = int(r0), int(c0)
        a0, a1, b0, b1 = r0 - R, r0 + R + 1, c0 - R, c0 + R + 1
        if a1 <= 0 or b1 <= 0 or a0 >= H or b0 >= W:
            continue
        rng_k = ranges[k]
        state = np.zeros((2 * n360, n_rad), np.uint8)  # a full turn twice: no wrap in the look-up
        ok = ~np.isnan(rng_k)
        rk = rng_k[ok]
        # per beam: samples before its end free (1), within half a cell of it the hit (2)
        n_free = np.searchsorted(rho, rk - half, side="left")
        n_end = np.where(np.isfinite(rk), np.searchsorted(rho, rk + half, side="right"), n_free)
        col = np.arange(n_rad, dtype=np.int32)[None, :]
        st = ((col < n_free[:, None]).view(np.uint8)
              + 2 * ((col >= n_free[:, None]) & (col < n_end[:, None])).view(np.uint8))
        state[rows[ok]] = st
        state[n360:] = state[:n360]
        mapy = ang_base + np.float32(n360 - (th / dth) % n360)  # in [0, 2 * n360)
        cells = cv2.remap(state, mapx, mapy, cv2.INTER_NEAREST, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
        ca0, ca1, cb0, cb1 = max(a0, 0), min(a1, H), max(b0, 0), min(b1, W)
        upd = np.take(lut, cells[ca0 - a0:ca1 - a0, cb0 - b0:cb1 - b0])
        roi = L[ca0:ca1, cb0:cb1]
        roi += upd
        np.clip(roi, lo, hi, out=roi)
    return L


# --------------------------------------------------------------------------
# Stage 7: the map
# --------------------------------------------------------------------------

def to_grid(logodds: np.ndarray, plan: FloorPlan, options: Optional[ScanOptions] = None) -> OccupancyGrid:
    """The trinary map ``map_saver`` writes: occupied where the occupancy probability is at
    least ``occupied_thresh``, free where at most ``free_thresh``, unknown elsewhere (never seen
    included), on the plan's grid (its resolution and origin; ``source`` is the plan's name)."""
    options = options or ScanOptions()
    p = 1.0 / (1.0 + np.exp(-logodds.astype(np.float64)))
    cells = np.full(logodds.shape, UNKNOWN, np.int8)
    cells[(p <= options.free_thresh) & (logodds != 0)] = FREE
    cells[(p >= options.occupied_thresh) & (logodds != 0)] = OCCUPIED
    return OccupancyGrid(cells, resolution=plan.resolution, origin=plan.origin,
                         source=f"{plan.name} (simulated scan)")


# --------------------------------------------------------------------------
# The whole scan
# --------------------------------------------------------------------------

def _people(path_poses: np.ndarray, free: np.ndarray, resolution: float, options: ScanOptions, rng):
    """People near the path: ``(row, col, radius, first, last)`` discs and their cells."""
    K = len(path_poses)
    if K < 2 or options.people_per_metre <= 0:
        return []
    d = np.hypot(*np.diff(path_poses[:, :2], axis=0).T) * resolution
    s = np.concatenate([[0.0], np.cumsum(d)])
    n = int(rng.poisson(options.people_per_metre * s[-1]))
    rad = options.person_width / 2 / resolution
    out = []
    H, W = free.shape
    for _ in range(n):
        at = rng.uniform(0, s[-1])
        k = int(np.searchsorted(s, at).clip(0, K - 1))
        for _try in range(10):
            dist = rng.uniform(0.6, 2.0) / resolution  # in view, out of the robot's way
            a = rng.uniform(0, 2 * math.pi)
            r, c = path_poses[k, 0] - dist * math.sin(a), path_poses[k, 1] + dist * math.cos(a)
            ri, ci = int(round(r)), int(round(c))
            if 0 <= ri < H and 0 <= ci < W and free[ri, ci]:
                first = int(np.searchsorted(s, at - options.person_seen_for / 2))
                last = int(np.searchsorted(s, at + options.person_seen_for / 2, side="right")) - 1
                out.append((float(r), float(c), float(rad), first, max(last, first)))
                break
    return out


def simulate_scan(plan: FloorPlan, *, options: Optional[ScanOptions] = None, seed: int = 0) -> ScanResult:
    """Simulate a robot's laser SLAM map of a floor plan.

    Parameters
    ----------
    plan : FloorPlan
        The home to scan.
    options : ScanOptions, optional
        The laser, path, occupancy update and faults (defaults: a 10 m,
        270 deg, 0.5 deg laser through every room, the usual faults).
    seed : int
        Seed of the one random generator every stage draws from: the same
        plan, options and seed give the same map.

    Returns
    -------
    ScanResult
        The map on the plan's grid and the intermediates.

    Raises
    ------
    ParameterError
        ``plan`` is not a FloorPlan of consistent arrays, ``options`` not a
        ScanOptions, or ``seed`` not an integer.
    """
    if options is None:
        options = ScanOptions()
    elif not isinstance(options, ScanOptions):
        raise ParameterError(f"options must be a ScanOptions, got {options!r}")
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ParameterError(f"seed must be an integer >= 0, got {seed!r}")
    _check_plan(plan)
    rng = np.random.default_rng(int(seed))
    res = plan.resolution
    world = build_world(plan, options, rng)
    path, visited = robot_path(plan, options, rng, world=world)
    true, believed = scan_poses(path, res, options, rng)
    people = _people(true, plan.inside & ~plan.walls & ~world.blocked, res, options, rng)
    ranges = cast_rays(world.opaque, true, res, options, rng, people=people)
    L = integrate(plan.shape, believed, ranges, res, options)
    grid = to_grid(L, plan, options)
    yaw0 = float(plan.origin[2]) if len(plan.origin) > 2 else 0.0

    def world_poses(p):
        return np.column_stack([_to_world(plan, p[:, :2]), p[:, 2] + yaw0])

    length = float(np.hypot(*np.diff(path, axis=0).T).sum() * res) if len(path) > 1 else 0.0
    log.info("%s: %d scans along %.1f m through %d rooms; %d free, %d occupied cells", plan.name,
             len(true), length, len(visited), int(grid.free.sum()), int(grid.occupied.sum()))
    return ScanResult(grid=grid, path=_to_world(plan, path), poses=world_poses(true),
                      map_poses=world_poses(believed), visited=visited, world=world,
                      people=_to_world(plan, [(r, c) for r, c, *_ in people]), logodds=L)


# --------------------------------------------------------------------------
# The ground truth of a robot map: the rooms it shows
# --------------------------------------------------------------------------

#: Least area of a room that a robot map shows free for the room to be in that map's ground
#: truth, m²: 1 m² (20 x 20 cells at 0.05 m), a patch a person labelling the map draws as a room;
#: a room behind a closed door or never reached shows at most a few specks of free cells.
SHOWN_AREA = 1.0


def shown_rooms(rooms, free, *, resolution: float, min_area: float = SHOWN_AREA) -> np.ndarray:
    """The ground truth of a robot map: the true rooms the map shows, each whole.

    A person labelling a robot map draws the rooms they see in it; a room
    the robot never saw (behind a closed door, or never reached in a
    partial exploration) is unknown in the map, and no one can draw it. So
    the rooms of a scan's ground truth are the rooms with at least
    ``min_area`` of their cells free in the map, kept whole (with their
    cells the map leaves unknown or occupied, as the original protocol of
    Bormann et al. wants true rooms).

    Parameters
    ----------
    rooms : (M, N) array_like of int
        The true rooms of the plan (0 = no room).
    free : (M, N) array_like of bool
        The free cells of the robot map, on the same grid.
    resolution : float
        Metres per cell.
    min_area : float, optional
        Least free area of a shown room, m² (:data:`SHOWN_AREA`).

    Returns
    -------
    (M, N) ndarray
        ``rooms`` (its dtype) with the rooms the map does not show set to 0.
    """
    rooms = np.asarray(rooms)
    free = np.asarray(free, bool)
    if rooms.shape != free.shape:
        raise ParameterError(f"<array>: rooms {rooms.shape} and free cells {free.shape} differ in shape")
    res = check_resolution(resolution, name="resolution")
    min_cells = check_area("min_area", min_area) / res ** 2
    lab = np.where(rooms > 0, rooms, 0).astype(np.int64)
    seen = np.bincount(lab[free], minlength=int(lab.max(initial=0)) + 1)
    keep = seen >= min_cells - 1e-9
    keep[0] = False
    return np.where(keep[lab], rooms, 0).astype(rooms.dtype)


def shown_doors(doors, rooms) -> list:
    """The doors of a robot map's ground truth: those whose rooms are each shown or the outside.

    Parameters
    ----------
    doors : iterable of PlanDoor or dict
        Doors with their two rooms (``door.rooms`` or ``door["rooms"]``; 0 = outside).
    rooms : (M, N) array_like of int
        The shown rooms (:func:`shown_rooms`).

    Returns
    -------
    list
        The doors, in their order, whose every room is 0 or a label of ``rooms``.
    """
    labels = set(np.unique(np.asarray(rooms)).tolist()) | {0}
    return [d for d in doors
            if all(int(r) in labels for r in (d["rooms"] if isinstance(d, dict) else d.rooms))]
