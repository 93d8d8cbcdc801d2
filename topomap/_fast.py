"""Fast whole-image primitives, chosen by measurement.

OpenCV's exact Euclidean distance transform is much faster than
:func:`scipy.ndimage.distance_transform_edt`, and its connected components
faster than scipy's; both give the same (exact) results, so topomap uses
OpenCV for them. A table lookup over a label image (``table[labels]``) is
faster with OpenCV's ``LUT`` (16-bit labels) than with numpy.
"""

from __future__ import annotations

import ctypes
import sys
import threading

import numpy as np

__all__ = ["BackgroundCall", "edt", "label", "label_stats", "lookup", "one_thread", "ranges"]


def _bytes(mask: np.ndarray) -> np.ndarray:
    """``mask`` as a C-contiguous uint8 image (a contiguous bool array is viewed, not copied)."""
    mask = np.asarray(mask)
    if mask.dtype == bool and mask.flags.c_contiguous:
        return mask.view(np.uint8)
    return np.ascontiguousarray(mask, dtype=np.uint8)


def edt(mask: np.ndarray, *, exact: bool = True) -> np.ndarray:
    """Euclidean distance (pixels) of each True cell to the nearest False cell.

    ``exact=False`` uses OpenCV's 5x5 chamfer approximation (relative error
    under 2 %, faster), for distances that are only compared
    with a threshold or averaged.

    Parameters
    ----------
    mask : (M, N) ndarray of bool

    Returns
    -------
    (M, N) ndarray of float32
        0 on False cells. Cells beyond the image border are *not* counted as
        False (unlike a padded transform), matching scipy's behaviour.
    """
    import cv2

    m = _bytes(mask)
    if m.all():
        # no background at all: infinite distance; report a large finite value
        return np.full(m.shape, float(max(m.shape)), np.float32)
    return cv2.distanceTransform(m, cv2.DIST_L2, cv2.DIST_MASK_PRECISE if exact else 5)


def label(mask: np.ndarray, connectivity: int = 8, *, small: bool = False):
    """Connected components of ``mask``: ``(labels int32, count)``; 0 = background. With
    ``small``, the labels are 16-bit when they fit (:func:`_small_labels`)."""
    import cv2

    n, lab = cv2.connectedComponents(_bytes(mask), connectivity=connectivity, ltype=cv2.CV_32S)
    return (_small_labels(lab, n) if small else lab), n - 1


def label_stats(mask: np.ndarray, connectivity: int = 8):
    """:func:`cv2.connectedComponentsWithStats` of ``mask``: ``(count + 1, labels, stats,
    centroids)``, the labels 16-bit when they fit (the lookups on them are faster), int32 otherwise.

    OpenCV labels in 32 bits, converted after: faster than its own 16-bit
    labelling (measured on the ipa maps).
    """
    import cv2

    n, lab, stats, cen = cv2.connectedComponentsWithStats(_bytes(mask), connectivity=connectivity, ltype=cv2.CV_32S)
    return n, _small_labels(lab, n), stats, cen


def _small_labels(lab: np.ndarray, n: int) -> np.ndarray:
    """OpenCV's int32 labels ``lab`` (``n`` labels, background included) as 16-bit labels when
    they fit (the lookups on them are faster, :func:`lookup`), as they are otherwise."""
    return lab.astype(np.uint16) if n <= 2 ** 16 else lab


def lookup(table: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """``table[labels]``: the same array, by OpenCV's table lookup when it can.

    Parameters
    ----------
    table : (K,) ndarray
        The values; OpenCV serves int32, 16- and 8-bit and float tables.
    labels : ndarray of int
        Indices into ``table``, each in ``0..K-1`` (the caller's guarantee:
        an index out of that range is not checked).

    Returns
    -------
    ndarray
        ``table[labels]`` (shape of ``labels``, dtype of ``table``).
    """
    table = np.asarray(table)
    labels = np.asarray(labels)
    if (labels.ndim != 2 or labels.dtype.kind not in "iu" or table.ndim != 1 or not 0 < table.size <= 2 ** 16
            or table.dtype not in _LUT_TYPES or labels.size < 2 ** 12):
        return table[labels]
    import cv2

    if labels.dtype == np.uint8:
        idx, size = labels, 2 ** 8
    else:
        idx, size = (labels if labels.dtype == np.uint16 else labels.astype(np.uint16)), 2 ** 16  # each < 2**16
    full = np.zeros(size, table.dtype)
    full[:min(table.size, size)] = table[:size]
    return cv2.LUT(np.ascontiguousarray(idx), full)


_LUT_TYPES = tuple(np.dtype(t) for t in (np.uint8, np.int8, np.uint16, np.int16, np.int32, np.float32, np.float64))


def ranges(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """``lo[0]..hi[0]-1, lo[1]..hi[1]-1, ...`` in one int array (``hi >= lo``): the
    concatenated :func:`numpy.arange` of every pair, without a Python loop."""
    lo, hi = np.asarray(lo), np.asarray(hi)
    n = hi - lo
    return np.arange(int(n.sum())) + np.repeat(lo - (np.cumsum(n) - n), n)


#: Whether :class:`BackgroundCall` starts a thread; see :func:`one_thread`.
_BACKGROUND_THREADS = True


def one_thread() -> None:
    """Make :class:`BackgroundCall` run its call at once, on the caller's thread, in this process.

    For the worker processes of a batch that already runs one map per core
    (``segment_many(jobs=...)``): a second thread per map would only compete
    with the other workers for the same cores.
    """
    global _BACKGROUND_THREADS
    _BACKGROUND_THREADS = False


class BackgroundCall:
    """``fn(*args, **kwargs)`` run on a thread of its own while the caller goes on; :meth:`result` waits.

    For work done in compiled code that lets go of Python's lock (OpenCV's
    distance transform and drawing, scikit-image's thinning, zlib): it then
    runs on a second core beside the caller's own work, and the result is the
    same as a plain call. An exception raised by ``fn`` is raised again by
    :meth:`result`. The thread is a daemon and holds no state of its own, so
    a caller that never asks for the result (it failed first) leaves nothing
    behind but the finished thread.
    """

    __slots__ = ("_thread", "_value", "_error")

    def __init__(self, fn, *args, **kwargs):
        self._value = self._error = self._thread = None

        def run():
            try:
                self._value = fn(*args, **kwargs)
            except BaseException as exc:  # noqa: BLE001 - handed to result()
                self._error = exc

        if not _BACKGROUND_THREADS:  # the cores are busy with other maps: the call runs here and now
            run()
            return
        self._thread = threading.Thread(target=run, name="topomap-beside", daemon=True)
        self._thread.start()

    def result(self):
        """``fn``'s return value, once it has finished (its exception raised here)."""
        if self._thread is not None:
            self._thread.join()
        if self._error is not None:
            raise self._error
        return self._value




#: glibc's ``mallopt`` parameters (``malloc.h``) set by :func:`keep_freed_memory`.
_M_TRIM_THRESHOLD, _M_TOP_PAD, _M_MMAP_THRESHOLD, _M_ARENA_MAX = -1, -2, -3, -8
#: Blocks below this many bytes come from the heap, which the process keeps (glibc's largest
#: allowed ``M_MMAP_THRESHOLD`` on 64-bit systems); larger ones are mapped and unmapped each time.
_HEAP_BLOCK = 32 << 20


def keep_freed_memory() -> bool:
    """Keep the memory a process frees for its next arrays (glibc only; a no-op elsewhere).

    For commands that run many maps in one process. By default glibc returns
    freed memory to the system (and maps every block above a threshold it
    adjusts as it goes afresh), so each map touches new pages again; on a
    virtual machine a fresh page costs far more than a reused one. After
    this call blocks of up to :data:`_HEAP_BLOCK` bytes come from the heap
    and the heap is never trimmed: on the ipa maps in one ``topomap
    segment`` the minor page faults fell to a fraction, and system time and
    the whole command with them, the peak memory unchanged. All threads share
    that one heap (glibc gives each thread an arena of its own by default,
    and the arrays a map's second thread makes and frees
    (:class:`BackgroundCall`) were not reused by the others: a large map
    peaked higher). The process keeps its peak memory until it exits.
    Not for a library: a user's Python session keeps its own allocator
    settings.

    Returns
    -------
    bool
        Whether the settings were taken.
    """
    if not sys.platform.startswith("linux"):
        return False
    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes, mallopt.restype = [ctypes.c_int, ctypes.c_int], ctypes.c_int
    ok = mallopt(_M_MMAP_THRESHOLD, _HEAP_BLOCK) == 1
    ok &= mallopt(_M_TRIM_THRESHOLD, 1 << 30) == 1
    ok &= mallopt(_M_TOP_PAD, 64 << 20) == 1
    ok &= mallopt(_M_ARENA_MAX, 1) == 1
    return bool(ok)
