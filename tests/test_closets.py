"""Openings into shallow spaces: a closet or a balcony behind a door is a room of its own; a niche
(as wide as its mouth) stays part of the room it opens onto (TopomapOptions.closet_depth)."""

import numpy as np

import topomap
from topomap.io import FREE, OCCUPIED, UNKNOWN, OccupancyGrid


def _plan(behind: str):
    """A 6 x 4 m room (0.05 m cells, walls 0.15 m); along its top wall a 1 m deep space behind a
    1.0 m gap in the wall: ``closet``: 4 m wide, running on 1.5 m past both ends of the gap;
    ``niche``: as wide as the gap."""
    c = np.full((140, 160), UNKNOWN, np.int8)
    c[10:128, 10:150] = OCCUPIED
    c[43:125, 13:147] = FREE                      # the room, 6.7 x 4.1 m
    c[40:43, 13:147] = OCCUPIED                   # its top wall, 0.15 m
    c[40:43, 70:90] = FREE                        # a 1.0 m gap in it
    if behind == "closet":
        c[20:40, 40:120] = FREE                   # 1.0 m deep, 4 m wide
    else:
        c[20:40, 70:90] = FREE                    # 1.0 m deep, as wide as the gap
    return OccupancyGrid(c, 0.05)


def test_a_closet_behind_its_door_is_a_room():
    seg = topomap.segment(_plan("closet"))
    assert seg.n_rooms == 2 and len(seg.doors) == 1
    assert seg.doors[0].width < 1.2
    off = topomap.segment(_plan("closet"), closet_depth=0, gaps=False)   # the alcove rule alone: one room
    assert off.n_rooms == 1
    # the gap in the thin wall shows the closet's door too (TopomapOptions.gaps)
    assert topomap.segment(_plan("closet"), closet_depth=0).n_rooms == 2


def test_a_niche_stays_part_of_its_room():
    seg = topomap.segment(_plan("niche"))
    assert seg.n_rooms == 1
