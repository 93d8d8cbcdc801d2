"""The grid walls are found on: cells of about ``wall_cell`` (0.05 m) whatever the map's resolution.

A map finer than 0.05 m has its cells joined for the walls; a coarser one (a laser SLAM map
at 0.10 m) has each cell split into 0.05 m cells, so the rules counted in wall cells (the band
of a cell either side of a wall's line) keep their lengths in metres, unless its walls are
straight on the split cells too (a drawn plan, whose pieces of one wall may lie a whole cell
apart as drawn, keeps its own cells).
"""

import numpy as np
import pytest

from topomap.bench.datasets import load_labelled, real_maps_dir
from topomap.core.segmentation import _wall_grid, _WallGrid, segment, wall_split
from topomap.io import from_array
from topomap.options import TopomapOptions


def coarse(a):
    """``a`` (True = free) on cells twice as large: free where all four cells are (occupied if any
    is, as a SLAM map on a coarser grid marks a cell any hit falls in)."""
    H, W = a.shape
    return a.reshape(H // 2, 2, W // 2, 2).all(axis=(1, 3))


def room_with_a_box_in_line():
    """A 10 x 6 m room (0.05 m cells); from its left wall a partition 2 m long and 0.1 m thick,
    and 1.5 m past its end, on its line, a free-standing box 1.2 m long and 0.3 m thick. On
    0.10 m cells the box's faces lie one cell either side of the partition's line."""
    a = np.zeros((128, 208), bool)
    a[4:124, 4:204] = True
    a[62:64, 4:44] = False   # the partition: rows 62-63, up to x = 2.2 m
    a[60:66, 74:98] = False  # the box: rows 60-65, x = 3.7-4.9 m
    return a


def _openings_m(grid, split):
    opts = TopomapOptions()
    ops = _WallGrid(grid, opts, split=split).openings(opts)
    return sorted(tuple(np.round((np.r_[p, q] + 0.5) * grid.resolution, 2)) for p, q in ops)


def test_wall_split_is_the_map_cell_over_the_wall_cell():
    assert wall_split(0.05, 0.05) == 1
    assert wall_split(0.05, 0.025) == 1   # finer maps have their cells joined instead
    assert wall_split(0.05, 0.10) == 2
    assert wall_split(0.05, 0.075) == 1   # less than two wall cells: the map's own
    # at most two per side: the walls' grid holds at most four times the map's cells
    assert wall_split(0.05, 0.20) == 2
    assert wall_split(0.05, 10.0) == 2


def test_split_cells_find_the_openings_of_the_finer_map():
    """On 0.10 m cells split in four the wall openings are, in metres, those found on the same
    room drawn at 0.05 m; on the 0.10 m cells themselves, where a band of one cell either side
    of a line is 0.3 m wide, the box's outline counts for the partition going on and the
    openings differ."""
    fine = from_array(room_with_a_box_in_line(), resolution=0.05)
    rough = from_array(coarse(room_with_a_box_in_line()), resolution=0.10)
    at_005 = _openings_m(fine, None)
    assert at_005  # the gap from the partition's end to the box
    assert _openings_m(rough, 2) == at_005
    assert _openings_m(rough, 1) != at_005


def test_a_drawn_plan_at_0_10_keeps_its_own_cells():
    """Walls straight on the split cells too (a drawn plan): the walls stay on the map's cells,
    and the plan has the same rooms at 0.05 and 0.10 m."""
    a = np.zeros((128, 208), bool)
    a[4:124, 4:100] = True     # room A, 4.8 x 6 m
    a[4:124, 104:204] = True   # room B beyond a 0.2 m wall
    a[50:70, 100:104] = True   # a 1 m doorway in it
    opts = TopomapOptions()
    rough = from_array(coarse(a), resolution=0.10)
    assert _wall_grid(rough, opts).split == 1
    assert segment(from_array(a, resolution=0.05)).n_rooms == segment(rough).n_rooms == 2


@pytest.mark.skipif(real_maps_dir() is None, reason="real labelled maps not available")
def test_a_laser_map_at_0_10_has_its_walls_on_split_cells():
    """A laser SLAM map (Freiburg 079, a partial map) resampled to 0.10 m: on 0.05 m cells its
    walls are not straight (less than ``straight_walls`` of the faces on lines), so they are
    found there; on its own cells they look straight (the share that sets ``rise`` still takes
    it for a plan: a wall's wander is within one 0.10 m cell)."""
    (bm,) = [b for b in load_labelled(real_maps_dir()) if b.name == "freiburg079_partial_02"]
    g = bm.load()
    free = g.free[:g.free.shape[0] // 2 * 2, :g.free.shape[1] // 2 * 2]
    occ = g.occupied[:free.shape[0], :free.shape[1]]
    H, W = free.shape
    occ2 = occ.reshape(H // 2, 2, W // 2, 2).any(axis=(1, 3))
    free2 = free.reshape(H // 2, 2, W // 2, 2).any(axis=(1, 3)) & ~occ2
    cells = np.where(occ2, 100, np.where(free2, 0, -1)).astype(np.int8)
    rough = from_array(cells, resolution=0.10)
    opts = TopomapOptions()
    walls = _wall_grid(rough, opts)
    assert walls.split == 2
    assert walls.straight_share() >= opts.straight_walls
