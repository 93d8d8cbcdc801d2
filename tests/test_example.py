"""The shipped example office map matches its generator and its ground truth."""

import numpy as np
import pytest
import yaml
from scipy import ndimage as ndi

from topomap.io import example as _example
from topomap.io import FREE, OCCUPIED, UNKNOWN, load_map


@pytest.fixture(scope="module")
def ex():
    return _example.make_example_office()


def test_files_on_disk_match_generator():
    path = _example.example_map_path()
    assert path.name == "example_office.yaml" and path.is_file()
    for fname, data in _example.example_file_bytes().items():
        assert (path.parent / fname).read_bytes() == data, f"{fname} is stale: run python -m topomap.io.example"


def test_write_example_files(tmp_path):
    out = _example.write_example_files(tmp_path)
    assert out.read_bytes() == _example.example_map_path().read_bytes()
    assert (tmp_path / "example_office.pgm").read_bytes() == \
        (_example.example_map_path().parent / "example_office.pgm").read_bytes()


def test_deterministic(ex):
    again = _example.make_example_office()
    np.testing.assert_array_equal(ex.gray, again.gray)
    np.testing.assert_array_equal(ex.rooms, again.rooms)
    assert ex.doors == again.doors and ex.yaml == again.yaml


def test_tuple_unpacking(ex):
    gray, meta = _example.make_example_office()
    np.testing.assert_array_equal(gray, ex.gray)
    assert meta == ex.yaml


def test_yaml_metadata(ex):
    meta = yaml.safe_load(_example.example_map_path().read_text())
    assert meta == ex.yaml
    assert meta == {"image": "example_office.pgm", "resolution": 0.05, "origin": [-10.0, -7.0, 0.0],
                    "negate": 0, "occupied_thresh": 0.65, "free_thresh": 0.196}


def test_loads(ex):
    g = load_map(_example.example_map_path())
    assert g.shape == (280, 400)
    assert g.resolution == 0.05 and g.origin == (-10.0, -7.0, 0.0)
    np.testing.assert_array_equal(g.gray, ex.gray)
    assert set(np.unique(ex.gray)) == {0, 205, 254}
    assert g.free.sum() > 0.6 * g.cells.size
    # world extent ~ 20 m x 14 m
    x0, y0 = g.pixel_to_world(279, 0)
    x1, y1 = g.pixel_to_world(0, 399)
    assert x1 - x0 == pytest.approx(19.95) and y1 - y0 == pytest.approx(13.95)


def test_outside_unknown_and_building_closed(ex):
    g = load_map(_example.example_map_path())
    assert (g.cells[0, :] == UNKNOWN).all() and (g.cells[:, 0] == UNKNOWN).all()
    # free space is one connected component (every room reachable) that never touches unknown
    lab, n = ndi.label(g.free)
    assert n == 1
    assert not (ndi.binary_dilation(g.free) & g.unknown).any()


def test_rooms_ground_truth(ex):
    g = load_map(_example.example_map_path())
    labels = np.unique(ex.rooms)
    assert list(labels) == list(range(9))
    assert set(_example.ROOM_NAMES) == set(range(1, 9))
    assert ex.rooms.dtype == np.int32 and ex.rooms.shape == ex.gray.shape
    # only free cells are labelled; every room is one 4-connected component
    assert (g.free[ex.rooms > 0]).all()
    for k in range(1, 9):
        _, n = ndi.label(ex.rooms == k)
        assert n == 1, k
    # rooms touch only through door gaps: walls separate different labels
    unlabelled_free = g.free & (ex.rooms == 0)
    door_px = np.zeros_like(unlabelled_free)
    for (r0, c0), (r1, c1) in ex.doors:
        door_px[min(r0, r1):max(r0, r1) + 1, min(c0, c1):max(c0, c1) + 1] = True
    # every unlabelled free pixel is part of a door gap (same row/column strip as a door segment)
    gaps, _ = ndi.label(unlabelled_free)
    assert set(np.unique(gaps[door_px])) - {0} == set(np.unique(gaps)) - {0}


def test_l_shaped_room(ex):
    room = ex.rooms == 6
    area = room.sum()
    rows, cols = np.nonzero(room)
    bbox = (np.ptp(rows) + 1) * (np.ptp(cols) + 1)
    assert 0.5 * bbox < area < 0.9 * bbox  # clearly not a rectangle


def test_doors(ex):
    g = load_map(_example.example_map_path())
    assert len(ex.doors) == len(ex.door_rooms) == len(ex.door_widths) >= 7
    assert all(0.7 <= w <= 1.2 for w in ex.door_widths if w < 1.5)
    assert any(w == pytest.approx(1.6) for w in ex.door_widths)
    assert len({round(w, 2) for w in ex.door_widths}) >= 4
    for ((r0, c0), (r1, c1)), (a, b), w in zip(ex.doors, ex.door_rooms, ex.door_widths):
        assert r0 == r1 or c0 == c1
        assert max(r1 - r0, c1 - c0) + 1 == round(w / 0.05)
        seg = g.cells[r0:r1 + 1, c0:c1 + 1]
        assert (seg == FREE).all()
        # door jambs are walls
        if r0 == r1:
            assert g.cells[r0, c0 - 1] == OCCUPIED and g.cells[r0, c1 + 1] == OCCUPIED
            near = {ex.rooms[r0 - 3, c0 + 2], ex.rooms[r0 + 3, c0 + 2]}
        else:
            assert g.cells[r0 - 1, c0] == OCCUPIED and g.cells[r1 + 1, c0] == OCCUPIED
            near = {ex.rooms[r0 + 2, c0 - 3], ex.rooms[r0 + 2, c0 + 3]}
        assert near == {a, b}


def test_walls_and_furniture(ex):
    occ = ex.gray == 0
    # wall thicknesses 0.2 m (inner), 0.25 m (outer), 0.15 m (closet)
    assert occ[116:120, 100].all() and not occ[115, 100] and not occ[120, 100]   # 0.2 m
    assert occ[10:15, 200].all() and not occ[15, 200]                            # 0.25 m
    assert occ[200, 323:326].all() and not occ[200, 322] and not occ[200, 326]   # 0.15 m
    # furniture: occupied blobs not touching the outer hull, sizes 0.3-1 m
    blobs, n = ndi.label(occ)
    sizes = []
    for sl in ndi.find_objects(blobs):
        h, w = sl[0].stop - sl[0].start, sl[1].stop - sl[1].start
        if max(h, w) < 30:
            sizes.append((h, w))
    assert len(sizes) >= 3  # free-standing: table, chair, plant, desk
    assert all(6 <= max(s) <= 20 for s in sizes)
