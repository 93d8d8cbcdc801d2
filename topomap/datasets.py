"""Loading room-segmentation benchmarks and labelled map pairs.

The benchmark is the one of Bormann et al. (ICRA 2016), from the
``ipa_room_segmentation`` package: per map ``NAME``, ``NAME.png`` (map
without furniture), ``NAME_furnitures.png`` (with furniture) and
``NAME_gt_segmentation.png`` (ground truth drawing: room space white, rooms
separated by black lines across doorways). Resolution 0.05 m per pixel.

The data set's licence forbids redistributing it, so topomap never ships
it: code reads it from a directory given at run time (see
:func:`benchmark_dir`).

All images are read as 8-bit gray with Pillow's ``convert("L")`` whatever
their mode (L, LA, RGB, RGBA, P; alpha is dropped), as the original
evaluation does.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Optional

import numpy as np

from .errors import MapError, MapFileError, ParameterError

__all__ = [
    "BENCHMARK_RESOLUTION",
    "BenchmarkNotFoundError",
    "BenchmarkMap",
    "LabeledMap",
    "read_gray",
    "read_label_image",
    "load_benchmark",
    "load_pairs",
    "benchmark_dir",
]

#: Metres per pixel of every benchmark map.
BENCHMARK_RESOLUTION = 0.05

_GT_SUFFIX = "_gt_segmentation.png"
_FURN_SUFFIX = "_furnitures.png"
_VARIANTS = ("unfurnished", "furnished")


class BenchmarkNotFoundError(MapFileError, FileNotFoundError):
    """No benchmark maps in a directory (or the directory does not exist)."""


@dataclass(frozen=True, eq=False)
class BenchmarkMap:
    """One benchmark map with its ground truth.

    Parameters
    ----------
    name : str
        Map name (``NAME`` of the files).
    variant : str
        ``"unfurnished"`` or ``"furnished"``.
    map_path, gt_path : Path
        The map image read and the ground-truth drawing.
    map_gray, gt_gray : (M, N) ndarray of uint8
        Both images as 8-bit gray.
    resolution : float
        Metres per pixel (0.05 for the benchmark).
    unfurnished_gray : (M, N) ndarray of uint8, optional
        The map without furniture (``NAME.png``), the same array as
        ``map_gray`` for the unfurnished variant. Extract true doors from it
        in both variants (furniture next to a door line would otherwise
        merge into the door's cell group). Defaults to ``map_gray``.
    """

    name: str
    variant: str
    map_path: Path
    gt_path: Path
    map_gray: np.ndarray = field(repr=False)
    gt_gray: np.ndarray = field(repr=False)
    resolution: float = BENCHMARK_RESOLUTION
    unfurnished_gray: Optional[np.ndarray] = field(default=None, repr=False)

    def __post_init__(self):
        if self.unfurnished_gray is None:
            object.__setattr__(self, "unfurnished_gray", self.map_gray)

    @property
    def scored(self) -> np.ndarray:
        """Cells the metric scores: ``map_gray >= 250`` (bool array)."""
        return self.map_gray >= 250


@dataclass(frozen=True, eq=False)
class LabeledMap:
    """A map image with an integer room-label image.

    Parameters
    ----------
    name : str
        The map file's stem.
    map_path, label_path : Path
    map_gray : (M, N) ndarray of uint8
        The map as 8-bit gray.
    labels : (M, N) ndarray of int32
        Room labels, 0 = no room.
    """

    name: str
    map_path: Path
    label_path: Path
    map_gray: np.ndarray = field(repr=False)
    labels: np.ndarray = field(repr=False)


def _open(path: Path):
    from PIL import Image, UnidentifiedImageError

    if not path.exists():
        raise MapFileError(f"{path}: file does not exist")
    if path.is_dir():
        raise MapFileError(f"{path}: is a directory, not an image")
    try:
        img = Image.open(path)
        img.load()
    except UnidentifiedImageError as exc:
        raise MapError(f"{path}: not a readable image ({exc})") from None
    except OSError as exc:
        raise MapFileError(f"{path}: cannot be read ({exc})") from None
    return img


def read_gray(path) -> np.ndarray:
    """Read an image of any Pillow mode as an (M, N) uint8 gray array (``convert("L")``)."""
    path = Path(path)
    img = _open(path)
    if img.mode in ("I;16", "I;16B", "I;16L", "I"):
        arr = np.asarray(img)
        return np.clip(arr, 0, 255).astype(np.uint8)
    return np.asarray(img.convert("L"), dtype=np.uint8).copy()


def read_label_image(path) -> np.ndarray:
    """Read an integer room-label image.

    Parameters
    ----------
    path : str or Path
        A PNG (or other Pillow-readable image). Gray images (8-bit ``L``,
        16-bit ``I;16``, 32-bit ``I``) and palette images (``P``, the palette
        index is the label) give their values directly; ``LA`` uses the gray
        channel; colour images (``RGB``/``RGBA``) get one label per distinct
        colour, numbered 1.. in order of the packed colour value, with black
        (and fully transparent pixels) as 0.

    Returns
    -------
    (M, N) ndarray of int32
        0 = no room.
    """
    path = Path(path)
    img = _open(path)
    mode = img.mode
    if mode in ("L", "P", "I", "I;16", "I;16B", "I;16L", "1"):
        return np.asarray(img).astype(np.int32)
    if mode == "LA":
        return np.asarray(img)[..., 0].astype(np.int32)
    if mode in ("RGB", "RGBA"):
        arr = np.asarray(img)
        rgb = arr[..., :3].astype(np.int64)
        key = (rgb[..., 0] << 16) | (rgb[..., 1] << 8) | rgb[..., 2]
        if mode == "RGBA":
            key = np.where(arr[..., 3] == 0, 0, key)
        uniq, inv = np.unique(key, return_inverse=True)
        ids = np.arange(uniq.size, dtype=np.int32) + (0 if uniq[0] == 0 else 1)
        return ids[inv.reshape(key.shape)]
    raise MapError(f"{path}: unsupported image mode {mode!r} for a label image")


def load_benchmark(directory, *, variant: str = "unfurnished",
                   names: Optional[Iterable[str]] = None) -> list:
    """Load the benchmark maps of a directory.

    Parameters
    ----------
    directory : str or Path
        Folder with ``NAME.png``, ``NAME_furnitures.png`` and
        ``NAME_gt_segmentation.png`` files. Maps are discovered from their
        ground-truth files; other files (e.g. ``*.pgm``) are ignored.
    variant : {"unfurnished", "furnished"}
        Which map image to read: ``NAME.png`` or ``NAME_furnitures.png``.
    names : iterable of str, optional
        Load only these maps.

    Returns
    -------
    list of BenchmarkMap
        Sorted by name.

    Raises
    ------
    BenchmarkNotFoundError
        The directory does not exist or holds no ground-truth file (a
        ``FileNotFoundError`` and :class:`~topomap.errors.MapFileError`).
    MapFileError
        A ground-truth file has no map image for ``variant``.
    MapError
        A map and its ground truth differ in size.
    ParameterError
        ``variant`` is not one of the two variants.
    """
    if variant not in _VARIANTS:
        raise ParameterError(
            f"<array>: variant must be 'unfurnished' or 'furnished', got {variant!r}")
    directory = Path(directory)
    if not directory.is_dir():
        raise BenchmarkNotFoundError(f"{directory}: benchmark directory does not exist")
    gts = sorted(directory.glob("*" + _GT_SUFFIX))
    wanted = None if names is None else set(names)
    maps = []
    for gt_path in gts:
        name = gt_path.name[: -len(_GT_SUFFIX)]
        if not name or (wanted is not None and name not in wanted):
            continue
        suffix = ".png" if variant == "unfurnished" else _FURN_SUFFIX
        map_path = directory / (name + suffix)
        if not map_path.is_file():
            raise MapFileError(f"{map_path}: missing {variant} map for ground truth {gt_path.name}")
        map_gray = read_gray(map_path)
        gt_gray = read_gray(gt_path)
        if map_gray.shape != gt_gray.shape:
            raise MapError(f"{gt_path}: ground truth shape {gt_gray.shape} differs from map "
                           f"{map_path.name} shape {map_gray.shape}")
        if variant == "unfurnished":
            base = map_gray
        else:
            base_path = directory / (name + ".png")
            base = read_gray(base_path) if base_path.is_file() else None
            if base is not None and base.shape != map_gray.shape:
                raise MapError(f"{base_path}: shape {base.shape} differs from "
                               f"{map_path.name} shape {map_gray.shape}")
        maps.append(BenchmarkMap(name, variant, map_path, gt_path, map_gray, gt_gray,
                                 unfurnished_gray=base))
    if not maps:
        what = "no *_gt_segmentation.png files" if wanted is None else \
            f"none of the maps {sorted(wanted)}"
        raise BenchmarkNotFoundError(f"{directory}: {what} found")
    maps.sort(key=lambda m: m.name)
    return maps


def load_pairs(pairs) -> list:
    """Load (map image, integer label image) pairs.

    Parameters
    ----------
    pairs : iterable of (path, path)
        Map image (read as 8-bit gray) and room-label image (read with
        :func:`read_label_image`: 8- or 16-bit gray values are the labels,
        0 = no room).

    Returns
    -------
    list of LabeledMap
        In the order given.

    Raises
    ------
    MapFileError
        A file is missing or unreadable.
    MapError
        A label image differs in size from its map.
    """
    out = []
    for item in pairs:
        try:
            map_path, label_path = item
        except (TypeError, ValueError):
            raise ParameterError(
                f"<array>: pairs must hold (map, labels) path pairs, got {item!r}") from None
        map_path, label_path = Path(map_path), Path(label_path)
        map_gray = read_gray(map_path)
        labels = read_label_image(label_path)
        if labels.shape != map_gray.shape:
            raise MapError(f"{label_path}: label image shape {labels.shape} differs from map "
                           f"{map_path.name} shape {map_gray.shape}")
        out.append(LabeledMap(map_path.stem, map_path, label_path, map_gray, labels))
    return out


def benchmark_dir() -> Optional[Path]:
    """Where the benchmark maps are, if anywhere.

    Returns
    -------
    Path or None
        ``$TOPOMAP_BENCHMARK_DIR`` if that variable names an existing
        directory; else ``<repo>/../shared/datasets/ipa_room_segmentation``
        if it exists; else None (tests skip then).
    """
    env = os.environ.get("TOPOMAP_BENCHMARK_DIR")
    if env and Path(env).is_dir():
        return Path(env)
    repo = Path(__file__).resolve().parent.parent
    cand = repo.parent / "shared" / "datasets" / "ipa_room_segmentation"
    if cand.is_dir():
        return cand
    return None
