"""Loading room-segmentation benchmarks and labelled map pairs.

Three data-set layouts are read (:func:`detect_layout` tells them apart):

``"ipa"`` -- the benchmark of Bormann et al. (ICRA 2016), from the
``ipa_room_segmentation`` package: per map ``NAME``, ``NAME.png`` (map
without furniture), ``NAME_furnitures.png`` (with furniture) and
``NAME_gt_segmentation.png`` (ground truth drawing: room space white, rooms
separated by black lines across doorways). Resolution 0.05 m per pixel. The
maps are bare images, loaded as a user loads them
(``load_map(path, resolution=0.05)``, i.e. ``topomap segment PATH
--resolution 0.05``).

``"labelled"`` -- real SLAM maps with label images (e.g. the ROSE² data of
Luperto et al. 2022): per map ``NAME.png``, a map_server ``NAME.yaml`` for it
and ``NAME_gt.png``, an 8- or 16-bit label image (0 = no room, 1..K = rooms;
a room may be several pieces). The map is loaded through its YAML
(``load_map("NAME.yaml")``, i.e. ``topomap segment NAME.yaml``).

``"simulated"`` -- a corpus of simulated cases (``topomap simulate PLAN...
-o CORPUS``): one folder ``CORPUS/CASE/`` per case, with the simulated robot
map ``map.pgm`` + ``map.yaml`` (variant ``"scan"``), the drawn floor plan on
the same grid ``plan.pgm`` + ``plan.yaml`` (variant ``"plan"``), the room
labels ``gt_rooms.png`` (16-bit, 0 = no room) and the true doors
``gt_doors.json`` (``{"doors": [{"p1": [x, y], "p2": [x, y], "rooms": [a, b],
...}]}``, metres in the map frame of the YAML, room 0 = outside). The scan
has its own ground truth, ``gt_rooms_scan.png`` and ``gt_doors_scan.json``:
the rooms the scan shows and their doors (a room the robot never saw cannot
be drawn by a person labelling its map). Each map is loaded through its
YAML, as a user loads it.

The data sets' licences may forbid redistributing them, so topomap never
ships them: code reads them from a directory given at run time (see
:func:`benchmark_dir`).

Ground-truth drawings are read as 8-bit gray with Pillow's ``convert("L")``
whatever their mode (L, LA, RGB, RGBA, P; alpha is dropped), as the original
evaluation does.
"""

from __future__ import annotations

import fnmatch
import hashlib
import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Optional

import numpy as np

from ..core.geometry import line_pixels
from ..errors import BenchmarkNotFoundError, MapError, MapFileError, ParameterError, first_line
from ..io.export import read_gray, read_label_image  # re-exported: their home was here
from ..io.maps import FREE_GRAY, load_map  # FREE_GRAY re-exported: the benchmark's white level
from .evaluation import gt_rooms_from_image
from .simulate import shown_doors, shown_rooms

__all__ = [
    "BENCHMARK_RESOLUTION",
    "FREE_GRAY",
    "VARIANTS",
    "LABELLED_VARIANT",
    "SIMULATED_VARIANTS",
    "BenchmarkNotFoundError",
    "BenchmarkMap",
    "LabeledMap",
    "read_gray",
    "read_label_image",
    "detect_layout",
    "load_benchmark",
    "load_labelled",
    "load_simulated",
    "plan_split",
    "SPLITS",
    "read_doors",
    "door_cells",
    "load_dataset",
    "load_pairs",
    "select_names",
    "benchmark_dir",
    "real_maps_dir",
]

#: Metres per pixel of every benchmark map.
BENCHMARK_RESOLUTION = 0.05

#: The two map variants of the ipa_room_segmentation layout.
VARIANTS = ("unfurnished", "furnished")
#: The one variant of the labelled layout: the map as given.
LABELLED_VARIANT = "map"
#: The two variants of the simulated layout: the drawn floor plan, the simulated robot map.
SIMULATED_VARIANTS = ("plan", "scan")

_GT_SUFFIX = "_gt_segmentation.png"
_FURN_SUFFIX = "_furnitures.png"
_LABEL_SUFFIX = "_gt.png"
#: Files of one case of the simulated layout: the map of each variant (YAML stem), the ground truth
#: (rooms, doors) of each variant.
_CASE_MAPS = {"plan": "plan", "scan": "map"}
_CASE_ROOMS = "gt_rooms.png"
_CASE_DOORS = "gt_doors.json"
_CASE_TRUTH = {"plan": (_CASE_ROOMS, _CASE_DOORS), "scan": ("gt_rooms_scan.png", "gt_doors_scan.json")}


@dataclass(frozen=True, eq=False)
class BenchmarkMap:
    """One benchmark map with its ground truth.

    Parameters
    ----------
    name : str
        Map name (``NAME`` of the files).
    variant : str
        ``"unfurnished"`` or ``"furnished"`` (ipa layout), ``"map"``
        (:data:`LABELLED_VARIANT`, labelled layout).
    map_path, gt_path : Path
        The map image and the ground truth (drawing or label image).
    map_gray : (M, N) ndarray of uint8
        The map image as 8-bit gray.
    gt_gray : (M, N) ndarray of uint8 or None
        The ground-truth drawing as 8-bit gray (ipa layout); None for a
        label image.
    resolution : float
        Metres per pixel (0.05 for the benchmark).
    unfurnished_gray : (M, N) ndarray of uint8, optional
        The map without furniture (``NAME.png``), the same array as
        ``map_gray`` for the unfurnished variant. Extract true doors from it
        in both variants (furniture next to a door line would otherwise
        merge into the door's cell group). Defaults to ``map_gray``.
    load_path : Path, optional
        What a user passes to ``topomap segment``: the map image (ipa
        layout, default) or its YAML (labelled layout).
    load_kwargs : dict, optional
        Keyword arguments of :func:`topomap.io.load_map` a user gives with
        it; default ``{"resolution": resolution}`` for an image, ``{}`` for a
        YAML.
    gt_rooms : (M, N) ndarray of int32, optional
        Ground-truth room labels (0 = no room); default derived from
        ``gt_gray`` (:func:`topomap.bench.evaluation.gt_rooms_from_image`).
    gt_doors : tuple of dict, optional
        True doors in map-frame metres (simulated layout, :func:`read_doors`):
        ``{"p1": (x, y), "p2": (x, y), "rooms": (a, b)}``; None when the true
        doors are the lines of ``gt_gray`` (ipa layout) or unknown.
    """

    name: str
    variant: str
    map_path: Path
    gt_path: Path
    map_gray: np.ndarray = field(repr=False)
    gt_gray: Optional[np.ndarray] = field(repr=False)
    resolution: float = BENCHMARK_RESOLUTION
    unfurnished_gray: Optional[np.ndarray] = field(default=None, repr=False)
    load_path: Optional[Path] = None
    load_kwargs: Optional[dict] = None
    gt_rooms: Optional[np.ndarray] = field(default=None, repr=False)
    gt_doors: Optional[tuple] = field(default=None, repr=False)

    def __post_init__(self):
        if self.unfurnished_gray is None:
            object.__setattr__(self, "unfurnished_gray", self.map_gray)
        if self.load_path is None:
            object.__setattr__(self, "load_path", Path(self.map_path))
        if self.load_kwargs is None:
            is_yaml = Path(self.load_path).suffix.lower() in (".yaml", ".yml")
            object.__setattr__(self, "load_kwargs", {} if is_yaml else {"resolution": self.resolution})
        if self.gt_rooms is None:
            if self.gt_gray is None:
                raise ParameterError(f"{self.gt_path}: a benchmark map needs gt_gray or gt_rooms")
            object.__setattr__(self, "gt_rooms", gt_rooms_from_image(self.gt_gray))

    def load(self):
        """The map as a user loads it: ``load_map(load_path, **load_kwargs)``.

        Returns
        -------
        topomap.io.OccupancyGrid
        """
        return load_map(self.load_path, **self.load_kwargs)

    @property
    def command(self) -> str:
        """The ``topomap segment`` command line that loads the map the same way."""
        opts = "".join(f" --{k} {v}" for k, v in self.load_kwargs.items())
        return f"topomap segment {Path(self.load_path).name}{opts}"

    @property
    def scored(self) -> np.ndarray:
        """Cells the metric scores: the free cells of the map as a user loads it (bool)."""
        return self.load().free


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
    names : iterable of str or str, optional
        Load only these maps (names or shell patterns, see
        :func:`select_names`).

    Returns
    -------
    list of BenchmarkMap
        Sorted by name; ``load_path`` the map image, loaded with
        ``resolution=0.05`` as ``topomap segment PATH --resolution 0.05``
        loads it.

    Raises
    ------
    BenchmarkNotFoundError
        The directory does not exist or holds no ground-truth file, or a
        name pattern matches no map (a ``FileNotFoundError`` and
        :class:`~topomap.errors.MapFileError`).
    MapFileError
        A ground-truth file has no map image for ``variant``.
    MapError
        A map and its ground truth differ in size.
    ParameterError
        ``variant`` is not one of the two variants.
    """
    if variant not in VARIANTS:
        raise ParameterError(
            f"<array>: variant must be 'unfurnished' or 'furnished', got {variant!r}")
    directory = Path(directory)
    if not directory.is_dir():
        raise BenchmarkNotFoundError(f"{directory}: benchmark directory does not exist")
    found = {p.name[: -len(_GT_SUFFIX)]: p for p in directory.glob("*" + _GT_SUFFIX)}
    found.pop("", None)
    if not found:
        raise BenchmarkNotFoundError(f"{directory}: no *_gt_segmentation.png files found")
    maps = []
    for name in select_names(found, names, directory):
        gt_path = found[name]
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
    maps.sort(key=lambda m: m.name)
    return maps


def select_names(available, patterns, directory="<directory>") -> list:
    """The names of ``available`` that match ``patterns``, sorted.

    Parameters
    ----------
    available : iterable of str
    patterns : iterable of str, str or None
        Map names or shell-style patterns (``fnmatch``: ``*``, ``?``,
        ``[...]``); a string may hold several, comma-separated. None selects
        every name.
    directory : str or Path
        Named in the error message.

    Raises
    ------
    BenchmarkNotFoundError
        A pattern matches no name (a typo should not silently shrink a run).
    """
    available = sorted(available)
    if patterns is None:
        return available
    if isinstance(patterns, str):
        patterns = patterns.split(",")
    patterns = [str(p).strip() for p in patterns if str(p).strip()]
    chosen = set()
    for pat in patterns:
        hit = fnmatch.filter(available, pat)
        if not hit:
            raise BenchmarkNotFoundError(
                f"{directory}: no map matches {pat!r} (maps: {', '.join(available)})"[:300])
        chosen.update(hit)
    if not chosen:
        raise BenchmarkNotFoundError(f"{directory}: no map selected")
    return sorted(chosen)


def _labelled_names(directory: Path) -> dict:
    """``{NAME: (png, yaml, gt)}`` of the complete labelled triples in ``directory``."""
    out = {}
    for gt in directory.glob("*" + _LABEL_SUFFIX):
        name = gt.name[: -len(_LABEL_SUFFIX)]
        png, yml = directory / (name + ".png"), directory / (name + ".yaml")
        if name and png.is_file() and yml.is_file():
            out[name] = (png, yml, gt)
    return out


def _simulated_cases(directory: Path) -> dict:
    """``{CASE: folder}`` of the case folders (holding a ``gt_rooms.png``) of a simulated corpus."""
    return {p.name: p for p in directory.iterdir()
            if p.is_dir() and (p / _CASE_ROOMS).is_file()} if directory.is_dir() else {}


def detect_layout(directory) -> str:
    """Which data-set layout ``directory`` holds: ``"ipa"``, ``"labelled"`` or ``"simulated"``.

    ``"ipa"`` if it holds a ``*_gt_segmentation.png``, else ``"labelled"`` if
    it holds a ``NAME.png`` + ``NAME.yaml`` + ``NAME_gt.png`` triple, else
    ``"simulated"`` if it holds case folders with a ``gt_rooms.png``.

    Raises
    ------
    BenchmarkNotFoundError
        The directory does not exist or holds none of these.
    """
    directory = Path(directory)
    if not directory.is_dir():
        raise BenchmarkNotFoundError(f"{directory}: benchmark directory does not exist")
    if any(p.name != _GT_SUFFIX for p in directory.glob("*" + _GT_SUFFIX)):
        return "ipa"
    if _labelled_names(directory):
        return "labelled"
    if _simulated_cases(directory):
        return "simulated"
    raise BenchmarkNotFoundError(
        f"{directory}: no benchmark maps found (neither NAME_gt_segmentation.png files, "
        "NAME.png + NAME.yaml + NAME_gt.png triples nor CASE/gt_rooms.png case folders)")


def load_labelled(directory, *, names=None) -> list:
    """Load the maps of a labelled data set (``NAME.png`` + ``NAME.yaml`` + ``NAME_gt.png``).

    Parameters
    ----------
    directory : str or Path
    names : iterable of str or str, optional
        Only these maps (names or shell patterns, see :func:`select_names`).

    Returns
    -------
    list of BenchmarkMap
        Sorted by name; variant :data:`LABELLED_VARIANT`, ``gt_gray`` None,
        ``gt_rooms`` the label image, ``load_path`` the YAML (the map is
        scored on the free cells of the map as read through its YAML).

    Raises
    ------
    BenchmarkNotFoundError
        No such triple in ``directory``, or a pattern matches no map.
    MapError
        A label image differs in size from its map.
    """
    directory = Path(directory)
    found = _labelled_names(directory) if directory.is_dir() else {}
    if not found:
        detect_layout(directory)  # raises the right message
        raise BenchmarkNotFoundError(f"{directory}: no NAME.png + NAME.yaml + NAME_gt.png maps")
    maps = []
    for name in select_names(found, names, directory):
        png, yml, gt = found[name]
        map_gray = read_gray(png)
        labels = read_label_image(gt)
        if labels.shape != map_gray.shape:
            raise MapError(f"{gt}: label image shape {labels.shape} differs from map "
                           f"{png.name} shape {map_gray.shape}")
        maps.append(BenchmarkMap(name, LABELLED_VARIANT, png, gt, map_gray, None,
                                 load_path=yml, load_kwargs={}, gt_rooms=labels))
    return maps


def _point(path, i, key, value) -> tuple:
    try:
        x, y = (float(v) for v in value)
    except (TypeError, ValueError):
        raise MapError(f"{path}: door {i}: {key} must be [x, y] in metres, got {value!r}"[:300]) from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise MapError(f"{path}: door {i}: {key} must be finite, got {value!r}")
    return x, y


def read_doors(path) -> tuple:
    """Read the true doors of a simulated case (``gt_doors.json``).

    Parameters
    ----------
    path : str or Path
        ``{"doors": [{"p1": [x, y], "p2": [x, y], "rooms": [a, b], ...}, ...]}``:
        the end points of each doorway in map-frame metres and the two
        ground-truth rooms it joins (0 = outside; ``rooms`` may be absent).
        Other keys (``id``, ``width``) are ignored.

    Returns
    -------
    tuple of dict
        ``{"p1": (x, y), "p2": (x, y), "rooms": (a, b) or ()}`` per door.

    Raises
    ------
    MapFileError
        The file is missing or unreadable.
    MapError
        It is not JSON of that shape (the message names the file and the door).
    """
    path = Path(path)
    if not path.is_file():
        raise MapFileError(f"{path}: file does not exist")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise MapError(f"{path}: not valid JSON ({first_line(exc)})") from None
    except OSError as exc:
        raise MapFileError(f"{path}: cannot be read ({exc.strerror or exc})") from None
    doors = data.get("doors") if isinstance(data, dict) else None
    if not isinstance(doors, list):
        raise MapError(f"{path}: expected an object with a list 'doors'")
    out = []
    for i, d in enumerate(doors):
        if not isinstance(d, dict):
            raise MapError(f"{path}: door {i}: expected an object, got {d!r}"[:300])
        rooms = d.get("rooms", ())
        try:
            if not isinstance(rooms, (list, tuple)) or any(isinstance(r, (bool, float)) for r in rooms):
                raise TypeError
            rooms = tuple(int(r) for r in rooms)
        except (TypeError, ValueError):
            raise MapError(f"{path}: door {i}: rooms must be integer labels, got {rooms!r}"[:300]) from None
        out.append({"p1": _point(path, i, "p1", d.get("p1")), "p2": _point(path, i, "p2", d.get("p2")),
                    "rooms": rooms})
    return tuple(out)


def door_cells(doors, grid) -> list:
    """True doors in metres as pixel cell groups of ``grid`` (for :func:`topomap.bench.evaluation.score_doors`).

    Parameters
    ----------
    doors : iterable of dict
        As :func:`read_doors` returns them.
    grid : topomap.io.OccupancyGrid
        The map the doors are drawn on (its origin and resolution).

    Returns
    -------
    list of (K, 2) ndarray of int
        The cells ``(row, col)`` of the digital line from ``p1`` to ``p2``
        (:func:`topomap.core.geometry.line_pixels`), one array per door.
    """
    out = []
    for d in doors:
        (x1, y1), (x2, y2) = d["p1"], d["p2"]
        r, c = line_pixels(grid.world_to_pixel(x1, y1), grid.world_to_pixel(x2, y2), grid.shape)
        out.append(np.column_stack([r, c]))
    return out


#: The two halves of the plans of a simulated corpus (:func:`plan_split`): tune on ``"dev"``,
#: report on ``"held-out"``.
SPLITS = ("dev", "held-out")


def plan_split(name) -> str:
    """The half of the plans a plan, or its case, belongs to: ``"dev"`` or ``"held-out"``.

    A fixed rule on the name alone, so every user of a corpus splits it the
    same way, whichever plans it holds: ``"dev"`` when the first byte of the
    SHA-256 digest of the plan's name (UTF-8) is even, ``"held-out"`` when
    it is odd. About half each (502 and 522 of the 1,024 R2V plans).

    Parameters
    ----------
    name : str or os.PathLike
        The plan's name: the stem of its file, which is also the name of its
        case folder in a corpus (``topomap simulate plans/*.txt -o CORPUS``
        writes ``CORPUS/NAME/``). A path or a ``NAME.txt`` file name is
        reduced to that name.

    Returns
    -------
    str
        ``"dev"`` or ``"held-out"`` (:data:`SPLITS`).
    """
    if not isinstance(name, (str, os.PathLike)):
        raise ParameterError(f"<plan name>: expected a plan name (str), got {name!r}")
    stem = Path(name).name
    if stem.lower().endswith(".txt"):
        stem = stem[:-4]
    if not stem:
        raise ParameterError(f"<plan name>: empty plan name in {os.fspath(name)!r}")
    digest = hashlib.sha256(stem.encode("utf-8", "surrogateescape")).digest()
    return SPLITS[digest[0] % 2]


def load_simulated(directory, *, variant: str = "scan", names=None) -> list:
    """Load the cases of a simulated corpus (one folder per case).

    Parameters
    ----------
    directory : str or Path
        A folder of case folders ``CASE/`` holding ``map.pgm`` + ``map.yaml``
        (the simulated robot map), ``plan.pgm`` + ``plan.yaml`` (the drawn
        floor plan on the same grid), ``gt_rooms.png`` (room labels, 0 = no
        room) and ``gt_doors.json`` (:func:`read_doors`), the plan's ground
        truth, and ``gt_rooms_scan.png`` + ``gt_doors_scan.json``, the
        scan's (the rooms the scan shows, whole, and their doors).
    variant : {"scan", "plan"}
        Which map and its ground truth: ``map.yaml`` with
        ``gt_rooms_scan.png`` + ``gt_doors_scan.json``, or ``plan.yaml``
        with ``gt_rooms.png`` + ``gt_doors.json``. A case without the
        scan's files (written before they were) gets them derived as
        ``topomap simulate`` derives them
        (:func:`topomap.bench.simulate.shown_rooms`, :func:`~topomap.bench.simulate.shown_doors`).
    names : iterable of str or str, optional
        Only these cases (names or shell patterns, see :func:`select_names`).

    Returns
    -------
    list of BenchmarkMap
        Sorted by case name; ``load_path`` the variant's YAML (loaded as
        ``topomap segment CASE/map.yaml``, scored on the free cells of the
        grid as loaded, the true rooms kept whole), ``gt_rooms`` the
        variant's label image, ``gt_doors`` its doors.

    Raises
    ------
    BenchmarkNotFoundError
        No case folder, or a pattern matches no case.
    MapFileError
        A case lacks the variant's map or its ``gt_doors.json``.
    MapError
        A file is unreadable (bad JSON, not an image), or the label image
        differs in size from the map.
    ParameterError
        ``variant`` is not one of :data:`SIMULATED_VARIANTS`.
    """
    if variant not in SIMULATED_VARIANTS:
        raise ParameterError(f"<array>: variant of a simulated corpus must be 'plan' or 'scan', got {variant!r}")
    directory = Path(directory)
    found = _simulated_cases(directory)
    if not found:
        detect_layout(directory)  # raises the right message
        raise BenchmarkNotFoundError(f"{directory}: no CASE/{_CASE_ROOMS} case folders")
    maps = []
    stem = _CASE_MAPS[variant]
    for name in select_names(found, names, directory):
        case = found[name]
        yml, pgm = case / f"{stem}.yaml", case / f"{stem}.pgm"
        for f in (yml, pgm):
            if not f.is_file():
                raise MapFileError(f"{f}: missing {variant} map of case {name}")
        rooms_file, doors_file = (case / f for f in _CASE_TRUTH[variant])
        derive = variant == "scan" and not rooms_file.is_file() and not doors_file.is_file()
        gt = case / _CASE_ROOMS if derive else rooms_file
        map_gray = read_gray(pgm)
        labels = read_label_image(gt)
        if labels.shape != map_gray.shape:
            raise MapError(f"{gt}: label image shape {labels.shape} differs from map "
                           f"{pgm.name} shape {map_gray.shape}")
        doors = read_doors(case / _CASE_DOORS if derive else doors_file)
        if derive:  # a case written before the scan had its own ground truth
            grid = load_map(yml)
            labels = shown_rooms(labels, grid.free, resolution=grid.resolution)
            doors = tuple(shown_doors(doors, labels))
        maps.append(BenchmarkMap(name, variant, pgm, gt, map_gray, None, load_path=yml, load_kwargs={},
                                 gt_rooms=labels, gt_doors=doors))
    return maps


def load_dataset(directory, *, variant: Optional[str] = None, names=None) -> list:
    """Load the maps of any layout (:func:`detect_layout`).

    ``variant`` selects the map image of the ipa layout (``"unfurnished"``,
    the default, or ``"furnished"``) or the map of a simulated case
    (``"scan"``, the default, or ``"plan"``), and is ignored for the labelled
    layout (one variant). ``names``: names or shell patterns.
    """
    layout = detect_layout(directory)
    if layout == "ipa":
        return load_benchmark(directory, variant=variant or VARIANTS[0], names=names)
    if layout == "simulated":
        return load_simulated(directory, variant=variant or "scan", names=names)
    return load_labelled(directory, names=names)


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


def _shared_dataset(name: str) -> Optional[Path]:
    repo = Path(__file__).resolve().parents[2]
    cand = repo.parent / "shared" / "datasets" / name
    return cand if cand.is_dir() else None


def benchmark_dir() -> Optional[Path]:
    """Where the ipa_room_segmentation benchmark maps are, if anywhere.

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
    return _shared_dataset("ipa_room_segmentation")


def real_maps_dir() -> Optional[Path]:
    """Where the labelled real maps (ROSE² data) are, if anywhere.

    Returns
    -------
    Path or None
        ``$TOPOMAP_REAL_MAPS_DIR`` if that variable names an existing
        directory; else ``<repo>/../shared/datasets/rose2_real`` if it
        exists; else None (tests skip then).
    """
    env = os.environ.get("TOPOMAP_REAL_MAPS_DIR")
    if env and Path(env).is_dir():
        return Path(env)
    return _shared_dataset("rose2_real")
