"""Invariants of segment() as property tests on generated floor plans.

Exact, for every generated map:

* every free cell is in exactly one room and only free cells are labelled
  (all methods in METHODS);
* the room graph matches the labels: one node per label 1..N with its cell
  count, and every door joins two distinct rooms that both touch the door
  segment (all methods);
* the same input gives the same output, IDs included (default method).

Measured for the default method (DEFAULT_METHOD; "paper" alike, numbers per
method in docs/errors.md), because its skeletons are
discretised on the pixel grid and are not exactly invariant under a 90°
rotation, a flip or a 2x upscaling (numbers in docs/errors.md):

* rotation / flip: exact (isomorphic room graph, same door count) on every
  hand-drawn map of tests/_testdata.py (areas within 2 %: a door gap's cells
  may go to the other room); on generated plans the room count stays within
  ±1 on furniture-free plans (hypothesis), and over a fixed sample of 80
  plans with furniture the graph was exact for 80/80 (rot90) and 80/80
  (flip) at commit b91fe65 (78/80 and 78/80 before clutter was looked
  through), rooms within ±1 80/80; the test requires >= 95 %;
* resolution (np.kron 2x, resolution halved): exact on the hand-drawn maps;
  on fixed samples of 80 plans the room count was the same for 74/80
  furniture-free and 73/80 furnished plans at b91fe65 (earlier 78/80 and
  69/80; required >= 90 % and >= 85 %), and whenever it is the same every
  room's area is within max(5 %, 0.3 m²) (measured worst 1.17 % = 0.070 m²).
"""

import numpy as np
import networkx as nx
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import _testdata as T
from topomap.io import from_array
from topomap.core.segmentation import DEFAULT_METHOD, METHODS, segment

SETTINGS = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])

_NR = np.array([-1, -1, -1, 0, 0, 1, 1, 1, 0])
_NC = np.array([-1, 0, 1, -1, 1, -1, 0, 1, 0])


# --------------------------------------------------------------------------
# Generated floor plans
# --------------------------------------------------------------------------

def floor_plan(rng: np.random.Generator, *, furniture: bool = True) -> np.ndarray:
    """A bool free mask: 1-3 x 1-2 rectangular rooms, outer wall 3-6 px, inner
    walls 3-5 px, a 0.7-1.1 m door in every wall between side-by-side rooms
    and in about half of the others, and up to 4 furniture blocks."""
    ow, iw = int(rng.integers(3, 7)), int(rng.integers(3, 6))
    ncols, nrows = int(rng.integers(1, 4)), int(rng.integers(1, 3))
    widths = [int(rng.integers(40, 81)) for _ in range(ncols)]
    heights = [int(rng.integers(40, 71)) for _ in range(nrows)]
    xs = np.concatenate([[ow], ow + np.cumsum([w + iw for w in widths])]).astype(int)
    ys = np.concatenate([[ow], ow + np.cumsum([h + iw for h in heights])]).astype(int)
    H, W = int(ys[-1] - iw + ow), int(xs[-1] - iw + ow)
    a = np.zeros((H, W), bool)
    for i in range(nrows):
        for j in range(ncols):
            a[ys[i]:ys[i] + heights[i], xs[j]:xs[j] + widths[j]] = True
    for i in range(nrows):
        for j in range(ncols - 1):
            dw = int(rng.integers(14, 23))
            r0 = ys[i] + int(rng.integers(0, heights[i] - dw + 1))
            c = xs[j] + widths[j]
            a[r0:r0 + dw, c:c + iw] = True
    for i in range(nrows - 1):
        for j in range(ncols):
            if rng.random() < 0.5:
                dw = int(rng.integers(14, 23))
                c0 = xs[j] + int(rng.integers(0, widths[j] - dw + 1))
                r = ys[i] + heights[i]
                a[r:r + iw, c0:c0 + dw] = True
    for _ in range(int(rng.integers(0, 5)) if furniture else 0):
        i, j = int(rng.integers(0, nrows)), int(rng.integers(0, ncols))
        fh, fw = int(rng.integers(3, 17)), int(rng.integers(3, 17))
        r0 = ys[i] + int(rng.integers(0, heights[i] - fh + 1))
        c0 = xs[j] + int(rng.integers(0, widths[j] - fw + 1))
        a[r0:r0 + fh, c0:c0 + fw] = False
    return a


plans = st.integers(0, 2**32 - 1).map(lambda s: floor_plan(np.random.default_rng(s)))
bare_plans = st.integers(0, 2**32 - 1).map(lambda s: floor_plan(np.random.default_rng(s), furniture=False))


def run(a, method=DEFAULT_METHOD, resolution=T.RES):
    return segment(from_array(np.ascontiguousarray(a), resolution=resolution), method=method)


# --------------------------------------------------------------------------
# Checks
# --------------------------------------------------------------------------

def check_labels(seg):
    lab, free = seg.labels, seg.grid.free
    assert lab.dtype == np.int32 and lab.shape == free.shape
    assert ((lab > 0) == free).all(), "a free cell without a room, or a room on a non-free cell"
    n = seg.n_rooms
    assert (lab >= 0).all()
    assert np.array_equal(np.unique(lab[free]), np.arange(1, n + 1)) if n else not free.any()


def check_graph(seg):
    lab = seg.labels
    G = seg.room_graph
    n = seg.n_rooms
    assert sorted(G.nodes) == list(range(1, n + 1))
    counts = np.bincount(lab.ravel(), minlength=n + 1)
    for i, d in G.nodes(data=True):
        assert d["cells"] == counts[i]
        assert d["area"] == pytest.approx(counts[i] * seg.grid.resolution ** 2)
    assert G.number_of_edges() == len(seg.doors)
    H, W = lab.shape
    from skimage.draw import line

    for door in seg.doors:
        a, b = door.rooms
        assert a != b and 1 <= a <= n and 1 <= b <= n
        assert G.has_edge(a, b, key=door.id)
        (r1, c1), (r2, c2) = door.p1, door.p2
        rr, cc = line(*(int(np.clip(round(v), 0, m - 1)) for v, m in ((r1, H), (c1, W), (r2, H), (c2, W))))
        near = lab[np.clip(rr[:, None] + _NR, 0, H - 1), np.clip(cc[:, None] + _NC, 0, W - 1)]
        assert a in near and b in near, f"door {door.id} does not touch rooms {a} and {b}"


def simple_graph(seg):
    """Room graph as a simple graph with door multiplicity as an edge attribute."""
    g = nx.Graph()
    g.add_nodes_from(seg.room_graph.nodes)
    for u, v in seg.room_graph.edges():
        w = g.get_edge_data(u, v, {"n": 0})["n"]
        g.add_edge(u, v, n=w + 1)
    return g


def isomorphic(s1, s2):
    return len(s1.doors) == len(s2.doors) and nx.is_isomorphic(
        simple_graph(s1), simple_graph(s2), edge_match=lambda x, y: x["n"] == y["n"])


TRANSFORMS = {
    "rot90": np.rot90,
    "rot180": lambda a: np.rot90(a, 2),
    "rot270": lambda a: np.rot90(a, 3),
    "flip_lr": np.fliplr,
    "flip_ud": np.flipud,
    "transpose": np.transpose,
}


def upscale(a):
    return np.kron(a, np.ones((2, 2), a.dtype))


def areas(seg):
    return sorted(d["area"] for _, d in seg.room_graph.nodes(data=True))


# --------------------------------------------------------------------------
# Exact invariants on generated maps
# --------------------------------------------------------------------------

@pytest.mark.parametrize("method", sorted(METHODS))
@SETTINGS
@given(a=plans)
def test_labels_and_graph_every_method(method, a):
    seg = run(a, method)
    check_labels(seg)
    check_graph(seg)


@SETTINGS
@given(a=plans)
def test_same_input_same_output(a):
    s1, s2 = run(a), run(a.copy())
    assert np.array_equal(s1.labels, s2.labels)
    assert [(d.id, d.rooms, d.p1, d.p2) for d in s1.doors] == [(d.id, d.rooms, d.p1, d.p2) for d in s2.doors]
    g1, g2 = s1.room_graph, s2.room_graph
    assert list(g1.nodes(data="cells")) == list(g2.nodes(data="cells"))
    assert list(g1.edges(keys=True)) == list(g2.edges(keys=True))


@SETTINGS
@given(a=bare_plans, t=st.sampled_from(sorted(TRANSFORMS)))
def test_rotation_keeps_room_count_within_one_on_bare_plans(a, t):
    s1, s2 = run(a), run(TRANSFORMS[t](a))
    check_labels(s2)
    assert abs(s1.n_rooms - s2.n_rooms) <= 1, (s1.n_rooms, s2.n_rooms)


@pytest.mark.xfail(strict=True, reason="a bare plan whose room count changes by 2 when it is flipped upside "
                                       "down (6 rooms, 4 flipped): the door decisions on the coarse skeleton grid "
                                       "depend on where the grid's cells fall; found by the property test above")
def test_rotation_known_case_flip_ud():
    a = floor_plan(np.random.default_rng(1359799), furniture=False)
    s1, s2 = run(a), run(TRANSFORMS["flip_ud"](a))
    assert abs(s1.n_rooms - s2.n_rooms) <= 1, (s1.n_rooms, s2.n_rooms)


# --------------------------------------------------------------------------
# Rotation, flip and resolution: exact on the hand-drawn maps
# --------------------------------------------------------------------------

HAND = [T.two_rooms, T.corridor_with_rooms, T.room_with_furniture, T.l_shaped_room,
        T.door_at_map_edge, T.gray_two_rooms_unknown_outside, T.one_room, T.disconnected_regions]


@pytest.mark.parametrize("t", sorted(TRANSFORMS))
@pytest.mark.parametrize("make", HAND, ids=lambda f: f.__name__)
def test_hand_maps_rotation_and_flip_exact(make, t):
    a = make().array
    s1, s2 = run(a), run(TRANSFORMS[t](a))
    assert isomorphic(s1, s2), (s1.n_rooms, len(s1.doors), s2.n_rooms, len(s2.doors))
    # the cells of a door gap may go to the other room: areas within 2 %
    assert areas(s2) == pytest.approx(areas(s1), rel=0.02)


@pytest.mark.parametrize("make", HAND, ids=lambda f: f.__name__)
def test_hand_maps_resolution_exact(make):
    a = make().array
    s1, s2 = run(a), run(upscale(a), resolution=T.RES / 2)
    assert isomorphic(s1, s2), (s1.n_rooms, len(s1.doors), s2.n_rooms, len(s2.doors))
    assert areas(s2) == pytest.approx(areas(s1), rel=0.02)
    for d1, d2 in zip(sorted(s1.doors, key=lambda d: d.midpoint), sorted(s2.doors, key=lambda d: d.midpoint)):
        assert np.hypot(d1.midpoint[0] - d2.midpoint[0], d1.midpoint[1] - d2.midpoint[1]) <= 0.1


# --------------------------------------------------------------------------
# Rotation, flip and resolution: measured on a fixed sample of generated plans
# --------------------------------------------------------------------------

SAMPLE = 80
MIN_RATE = 0.95


@pytest.fixture(scope="module")
def sample():
    return [floor_plan(np.random.default_rng(1000 + i)) for i in range(SAMPLE)]


def test_rotation_flip_rate(sample):
    ok = {"rot90": 0, "flip_lr": 0}
    within1 = dict(ok)
    for a in sample:
        s1 = run(a)
        for t in ok:
            s2 = run(TRANSFORMS[t](a))
            ok[t] += isomorphic(s1, s2)
            within1[t] += abs(s1.n_rooms - s2.n_rooms) <= 1
    print(f"\nrotation/flip over {SAMPLE} plans: exact {ok}, rooms within ±1 {within1}")
    for t in ok:
        assert ok[t] >= MIN_RATE * SAMPLE, (t, ok[t])


@pytest.fixture(scope="module")
def bare_sample():
    return [floor_plan(np.random.default_rng(1000 + i), furniture=False) for i in range(SAMPLE)]


#: Lowest share of plans whose room count survives the 2x upscaling.
#: Measured at b91fe65: 74/80 furniture-free plans, 73/80 plans with furniture.
RES_MIN_RATE = {"bare": 0.90, "furnished": 0.85}


@pytest.mark.parametrize("which", ["bare", "furnished"])
def test_resolution_rate(which, request):
    plans_ = request.getfixturevalue("bare_sample" if which == "bare" else "sample")
    same, worst_rel, worst_abs = 0, 0.0, 0.0
    for a in plans_:
        s1, s2 = run(a), run(upscale(a), resolution=T.RES / 2)
        check_labels(s2)
        check_graph(s2)
        if s1.n_rooms == s2.n_rooms:
            same += 1
            for x, y in zip(areas(s1), areas(s2)):
                worst_rel = max(worst_rel, abs(x - y) / x)
                worst_abs = max(worst_abs, abs(x - y))
                # a door gap (<= 1.1 m x 0.25 m) may change rooms
                assert abs(x - y) <= max(0.05 * x, 0.3), (x, y)
    print(f"\nresolution 2x over {SAMPLE} {which} plans: same room count {same}, "
          f"worst area change {worst_rel:.2%} / {worst_abs:.3f} m2")
    assert same >= RES_MIN_RATE[which] * SAMPLE, same
