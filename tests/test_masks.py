"""Mask helpers of the default method against their plain definitions.

``clutter_mask`` measures a bulky piece's thickness on the piece's own box
(grown by one cell); it must equal the definition on the whole map: the
largest value of the distance transform of the obstacles over the piece.
"""

import cv2
import numpy as np
import pytest
from scipy import ndimage as ndi

from topomap.core.masks import clutter_mask


def _reference(free, max_extent_px, furniture_px, wall_thickness_px):
    n, comp, stats, _ = cv2.connectedComponentsWithStats((~free).astype(np.uint8), connectivity=8)
    extent = np.maximum(stats[:, cv2.CC_STAT_WIDTH], stats[:, cv2.CC_STAT_HEIGHT])
    small = extent < max_extent_px
    bulky = (extent < furniture_px) & ~small
    bulky[0] = False
    inside = cv2.distanceTransform((~free).astype(np.uint8), cv2.DIST_L2, 3)
    radius = np.asarray(ndi.maximum(inside, comp, index=np.arange(n)))
    small |= bulky & (2 * radius >= wall_thickness_px)
    small[0] = False
    return small[comp]


@pytest.mark.parametrize("seed", range(6))
def test_clutter_mask_is_its_definition(seed):
    rng = np.random.default_rng(seed)
    free = np.ones((150, 170), bool)
    for _ in range(60):  # blocks of every size and thickness, some touching each other or the border
        r, c = rng.integers(-5, 150), rng.integers(-5, 170)
        free[max(r, 0):r + rng.integers(1, 30), max(c, 0):c + rng.integers(1, 30)] = False
    free[rng.random(free.shape) < 0.01] = False  # specks
    for furniture_px, wall_px in ((25, 4), (40, 9), (0, np.inf), (200, 1)):
        got = clutter_mask(free, 8, furniture_px=furniture_px, wall_thickness_px=wall_px)
        want = _reference(free, 8, furniture_px, wall_px)
        assert got.dtype == want.dtype == bool
        np.testing.assert_array_equal(got, want)
        assert got[free].sum() == 0


@pytest.mark.parametrize("seed", range(4))
def test_clutter_mask_keep_and_shared_parts(seed):
    # with keep: the clutter components touching a kept cell are none; the parts made once
    # (the furniture stage asks with and without keep) give the same masks
    from topomap.core.masks import clutter_parts

    rng = np.random.default_rng(seed)
    free = np.ones((150, 170), bool)
    for _ in range(60):
        r, c = rng.integers(-5, 150), rng.integers(-5, 170)
        free[max(r, 0):r + rng.integers(1, 30), max(c, 0):c + rng.integers(1, 30)] = False
    keep = np.zeros(free.shape, bool)
    keep[rng.integers(0, 150, 40), rng.integers(0, 170, 40)] = True
    every = _reference(free, 8, 40, 9)
    n, comp = cv2.connectedComponents((~free).astype(np.uint8), connectivity=8)
    touched = np.zeros(n, bool)
    touched[comp[keep]] = True
    touched[0] = False
    want = every & ~touched[comp]
    assert (every & touched[comp]).any() and want.any()  # the case is not empty either way
    parts = clutter_parts(free, 8, furniture_px=40, wall_thickness_px=9)
    for p in (None, parts):
        np.testing.assert_array_equal(clutter_mask(free, 8, furniture_px=40, wall_thickness_px=9, parts=p), every)
        np.testing.assert_array_equal(clutter_mask(free, 8, furniture_px=40, wall_thickness_px=9, keep=keep,
                                                   parts=p), want)


@pytest.mark.parametrize("seed", range(4))
def test_close_by_distance_is_the_closing(seed):
    from topomap.core.geometry import disk
    from topomap.core.masks import _close_by_distance

    rng = np.random.default_rng(seed)
    free = rng.random((130, 170)) < rng.uniform(0.6, 0.97)
    free[:, :3] = seed % 2 == 0  # obstacles on the image edge, or free cells there
    for r in (2, 6, 12, 19):
        want = cv2.morphologyEx((~free).astype(np.uint8), cv2.MORPH_CLOSE, disk(r),
                                borderType=cv2.BORDER_CONSTANT, borderValue=0) > 0
        np.testing.assert_array_equal(_close_by_distance(free, r), want)
    assert not _close_by_distance(np.ones((20, 20), bool), 13).any()


@pytest.mark.parametrize("resolution", [0.05, 0.02, 0.01])
def test_free_mask_median_is_medianblur(resolution):
    # a fine map: median windows wider than 5 cells take the box-count route
    from topomap.core.geometry import disk, metres_to_px
    from topomap.io import from_array
    from topomap.options import TopomapOptions
    from topomap.core.masks import preprocess_masks

    rng = np.random.default_rng(int(resolution * 1000))
    free = ndi.binary_opening(rng.random((160, 190)) < 0.8)
    opts = TopomapOptions()
    f, _, _ = preprocess_masks(from_array(free, resolution=resolution), opts)
    er, med = metres_to_px(opts.erosion_radius, resolution), metres_to_px(opts.median_size, resolution)
    ref = free.astype(np.uint8)
    if er > 0:
        ref = cv2.erode(ref, disk(er), borderType=cv2.BORDER_CONSTANT, borderValue=0)
    k = med if med % 2 else med + 1
    np.testing.assert_array_equal(f, cv2.medianBlur(ref * 255, k) > 127)


def test_masks_without_clearance_are_the_same_masks():
    # segment_topomap computes the clearance itself (on a second thread): the masks must not change
    from topomap.io import from_array
    from topomap.options import TopomapOptions
    from topomap.core.masks import preprocess_masks

    rng = np.random.default_rng(7)
    grid = from_array(ndi.binary_opening(rng.random((120, 150)) < 0.8), resolution=0.05)
    f, d, occ = preprocess_masks(grid, TopomapOptions())
    f2, d2, occ2 = preprocess_masks(grid, TopomapOptions(), clearance=False)
    assert d2 is None and d is not None
    np.testing.assert_array_equal(f, f2)
    np.testing.assert_array_equal(occ, occ2)


def test_segmentation_clearance_is_the_distance_transform_of_its_free_space():
    # the clearance made beside the masks is the exact distance transform of the searched free space
    from topomap import load_map, segment
    from topomap.io.example import example_map_path
    from topomap._fast import edt

    grid = load_map(example_map_path())
    seg = segment(grid)
    d = seg.intermediates.clearance
    assert d.shape == seg.intermediates.free_mask.shape
    free = d > 0
    np.testing.assert_array_equal(d, edt(free))
    assert free.sum() >= 0.9 * grid.free.sum()


def test_background_call_returns_the_value_and_raises_the_error_of_its_call():
    import threading

    from topomap._fast import BackgroundCall

    seen = []
    job = BackgroundCall(lambda a, b=0: (seen.append(threading.current_thread().name), a + b)[1], 2, b=3)
    assert job.result() == 5 and job.result() == 5
    assert seen == ["topomap-beside"]
    bad = BackgroundCall(lambda: 1 / 0)
    with pytest.raises(ZeroDivisionError):
        bad.result()


def test_background_call_runs_inline_in_a_batch_worker(monkeypatch):
    # segment_many's worker processes (one per core) call one_thread(): no second thread per map
    import threading

    from topomap import _fast
    from topomap._fast import BackgroundCall, one_thread

    monkeypatch.setattr(_fast, "_BACKGROUND_THREADS", True)
    one_thread()
    seen = []
    job = BackgroundCall(lambda: seen.append(threading.current_thread().name) or 7)
    assert seen == [threading.current_thread().name]  # already done, here
    assert job.result() == 7
    with pytest.raises(ZeroDivisionError):
        BackgroundCall(lambda: 1 / 0).result()


def test_batch_workers_run_maps_on_one_thread():
    # the pool initializer of segment_many(jobs > 1) switches the second thread off in the worker
    from concurrent.futures import ProcessPoolExecutor

    from topomap.run import batch

    with ProcessPoolExecutor(1, initializer=batch._pool_init) as ex:
        assert ex.submit(_background_threads_flag).result() is False


def _background_threads_flag():
    from topomap import _fast

    return _fast._BACKGROUND_THREADS
