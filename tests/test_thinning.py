"""skeleton._thin is scikit-image's Zhang thinning, pixel for pixel.

The free-space skeleton of large maps is thinned by ``_thin`` (it visits only
the pixels whose neighbourhood changed); it must equal
``skimage.morphology.skeletonize`` on any mask: random masks of every
density (each of the 256 neighbourhoods occurs), blocks with holes, masks
touching the image edge, and through ``skeletonize`` on a large mask.
"""

import numpy as np
import pytest
from scipy import ndimage as ndi
from skimage.morphology import skeletonize as sk

from topomap.core.skeleton import _THIN_SPARSE_CELLS, _thin, skeletonize


@pytest.mark.parametrize("seed", range(8))
def test_thin_is_skimage(seed):
    rng = np.random.default_rng(seed)
    for _ in range(25):
        h, w = (int(v) for v in rng.integers(3, 70, 2))
        m = rng.random((h, w)) < rng.uniform(0.2, 0.97)
        if rng.random() < 0.5:
            m = ndi.binary_closing(m, iterations=int(rng.integers(1, 4)))
        np.testing.assert_array_equal(_thin(m), sk(m))


def test_skeletonize_large_wide_mask():
    rng = np.random.default_rng(11)
    side = int(np.sqrt(_THIN_SPARSE_CELLS)) + 40
    m = np.zeros((side, side), bool)
    for _ in range(40):  # wide rooms joined into a free space
        r, c = rng.integers(0, side - 60, 2)
        m[r:r + rng.integers(20, 120), c:c + rng.integers(20, 120)] = True
    m[rng.random(m.shape) < 0.01] = False  # specks of furniture
    assert m.mean() > 0.15
    np.testing.assert_array_equal(skeletonize(m), sk(m))
