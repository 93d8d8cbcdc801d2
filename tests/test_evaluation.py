"""Tests of topomap.bench.evaluation on small hand-made label images.

Every expected value is worked out by hand in the comments.
"""

import math

import numpy as np
import pytest

from topomap.errors import ParameterError
from topomap.bench.evaluation import (
    PROTOCOLS,
    ceiling,
    door_distance_matrix,
    evaluate,
    gt_doors_from_images,
    gt_rooms_from_image,
    points_to_segment_distance,
    room_adjacency_from_doors,
    score_adjacency,
    score_doors,
    score_segmentation,
    summarize,
    true_adjacency,
)


def two_rooms():
    """20 x 40 grid: true room 1 = columns 0..19, room 2 = columns 20..39 (400 px each)."""
    gt = np.zeros((20, 40), np.int32)
    gt[:, :20] = 1
    gt[:, 20:] = 2
    return gt


# --------------------------------------------------------------------------
# room metric
# --------------------------------------------------------------------------

def _split_room_1():
    # room 1 (20x20 = 400 px) split into a top and bottom half (200 px each),
    # room 2 predicted exactly: precision: every segment lies inside one room
    # -> 1, 1, 1 -> P = 1. Recall: room 1 best segment 200/400 = 0.5,
    # room 2 400/400 = 1 -> R = 0.75.
    lab = np.zeros((20, 40), np.int32)
    lab[:10, :20] = 1
    lab[10:, :20] = 2
    lab[:, 20:] = 3
    return lab


CASES = [
    # name, labels, gt, expected (P, R, n_segments, n_rooms)
    ("identical", two_rooms(), two_rooms(), (1.0, 1.0, 2, 2)),
    # relabelled with other ids: the metric does not care about the numbers
    ("renumbered", two_rooms() * 7 + 3, two_rooms(), (1.0, 1.0, 2, 2)),
    ("split", _split_room_1(), two_rooms(), (1.0, 0.75, 3, 2)),
    # both rooms merged into one segment of 800 px: P = max(400, 400)/800 = 0.5;
    # each room is fully inside it: R = (1 + 1)/2 = 1.
    ("merged", np.ones((20, 40), np.int32), two_rooms(), (0.5, 1.0, 1, 2)),
]


@pytest.mark.parametrize("name,labels,gt,expected", CASES, ids=[c[0] for c in CASES])
def test_score_segmentation_cases(name, labels, gt, expected):
    s = score_segmentation(labels, gt)
    p, r, ns, nr = expected
    assert s["precision"] == pytest.approx(p)
    assert s["recall"] == pytest.approx(r)
    assert s["n_segments"] == ns
    assert s["n_rooms"] == nr
    assert s["room_count_error"] == ns - nr


def test_one_room_split_in_two_halves():
    # a single 20x20 true room split into two 20x10 halves (200 px > 100 each):
    # P = (200/200 + 200/200)/2 = 1; R = max(200, 200)/400 = 0.5.
    gt = np.ones((20, 20), np.int32)
    lab = np.ones((20, 20), np.int32)
    lab[:, 10:] = 2
    s = score_segmentation(lab, gt)
    assert (s["precision"], s["recall"]) == (1.0, 0.5)
    assert s["room_count_error"] == 1


def test_tiny_segments_ignored():
    # identical prediction plus a 10x10 = 100 px segment (<= 100: ignored)
    # cut out of room 1. Room 1 now has best overlap 300/400 (|G| still counts
    # the 100 cells labelled by the ignored segment) -> R = (0.75 + 1)/2.
    # Precision over the 2 kept segments: 300/300 and 400/400 -> 1.
    lab = two_rooms()
    lab[:10, :10] = 9
    s = score_segmentation(lab, two_rooms())
    assert s["n_segments"] == 2
    assert s["precision"] == 1.0
    assert s["recall"] == pytest.approx(0.875)
    # with min_size = 99 the 100 px segment counts: P = 1, n_segments = 3
    s = score_segmentation(lab, two_rooms(), min_size=99)
    assert s["n_segments"] == 3 and s["precision"] == 1.0


def test_tiny_rooms_ignored():
    # a true room of 100 px (<= 100) is not scored, so a segment covering it
    # and room 1 loses precision but no room loses recall.
    gt = np.zeros((20, 50), np.int32)
    gt[:, :20] = 1
    gt[:, 20:40] = 2
    gt[:10, 40:50] = 3  # 100 px: ignored
    lab = gt.copy()
    lab[lab == 3] = 2   # segment 2 = room 2 (400) + 100 cells of the tiny room
    s = score_segmentation(lab, gt)
    assert s["n_rooms"] == 2
    # P = (400/400 + 400/500)/2 = 0.9 ; R = 1
    assert s["precision"] == pytest.approx(0.9)
    assert s["recall"] == 1.0


def test_macro_differs_from_micro():
    # true rooms: A = 20x30 (600 px, columns 0..29), B = 20x10 (200 px, cols 30..39).
    # prediction: segment 1 = cols 0..14 (300 px, in A), segment 2 = cols 15..39
    # (500 px: 300 in A, 200 in B).
    # micro P = (300/300 + 300/500)/2 = (1 + 0.6)/2 = 0.8
    # macro P = (300 + 300)/(300 + 500) = 0.75
    # micro R = (300/600 + 200/200)/2 = 0.75 ; macro R = (300 + 200)/800 = 0.625
    gt = np.zeros((20, 40), np.int32)
    gt[:, :30] = 1
    gt[:, 30:] = 2
    lab = np.zeros((20, 40), np.int32)
    lab[:, :15] = 1
    lab[:, 15:] = 2
    s = score_segmentation(lab, gt)
    assert s["precision"] == pytest.approx(0.8)
    assert s["precision_macro"] == pytest.approx(0.75)
    assert s["recall"] == pytest.approx(0.75)
    assert s["recall_macro"] == pytest.approx(0.625)


def test_scored_mask_restricts_sizes():
    # Only the top 15 rows are scored. Room 1 restricted: 15x20 = 300 px.
    # The segment spills over 5 unscored rows of room 2: those do not count.
    gt = two_rooms()
    lab = gt.copy()
    lab[15:, 20:] = 1
    scored = np.zeros(gt.shape, bool)
    scored[:15] = True
    s = score_segmentation(lab, gt, scored=scored, protocol="free-cells")
    assert (s["precision"], s["recall"]) == (1.0, 1.0)
    # original protocol: the rooms stay whole (400 px each), the segments are
    # the scored 300 px: P = (1 + 1)/2, R = (300/400 + 300/400)/2 = 0.75
    s = score_segmentation(lab, gt, scored=scored, protocol="original")
    assert s["precision"] == 1.0 and s["recall"] == pytest.approx(0.75)
    assert s == score_segmentation(lab, gt, scored=scored)  # the default
    # unscored: segment 1 = 400 + 100 = 500 px, P = (400/500 + 1)/2 = 0.9,
    # room 2 best overlap 300/400 -> R = (1 + 0.75)/2 = 0.875
    s = score_segmentation(lab, gt)
    assert s["precision"] == pytest.approx(0.9)
    assert s["recall"] == pytest.approx(0.875)


def test_original_protocol_keeps_furnished_rooms_whole():
    # Room 1 has a 10 x 10 block of furniture (100 cells) the method is not
    # given; the method labels the rest of room 1 and room 2 exactly.
    gt = two_rooms()
    scored = np.ones(gt.shape, bool)
    scored[5:15, 5:15] = False
    lab = np.where(scored, gt, 0)
    orig = score_segmentation(lab, gt, scored=scored, protocol="original")
    free = score_segmentation(lab, gt, scored=scored, protocol="free-cells")
    # original: R = (300/400 + 400/400)/2 -- the furniture stays in room 1
    assert orig["precision"] == 1.0 and orig["recall"] == pytest.approx((300 / 400 + 1) / 2)
    assert orig["recall_macro"] == pytest.approx(700 / 800)
    assert free["precision"] == 1.0 and free["recall"] == 1.0
    # labels on cells the method was not given are dropped, not counted
    lab2 = gt.copy()
    assert score_segmentation(lab2, gt, scored=scored, protocol="original") == orig
    # that is the ceiling: the ground truth itself scores the same
    c = ceiling(gt, scored=scored)
    assert c["original"] == orig and c["free-cells"] == free
    assert set(c) == set(PROTOCOLS) == {"original", "free-cells"}


def test_original_protocol_size_filter_counts_whole_rooms():
    # a 12 x 10 room (120 cells) of which 30 cells are scored: kept whole
    # under the original protocol, dropped (30 <= 100) under free-cells
    gt = np.zeros((12, 30), np.int32)
    gt[:, :10] = 1
    gt[:, 10:] = 2
    scored = np.ones(gt.shape, bool)
    scored[3:, :10] = False
    lab = np.where(scored, gt, 0)
    assert score_segmentation(lab, gt, scored=scored)["n_rooms"] == 2
    assert score_segmentation(lab, gt, scored=scored, protocol="free-cells")["n_rooms"] == 1


def test_unknown_protocol_raises():
    with pytest.raises(ParameterError, match="protocol"):
        score_segmentation(two_rooms(), two_rooms(), protocol="bormann")


def test_segment_cells_outside_rooms_count_in_size():
    # Two 20x20 rooms with a 20x2 unlabelled GT wall band between them that is
    # scored (e.g. a door line). Segment 1 covers room 1 and the band:
    # |S| = 440, best overlap 400 -> 400/440; segment 2 = room 2 -> 1.
    gt = np.zeros((20, 42), np.int32)
    gt[:, :20] = 1
    gt[:, 22:] = 2
    lab = np.zeros_like(gt)
    lab[:, :22] = 1
    lab[:, 22:] = 2
    s = score_segmentation(lab, gt)
    assert s["precision"] == pytest.approx((400 / 440 + 1) / 2)
    assert s["recall"] == 1.0


def test_unlabelled_room_cells_lower_recall():
    # room 1 only half labelled (other half label 0): R = (0.5 + 1)/2
    lab = two_rooms()
    lab[10:, :20] = 0
    s = score_segmentation(lab, two_rooms())
    assert s["recall"] == pytest.approx(0.75)
    assert s["precision"] == 1.0


@pytest.mark.parametrize("labels,gt,expected", [
    (np.zeros((5, 5), int), np.zeros((5, 5), int), 1.0),   # nothing vs nothing
    (np.zeros((20, 20), int), np.ones((20, 20), int), 0.0),  # nothing predicted
    (np.ones((20, 20), int), np.zeros((20, 20), int), 0.0),  # no true rooms
])
def test_degenerate(labels, gt, expected):
    s = score_segmentation(labels, gt)
    assert s["precision"] == expected and s["recall"] == expected


def test_all_unscored():
    none = np.zeros((20, 40), bool)
    s = score_segmentation(two_rooms(), two_rooms(), scored=none, protocol="free-cells")
    assert s["n_segments"] == 0 and s["n_rooms"] == 0 and s["precision"] == 1.0
    # the original protocol keeps the rooms: nothing labels them
    s = score_segmentation(two_rooms(), two_rooms(), scored=none)
    assert s["n_segments"] == 0 and s["n_rooms"] == 2 and s["recall"] == 0.0


def test_shape_mismatch_raises():
    with pytest.raises(ParameterError):
        score_segmentation(np.zeros((3, 3)), np.zeros((3, 4)))
    with pytest.raises(ValueError):
        score_segmentation(np.zeros((3, 3)), np.zeros((3, 3)), scored=np.ones((2, 2), bool))


def test_large_label_count_is_fast():
    # 1000 x 1000 grid with 10000 tiny segments (10x10, all ignored) and
    # 4 rooms: exercises the sparse table.
    lab = (np.arange(1000)[:, None] // 10) * 100 + np.arange(1000)[None, :] // 10 + 1
    gt = (np.arange(1000)[:, None] // 500) * 2 + np.arange(1000)[None, :] // 500 + 1
    s = score_segmentation(lab, gt)
    assert s["n_segments"] == 0 and s["n_rooms"] == 4
    s = score_segmentation(lab, gt, min_size=0)
    assert s["n_segments"] == 10000 and s["precision"] == 1.0
    assert s["recall"] == pytest.approx(100 / 250000)


# --------------------------------------------------------------------------
# ground truth from images
# --------------------------------------------------------------------------

def drawn_gt():
    """A 30 x 62 drawing: walls, two 20x25 rooms joined by a doorway.

    Map: border wall (rows 0, 29; cols 0, 61) and an inner wall at columns
    30..31 with a doorway at rows 10..17 (8 rows). GT: the same walls plus a
    black door line across the doorway (rows 10..17, cols 30..31: 16 px),
    plus one white speckle pixel inside the wall and one 2 px black speckle
    in room 1.
    """
    m = np.full((30, 62), 255, np.uint8)
    m[[0, -1], :] = 0
    m[:, [0, -1]] = 0
    m[:, 30:32] = 0
    m[10:18, 30:32] = 255            # doorway, free in the map
    g = m.copy()
    g[10:18, 30:32] = 0              # door line in the ground truth
    g[3, 5:7] = 0                    # 2 px black speckle inside room 1
    g[0, 10] = 255                   # 1 px white speckle on the wall
    return m, g


def test_gt_rooms_from_image():
    _, g = drawn_gt()
    rooms = gt_rooms_from_image(g)
    # two rooms of 28 rows x 29 cols = 812 px, minus the 2 px speckle in room 1;
    # the white wall pixel (0, 10) touches room 1 diagonally/vertically, so it
    # joins room 1 (8-connected): 812 - 2 + 1 = 811.
    assert rooms.dtype == np.int32
    assert rooms.max() == 2
    sizes = sorted(np.bincount(rooms.ravel())[1:].tolist())
    assert sizes == [811, 812]
    # with min_size above both sizes nothing is left
    assert gt_rooms_from_image(g, min_size=812).max() == 0


def test_gt_rooms_drop_small_components():
    g = np.zeros((30, 30), np.uint8)
    g[1:11, 1:11] = 255     # 100 px: dropped (<= 100)
    g[15:26, 15:26] = 255   # 121 px: kept
    rooms = gt_rooms_from_image(g)
    assert rooms.max() == 1 and (rooms == 1).sum() == 121


def test_gt_doors_from_images():
    m, g = drawn_gt()
    doors = gt_doors_from_images(m, g)
    # the 2 px speckle (free in map, black in GT) is dropped as speckle,
    # the 16 px door line is kept
    assert len(doors) == 1
    d = doors[0]
    assert d.shape == (16, 2)
    assert set(map(tuple, d.tolist())) == {(r, c) for r in range(10, 18) for c in (30, 31)}
    # keep everything with min_size=1 and min_rooms=0: door + speckle
    assert len(gt_doors_from_images(m, g, min_size=1, min_rooms=0)) == 2
    # the speckle touches only one room: min_rooms=2 drops it even at min_size=1
    assert len(gt_doors_from_images(m, g, min_size=1)) == 1


def test_true_adjacency():
    m, g = drawn_gt()
    rooms = gt_rooms_from_image(g)
    doors = gt_doors_from_images(m, g)
    assert true_adjacency(rooms, doors) == {(1, 2)}
    assert true_adjacency(rooms, []) == set()


# --------------------------------------------------------------------------
# doors
# --------------------------------------------------------------------------

def test_points_to_segment_distance():
    p = np.array([[0, 0], [0, 5], [3, 10], [0, -4], [-3, 14]])
    d = points_to_segment_distance(p, (0, 0), (0, 10))
    # on the segment: 0, 0; beside the end (10): 3; before start: 4;
    # beyond the end: hypot(3, 4) = 5
    np.testing.assert_allclose(d, [0, 0, 3, 4, 5])
    # degenerate segment = a point
    np.testing.assert_allclose(points_to_segment_distance([[3, 4]], (0, 0), (0, 0)), [5])


def vertical_door(col, r0=10, r1=18):
    """A true door: 2 px wide line, rows r0..r1-1, columns col, col+1."""
    return np.array([(r, c) for r in range(r0, r1) for c in (col, col + 1)])


RES = 0.05  # m per pixel: 0.5 m = 10 px


def test_door_within_tolerance_matches():
    true = [vertical_door(30)]
    # the segment lies on column 30.5 (the line's middle): median distance 0.5 px
    s = score_doors([((10, 30.5), (17, 30.5))], true, resolution=RES)
    assert (s["tp"], s["fp"], s["fn"]) == (1, 0, 0)
    assert s["precision"] == s["recall"] == s["f1"] == 1.0
    # shifted by 9 px (0.45 m) sideways: cells at 8.5, 9.5 px -> median
    # 9 px = 0.45 m <= 0.5 m: still a match
    s = score_doors([((10, 39.5), (17, 39.5))], true, resolution=RES)
    assert s["tp"] == 1 and s["matches"][0][2] == pytest.approx(0.45)


def test_door_outside_tolerance():
    true = [vertical_door(30)]
    # shifted by 12 px: cells at 11.5, 12.5 px, median 12 px = 0.6 m > 0.5 m
    s = score_doors([((10, 42.5), (17, 42.5))], true, resolution=RES)
    assert (s["tp"], s["fp"], s["fn"]) == (0, 1, 1)
    assert s["precision"] == 0.0 and s["recall"] == 0.0 and s["f1"] == 0.0
    # a wider tolerance (0.7 m) accepts it
    assert score_doors([((10, 42.5), (17, 42.5))], true, resolution=RES, tol_m=0.7)["tp"] == 1


def test_missed_door():
    true = [vertical_door(30), vertical_door(60)]
    s = score_doors([((10, 30.5), (17, 30.5))], true, resolution=RES)
    # tp 1, fp 0, fn 1: P = 1, R = 0.5, F1 = 2 * 0.5 / 1.5 = 2/3
    assert (s["tp"], s["fp"], s["fn"]) == (1, 0, 1)
    assert s["precision"] == 1.0 and s["recall"] == 0.5
    assert s["f1"] == pytest.approx(2 / 3)


def test_spurious_door():
    true = [vertical_door(30)]
    pred = [((10, 30.5), (17, 30.5)), ((50, 80), (50, 90))]
    s = score_doors(pred, true, resolution=RES)
    # tp 1, fp 1: P = 0.5, R = 1, F1 = 2/3
    assert (s["tp"], s["fp"], s["fn"]) == (1, 1, 0)
    assert s["precision"] == 0.5 and s["recall"] == 1.0
    assert s["f1"] == pytest.approx(2 / 3)


def test_door_matching_is_one_to_one_and_greedy_closest_first():
    # two detections near one true door: only the closer one matches
    true = [vertical_door(30)]
    pred = [((10, 35.5), (17, 35.5)), ((10, 30.5), (17, 30.5))]
    s = score_doors(pred, true, resolution=RES)
    assert s["tp"] == 1 and s["fp"] == 1
    assert s["matches"][0][:2] == (1, 0)
    # two true doors 6 px apart, one detection between but closer to door B:
    # it takes B; A is missed
    true = [vertical_door(30), vertical_door(36)]
    s = score_doors([((10, 34.5), (17, 34.5))], true, resolution=RES)
    assert s["matches"][0][:2] == (0, 1) and s["fn"] == 1


@pytest.mark.parametrize("pred,true,expected", [
    ([], [], (1.0, 1.0, 1.0)),
    ([], [vertical_door(30)], (1.0, 0.0, 0.0)),
    ([((0, 0), (0, 5))], [], (0.0, 1.0, 0.0)),
])
def test_door_empty_sets(pred, true, expected):
    s = score_doors(pred, true, resolution=RES)
    assert (s["precision"], s["recall"], s["f1"]) == expected


def test_door_distance_matrix_shape_and_units():
    true = [vertical_door(30), vertical_door(60)]
    D = door_distance_matrix([((10, 30.5), (17, 30.5))], true, resolution=0.1)
    assert D.shape == (1, 2)
    assert D[0, 0] == pytest.approx(0.05)          # 0.5 px * 0.1 m
    assert D[0, 1] == pytest.approx(3.0)           # 30 px (median of 29.5, 30.5)


def test_door_bad_input():
    with pytest.raises(ParameterError):
        score_doors([((0, 0, 0), (1, 1, 1))], [], resolution=RES)
    with pytest.raises(ParameterError):
        score_doors([], [], resolution=0)


# --------------------------------------------------------------------------
# adjacency
# --------------------------------------------------------------------------

def three_rooms_in_a_row():
    """20 x 60: true rooms 1, 2, 3 of 20x20; doors between 1-2 and 2-3."""
    gt = np.zeros((20, 60), np.int32)
    gt[:, :20] = 1
    gt[:, 20:40] = 2
    gt[:, 40:] = 3
    return gt


def test_room_adjacency_from_doors():
    gt = three_rooms_in_a_row()
    # a door segment on the boundary column 19/20 touches rooms 1 and 2
    edges = room_adjacency_from_doors(gt, [((5, 19.6), (14, 19.6))])
    assert edges == {(1, 2)}
    # a segment inside room 3 touches only room 3: no edge
    assert room_adjacency_from_doors(gt, [((5, 50), (14, 50))]) == set()
    # a segment off the image is ignored
    assert room_adjacency_from_doors(gt, [((-10, -10), (-5, -5))]) == set()


def test_score_adjacency_perfect():
    gt = three_rooms_in_a_row()
    s = score_adjacency(gt, gt, {(1, 2), (2, 3)}, {(1, 2), (3, 2)})
    assert (s["precision"], s["recall"], s["f1"]) == (1.0, 1.0, 1.0)


def test_score_adjacency_oversegmented_and_spurious():
    gt = three_rooms_in_a_row()
    # prediction: room 2 split in two segments 5 and 6 (top / bottom, 200 px
    # each), joined by a (spurious) door -> self-loop (2, 2), dropped.
    # Edges: (1, 5) -> (1, 2) correct; (6, 3) -> (2, 3) correct;
    # (1, 3) -> wrong (rooms 1 and 3 share no door).
    lab = gt.copy()
    lab[:10, 20:40] = 5
    lab[10:, 20:40] = 6
    pred = {(1, 5), (5, 6), (6, 3), (1, 3)}
    s = score_adjacency(lab, gt, pred, {(1, 2), (2, 3)})
    assert s["mapping"] == {1: 1, 3: 3, 5: 2, 6: 2}
    # mapped edges {(1,2), (2,3), (1,3)}: tp 2, fp 1, fn 0
    assert (s["tp"], s["fp"], s["fn"]) == (2, 1, 0)
    assert s["precision"] == pytest.approx(2 / 3) and s["recall"] == 1.0


def test_score_adjacency_missed_edge_and_unmapped_room():
    gt = three_rooms_in_a_row()
    lab = gt.copy()
    lab[:, 40:] = 0         # room 3 left unlabelled
    lab[0:5, 0:5] = 9       # 25 px segment: below min_size, unmapped
    s = score_adjacency(lab, gt, {(1, 2), (2, 9)}, {(1, 2), (2, 3)})
    # (2, 9): 9 unmapped, dropped; mapped {(1, 2)}: tp 1, fp 0, fn 1
    assert (s["tp"], s["fp"], s["fn"]) == (1, 0, 1)
    assert s["precision"] == 1.0 and s["recall"] == 0.5


# --------------------------------------------------------------------------
# whole map
# --------------------------------------------------------------------------

def test_evaluate_on_drawn_map():
    m, g = drawn_gt()
    # a perfect prediction that fills all free cells: rooms split at column 30.5
    lab = np.zeros(m.shape, np.int32)
    lab[:, :31] = 1
    lab[:, 31:] = 2
    lab[m < 250] = 0
    out = evaluate(lab, m, g, pred_doors=[((10, 30.5), (17, 30.5))])
    assert out["recall_free"] == 1.0
    # original protocol: room 1 keeps its white wall pixel (0, 10), which is
    # not free in the map, so no method labels it: R = (810/811 + 1)/2,
    # exactly the ceiling
    assert out["recall"] == pytest.approx((810 / 811 + 1) / 2)
    assert out["ceiling_recall"] == out["recall"] and out["ceiling_precision"] == 1.0
    assert out["ceiling_recall_free"] == 1.0 == out["ceiling_precision_free"]
    assert out["n_true_rooms"] == 2 and out["n_segments"] == 2
    # segment 1: 812 room-1 cells... minus nothing: 811 room cells + 2 speckle
    # cells + 8 door cells (col 30) + wall speckle? (0, 10) is a wall in the map
    # -> not scored. |S1| = 812 + 8 = 820, overlap = 812 - 2 = 810 (speckle is
    # black in GT) -> 810/820; |S2| = 812 + 8, overlap 812 -> 812/820
    assert out["precision"] == pytest.approx((810 / 820 + 812 / 820) / 2)
    assert out["precision_free"] == out["precision"]
    # the same scores from a label image and an explicit scored mask
    gt = gt_rooms_from_image(g)
    out2 = evaluate(lab, m, None, gt_rooms=gt, scored=m >= 250)
    assert {k: out[k] for k in out2} == out2 and "door_f1" not in out2
    assert out["door_f1"] == 1.0 and out["adjacency_f1"] == 1.0
    assert 0 < out["f1"] < 1


# --------------------------------------------------------------------------
# summarize
# --------------------------------------------------------------------------

def test_summarize():
    rows = [{"name": "a", "precision": 1.0, "n": 2, "ok": True},
            {"name": "b", "precision": 0.5, "n": 4, "ok": False},
            {"name": "c", "precision": 0.0, "n": float("nan")}]
    s = summarize(rows)
    assert set(s) == {"precision", "n"}            # strings and bools skipped
    assert s["precision"]["mean"] == pytest.approx(0.5)
    assert s["precision"]["sd"] == pytest.approx(0.5)   # sample sd of 1, .5, 0
    assert s["precision"]["median"] == 0.5
    assert s["precision"]["n"] == 3
    # NaN left out: n over 2 and 4
    assert s["n"]["n"] == 2 and s["n"]["mean"] == 3.0
    assert s["n"]["sd"] == pytest.approx(math.sqrt(2))
    pop = summarize(rows, keys=["precision"], ddof=0)
    assert pop["precision"]["sd"] == pytest.approx(math.sqrt(1 / 6))
    one = summarize([{"x": 1.0}])
    assert one["x"]["mean"] == 1.0 and math.isnan(one["x"]["sd"])
    assert summarize([], keys=["x"])["x"]["n"] == 0
