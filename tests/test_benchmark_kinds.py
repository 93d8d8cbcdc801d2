"""The separability check of benchmarks/kinds.py: the tree it fits finds a split that is there, and no more."""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import kinds  # noqa: E402


def _rows(half, n, rng, corridor):
    """``n`` own-room rows of one half: width and doors drawn at random, the true kind from ``corridor``."""
    rows = []
    for _ in range(n):
        r = {"variant": "truth", "half": half, "area": float(rng.uniform(2, 20)), "width": float(rng.uniform(0.6, 4)),
             "doors": int(rng.integers(0, 6)), "cut": bool(rng.integers(0, 2)), "dead_ends": int(rng.integers(0, 3)),
             "widest_door": float(rng.uniform(0.7, 2.5)), "outside_doors": int(rng.integers(0, 2))}
        r["length"] = r["area"] / r["width"]
        r["truth"] = "corridor" if corridor(r) else "other"
        rows.append(r)
    return rows


def test_a_split_on_one_measure_is_found_and_carries_to_the_other_half():
    rng = np.random.default_rng(0)

    def rule(r):
        return r["width"] <= 1.5 and r["doors"] >= 3

    rows = _rows("training", 600, rng, rule) + _rows("held out", 600, rng, rule)
    (p1, r1), (p2, r2) = kinds.tree_ceiling(rows, kinds.MEASURES, 2)
    assert min(p1, r1, p2, r2) > 90.0


def test_a_measure_the_tree_is_not_given_cannot_be_learnt():
    rng = np.random.default_rng(1)

    def rule(r):  # the truth depends on the doors to the outside alone
        return r["outside_doors"] == 1

    rows = _rows("training", 600, rng, rule) + _rows("held out", 600, rng, rule)
    (_, _), (p_without, r_without) = kinds.tree_ceiling(rows, kinds.MEASURES, 4)
    (_, _), (p_with, r_with) = kinds.tree_ceiling(rows, kinds.MEASURES + (kinds.FRONT,), 4)
    assert min(p_with, r_with) > 99.0
    assert min(p_without, r_without) < 75.0


def test_mixed_rooms_and_segmented_rooms_are_left_out():
    rng = np.random.default_rng(2)
    rows = _rows("training", 300, rng, lambda r: r["doors"] >= 3) + _rows("held out", 300, rng, lambda r: r["doors"] >= 3)
    noise = [dict(r, truth="mixed") for r in rows[:50]] + [dict(r, variant="plan", truth="corridor") for r in rows[:50]]
    assert kinds.tree_ceiling(rows + noise, kinds.MEASURES, 2) == kinds.tree_ceiling(rows, kinds.MEASURES, 2)
