"""Door-finding building blocks of the default method (topomap.core.doors)."""

import cv2
import numpy as np
import pytest

from topomap.core import doors as D
from topomap.core import skeleton as S
from topomap._fast import edt


def _map():
    rng = np.random.default_rng(1)
    free = np.ones((120, 150), bool)
    free[40:60, :70] = False
    free[:, 100:104] = False
    free[rng.random(free.shape) > 0.97] = False
    return free


@pytest.mark.parametrize("radius,look", [(5, 1), (12, 3), (20, 6)])
def test_protrusion_at_equals_whole_map_filter(radius, look):
    free = _map()
    pts = [np.array(p, float) for p in [(50, 69), (0, 101), (119, 149), (45.3, 30.7), (10.6, 99.5)]]
    whole = D.protrusion(free, radius)
    whole = cv2.dilate(np.where(free, 0, whole).astype(np.float32), np.ones((2 * look + 1,) * 2, np.uint8))
    expect = [whole[int(round(p[0])), int(round(p[1]))] for p in pts]
    np.testing.assert_allclose(D.protrusion_at(free, pts, radius, look), expect, atol=1e-6)


def test_protrusion_values_on_simple_shapes():
    free = np.ones((81, 81), bool)
    free[40:, :] = False  # straight wall: half the disk is free
    assert D.protrusion(free, 10)[40, 40] == pytest.approx(0.5, abs=0.05)
    free = np.ones((81, 81), bool)
    free[40:, 40:] = False  # convex right-angled corner: three quarters free
    assert D.protrusion(free, 10)[40, 40] == pytest.approx(0.75, abs=0.05)


def _two_rooms_with_door(door_px=18):
    """Two 3 m rooms, a 0.2 m wall, a door of ``door_px`` cells (0.05 m/px)."""
    free = np.zeros((70, 134), bool)
    free[5:65, 5:65] = True
    free[5:65, 69:129] = True
    top = 35 - door_px // 2
    free[top:top + door_px, 65:69] = True
    return free


def test_passage_minima_finds_the_door_and_its_posts():
    free = _two_rooms_with_door()
    G = S.skeleton_graph(S.skeletonize(free), radius=edt(free), resolution=0.05)
    cands = D.passage_minima(G, window_px=10, rise_px=3, reach_px=30)
    assert len(cands) == 1
    D.nearest_wall_points(cands, ~free, max_px=40, depth_px=4)
    c = cands[0]
    rows = sorted([c.ip1[0], c.ip2[0]])
    # the posts are the wall ends above and below the 18-cell gap
    assert rows[0] == pytest.approx(25, abs=1) and rows[1] == pytest.approx(44, abs=1)
    # and the door line runs through the middle of the 4-cell wall
    assert (c.ip1[1] + c.ip2[1]) / 2 == pytest.approx(66.5, abs=1.0)


def test_accumulate_runs_is_each_run_on_its_own():
    """Running sums and maxima of runs laid end to end equal, bit for bit, those of each run alone."""
    rng = np.random.default_rng(3)
    n = np.array([0, 1, 2, 3, 7, 0, 64, 65, 5, 300, 1])
    x = rng.random(int(n.sum())) * 10.0 ** rng.integers(-3, 4, int(n.sum()))
    start = np.cumsum(n) - n
    for ufunc in (np.add, np.maximum):
        got = D._accumulate_runs(ufunc, x, n)
        for s, m in zip(start, n):
            assert np.array_equal(got[s:s + m], ufunc.accumulate(x[s:s + m]))


def test_accumulate_runs_in_groups_is_each_run_on_its_own():
    """Runs too unequal to pad to the longest are grouped by length: the same values."""
    rng = np.random.default_rng(4)
    n = np.r_[rng.integers(0, 9, 400), 6000, 3, 1500]
    x = rng.random(int(n.sum())) * 10.0 ** rng.integers(-3, 4, int(n.sum()))
    got = D._accumulate_runs(np.add, x, n)
    for s, m in zip(np.cumsum(n) - n, n):
        assert np.array_equal(got[s:s + m], np.add.accumulate(x[s:s + m]))


def test_running_max_is_each_run_on_its_own():
    """Running maxima on ranks, forwards and backwards, equal those of each run alone (ties included)."""
    rng = np.random.default_rng(5)
    n = np.array([1, 2, 0, 5, 40, 1, 300, 7])
    x = rng.integers(0, 20, int(n.sum())) / 7.0
    start = np.cumsum(n) - n
    run = np.repeat(np.arange(n.size), n)
    back = start[run] + np.repeat(start + n - 1, n) - np.arange(x.size)
    fwd, bwd = D._running_max(x, run, back)
    for s, m in zip(start, n):
        assert np.array_equal(fwd[s:s + m], np.maximum.accumulate(x[s:s + m]))
        assert np.array_equal(bwd[s:s + m], np.maximum.accumulate(x[s:s + m][::-1]))


def test_uniform_corridor_has_no_bottleneck():
    free = np.zeros((30, 200), bool)
    free[5:25, 5:195] = True
    G = S.skeleton_graph(S.skeletonize(free), radius=edt(free), resolution=0.05)
    assert D.passage_minima(G, window_px=10, rise_px=3, reach_px=30) == []


def test_unknown_margin_does_not_change_the_result():
    """The default method works on the free space's bounding box; a wide
    unknown margin around the map must not change rooms, doors or world
    coordinates."""
    from topomap.io.example import example_map_path
    from topomap.io import UNKNOWN, OccupancyGrid, load_map
    from topomap.core.segmentation import segment

    g = load_map(example_map_path())
    pad = 64
    cells = np.pad(g.cells, pad, constant_values=UNKNOWN)
    ox, oy, yaw = g.origin
    big = OccupancyGrid(cells, g.resolution, (ox - pad * g.resolution, oy - pad * g.resolution, yaw))
    a, b = segment(g), segment(big)
    np.testing.assert_array_equal(b.labels[pad:-pad, pad:-pad], a.labels)
    assert len(a.doors) == len(b.doors)
    for da, db in zip(a.doors, b.doors):
        assert db.xy1 == pytest.approx(da.xy1) and db.xy2 == pytest.approx(da.xy2)
        assert db.p1 == pytest.approx((da.p1[0] + pad, da.p1[1] + pad))
    na = a.free_graph.nodes[0]
    nb = b.free_graph.nodes[0]
    assert nb["pixel"] == (na["pixel"][0] + pad, na["pixel"][1] + pad)
    assert (nb["x"], nb["y"]) == pytest.approx((na["x"], na["y"]))


def test_a_door_needs_a_laser_hit_at_one_post_at_least():
    from topomap.core.doors import UNEXPLORED_POSTS, Candidate, seen_posts

    seen = np.zeros((20, 20), bool)
    seen[5, 2] = True                                  # a hit at the first door's upper post
    a = Candidate(edge=None, centroid=np.array([5.0, 5.0]), direction=np.array([0.0, 1.0]), radius=3.0,
                  ip1=np.array([5.0, 2.0]), ip2=np.array([5.0, 8.0]))
    b = Candidate(edge=None, centroid=np.array([12.0, 5.0]), direction=np.array([0.0, 1.0]), radius=3.0,
                  ip1=np.array([12.0, 2.0]), ip2=np.array([12.0, 8.0]))
    kept = seen_posts([(0.3, a), (0.3, b)], seen)
    assert [c for _, c in kept] == [a]
    assert b.status == UNEXPLORED_POSTS


def test_posts_on_unexplored_edges_only_on_maps_whose_walls_are_hits():
    from topomap.io import from_array
    from topomap.core.segmentation import _near_hits

    free = np.zeros((40, 40), bool)
    free[5:35, 5:35] = True
    walls = ~free
    grid = from_array(free, resolution=0.05)
    assert _near_hits(grid, walls, 2.0) is not None            # walls occupied: a laser map
    assert _near_hits(grid, np.zeros_like(free), 2.0) is None  # walls drawn as unknown: a plan


@pytest.mark.parametrize("depth", [0.0, 2.0, 4.5, 12.0])
def test_nearest_wall_points_batched_equals_one_window_at_a_time(depth):
    """All candidates at once give the posts of one window per candidate, bit
    for bit (windows cut by the map's edges, empty windows, no opposite side)."""
    free = _map()
    free[:, 140:] = True  # a strip without obstacles: empty windows
    rng = np.random.default_rng(7)
    pts = [(r, c) for r, c in zip(rng.integers(0, 120, 60), rng.integers(0, 150, 60))] + [(0, 0), (119, 149), (5, 146)]
    cands = [D.Candidate(edge=(0, 1, 0), centroid=np.array(p, float), direction=np.array([1.0, 0.0]),
                         radius=float(rng.uniform(0.5, 15)), status=D.MOUTH if n % 7 == 3 else D.CANDIDATE)
             for n, p in enumerate(pts)]
    one = [D.Candidate(edge=c.edge, centroid=c.centroid.copy(), direction=c.direction, radius=c.radius,
                       status=c.status) for c in cands]
    D.nearest_wall_points(cands, ~free, max_px=25, depth_px=depth)
    for c in one:
        D._nearest_wall_points_one(c, ~free, 25, depth)
    assert sum(c.ip2 is not None for c in one) > 20
    for c, o in zip(cands, one):
        for p, q in ((c.ip1, o.ip1), (c.ip2, o.ip2)):
            assert (p is None) == (q is None)
            if p is not None:
                assert p.dtype == q.dtype and np.array_equal(p, q)


def test_nearest_wall_points_off_cell_centroid_takes_its_own_window():
    free = _two_rooms_with_door()
    c = D.Candidate(edge=(0, 1, 0), centroid=np.array([35.25, 66.5]), direction=np.array([0.0, 1.0]), radius=9.0)
    o = D.Candidate(edge=(0, 1, 0), centroid=c.centroid.copy(), direction=c.direction, radius=9.0)
    D.nearest_wall_points([c], ~free, max_px=40, depth_px=4)
    D._nearest_wall_points_one(o, ~free, 40, 4)
    assert c.ip2 is not None and np.array_equal(c.ip1, o.ip1) and np.array_equal(c.ip2, o.ip2)


def test_protrusion_at_posts_on_one_cell_get_the_value_of_each_alone():
    free = _map()
    pts = [np.array(p, float) for p in [(50, 69), (45.3, 30.7), (50.2, 68.9), (45, 31), (0, 101), (50, 69)]]
    got = D.protrusion_at(free, pts, 9, 4)
    alone = [D.protrusion_at(free, [p], 9, 4)[0] for p in pts]
    assert got.tolist() == alone and got[0] > 0


def test_strip_cells_are_the_edge_of_the_half_plane():
    """``_strip_cells``: exactly the window cells with ``-max|u| < v . u <= 0``."""
    rng = np.random.default_rng(3)
    u0, u1 = rng.integers(-9, 10, 40), rng.integers(-9, 10, 40)
    u0[(u0 == 0) & (u1 == 0)] = 1
    u0[:4], u1[:4] = [0, 5, 0, -3], [4, 0, -1, 3]
    r0, c0 = rng.integers(0, 30, 40), rng.integers(0, 30, 40)
    ra, ca = np.maximum(r0 - rng.integers(0, 9, 40), 0), np.maximum(c0 - rng.integers(0, 9, 40), 0)
    rb, cb = r0 + rng.integers(1, 9, 40), c0 + rng.integers(1, 9, 40)
    rows, cols, seg = D._strip_cells(u0, u1, r0, c0, ra, rb, ca, cb)
    for k in range(40):
        y, x = np.mgrid[ra[k]:rb[k], ca[k]:cb[k]]
        dot = (y - r0[k]) * u0[k] + (x - c0[k]) * u1[k]
        want = (dot > -max(abs(u0[k]), abs(u1[k]))) & (dot <= 0)
        got = np.zeros_like(want)
        got[rows[seg == k] - ra[k], cols[seg == k] - ca[k]] = True
        assert np.array_equal(got, want)


@pytest.mark.parametrize("n", [3, 400])
def test_window_faces_are_the_faces_of_each_window(n):
    """Both ways of ``_window_faces`` (a few windows far apart on a large map,
    many windows): the faces of each window on its own, in row-major order."""
    from topomap.core.walls import wall_faces

    rng = np.random.default_rng(n)
    obstacle = rng.random((900, 700)) > 0.6
    r0, c0 = rng.integers(0, 900, n), rng.integers(0, 700, n)
    R = rng.integers(1, 40, n)
    ra, rb = np.maximum(r0 - R, 0), np.minimum(r0 + R + 1, 900)
    ca, cb = np.maximum(c0 - R, 0), np.minimum(c0 + R + 1, 700)
    got = D._window_faces(obstacle, ra, rb, ca, cb)
    # the map's own faces given (as the walls stage has them): the same cells
    given = D._window_faces(obstacle, ra, rb, ca, cb, wall_faces(obstacle, ~obstacle))
    assert all(np.array_equal(a, b) for a, b in zip(got, given))
    rows, cols, seg = got
    assert np.all(np.diff(seg) >= 0)
    for k in range(n):
        win = obstacle[ra[k]:rb[k], ca[k]:cb[k]]
        r, c = np.nonzero(wall_faces(win, ~win))
        assert np.array_equal(rows[seg == k], r + ra[k]) and np.array_equal(cols[seg == k], c + ca[k])


def test_prune_spurs_in_place_prunes_as_a_copy_does():
    # the default method prunes the occupied skeleton graph it has just made in place (copy=False):
    # the same nodes and branches as a pruned copy (merged paths may run the other way)
    import networkx as nx

    from topomap.core.skeleton import prune_spurs, skeleton_graph, skeletonize

    free = np.zeros((60, 90), bool)
    free[5:55, 5:85] = True
    free[25:35, 40:50] = False  # a pillar: the skeleton is a loop around it
    free[2:5, 60:75] = True  # a shallow niche: a spur shorter than 1 m off the loop
    free[30:55, 60:64] = False  # a wall stub: the loop gets junctions and short spurs
    skel = skeletonize(free)
    G = skeleton_graph(skel, radius=edt(free), resolution=0.05)
    before = nx.node_link_data(G, edges="links")
    H = prune_spurs(G, 1.0)
    assert nx.node_link_data(G, edges="links") == before  # the input is left as it was
    assert H.number_of_edges() < G.number_of_edges()
    same = prune_spurs(G, 1.0, copy=False)
    assert same is G

    def branches(K):
        return sorted((tuple(sorted((u, v))), round(d["length"], 9), round(d["radius_min"], 9),
                       tuple(sorted(map(tuple, np.asarray(d["path"]).tolist()))))
                      for u, v, d in K.edges(data=True))

    assert dict(H.nodes(data="kind")) == dict(same.nodes(data="kind"))
    assert branches(H) == branches(same)


def test_pixel_graph_components_are_those_of_its_adjacency():
    # _PixelGraph.components labels the pixels' image with OpenCV: the same components as the
    # pixel graph's own 8-neighbour adjacency (scipy), numbered by their first pixel in row-major order
    from scipy import sparse
    from scipy.sparse import csgraph

    from topomap.core.skeleton import _PixelGraph

    rng = np.random.default_rng(3)
    for _ in range(30):
        img = rng.random((int(rng.integers(2, 60)), int(rng.integers(2, 60)))) < rng.uniform(0.05, 0.7)
        px = _PixelGraph(img)
        mask = rng.random(px.npx) < rng.uniform(0.3, 1.0)
        m = mask[px.src] & mask[px.dst]
        A = sparse.csr_matrix((np.ones(int(m.sum())), (px.src[m], px.dst[m])), shape=(px.npx, px.npx))
        _, comp = csgraph.connected_components(A, directed=False)
        lab = px.components(mask)
        assert (lab[~mask] == 0).all() and (lab[mask] > 0).all()
        got = lab[mask]
        for a in np.unique(comp[mask]):  # one label per component, one component per label
            assert np.unique(got[comp[mask] == a]).size == 1
        assert np.unique(got).size == np.unique(comp[mask]).size
        firsts = [np.flatnonzero(lab == k)[0] for k in range(1, got.max() + 1)]  # pixels are row-major
        assert firsts == sorted(firsts)


def test_across_corridor_keeps_the_door_at_a_corridors_mouth():
    from topomap.core import walls as W

    # a corridor 2 m wide (rows 20..59) between two 8 m walls (columns 5..164)
    free = np.zeros((80, 170), bool)
    free[20:60, 5:165] = True
    faces = W.wall_faces(~free, free)
    walls = W.long_walls(W.wall_lines(faces, min_length_px=20), max_gap_px=60, offset_px=4, min_span_px=80)

    def cand(col):
        return D.Candidate(edge=(0, 1, 0), centroid=np.array([40.0, col]), direction=np.array([0.0, 1.0]),
                           radius=19.0, ip1=np.array([19.5, col]), ip2=np.array([60.5, col]), status=D.DOOR)

    middle, mouth = cand(80.0), cand(163.0)
    kept = D.across_corridor([(2.0, middle), (2.0, mouth)], walls, depth_px=10)
    assert [c for _, c in kept] == [mouth]                      # both side walls end at the mouth
    assert middle.status == D.ACROSS_CORRIDOR and mouth.status == D.DOOR
