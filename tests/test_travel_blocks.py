"""The coarse travel grid's pieces: per block, the 8-connected pieces of the room's cells.

``planning._block_components`` labels sparse windows block by block in a
strip and dense ones all at once; both must give each block's pieces with
their centroids (the mean of their cells, as OpenCV computes it on the image
of blocks one empty cell apart: sum / area there, moved back).
"""

import numpy as np
import pytest
from scipy import ndimage as ndi

from topomap.planning import _block_any, _block_components


def _reference(mask, f):
    """{frozenset of (row, col) cells: centroid} of every piece."""
    out = {}
    h, w = mask.shape
    for r0 in range(0, h, f):
        for c0 in range(0, w, f):
            lab, n = ndi.label(mask[r0:r0 + f, c0:c0 + f], structure=np.ones((3, 3)))
            for i in range(1, n + 1):
                rr, cc = np.nonzero(lab == i)
                R, C = r0 // f, c0 // f
                # the spaced image's coordinates, their mean, one gap cell per block taken out
                cen = np.array([(R * (f + 1) + rr).sum() / rr.size, (C * (f + 1) + cc).sum() / cc.size])
                out[frozenset(zip((rr + r0).tolist(), (cc + c0).tolist()))] = cen - np.floor(cen / (f + 1))
    return out


@pytest.mark.parametrize("density", [0.03, 0.3, 0.9])
@pytest.mark.parametrize("f", [1, 3, 4])
def test_block_components(density, f):
    rng = np.random.default_rng(int(density * 100) + f)
    for _ in range(5):
        h, w = (int(v) for v in rng.integers(5, 60, 2))
        mask = rng.random((h, w)) < density
        lab, n, cen = _block_components(mask, f)
        got = {}
        for i in range(1, n + 1):
            rr, cc = np.nonzero(lab == i)
            got[frozenset(zip(rr.tolist(), cc.tolist()))] = cen[i]
        want = _reference(mask, f)
        assert got.keys() == want.keys()
        for k in want:
            np.testing.assert_array_equal(got[k], want[k])


@pytest.mark.parametrize("f", [1, 2, 3, 4, 5, 8])
def test_block_any(f):
    rng = np.random.default_rng(f)
    m = rng.random((7 * f, 11 * f)) < 0.02
    np.testing.assert_array_equal(_block_any(m, f), m.reshape(7, f, 11, f).any(axis=(1, 3)))
