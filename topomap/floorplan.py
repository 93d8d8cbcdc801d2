"""Floor plans on a grid, with their ground truth: the input of the simulator.

A :class:`FloorPlan` is a home (or any building) drawn on an occupancy grid:
walls with a thickness, doors open, the outside of the building apart, and
the ground truth a room-segmentation benchmark needs (room labels with the
doors closed, the door segments, each room's kinds). It is what
:func:`read_plan` makes of one vector plan of the R2V / LIFULL data set and
what :mod:`topomap.simulate` scans with a simulated robot.

Grid convention: the ROS one of :class:`topomap.io.OccupancyGrid`: row 0 is
the top of the image (largest y), ``origin`` is the world pose of the
lower-left corner of the grid, metres and radians.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["PlanDoor", "FloorPlan"]


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
        onto an outside that is not a room).
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
    rooms : (M, N) ndarray of uint16
        Ground-truth room labels on the same grid: 1..K inside the home with
        the doors closed (a closet behind its own door belongs to the room
        it opens into), 0 on walls, door cells and the outside.
    doors : tuple of PlanDoor
        The doors of the plan.
    kinds : dict
        Room label -> tuple of kind names from the plan's label boxes
        (``"bedroom"``, ``"corridor"``, ...); ``()`` for a room with none.
    outer_walls : (M, N) ndarray of bool
        The wall cells that face the outside (the facade): where glass may
        let laser rays through.
    objects : tuple
        Object boxes of the plan (fixtures, furniture) as
        ``(kind, x1, y1, x2, y2)`` in world metres.
    scale : float
        Metres per unit of the plan's own coordinates.
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

    @property
    def shape(self) -> tuple:
        return self.walls.shape
