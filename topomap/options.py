"""The options of each segmentation method, validated in one place.

Each Voronoi method has a frozen dataclass of its options:
:class:`TopomapOptions` (the default method,
:func:`topomap.core.segmentation.segment_topomap`) and :class:`PaperOptions`
(:func:`topomap.core.segmentation.segment_paper`). Lengths are in metres. Every
field is checked when the object is made: a wrong type, a negative or
non-finite length, a fraction outside ``[0, 1]``, an unknown ``rule`` or a
non-bool flag raises :class:`~topomap.errors.ParameterError` naming the
option and echoing the value; so does an unknown keyword
(:func:`options_from_kwargs`).

``segment(grid, window=0.4)`` builds the options from the keywords;
``segment(grid, options=TopomapOptions(window=0.4))`` passes them whole.
``seg.params`` is ``dataclasses.asdict`` of the options that ran (with
defaults that depend on the map, such as ``rise``, filled in).
"""

from __future__ import annotations

import dataclasses
import numbers
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from .errors import ParameterError

__all__ = ["TopomapOptions", "PaperOptions", "CheckedOptions", "RULES", "options_from_kwargs", "option",
           "check_length", "check_fraction", "check_area", "check_keywords"]

#: Values of :attr:`TopomapOptions.rule`.
RULES = ("oneflat", "either", "ep", "frac", "one")


def check_length(name: str, value, *, optional: bool = False) -> Optional[float]:
    """``value`` as a float length in metres (finite, >= 0), else ParameterError.

    ``optional=True`` also lets ``None`` through (returned as None).
    """
    if value is None and optional:
        return None
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise ParameterError(f"{name} must be a length in metres, got {value!r}")
    m = float(value)
    if not np.isfinite(m) or m < 0:
        raise ParameterError(f"{name} must be a length >= 0 m, got {value!r}")
    return m


def check_fraction(name: str, value) -> float:
    """``value`` as a float in ``[0, 1]``, else ParameterError naming ``name``."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise ParameterError(f"{name} must be a number in [0, 1], got {value!r}")
    v = float(value)
    if not (0.0 <= v <= 1.0):
        raise ParameterError(f"{name} must be a number in [0, 1], got {value!r}")
    return v


def _check_nonnegative(name: str, value, what: str, unit: str = "") -> float:
    """``value`` as a finite float >= 0 (``what`` and ``unit`` word the error)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise ParameterError(f"{name} must be {what}, got {value!r}")
    v = float(value)
    if not np.isfinite(v) or v < 0:
        raise ParameterError(f"{name} must be finite and >= 0{unit}, got {value!r}")
    return v


def _check_ratio(name: str, value) -> float:
    return _check_nonnegative(name, value, "a number")


def check_area(name: str, value) -> float:
    """``value`` as a float area in m² (finite, >= 0), else ParameterError naming ``name``."""
    return _check_nonnegative(name, value, "an area in m²", " m²")


def _check_bool(name: str, value) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def _check_rule(name: str, value) -> str:
    if not isinstance(value, str) or value not in RULES:
        raise ParameterError(f"{name} must be one of {', '.join(RULES)}; got {value!r}")
    return value



_CHECKS = {"length": check_length, "fraction": check_fraction, "ratio": _check_ratio, "area": check_area,
           "bool": _check_bool, "rule": _check_rule,
           "optional length": lambda n, v: check_length(n, v, optional=True)}


def option(default, kind: str):
    """A dataclass field of a :class:`CheckedOptions` class whose value is checked as ``kind``.

    Parameters
    ----------
    default
        The field's default value.
    kind : {"length", "optional length", "fraction", "ratio", "area", "bool", "rule"}
        The check: a length in metres (>= 0; "optional length" also lets None
        through), a fraction in ``[0, 1]``, a ratio (a number >= 0), an area
        in m² (>= 0), a bool, one of :data:`RULES`.

    Returns
    -------
    dataclasses.Field
    """
    return field(default=default, metadata={"kind": kind})


class CheckedOptions:
    """Validation shared by the option classes (frozen dataclasses whose fields are made by
    :func:`option`): every field is checked by the checker its ``kind`` names and stored converted
    (float / bool / str)."""

    def __post_init__(self):
        for f in dataclasses.fields(self):
            value = _CHECKS[f.metadata["kind"]](f.name, getattr(self, f.name))
            object.__setattr__(self, f.name, value)

    def as_params(self) -> dict:
        """The options as a plain dict (``seg.params``)."""
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class TopomapOptions(CheckedOptions):
    """Options of topomap's default method (:func:`~topomap.core.segmentation.segment_topomap`).

    Attributes
    ----------
    erosion_radius : float
        Radius (m) of the disk free space is eroded with before its skeleton
        is taken: 0.05 m (one cell at 0.05 m/px) removes free-space speckle
        without narrowing any door by more than a cell on each side.
    median_size : float
        Side (m) of the median filter that smooths the eroded free space:
        0.25 m rounds corners so they add no skeleton spurs.
    dilation_size : float
        Side (m) of the square occupied space is dilated with before its
        skeleton: 0.15 m closes one-cell gaps in scanned walls.
    wall_band : float
        Obstacle cells farther than this (m) from free space are left out of
        the occupied-space analysis (the outside of the building): 0.5 m
        keeps walls up to 1 m thick whole.
    min_occupied_branch : float
        End branches of the occupied skeleton shorter than this (m) are
        pruned: 0.3 m, about a wall's thickness — a spur shorter than the
        wall is thick is a corner artefact, not a protrusion (the paper's
        1 m also removes real wall stubs beside doors).
    min_door_width : float
        Narrowest door (m): 0.5 m is narrower than any door a person or
        robot uses.
    max_door_width : float
        Widest door (m): 3.0 m admits double doors and the wide openings
        between a room and a hall or an open office bay, which floor plans
        separate as rooms of their own.
    window : float
        A bottleneck is the narrowest point within this distance (m) along
        the skeleton: 0.5 m, half a door's width either way.
    rise : float or None
        The clearance must grow by this much (m) on both sides of a
        bottleneck within ``reach``: doors lead from one space into a wider
        one. None (default): measured on the map, as the noise the
        clearance carries without any door. On a map with straight walls
        (at least ``straight_walls`` of the wall faces on straight lines),
        the grid's own noise: the skeleton may run half a cell's diagonal
        off the true medial axis, and clearances are compared to half a
        cell, so ``(sqrt(2)/2 + 1/2) * max(skeleton_cell, resolution)``
        (0.12 m). On a map a laser scanner drew, ``scan_rise``. Filled in
        by :meth:`resolved` before the method runs.
    scan_rise : float
        ``rise`` (m) on a map whose walls are not straight (fewer than
        ``straight_walls`` of its wall faces on straight lines): a laser
        SLAM map draws each wall a cell or two (0.05-0.1 m) off its line,
        so a plain corridor's clearance wanders by up to 0.2 m with no door
        in it; a door frame narrows the passage by more. 0.25 m.
    straight_walls : float
        Share (0..1) of the wall-face cells on straight lines of at least
        ``min_wall_length`` (:func:`topomap.core.walls.straight_share`) from which
        a map counts as drawn with straight walls: 0.7, between the drawn
        floor plans of the benchmark (0.77-0.98, furnished or not) and its
        laser SLAM maps (0.14-0.67).
    wall_cell : float
        Walls — their straight faces and the share of them on lines, the
        openings in them and the long walls — are found on a grid of cells
        this size (m) when the map's own cells are smaller: 0.05 m, the cell
        size of the maps the ``straight_walls`` threshold and the openings
        were measured on. A straight wall is straight to within a cell of
        that size whatever the map's resolution, while a finer map draws
        every step of a diagonal and every bump of a wall a laser scanner
        saw (the same plan at 0.0125 m/px measured 0.63 on its own grid,
        0.89 on 0.05 m cells). On a map whose cells are larger, each cell
        is split into cells of about this size for the walls, so that the
        rules counted in wall cells (the band of a cell either side of a
        wall's line, faces grown by a cell) keep their lengths in metres:
        on 0.10 m cells a band of one cell is 0.3 m wide, and the outline
        of a chair or a box there passes for a wall going on past a gap
        (the laser maps resampled to 0.10 m: recall +1 to +7 points). Not
        where the split map's walls are still straight (at least
        ``straight_walls`` of the faces on lines: a drawn plan, whose pieces
        of one wall may lie a whole cell apart as drawn); the share that
        tells a plan from a scan is always measured on cells no smaller
        than the map's. Door posts, bottlenecks and rooms stay on the map's
        own cells.
    reach : float
        How far (m) along the skeleton the rise is looked for: 1.5 m, a
        door's frame and the first step into the room behind it.
    protrusion_min : float
        Fraction (0..1) of free cells in a disk of the map's wall-thickness
        threshold (at least 0.25 m) around a door post above which the wall
        protrudes there: 0.7 lies between a straight wall (0.5) and a
        right-angled convex corner (0.75), nearer the corner: a laser
        scanner's straight wall wanders a cell or two off its line, and at
        the 0.6 used before its bumps passed for wall ends (measured on the
        Freiburg partial maps in all eight orientations of the grid: recall
        +0.4 to +1.4 in every one, precision -0.1 to -0.4).
    flat_min : float
        With ``rule="oneflat"``, the fraction (0..1) the other post must
        reach: 0.45, a straight wall (0.5), not a concave corner (0.25).
    rule : {"oneflat", "either", "ep", "frac", "one"}
        Which protrusion evidence accepts a door: ``"ep"`` the paper's
        endpoint test at both posts; ``"frac"`` the convexity test at both
        posts; ``"either"`` one of these; ``"one"`` convexity at one post;
        ``"oneflat"`` (default) ``"either"``, or convexity at one post and a
        straight wall at the other (a door beside a wall).
    skeleton_cell : float
        Cell size (m) of the grid the free-space skeleton is taken on; the
        clearances are always sampled at the map's own resolution. 0.1 m:
        the narrowest door (0.5 m) is still five cells wide. Maps coarser
        than this use their own grid.
    mouths : bool
        Also look for corridor mouths: one-sided bottlenecks where a run of
        even clearance opens into a space at least ``2 * rise`` wider; they
        are doors only where the walls protrude on both sides.
    corridor_length : float
        A run of even clearance (within one cell) must be at least this long
        (m) to count as a corridor whose mouth can be a door: 1.0 m, longer
        than any door frame or gap between pieces of furniture.
    min_wall_length : float
        Free-standing obstacles less than this (m) across (bounding box) are
        clutter — chairs, plants, small tables, pillars — and are looked
        through while doors are searched: doors are in walls, and 1.0 m is
        shorter than any wall piece between two doors. Rooms are still cut
        from the map as it is (clutter cells stay out of every room). 0
        turns this off.
    facing : float
        The posts must face each other across the bottleneck: their distance
        must be at least ``facing`` times the bottleneck's diameter (0.9:
        about 130° apart seen from the narrowest point). Posts at a right
        angle to each other are a room's corner, not a doorway.
    wall_gap : float
        Gaps between obstacles narrower than this (m) are closed before
        doors are searched and rooms are cut: 0.5 m, the narrowest door
        (``min_door_width``). A laser SLAM map leaves gaps in its walls
        (glass, dark or shiny surfaces, missed beams, a wall seen at a
        grazing angle) and between furniture and the wall behind it; a gap
        narrower than any door is not a doorway, so it neither makes a door
        nor joins two rooms. The cells of a closed gap still belong to the
        room beside them. Free-standing clutter (``min_wall_length``) is
        taken out first, so a pillar near a wall is not joined to it. 0
        turns this off.
    wide_opening : float
        Openings wider than this (m) are doors only where the paper's own
        evidence holds at both posts (an endpoint of the occupied-space
        skeleton, i.e. the end of a wall, within the map's threshold): 1.5 m,
        the widest double door. Wider openings are more often the gap
        between furniture and a wall, or a corridor that widens, than a
        doorway; a doorway that wide is still found when walls end on both
        sides of it.
    min_room_area : float
        Smallest room (m²): 1.0 m², smaller than a WC or a storage closet
        (about 1.5 m²). A region of free space smaller than this — a free
        speck, a scan ray through a wall, the space behind a cupboard — is a
        *fragment*, not a room: it keeps a label (after the rooms) but is
        not in the room graph. A piece smaller than this cut off by a door
        is not a room of its own either: it joins the room it was cut from.
        The same holds for a region with no place a robot fits: nowhere
        ``wall_gap`` (0.5 m) wide — a strip of free cells along the map's
        edge, a single scan ray, however long.
        0 makes every region a room.
    openings : bool
        Also cut at openings in straight walls (:func:`topomap.core.walls.wall_openings`):
        a gap between ``min_door_width`` and ``max_door_width`` between two
        collinear pieces of a wall face, the piece it is seen from at least
        ``min_wall_length`` long and the wall going on for at least
        ``min_door_width`` past the gap. On a robot's map a room often opens
        onto a corridor through a doorway as wide as the corridor, where
        the clearance does not narrow; the wall's line shows the doorway.
    gaps : bool
        Also cut at gaps in thin walls across the free-space skeleton
        (:func:`topomap.core.walls.thin_wall_gaps`): where the line across
        the skeleton meets two laser hits (or drawn walls) between
        ``min_door_width`` and ``max_door_width`` apart, and beyond each the
        wall goes on along the line for ``gap_wall``, no thicker than
        ``wall_thickness``, on a structure at least ``partition_structure``
        long, and neither post a pillar or a bump on a wall (thin for less
        than ``pillar_depth``, then the wall it stands against). A doorway
        into a passage no wider than itself (the end of a hallway, a glass
        door onto a balcony strip) narrows nothing, so the clearance shows
        no door there; the wall it is in does. A doorway where a door is cut
        already (within its own width) is not cut again.
    gap_wall : float
        With ``gaps``, how far (m) the wall must go on past each post of a
        gap, along the gap's line: 0.3 m, the thickness of the thickest
        inner walls. A shorter stretch of obstacle beyond a post is a wall
        crossed across its thickness (the side wall of a corridor, met face
        on), not the wall the doorway is in.
    beside_wall : float
        With ``openings``, a gap at most this wide (m) between the end of a
        straight wall and the face of a wall that crosses its line is cut
        too: a door beside a wall, the end of a partition next to the
        corridor or outer wall it meets. 1.0 m, a single door leaf
        (0.7-1.0 m); wider gaps there are more often the passage between a
        partition's end and the wall across (kept whole). 0 turns this off.
    alcove_depth : float
        An opening in a wall is cut only where the space reaches at least
        this far (m) from it on both sides: 1.2 m, the depth of the smallest
        room (a WC). A shallower space behind a gap in a wall — a niche, an
        alcove, a recess for a radiator or a cupboard — belongs to the room
        or corridor it opens onto.
    closet_depth : float
        An opening whose space on one side is shallower than
        ``alcove_depth`` is still cut where that space is at least this deep
        (m) and runs on behind the wall past an end of the opening
        (``closet_behind``): 0.6 m, the depth of a wardrobe closet; a
        balcony behind a sliding door is 0.9-1.5 m deep. A niche or an
        alcove is as wide as its mouth; a closet or a balcony is wider than
        its door. 0 turns this off.
    closet_behind : float
        How far (m) the shallow space must run on past an end of the
        opening, along the wall: 0.5 m, beyond the width of a door frame
        and the slack of a scanned wall's end. 0 turns ``closet_depth``
        off.
    long_wall : float
        With ``openings``, a straight wall at least this long (m) whose
        pieces cover at least half of it is a structural wall — a
        corridor's side, a façade: 4.0 m, longer than any piece of furniture
        and than the wall of a small room. Pieces are found along the
        building's two main directions (:func:`topomap.core.walls.long_walls`).
        Every gap of ``min_door_width`` to ``max_door_width`` in such a wall,
        with space ``alcove_depth`` deep on both sides, is an opening, even
        with specks in it (an open door leaf, a person the laser saw); and an
        opening whose two ends lie on two such walls that it crosses spans
        the corridor between them and is no door. 0 turns both off.
    pillar_depth : float
        A bottleneck between two posts that each stand out less than this
        (m) from a long wall (``long_wall``), the door crossing both walls,
        is a narrowing of the corridor between those walls, not a door:
        0.5 m, as far as a pillar, a wall column, a radiator or a cupboard
        stands out from a corridor's side wall. A door across a corridor
        sits in a wall across it, which stands out farther (in a 2 m
        corridor, 0.5 m either side of a 1 m door). 0 turns this off.
    frontier_post : float
        A bottleneck neither of whose posts has an occupied cell within
        this distance (m) is no door (status ``between unexplored edges``):
        0.1 m, a cell or two. On a map still being explored, free space
        narrows between the edges of what the laser has seen (a room
        glimpsed through its door); a door stands in a wall, which the
        laser hits. Only on maps whose free space is bounded mostly by
        occupied cells (not on plans that draw walls in mid-gray). 0 turns
        this off.
    partition_wall : float
        With ``openings``, a straight wall face at least this long (m) on
        one of the building's main directions that ends in free space
        pointing at a wall across its line, ``min_door_width`` to
        ``max_door_width`` away, is a partition mapped only in part
        (:func:`topomap.core.walls.partition_gaps`): the gap is cut when the laser
        saw the partition go on (``partition_hits``). 1.5 m: longer than a
        cupboard or a desk stands out from a wall (0.6-1.2 m), as long as the
        shortest stretch of a room's dividing wall seen from a corridor
        door. 0 turns this off.
    partition_hits : float
        Occupied cells (within ``wall_wander`` of its line) along at least
        this length (m) of such a gap show the partition going on: 0.2 m, a
        few laser hits (glass, a wall seen edge-on, an open door leaf). A gap the laser saw nothing in is
        the way past the end of a wall or a cupboard and stays open (a door
        beside a wall, ``beside_wall``, needs no hits).
    partition_structure : float
        The obstacle a partition's face (``partition_wall``) lies on is at
        least this long or wide (m): 2.0 m, longer than a free-standing
        table or desk (1.2-1.8 m), whose side would otherwise pass for a
        partition; a partition is joined to the building's walls or seen
        over more than that.
    wall_wander : float
        Pieces of one long wall lie within this distance (m) of its line:
        0.2 m. A laser SLAM map draws a straight wall a few cells off its
        line over tens of metres (odometry drift, scan noise); two different
        walls are at least a wall's thickness plus a room apart.
    face_gap : float
        Gaps (m) along a straight wall face that still leave it one wall
        line (:func:`topomap.core.walls.straight_lines`): 0.25 m. A laser scan
        leaves such gaps where a beam missed or something stood in front of
        the wall; the narrowest door (``min_door_width``) is twice as wide,
        so a doorway is never bridged.
    furniture_size : float or None
        Free-standing obstacles less than this (m) across that are thicker
        than ``wall_thickness`` are furniture — desks, cupboards, a table
        with its chairs, a robot's scan of a sofa — and are looked through
        like smaller clutter, unless a long wall (``long_wall``) runs along
        them (a piece of a structural wall a scan saw thick). None
        (default): measured on the map, like ``rise``: on a map a laser
        scanner drew (fewer than ``straight_walls`` of its wall faces on
        straight lines) ``scan_furniture_size``, on a drawn plan
        ``plan_furniture_size``. Filled in by :meth:`resolved`.
    scan_furniture_size : float
        ``furniture_size`` (m) on a map a laser scanner drew: 3.0 m, longer
        than a desk or a cupboard (1.6-2.4 m) and shorter than a room; on
        the benchmark's real maps it keeps rooms whole where furniture
        stands free. A row of such pieces along one line (desks side by
        side) is looked through too: a scan does not draw a wall that way.
    plan_furniture_size : float
        ``furniture_size`` (m) on a drawn plan: 2.0 m, longer than a table
        or a desk (1.2-1.8 m) and shorter than the solid blocks a plan
        draws as structure (a lift shaft, a stair core, a chimney: 2 m and
        more across). On a plan, bulky pieces in a row along a long wall
        stay walls (a partition drawn as a row of solid blocks, or broken
        by openings), and the long walls keep only bulky pieces: the small
        clutter stays looked through as without furniture.
    wall_thickness : float
        Thickest free-standing piece of wall (m): 0.5 m. Inner walls are
        0.1-0.3 m thick and drawn thinner still by a laser scan; a
        free-standing obstacle thicker than this and smaller than
        ``furniture_size`` is furniture.
    prior_post_shift : float
        With a previous result (``segment(grid, previous=...)``), a previous
        door no new cut closes is cut again where walls still meet its line
        within this distance (m) beyond both its posts, or inside them (the
        opening narrowed; free-standing clutter is looked through, as when
        doors are searched): 0.15 m, as far as a laser SLAM map redraws a wall
        between two versions (a cell or two, 0.05-0.1 m, and half a cell of
        rounding; on the exploration sequences of the benchmark, the posts
        of a door found in two consecutive maps moved by at most 0.05 m in
        75 % of the cases, 0.15 m in 94 %); farther, the wall has moved
        away from the post. 0 turns this off (see
        :class:`topomap.core.identity.DoorPrior`).
    prior_changed_area : float
        With a previous result, a new cut inside a room the previous map had
        whole (the same previous room on both sides of it) is dropped when at
        most this area (m²) of the map within ``reach`` of it changed (cells
        free in one map and not in the other): 1.0 m², the smallest room
        (``min_room_area``). A smaller change cannot have uncovered a room
        behind the cut; the cut then comes from quantities measured over the
        whole map (the wall threshold, the skeleton elsewhere), not from
        what the map shows there. On the exploration sequences of the
        benchmark, 0.25 / 0.5 / 1.0 / 2.0 m² keep 91 / 94 / 95 / 96 % of the
        rooms' IDs, with a room F1 of 92 / 94 / 93 / 92 %. 0 turns this off.
    outside_enclosure : float
        A room whose cells are, on average, bounded by an obstacle in fewer
        than this share of the eight directions around them is *outside*
        (:mod:`topomap.core.outside`): 0.3. A room is bounded by walls or
        furniture nearly all round (a cell near its open door still sees
        walls in 5 to 8 directions); the free space a laser saw through a
        window or an open outer door fans out beyond the facade and ends in
        the unexplored world in most directions (0 to 2 of 8). An outside
        region is taken out of the rooms with its doors (a region of kind
        outside, reported apart from the rooms and fragments), so the room
        graph never joins two rooms through it. The same share is read
        cell by cell inside the rooms kept: a part of a room below it that
        is solid free space (at least ``min_room_area``, holding a free
        disk as wide as the smallest room, 1 m) is a fan the door stage did
        not cut off, and is taken out of the room as outside with the
        cells joined to it that are more open than enclosed
        (:func:`topomap.core.outside.outside_fans`); a thin bundle of rays
        never is (across a ray the unknown is beside every cell, whatever
        lies beyond). 0 turns this off.
    open_unknown_area : float
        Unknown regions inside free space smaller than this (m²) are
        obstacles seen in part (a chair, a box, clutter), not the unexplored
        world, for ``outside_enclosure``: 1.0 m², the smallest room.
    enclosure_window : float
        Side (m) of the window over which ``outside_enclosure``'s counts are
        averaged: 0.5 m. A scanned wall has gaps a single ray slips through;
        half a metre is wider than those and narrower than a door.
    """

    erosion_radius: float = option(0.05, "length")
    median_size: float = option(0.25, "length")
    dilation_size: float = option(0.15, "length")
    wall_band: float = option(0.5, "length")
    min_occupied_branch: float = option(0.3, "length")
    min_door_width: float = option(0.5, "length")
    max_door_width: float = option(3.0, "length")
    window: float = option(0.5, "length")
    rise: Optional[float] = option(None, "optional length")
    scan_rise: float = option(0.25, "length")
    straight_walls: float = option(0.7, "fraction")
    wall_cell: float = option(0.05, "length")
    reach: float = option(1.5, "length")
    protrusion_min: float = option(0.7, "fraction")
    flat_min: float = option(0.45, "fraction")
    rule: str = option("oneflat", "rule")
    skeleton_cell: float = option(0.1, "length")
    mouths: bool = option(True, "bool")
    corridor_length: float = option(1.0, "length")
    min_wall_length: float = option(1.0, "length")
    facing: float = option(0.9, "ratio")
    wall_gap: float = option(0.5, "length")
    wide_opening: float = option(1.5, "length")
    min_room_area: float = option(1.0, "area")
    openings: bool = option(True, "bool")
    gaps: bool = option(True, "bool")
    gap_wall: float = option(0.3, "length")
    beside_wall: float = option(1.0, "length")
    alcove_depth: float = option(1.2, "length")
    closet_depth: float = option(0.6, "length")
    closet_behind: float = option(0.5, "length")
    long_wall: float = option(4.0, "length")
    wall_wander: float = option(0.2, "length")
    face_gap: float = option(0.25, "length")
    pillar_depth: float = option(0.5, "length")
    frontier_post: float = option(0.1, "length")
    partition_wall: float = option(1.5, "length")
    partition_hits: float = option(0.2, "length")
    partition_structure: float = option(2.0, "length")
    furniture_size: Optional[float] = option(None, "optional length")
    scan_furniture_size: float = option(3.0, "length")
    plan_furniture_size: float = option(2.0, "length")
    wall_thickness: float = option(0.5, "length")
    prior_post_shift: float = option(0.15, "length")
    prior_changed_area: float = option(1.0, "area")
    outside_enclosure: float = option(0.3, "fraction")
    open_unknown_area: float = option(1.0, "area")
    enclosure_window: float = option(0.5, "length")

    def scanned(self, straight: float) -> bool:
        """Whether a map whose wall faces lie on straight lines at a share of
        ``straight`` was drawn by a laser scanner (less than ``straight_walls``)
        rather than drawn as a plan."""
        return straight < self.straight_walls

    def resolved(self, resolution: float, straight: float = 1.0) -> "TopomapOptions":
        """These options with the map-dependent defaults ``rise`` and
        ``furniture_size`` filled in for a map of ``resolution`` m/px whose
        wall faces lie on straight lines at a share of ``straight`` (what
        actually runs)."""
        scanned = self.scanned(straight)
        fill = {}
        if self.rise is None:
            fill["rise"] = (self.scan_rise if scanned
                            else max(self.skeleton_cell, resolution) * (np.sqrt(2) / 2 + 0.5))
        if self.furniture_size is None:
            fill["furniture_size"] = self.scan_furniture_size if scanned else self.plan_furniture_size
        return dataclasses.replace(self, **fill) if fill else self


@dataclass(frozen=True)
class PaperOptions(CheckedOptions):
    """Options of the paper's method (:func:`~topomap.core.segmentation.segment_paper`).

    Attributes
    ----------
    erosion_radius : float
        Radius (m) of the disk free space is eroded with before its skeleton
        is taken. 0.10 m (2 px at 0.05 m/px) removes free-space speckle and
        one-cell slits, which would otherwise add skeleton branches; it is
        far below any door's half width.
    median_size : float
        Side (m) of the median filter that rounds corners after the erosion.
        0.25 m (5 px): the smallest window that rounds a right-angled corner
        by more than one cell.
    dilation_size : float
        Side (m) of the square occupied space is dilated with. 0.15 m (3 px)
        closes one-cell gaps in scanned walls without rounding corners.
    wall_band : float
        Occupied cells farther than this (m) from free space are left out of
        the occupied-space analysis: what lies beyond is the outside of the
        building (or solid rock), not wall shape. 0.5 m keeps any wall up to
        1 m thick whole.
    min_free_branch : float
        Free-space branches shorter than this (m) are not analysed: the
        paper's 10 px at 0.05 m/px.
    min_occupied_branch : float
        Occupied-space end branches shorter than this (m) are pruned: the
        paper's 20 px at 0.05 m/px.
    max_door_search : float
        Longest ray (m) searched for a wall on either side of a passage: 3 m,
        the widest door.
    """

    erosion_radius: float = option(0.10, "length")
    median_size: float = option(0.25, "length")
    dilation_size: float = option(0.15, "length")
    wall_band: float = option(0.5, "length")
    min_free_branch: float = option(0.5, "length")
    min_occupied_branch: float = option(1.0, "length")
    max_door_search: float = option(3.0, "length")

    def resolved(self, resolution: float) -> "PaperOptions":
        """These options (none depends on the map)."""
        return self


def check_keywords(method: str, given, allowed) -> None:
    """Raise ParameterError naming the first of ``given`` not in ``allowed``."""
    for k in given:
        if k not in allowed:
            raise ParameterError(f"unknown option {k!r} for method {method!r} (got {given[k]!r}); "
                                 f"options: {', '.join(sorted(allowed))}")


def options_from_kwargs(cls, method: str, options=None, kwargs=None):
    """The ``cls`` options of one run: ``options`` (an instance of ``cls`` or
    None for the defaults) with the keyword options in ``kwargs`` replaced.

    Raises
    ------
    ParameterError
        ``options`` is not a ``cls``, a keyword is not an option of
        ``method``, or a value is invalid.
    """
    kwargs = kwargs or {}
    if options is None:
        options = cls()
    elif not isinstance(options, cls):
        raise ParameterError(f"options for method {method!r} must be a {cls.__name__}, got {options!r}")
    check_keywords(method, kwargs, {f.name for f in dataclasses.fields(cls)})
    return dataclasses.replace(options, **kwargs) if kwargs else options
