"""The realism statistics of benchmarks/realism.py on small hand-drawn maps."""

import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
import realism  # noqa: E402

from topomap.io import FREE, OCCUPIED, UNKNOWN, from_array, save_map  # noqa: E402

RES = 0.05


def _room(h=60, w=80, wall=3, outside=UNKNOWN):
    """A closed room of free cells inside walls ``wall`` cells thick, ``outside`` around it (ROS values)."""
    c = np.full((h, w), outside, np.int8)
    c[5:h - 5, 5:w - 5] = OCCUPIED
    c[5 + wall:h - 5 - wall, 5 + wall:w - 5 - wall] = FREE
    return c


def _masks(c):
    return c == FREE, c == OCCUPIED, c == UNKNOWN


@pytest.mark.parametrize("wall, metres", [(1, 0.05), (3, 0.15), (5, 0.25)])
def test_wall_thickness_of_odd_walls(wall, metres):
    _, occ, _ = _masks(_room(wall=wall))
    assert realism.wall_thickness(occ, RES) == pytest.approx(metres)
    assert realism.wall_thickness(occ, 0.1) == pytest.approx(2 * metres)


def test_wall_thickness_leaves_clutter_out():
    c = _room(wall=3)
    c[10:48:3, 10:68:3] = OCCUPIED  # 260 single-cell specks, more cells than the walls' skeleton
    free, occ, _ = _masks(c)
    assert realism.wall_thickness(occ, RES) == pytest.approx(0.15)
    assert realism.wall_thickness(occ, RES, min_area_m2=0) == pytest.approx(0.05)  # specks counted: 1 cell
    assert np.isnan(realism.wall_thickness(np.zeros((5, 5), bool), RES))


def test_unknown_share_in_the_box_of_the_known_cells():
    c = np.full((40, 50), UNKNOWN, np.int8)
    c[10:20, 10:30] = FREE  # 200 known cells ...
    c[12:14, 12:22] = UNKNOWN  # ... 20 of them unknown: a hole the robot did not see
    free, occ, _ = _masks(c)
    assert realism.unknown_share(free, occ) == pytest.approx(20 / 200)
    assert np.isnan(realism.unknown_share(np.zeros((3, 3), bool), np.zeros((3, 3), bool)))


def _fan(c, row, col, length):
    """Free spokes of single cells from (row, col) into the unknown, leftwards at three slopes."""
    cells = set()
    for k in range(length):
        for dr in (-0.5, 0.0, 0.5):
            cells.add((int(round(row + dr * k)), col - k))
    for r, cc in cells:
        c[r, cc] = FREE
    return len(cells)


def test_free_outside_the_outline_and_thin_spokes():
    c = np.pad(_room(h=80, w=120, wall=2), ((0, 0), (40, 0)), constant_values=UNKNOWN)  # room from col 45
    free, occ, unk = _masks(c)
    assert realism.outside_free_share(free, occ, RES) == 0.0
    assert realism.spoke_share(free, unk, RES) == 0.0  # corners of a drawn room end at walls
    c[38:42, 45:47] = FREE  # a 0.2 m gap in the left wall, and rays through it into the open
    n = _fan(c, 40, 44, 30)
    free, occ, unk = _masks(c)
    outside = free[:, :45].sum()
    assert outside == n
    # the fan, and at most the 8 cells of the gap itself (the shrinking takes back part of a straight gap)
    measured = realism.outside_free_share(free, occ, RES) * free.sum()
    assert outside <= round(measured) <= outside + 8
    spokes = realism.spoke_share(free, unk, RES) * free.sum()
    assert spokes >= outside  # the spokes, with the thin gap they come through
    assert spokes <= outside + 4 * 2 + 40  # and not the room


def test_an_open_building_is_counted_outside():
    c = _room(h=80, w=120, wall=2)
    c[30:60, 5:7] = FREE  # a 1.5 m opening: still closed by the 2 m outline
    free, occ, _ = _masks(c)
    assert realism.outside_free_share(free, occ, RES) == 0.0
    c[10:70, 5:7] = FREE  # a 3 m opening: the room is outside (the measure's known limit)
    free, occ, _ = _masks(c)
    assert realism.outside_free_share(free, occ, RES) > 0.5


def test_specks():
    c = _room(h=80, w=120, wall=2)
    c[20, 20] = OCCUPIED  # a speck
    c[30:33, 40:43] = OCCUPIED  # 9 cells, 0.0225 m²: a speck
    c[50:55, 50:55] = OCCUPIED  # 25 cells, 0.0625 m²: furniture, no speck
    c[60, 7] = OCCUPIED  # touching the wall: part of it
    c[40, 60] = OCCUPIED  # a speck next to an unknown cell: the edge of the seen space
    c[40, 61] = UNKNOWN
    free, occ, unk = _masks(c)
    assert realism.specks(free, occ, unk, RES) == 2
    edge = np.zeros((10, 10), np.int8)
    edge[0, 5] = OCCUPIED  # on the edge of the map
    edge[5, 5] = OCCUPIED
    assert realism.specks(*_masks(edge), RES) == 1
    stats = realism.map_statistics(from_array(c, resolution=RES))
    assert stats["n_specks"] == 2
    assert stats["specks_per_m2"] == pytest.approx(2 / (free.sum() * RES ** 2))
    assert stats["wall_thickness_m"] == pytest.approx(0.05) and stats["unknown_share"] < 0.01


def test_the_section_script(tmp_path):
    real = tmp_path / "real"
    real.mkdir()
    save_map(_room(h=60, w=90), real / "site_a", resolution=RES)
    corpus = tmp_path / "corpus"
    for case in ("c1", "c2"):
        (corpus / case).mkdir(parents=True)
        save_map(_room(wall=3), corpus / case / "map", resolution=RES)
        save_map(_room(wall=3), corpus / case / "plan", resolution=RES)
        Image.fromarray(np.zeros((60, 80), np.uint16)).save(corpus / case / "gt_rooms.png")
    out, fig = tmp_path / "s.md", tmp_path / "f.png"
    assert realism.main(["--real", str(real), "--out", str(out), "--figure", str(fig), "--jobs", "1"]) == 0
    text = out.read_text()
    assert "| ROSE² real maps | 1 | 0.15 (0.15–0.15) | 0.0 (0.0–0.0) | 0.0 (0.0–0.0) | 0.0 (0.0–0.0) |" in text
    assert "| simulated" not in text
    one = Image.open(fig).size
    assert realism.main([str(corpus), "--real", str(real), "--out", str(out), "--figure", str(fig),
                         "--jobs", "1"]) == 0
    text = out.read_text()
    save_map(_room(wall=1), corpus / "c2" / "map", resolution=RES)
    assert realism.main([str(corpus), "--real", str(real), "--out", str(out), "--figure", str(fig),
                         "--jobs", "1"]) == 0
    text = out.read_text()
    assert "| simulated scans | 2 | 0.10 (0.05–0.15) |" in text and "| simulated plans | 2 |" in text
    assert "benchmarks/realism.py CORPUS" in text
    assert Image.open(fig).size[0] > one[0]  # the simulated scan beside the real map
