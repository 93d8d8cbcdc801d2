"""The vectorised parts of topomap.skeleton give exactly what the plain ones they replaced gave.

Each fast path is compared with the straightforward computation it stands for, on random
inputs: same values, same dtype, same shape, same order.
"""

import numpy as np
import pytest

from topomap.skeleton import _unique_pixels


@pytest.mark.parametrize("dtype", [np.int64, np.int32, np.int16, np.uint8, np.uint64, np.float64])
def test_unique_pixels_is_numpy_unique_rows(dtype):
    rng = np.random.default_rng(0)
    for _ in range(200):
        lo = int(rng.integers(-100, 50)) if np.dtype(dtype).kind in "if" else 0
        P = rng.integers(lo, lo + int(rng.integers(1, 100)), (int(rng.integers(0, 300)), 2)).astype(dtype)
        if rng.random() < 0.3:
            P = P[::-1]
        want, got = np.unique(P, axis=0), _unique_pixels(P)
        assert got.dtype == want.dtype and got.shape == want.shape and np.array_equal(got, want)


def test_unique_pixels_far_apart():
    for P in (np.array([[2 ** 40, 5], [-2 ** 40, 3], [2 ** 40, -2 ** 30], [0, 2 ** 30], [0, 2 ** 30]]),
              np.array([[2 ** 62, 5], [-2 ** 62, 3]])):
        assert np.array_equal(_unique_pixels(P), np.unique(P, axis=0))
