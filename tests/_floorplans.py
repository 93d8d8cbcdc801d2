"""Small hand-drawn :class:`topomap.bench.floorplan.FloorPlan` homes for the simulator's tests.

A plan is drawn from room rectangles (interiors, world metres) and doors
(centre, width, the axis the door's wall runs along): every cell within
``wall`` metres of a room that is not a room is wall, the rest the outside;
a door carves its width through the wall. The grid has a margin of outside
around the building and the origin ``origin`` (lower-left corner).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage as ndi

from topomap.bench.floorplan import FloorPlan, PlanDoor

RES = 0.05


def draw_plan(rooms, doors=(), *, wall=0.2, res=RES, margin=1.0, origin=(0.0, 0.0, 0.0),
              objects=(), name="plan"):
    """A FloorPlan of ``rooms`` [(x0, y0, x1, y1) interiors, metres] and ``doors``
    [(x, y, width, along) with ``along`` 'x' for a door in a wall running along x]."""
    xs = [v for r in rooms for v in (r[0], r[2])]
    ys = [v for r in rooms for v in (r[1], r[3])]
    x_lo, y_lo = min(xs) - wall - margin, min(ys) - wall - margin
    x_hi, y_hi = max(xs) + wall + margin, max(ys) + wall + margin
    W = int(round((x_hi - x_lo) / res))
    H = int(round((y_hi - y_lo) / res))
    ox, oy = origin[0] + x_lo, origin[1] + y_lo
    cx = ox + (np.arange(W) + 0.5) * res            # cell centres, x per column
    cy = oy + (H - np.arange(H) - 0.5) * res        # y per row (row 0 on top)
    X, Y = np.meshgrid(cx, cy)
    labels = np.zeros((H, W), np.uint16)
    for i, (x0, y0, x1, y1) in enumerate(rooms, 1):
        labels[(X > x0) & (X < x1) & (Y > y0) & (Y < y1)] = i
    interior = labels > 0
    building = ndi.distance_transform_edt(~interior) * res <= wall + 1e-9
    building = ndi.binary_fill_holes(building)
    walls = building & ~interior
    door_cells = np.zeros((H, W), bool)
    plan_doors = []
    for x, y, width, along in doors:
        if along == "x":
            m = (np.abs(X - x) < width / 2) & (np.abs(Y - y) <= wall / 2 + res)
            p1, p2 = (x - width / 2, y), (x + width / 2, y)
            probe = [(x, y - wall), (x, y + wall)]
        else:
            m = (np.abs(Y - y) < width / 2) & (np.abs(X - x) <= wall / 2 + res)
            p1, p2 = (x, y - width / 2), (x, y + width / 2)
            probe = [(x - wall, y), (x + wall, y)]
        m &= walls
        door_cells |= m
        pair = []
        for px, py in probe:
            c = int((px - ox) / res)
            r = H - 1 - int((py - oy) / res)
            pair.append(int(labels[r, c]) if 0 <= r < H and 0 <= c < W else 0)
        plan_doors.append(PlanDoor(p1=p1, p2=p2, rooms=tuple(sorted(pair)), width=float(width)))
    walls &= ~door_cells
    inside = interior | door_cells
    outside = ~building
    outer = walls & (ndi.distance_transform_edt(~outside) * res <= wall + res)
    return FloorPlan(name=name, resolution=res, origin=(ox, oy, float(origin[2]) if len(origin) > 2 else 0.0),
                     walls=walls, inside=inside, rooms=labels, doors=tuple(plan_doors),
                     kinds={i: () for i in range(1, len(rooms) + 1)}, outer_walls=outer,
                     objects=tuple(objects))


def home(**kw):
    """A 10 m x 7 m home: a corridor (room 1) with rooms 2, 3 (north) and 4 (south) off it
    through doors, and room 5 (south-east) a box room with no door."""
    rooms = [(0.2, 2.6, 9.8, 3.8),   # 1 corridor
             (0.2, 4.0, 4.9, 6.8),   # 2
             (5.1, 4.0, 9.8, 6.8),   # 3
             (0.2, 0.2, 4.9, 2.4),   # 4
             (5.1, 0.2, 9.8, 2.4)]   # 5: no door
    doors = [(2.5, 3.9, 0.9, "x"), (7.5, 3.9, 0.9, "x"), (2.5, 2.5, 0.9, "x")]
    return draw_plan(rooms, doors, **kw)


def big_home(nx=4, ny=3, room=4.0, **kw):
    """``nx`` x ``ny`` rooms of ``room`` metres along a corridor per row pair: a home (or
    office) of about ``nx * ny * room**2`` m², every room with a door onto a corridor."""
    rooms, doors = [], []
    wall = kw.get("wall", 0.2)
    corr = 1.6
    y = 0.0
    for j in range(ny):
        rooms.append((0.0, y, nx * (room + wall) - wall, y + corr))  # corridor
        y_c = y
        y += corr + wall
        for i in range(nx):
            x0 = i * (room + wall)
            rooms.append((x0, y, x0 + room, y + room))
            doors.append((x0 + room / 2, y - wall / 2, 0.9, "x"))
        y += room + wall
        if j:
            doors.append((0.8, y_c - wall / 2, 0.9, "x"))  # the corridor up to the previous row
    return draw_plan(rooms, doors, **kw)
