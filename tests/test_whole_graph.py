"""The room graph is whole: rooms whose cells touch are joined by a door (or are one room), so the
room graph has exactly as many components as the free space the rooms cover.

Checked on hand-drawn cuts (two cuts across the two faces of a doorway in a thick wall, a boundary
wider than any door), on fuzzed maps for the Voronoi methods (the baselines keep the doors of
their own cuts only, as the methods they reproduce), and on a sample of the benchmark and real
maps when they are present (skipped otherwise).
"""

import os
from pathlib import Path

import numpy as np
import networkx as nx
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy import ndimage as ndi

import _testdata as T
from topomap.bench.datasets import _shared_dataset, benchmark_dir, real_maps_dir
from topomap.io import from_array, load_map
from topomap.core.rooms import cut_rooms, join_touching_rooms
from topomap.core.segmentation import segment

_FORWARD = ((0, 1), (1, -1), (1, 0), (1, 1))


def touching_pairs(labels, n):
    """The pairs ``(a, b)``, ``a < b``, of rooms ``1..n`` with 8-adjacent cells (counted here by
    shifting the whole image, independently of the library's own search)."""
    P = np.pad(labels, 1)
    H, W = labels.shape
    C = P[1:-1, 1:-1]
    out = set()
    for dr, dc in _FORWARD:
        B = P[1 + dr:1 + dr + H, 1 + dc:1 + dc + W]
        m = (C > 0) & (B > 0) & (C != B) & (C <= n) & (B <= n)
        out |= set(zip(np.minimum(C[m], B[m]).tolist(), np.maximum(C[m], B[m]).tolist()))
    return out


def check_whole(labels, n_rooms, doors, G=None):
    """Every two touching rooms joined by a door, every door between touching rooms, and (with the
    room graph ``G``) as many graph components as 8-connected components of the rooms' cells."""
    touching = touching_pairs(labels, n_rooms)
    joined = {tuple(sorted(d.rooms)) for d in doors}
    assert not touching - joined, f"rooms touching without a door: {sorted(touching - joined)[:10]}"
    assert not joined - touching, f"doors between rooms that do not touch: {sorted(joined - touching)[:10]}"
    if G is not None:
        _, n_cover = ndi.label((labels > 0) & (labels <= n_rooms), structure=np.ones((3, 3), bool))
        assert nx.number_connected_components(G) == n_cover


# --------------------------------------------------------------------------
# hand-drawn cuts
# --------------------------------------------------------------------------

def _thick_wall_doorway():
    """A corridor (rows 5-24) and a room (rows 37-76) with a 12-cell (0.6 m) wall between them and
    a 16-cell (0.8 m) doorway through it at columns 40-55."""
    a = np.zeros((82, 100), bool)
    a[5:25, 5:95] = True
    a[37:77, 5:95] = True
    a[25:37, 40:56] = True
    return a


def test_two_cuts_across_a_thick_wall_make_one_door():
    a = _thick_wall_doorway()
    grid = from_array(a, resolution=T.RES)
    # a cut across each face of the doorway: the sliver between them is too small to be a room
    segs = [((25, 39), (25, 56)), ((36, 39), (36, 56))]
    labels, doors, n = cut_rooms(grid, segs, min_room_cells=400)
    assert n == 2
    check_whole(labels, n, doors)
    assert len(doors) == 1
    d = doors[0]
    assert d.rooms == (1, 2)
    # the door lies where the two rooms meet, inside the doorway, as wide as the doorway (16 cells)
    assert d.width == pytest.approx(16 * T.RES, abs=1.01 * T.RES)
    assert 25 <= (d.p1[0] + d.p2[0]) / 2 <= 36 and 39.5 <= (d.p1[1] + d.p2[1]) / 2 <= 55.5
    assert labels[int(round((d.p1[0] + d.p2[0]) / 2)), 47] in (1, 2)


def test_touching_rooms_get_a_door_of_the_boundary_length():
    grid = from_array(np.ones((20, 30), bool), resolution=0.1)
    labels = np.ones((20, 30), np.int32)
    labels[10:, :] = 2
    labels[10:, 20:] = 3  # room 3 touches room 1 along 10 cells and room 2 along 10 rows
    out, doors, n = join_touching_rooms(grid, labels, [], 3)
    assert out is labels and n == 3
    by = {d.rooms: d for d in doors}
    assert set(by) == {(1, 2), (1, 3), (2, 3)}
    assert by[(1, 2)].width == pytest.approx(2.0, abs=0.11)  # columns 0-19 (and the corner cell)
    assert by[(1, 3)].width == pytest.approx(1.0, abs=0.11)
    assert by[(2, 3)].width == pytest.approx(1.0, abs=1e-9)  # rows 10-19
    x, y = by[(2, 3)].midpoint
    r, c = grid.world_to_pixel(x, y)
    assert c == pytest.approx(19.5) and r == pytest.approx(14.5)
    assert [d.id for d in doors] == [0, 1, 2]


def test_rooms_touching_at_one_cell_get_a_one_cell_door_along_the_shared_edge():
    grid = from_array(np.ones((4, 4), bool), resolution=0.1)
    labels = np.array([[1, 1, 2, 2],
                       [1, 1, 2, 2],
                       [3, 3, 4, 4],
                       [3, 3, 4, 4]], np.int32)
    labels[1, 1], labels[2, 2] = 1, 4  # room 1 and room 4 touch at a corner only
    _, doors, _ = join_touching_rooms(grid, labels, [], 4)
    by = {d.rooms: d for d in doors}
    assert set(by) == {(1, 2), (1, 3), (2, 4), (3, 4), (1, 4), (2, 3)}
    check_whole(labels, 4, doors)
    # rooms 1 and 2 meet along column edge 1.5 | 2, rows 0-1: a door two cells long across it
    assert by[(1, 2)].width == pytest.approx(0.2, abs=1e-9)
    # the corner contacts (1, 4) and (2, 3) are one cell wide
    assert by[(1, 4)].width == pytest.approx(0.1, abs=1e-9)
    assert by[(2, 3)].width == pytest.approx(0.1, abs=1e-9)


def test_a_map_of_single_cell_rooms_wider_than_a_door_is_one_room():
    # a checkerboard read at 10 m per cell: every free cell is a room of its own, touching its neighbours
    # at a corner, one cell (10 m) wide: wider than any door, so all of them are one room
    a = (np.indices((30, 30)).sum(0) % 2).astype(bool)
    grid = from_array(a, resolution=10.0)
    labels = np.zeros(a.shape, np.int32)
    labels[a] = np.arange(1, int(a.sum()) + 1)
    out, doors, n = join_touching_rooms(grid, labels, [], int(a.sum()), max_door_width=3.0)
    assert n == 1 and doors == []
    assert (out[a] == 1).all()


def test_boundary_wider_than_any_door_merges():
    grid = from_array(np.ones((20, 80), bool), resolution=0.05)
    labels = np.ones((20, 80), np.int32)
    labels[10:, :] = 2  # 80 cells = 4 m: wider than a 3 m door
    labels[:, 70:] = 3  # room 3 joined to room 1 by a door, touching room 2 along 0.5 m
    labels[0, 0] = 4  # a fragment after the rooms (n_rooms = 3)
    from topomap.core.doors import Door

    door = Door(id=0, p1=(5, 69.5), p2=(5, 70.5), width=0.05, rooms=(1, 3))
    out, doors, n = join_touching_rooms(grid, labels, [door], 3, max_door_width=3.0)
    assert n == 2
    assert out[0, 0] == 3  # the fragment stays after the rooms
    assert (out[1:, :70] == 1).all() and (out[:, 70:] == 2).all()
    assert [d.rooms for d in doors] == [(1, 2)]  # the given door, renamed; no door across the merged cut
    check_whole(out, n, doors)
    # without a widest door the two get a door instead
    out2, doors2, n2 = join_touching_rooms(grid, labels, [door], 3)
    assert out2 is labels and n2 == 3
    assert sorted(d.rooms for d in doors2) == [(1, 2), (1, 3), (2, 3)]


def test_cut_end_on_a_wall_does_not_reach_across_it():
    """A cut whose end is a wall cell is not carried on through the wall into the room behind it
    (it made a door between rooms that do not touch)."""
    a = np.zeros((40, 60), bool)
    a[5:35, 5:29] = True  # room A
    a[5:35, 30:55] = True  # room B, a 1-cell wall between them (column 29)
    grid = from_array(a, resolution=T.RES)
    # a cut into room B from the thin wall, ending inside B: it cuts nothing apart
    labels, doors, n = cut_rooms(grid, [((20, 29), (20, 45))])
    assert n == 2
    check_whole(labels, n, doors)
    assert doors == []


# --------------------------------------------------------------------------
# fuzzed maps, every method
# --------------------------------------------------------------------------

def fuzz_map(rng):
    """Free rectangles, walls of random lines with gaps, and salt noise: rooms that touch in odd
    ways (corners, thin gaps, single cells)."""
    H, W = int(rng.integers(40, 90)), int(rng.integers(40, 90))
    a = np.zeros((H, W), bool)
    for _ in range(int(rng.integers(2, 7))):
        r0, c0 = int(rng.integers(0, H - 8)), int(rng.integers(0, W - 8))
        a[r0:r0 + int(rng.integers(8, 40)), c0:c0 + int(rng.integers(8, 40))] = True
    for _ in range(int(rng.integers(0, 6))):
        if rng.random() < 0.5:
            r = int(rng.integers(0, H))
            a[r:r + int(rng.integers(1, 4)), :] = False
        else:
            c = int(rng.integers(0, W))
            a[:, c:c + int(rng.integers(1, 4))] = False
        for _ in range(int(rng.integers(0, 3))):  # gaps in it
            r0, c0 = int(rng.integers(0, H)), int(rng.integers(0, W))
            a[r0:r0 + int(rng.integers(1, 20)), c0:c0 + int(rng.integers(1, 20))] = True
    noise = rng.random((H, W)) < rng.uniform(0, 0.04)
    return a ^ noise


fuzzed = st.integers(0, 2 ** 32 - 1).map(lambda s: fuzz_map(np.random.default_rng(s)))


@pytest.mark.parametrize("method", ["topomap", "paper"])  # the baselines keep their own doors only
@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(a=fuzzed)
def test_fuzzed_maps_whole_graph(method, a):
    seg = segment(from_array(a, resolution=T.RES), method=method)
    check_whole(seg.labels, seg.n_rooms, seg.doors, seg.room_graph)


@pytest.mark.parametrize("make", [T.two_rooms, T.corridor_with_rooms, T.room_with_desks,
                                  T.noisy_corridor_with_pillars, T.specks_outside_building])
def test_hand_drawn_maps_whole_graph(make):
    m = make()
    seg = segment(from_array(m.array, resolution=m.resolution))
    check_whole(seg.labels, seg.n_rooms, seg.doors, seg.room_graph)


# --------------------------------------------------------------------------
# benchmark and real maps (a sample; skipped when absent)
# --------------------------------------------------------------------------

def _real_nogt():
    env = os.environ.get("TOPOMAP_REAL_MAPS_DIR")
    if env and (Path(env).parent / "real_nogt").is_dir():
        return Path(env).parent / "real_nogt"
    return _shared_dataset("real_nogt")


def _maps():
    out = []
    nogt = _real_nogt()
    for name in ("willow_full/willow-full-0.05.yaml", "willow/willow-2010-02-18-0.10.yaml",
                 "nav2/depot.yaml", "bookstore/map.yaml", "small_house/map.yaml"):
        out.append(pytest.param(nogt / name if nogt else None, id=f"real_nogt/{name.split('/')[0]}"))
    rose = real_maps_dir()
    for name in ("bremen_cartesium_full", "bremen_cartesium_partial_13", "freiburg079_full",
                 "freiburg079_partial_02", "freiburg079_partial_07"):
        out.append(pytest.param(rose / f"{name}.yaml" if rose else None, id=f"rose2_real/{name}"))
    ipa = benchmark_dir()
    for name in ("office_i.png", "office_e_furnitures.png", "Freiburg52_scan.png"):
        out.append(pytest.param(ipa / name if ipa else None, id=f"ipa/{name}"))
    return out


@pytest.mark.parametrize("path", _maps())
def test_benchmark_maps_whole_graph(path):
    if path is None or not Path(path).exists():
        pytest.skip("map not available")
    grid = load_map(path, resolution=0.05) if Path(path).suffix == ".png" else load_map(path)
    seg = segment(grid)
    check_whole(seg.labels, seg.n_rooms, seg.doors, seg.room_graph)


# --------------------------------------------------------------------------
# JPEG maps: compression noise in walls and floor
# --------------------------------------------------------------------------

@pytest.mark.parametrize("quality", [75, 30])
@pytest.mark.parametrize("make", [T.corridor_with_rooms, T.noisy_corridor_with_pillars, T.room_with_desks])
def test_jpeg_map_every_free_cell_in_a_room_or_fragment(tmp_path, make, quality):
    """A map saved as JPEG (ringing round every wall, specks of free gray in them) and read back as a
    bare image: every free cell in exactly one room or fragment, only free cells labelled."""
    import cv2

    m = make()
    a = m.array
    gray = np.where(a, 254, 0).astype(np.uint8) if a.dtype == bool else a
    path = tmp_path / "map.jpg"
    cv2.imwrite(str(path), gray, [cv2.IMWRITE_JPEG_QUALITY, quality])
    grid = load_map(path, resolution=m.resolution)
    assert (grid.free != (gray >= 250)).any()  # the compression moved cells in or out of free space
    seg = segment(grid)
    free = grid.free
    assert ((seg.labels > 0) == free).all()
    top = int(seg.labels.max())
    assert np.array_equal(np.unique(seg.labels[free]), np.arange(1, top + 1))
    check_whole(seg.labels, seg.n_rooms, seg.doors, seg.room_graph)
