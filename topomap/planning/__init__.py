"""Planning over the room graph: which room a point is in, travel distances through doors, routes
(:func:`plan_path`), room orders (:func:`plan_tour`) and Nav2 route graphs.

:mod:`topomap.planning.paths` holds rooms, doors and routes (over the rasterised rooms of
:class:`topomap.core.roommap.RoomMap`); :mod:`topomap.planning.tour` the order of rooms;
:mod:`topomap.planning.nav2` the route graph for Nav2 (its files: :mod:`topomap.io.nav2`).
"""

from __future__ import annotations

from ..errors import NoPathError, NotInRoomError, PlanningError
from .paths import (
    EXACT_CELLS,
    MANY_DOORS,
    REFINE_CELLS,
    TRAVEL_CELL,
    door_graph,
    doors_between,
    neighbors,
    plan_path,
    room_at,
    room_distances,
    travel_graph,
)
from .tour import plan_tour, solve_order, stop_distances, tour_length, tour_lower_bound

__all__ = [
    "EXACT_CELLS", "MANY_DOORS", "REFINE_CELLS", "TRAVEL_CELL", "door_graph", "doors_between", "neighbors",
    "plan_path", "room_at", "room_distances", "travel_graph", "plan_tour", "solve_order", "stop_distances",
    "tour_length", "tour_lower_bound", "PlanningError", "NotInRoomError", "NoPathError",
]
