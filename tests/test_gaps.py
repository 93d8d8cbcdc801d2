"""Gaps in thin walls: doorways that narrow nothing are doors (``TopomapOptions.gaps``).

Hand-drawn maps at 0.05 m per cell (True = free). A hallway exactly as wide as
its doorways shows no clearance bottleneck at either end; the thin wall it
opens through does.
"""

import numpy as np
import pytest

from topomap.core.doors import WALL_GAP
from topomap.core.segmentation import segment
from topomap.core.walls import thin_wall_gaps
from topomap.io import from_array

RES = 0.05


def strip_behind_a_wide_gap():
    """A 2.8 x 4 m room and, behind a 0.15 m wall, a strip 1 m deep along it (a balcony, an
    entrance), open to it through a 1.6 m gap; the wall's pieces beside the gap are 0.6 m long.
    The strip is narrower than the gap: the clearance does not narrow there, and the pieces
    are too short for an opening in a straight wall (``min_wall_length``)."""
    a = np.zeros((120, 80), bool)
    a[7:27, 10:66] = True     # the strip: rows 7-26 (1 m), cols 10-65 (2.8 m)
    a[27:30, 22:54] = True    # the gap in the wall (rows 27-29), cols 22-53 (1.6 m)
    a[30:110, 10:66] = True   # the room
    return a


def hallway_between_rooms():
    """Two 4 x 4 m rooms, one above the other, joined by a 0.8 m wide, 2 m long hallway
    through 0.15 m walls: the hallway is as wide as the gaps it opens through."""
    a = np.zeros((200, 120), bool)
    a[10:90, 20:100] = True    # room A: rows 10-89 (4 m), walls 0.15 m below it
    a[93:133, 52:68] = True    # the hallway, 16 cells (0.8 m) wide
    a[90:93, 52:68] = True     # the gap in A's wall
    a[133:136, 52:68] = True   # the gap in B's wall
    a[136:196, 20:100] = True  # room B
    return a


def test_gap_onto_a_narrower_strip_is_a_door():
    seg = segment(from_array(strip_behind_a_wide_gap(), resolution=RES))
    assert seg.n_rooms == 2
    assert len(seg.doors) == 1
    (r1, c1), (r2, c2) = seg.doors[0].segment
    assert 26 <= r1 <= 30 and 26 <= r2 <= 30  # in the wall's gap
    assert sorted([c1, c2]) == pytest.approx([21, 54], abs=1.5)  # from post to post
    assert any(c.status == WALL_GAP for c in seg.candidates)


def test_without_gaps_the_strip_joins_the_room():
    # the stage is what finds it: neither the clearance nor the wall's lines show a door there
    seg = segment(from_array(strip_behind_a_wide_gap(), resolution=RES), gaps=False)
    assert seg.n_rooms == 1


def test_a_doorway_with_a_door_is_not_cut_again():
    # the hallway's doors are corridor mouths already; the gaps across the same walls add no
    # second cut (which would leave a sliver of the wall's thickness between two cuts)
    seg = segment(from_array(hallway_between_rooms(), resolution=RES))
    assert seg.n_rooms == 3
    assert len(seg.doors) == 2


def two_tables():
    """Two free-standing tables (1.0 x 0.4 m) end to end, 0.8 m apart, in a 6 x 6 m room: each
    looks like a thin wall going on along the line between them."""
    a = np.zeros((140, 140), bool)
    a[10:130, 10:130] = True
    a[66:74, 26:46] = False   # table 1: rows 66-73, cols 26-45
    a[66:74, 62:82] = False   # table 2: cols 62-81, 16 cells (0.8 m) from table 1
    return a


def _gaps(a, **kw):
    """:func:`thin_wall_gaps` on the skeleton of the free cells ``a``, with the defaults' lengths."""
    from topomap._fast import edt
    from topomap.core.skeleton import skeleton_graph, skeletonize

    G = skeleton_graph(skeletonize(a), radius=edt(a), resolution=RES)
    args = dict(min_width_px=0.5 / RES, max_width_px=3.0 / RES, along_px=0.3 / RES, thick_px=0.5 / RES,
                structure_px=2.0 / RES)
    args.update(kw)
    return thin_wall_gaps(G, a, ~a, **args)


def test_thin_wall_gaps_finds_the_gap_and_not_the_tables():
    gaps = _gaps(strip_behind_a_wide_gap())
    assert gaps
    for p, q in gaps:  # every one across the wall's gap, post to post
        assert 26 <= p[0] <= 30 and 26 <= q[0] <= 30
        assert sorted([p[1], q[1]]) == pytest.approx([21, 54], abs=1.5)
    assert _gaps(two_tables()) == []


def test_tables_would_pass_for_walls_without_the_structure_test():
    # what keeps the tables out: furniture is no structure (``partition_structure``)
    gaps = _gaps(two_tables(), structure_px=0.0)
    assert gaps and all(45 <= min(p[1], q[1]) and max(p[1], q[1]) <= 63 for p, q in gaps)


def test_corridor_cross_sections_are_no_gaps():
    a = np.zeros((120, 200), bool)
    a[10:110, 5:55] = True      # room A 5 x 5 m
    a[50:70, 55:145] = True     # corridor 1 m wide, its side walls 2 m thick
    a[10:110, 145:195] = True   # room B
    assert all(min(p[1], q[1]) <= 60 or max(p[1], q[1]) >= 140 for p, q in _gaps(a))


@pytest.mark.parametrize("gap_wall", [-0.1, float("nan")])
def test_gap_wall_is_checked(gap_wall):
    from topomap.errors import ParameterError

    with pytest.raises(ParameterError, match="gap_wall"):
        segment(from_array(strip_behind_a_wide_gap(), resolution=RES), gap_wall=gap_wall)


def pillars_in_a_corridor():
    """A 2 m corridor between 0.5 m thick walls with a pair of 0.35 m pillars against its walls,
    facing each other 1.3 m apart: each pillar looks like a wall's end beyond a doorway."""
    a = np.zeros((80, 200), bool)
    a[20:60, 0:200] = True       # the corridor, rows 20-59 (2 m)
    a[20:27, 96:103] = False     # pillar against the top wall (0.35 m deep, 0.35 m wide)
    a[53:60, 96:103] = False     # pillar against the bottom wall
    return a


def test_a_gap_at_a_pillar_is_no_doorway():
    assert _gaps(pillars_in_a_corridor(), pillar_px=0.5 / RES) == []
    # what keeps it out: the pillar test (thin for less than pillar_depth, then the wall)
    assert _gaps(pillars_in_a_corridor(), pillar_px=0.0)


def test_sphere_traced_march_finds_the_first_obstacle_of_a_step_by_step_march():
    # a noisy map: rays from every free cell in random directions, to the first obstacle cell
    from topomap._fast import edt
    from topomap.core.walls import _FAR, _first_obstacle, clearance_lookup

    rng = np.random.default_rng(3)
    free = rng.random((90, 110)) > 0.04
    free[:, :3] = False
    pad = 70
    solid = np.pad(~free, pad, constant_values=True)
    # the clearance as thin_wall_gaps looks it up (the map's edge counted)
    clear_at = clearance_lookup(edt(free))

    def look(img):
        return lambda Q: img[np.rint(Q[..., 0]).astype(np.intp) + pad, np.rint(Q[..., 1]).astype(np.intp) + pad]

    P = np.argwhere(free)[::7].astype(float) + rng.uniform(-0.4, 0.4, (len(np.argwhere(free)[::7]), 2))
    ang = rng.uniform(0, 2 * np.pi, len(P))
    D = np.stack([np.sin(ang), np.cos(ang)], 1)
    got = _first_obstacle(look(solid), clear_at, P, D, 60)
    steps = np.arange(0, 61)
    hit = look(solid)(P[:, None, :] + D[:, None, :] * steps[None, :, None])
    want = np.where(hit.any(1), hit.argmax(1), _FAR)
    assert np.array_equal(got, want)


def test_wall_samples_are_per_metre_whatever_the_resolution():
    # 0.3 m beyond a post: 6 samples on 0.05 m cells, 6 on 1 mm cells (every 50 pixels), not 300
    # (a 1 mm map of two rooms needed 8 GB when the samples went per pixel)
    from topomap.core.walls import _samples

    assert _samples(0.3 / 0.05, 1.0).tolist() == [1, 2, 3, 4, 5, 6]
    fine = _samples(0.3 / 0.001, 0.05 / 0.001)
    assert len(fine) == 6 and fine[-1] == pytest.approx(300)
