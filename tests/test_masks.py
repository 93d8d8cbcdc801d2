"""Mask helpers of the default method against their plain definitions.

``clutter_mask`` measures a bulky piece's thickness on the piece's own box
(grown by one cell); it must equal the definition on the whole map: the
largest value of the distance transform of the obstacles over the piece.
"""

import cv2
import numpy as np
import pytest
from scipy import ndimage as ndi

from topomap.segmentation import clutter_mask


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
