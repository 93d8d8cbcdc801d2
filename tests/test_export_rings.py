"""The batch ring encoder of write_outputs writes what the one-ring encoder writes."""

import numpy as np

from topomap.export import _ring_json, _rings_json


def test_rings_json_is_ring_json():
    rng = np.random.default_rng(5)
    rings = []
    for _ in range(40):  # lattice corners (few distinct values), as room outlines have, and odd values
        m = int(rng.integers(0, 30))
        ring = np.round(rng.integers(-50, 50, size=(m, 2)) * 0.05 + 3.1, 12)
        if m and rng.random() < 0.3:
            ring[0, 0] = rng.choice([-0.0, 0.0, 1e-300, 1e22, np.nan, np.inf, -np.inf])
        rings.append(ring)
    rings.append(np.array([[-0.0, 0.0], [0.0, -0.0]]))
    rings.append([(1.0, 2.0), (3.5, 4.25)])  # plain tuples, as shapely coordinates list them
    got = _rings_json(rings)
    assert got == [_ring_json(r) for r in rings]
    assert got[-2] == "[[-0.0, 0.0], [0.0, -0.0]]"
    assert _rings_json([]) == []
