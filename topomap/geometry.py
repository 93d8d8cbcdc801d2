"""Small geometry helpers on pixel grids, shared by every module.

One copy of each: distances from points to segments, the cells of a door
line, disk-shaped kernels, the bounding box of the true cells of a mask and
the conversion of metres to whole pixels. Coordinates are pixel
``(row, col)`` unless said otherwise; nothing here validates user input
(options are checked in :mod:`topomap.options`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["point_segment_distances", "line_pixels", "disk", "true_bbox", "metres_to_px"]


def point_segment_distances(p, a, b) -> np.ndarray:
    """Euclidean distance from points to closed segments, broadcast.

    Parameters
    ----------
    p : (..., 2) array_like of float
        Points.
    a, b : (..., 2) array_like of float
        Segment end points (same units as ``p``; ``a == b`` allowed, the
        distance is then to the point ``a``). ``p``, ``a`` and ``b``
        broadcast against each other: one point against many segments, many
        points against one segment, or pairwise.

    Returns
    -------
    ndarray of float
        The broadcast shape without the last axis.
    """
    p = np.asarray(p, float)
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    ab = b - a
    den = (ab * ab).sum(-1)
    nz = den > 0
    t = np.where(nz, ((p - a) * ab).sum(-1) / np.where(nz, den, 1), 0.0)
    t = np.clip(t, 0, 1)
    proj = a + t[..., None] * ab
    d = p - proj
    return np.hypot(d[..., 0], d[..., 1])


def line_pixels(p, q, shape):
    """Cells of the digital line from ``p`` to ``q`` (pixel ``(row, col)``).

    The end points are rounded to the nearest cell and clipped to an image
    of ``shape``; the line is :func:`skimage.draw.line` (8-connected).

    Returns
    -------
    rows, cols : ndarray of int
    """
    from skimage.draw import line

    H, W = shape[:2]
    r0, c0 = np.clip(np.rint(p), 0, [H - 1, W - 1]).astype(int)
    r1, c1 = np.clip(np.rint(q), 0, [H - 1, W - 1]).astype(int)
    return line(r0, c0, r1, c1)


def disk(r: int, dtype=np.uint8) -> np.ndarray:
    """``(2r+1, 2r+1)`` kernel, 1 on the cells within ``r`` of the centre."""
    y, x = np.ogrid[-r:r + 1, -r:r + 1]
    return (x * x + y * y <= r * r).astype(dtype)


def true_bbox(mask: np.ndarray, pad: int = 0):
    """Bounding box ``(r0, r1, c0, c1)`` (end exclusive) of the true cells.

    Grown by ``pad`` cells on every side and clipped to the array; None when
    no cell is true.
    """
    mask = np.asarray(mask)
    rows = np.flatnonzero(mask.any(axis=1))
    if rows.size == 0:
        return None
    cols = np.flatnonzero(mask.any(axis=0))
    H, W = mask.shape
    return (max(int(rows[0]) - pad, 0), min(int(rows[-1]) + pad + 1, H),
            max(int(cols[0]) - pad, 0), min(int(cols[-1]) + pad + 1, W))


def metres_to_px(metres: float, resolution: float, minimum: int = 0) -> int:
    """A length in metres as a whole number of cells, at least ``minimum``."""
    return max(int(round(float(metres) / resolution)), minimum)
