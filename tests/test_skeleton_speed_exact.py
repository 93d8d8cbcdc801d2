"""The vectorised parts of topomap.core.skeleton give exactly what the plain ones they replaced gave.

Each fast path is compared with the straightforward computation it stands for, on random
inputs: same values, same dtype, same shape, same order.
"""

import numpy as np
import pytest

from topomap.core.skeleton import _unique_pixels


@pytest.mark.parametrize("dtype", [np.int64, np.int32, np.int16, np.uint8, np.uint64, np.float64])
def test_unique_pixels_is_numpy_unique_rows(dtype):
    rng = np.random.default_rng(0)
    for _ in range(200):
        lo = int(rng.integers(-100, 50)) if np.dtype(dtype).kind in "if" else 0
        P = rng.integers(lo, lo + int(rng.integers(1, 100)), (int(rng.integers(0, 300)), 2)).astype(dtype)
        if rng.random() < 0.3:
            P = P[::-1]
        want, got = np.unique(P, axis=0), _unique_pixels(P)
        assert got.dtype == want.dtype and got.shape == want.shape and np.array_equal(got, want)


def test_unique_pixels_far_apart():
    for P in (np.array([[2 ** 40, 5], [-2 ** 40, 3], [2 ** 40, -2 ** 30], [0, 2 ** 30], [0, 2 ** 30]]),
              np.array([[2 ** 62, 5], [-2 ** 62, 3]])):
        assert np.array_equal(_unique_pixels(P), np.unique(P, axis=0))


def _branch_edges_one_by_one(rc, porder, bounds, en_p, en_n, rep, mr, mc, n_nodes):
    """The branch-by-branch tracing :func:`topomap.core.skeleton._branch_edges` replaced."""
    touch = {}
    for p, n in zip(en_p.tolist(), en_n.tolist()):
        touch.setdefault(p, []).append(n)
    extra = []

    def new(r, c):
        extra.append((int(r), int(c)))
        return n_nodes + len(extra)

    edges = []
    for k in range(bounds.size - 1):
        seg = porder[bounds[k]:bounds[k + 1]]
        path, a_nodes, b_nodes = rc[seg], touch.get(int(seg[0]), []), touch.get(int(seg[-1]), [])
        if seg.size == 1 and len(set(a_nodes)) >= 2:
            u, v = sorted(set(a_nodes))[:2]
            edges.append((u, v, np.vstack([rep[u][None], path, rep[v][None]])))
            continue
        if a_nodes:
            u, head = a_nodes[0], [rep[a_nodes[0]][None]]
        else:
            u, head = new(*path[0]), []
        tail = []
        if b_nodes and seg.size > 1:
            v = b_nodes[0]
            if v == u and len(b_nodes) > 1:
                v = b_nodes[1]
            tail = [rep[v][None]]
        elif seg.size > 1 or a_nodes:
            v = new(*path[-1])
        else:
            v = u
        edges.append((u, v, np.vstack(head + [path] + tail)))
    if extra:
        ex = np.array(extra, int)
        rep = np.vstack([rep, ex])
        mr = np.concatenate([mr, ex[:, 0].astype(float)])
        mc = np.concatenate([mc, ex[:, 1].astype(float)])
        n_nodes += len(extra)
    return edges, rep, mr, mc, n_nodes


def test_branch_edges_are_those_traced_one_by_one():
    # random branches whose ends touch no node, one, two or three nodes (the first and the
    # last pixel, one-pixel branches), the same node at both ends
    from topomap.core.skeleton import _branch_edges

    rng = np.random.default_rng(5)
    for _ in range(300):
        n_nodes = int(rng.integers(1, 8))
        sizes = rng.integers(1, 6, int(rng.integers(1, 12)))
        nbr = int(sizes.sum())
        rc = rng.integers(0, 50, (nbr, 2))
        porder = rng.permutation(nbr)
        bounds = np.r_[0, np.cumsum(sizes)]
        pairs = {(int(p), int(n)) for p in range(nbr) for n in range(1, n_nodes + 1) if rng.random() < 0.3}
        en = np.array(sorted(pairs), np.int64).reshape(-1, 2)
        rep = rng.integers(0, 50, (n_nodes + 1, 2))
        mr, mc = rng.random(n_nodes + 1), rng.random(n_nodes + 1)
        args = (rc, porder, bounds, en[:, 0], en[:, 1], rep, mr, mc, n_nodes)
        want, got = _branch_edges_one_by_one(*args), _branch_edges(*args)
        assert got[4] == want[4]
        for a, b in zip(got[1:4], want[1:4]):
            assert a.dtype == b.dtype and np.array_equal(a, b)
        assert len(got[0]) == len(want[0])
        for (u, v, p), (wu, wv, wp) in zip(got[0], want[0]):
            assert (u, v) == (wu, wv) and type(u) is type(wu) is int and type(v) is type(wv) is int
            assert p.dtype == wp.dtype and np.array_equal(p, wp)



@pytest.mark.parametrize("copy", [True, False])
def test_prune_spurs_kinds_follow_the_degrees(copy):
    # prune_spurs keeps the degrees up to date itself: the kinds must be those of the pruned graph
    from scipy import ndimage as ndi

    from topomap.core.skeleton import prune_spurs, skeleton_graph, skeletonize

    names = {0: "isolated", 1: "endpoint", 2: "loop"}
    rng = np.random.default_rng(7)
    for _ in range(40):
        m = ndi.binary_closing(rng.random(tuple(int(v) for v in rng.integers(10, 80, 2))) < 0.7)
        G = skeleton_graph(skeletonize(m), radius=np.ones(m.shape), resolution=0.05)
        H = prune_spurs(G, float(rng.uniform(0.05, 1.0)), copy=copy)
        assert {n: names.get(d, "junction") for n, d in H.degree} == dict(H.nodes(data="kind"))


def _rings_and_soups(rng, k):
    """Pixel sets with loops of every length (with and without touching lines) and random soups."""
    out = []
    for _ in range(k):
        h, w = (int(v) for v in rng.integers(6, 50, 2))
        m = rng.random((h, w)) < rng.uniform(0.02, 0.6)
        if rng.random() < 0.5:
            m[:] = False
            for _ in range(int(rng.integers(1, 4))):
                r0, c0 = int(rng.integers(0, h - 3)), int(rng.integers(0, w - 3))
                r1, c1 = int(rng.integers(r0 + 2, h)), int(rng.integers(c0 + 2, w))
                m[r0, c0:c1 + 1] = m[r1, c0:c1 + 1] = m[r0:r1 + 1, c0] = m[r0:r1 + 1, c1] = True
            if rng.random() < 0.5:
                m[int(rng.integers(0, h)), :] = True
        out.append(m)
    return out


def test_clusters_are_components():
    from topomap.core.skeleton import _PixelGraph

    rng = np.random.default_rng(11)
    for img in _rings_and_soups(rng, 200):
        px = _PixelGraph(img)
        for mask in (px.deg >= 3, rng.random(px.npx) < 0.5, np.ones(px.npx, bool)):
            lab = px.clusters(mask)
            assert lab.dtype == np.int64 and np.array_equal(lab, px.components(mask))


def test_branch_labels_are_components():
    # the branches' labels from pointer jumping are those of the branch pixels' image, loops
    # without a node (lists that never end) included; an end pixel's list ends at the other end
    from topomap.core.skeleton import _Branches, _PixelGraph

    rng = np.random.default_rng(12)
    for img in _rings_and_soups(rng, 300):
        px = _PixelGraph(img)
        # nodes as _find_nodes makes them (junctions, ends: a branch pixel has two neighbours), some more at random
        node_of = ((px.deg >= 3) | (px.deg <= 1) | (rng.random(px.npx) < rng.choice([0, 0.1]))).astype(np.int64)
        br = _Branches.of(px, node_of)
        if br is None:
            continue
        comp = px.components(node_of == 0)[br.bidx]
        assert np.array_equal(br.lab, comp)
        assert np.array_equal(br.first, [np.flatnonzero(comp == k)[0] for k in range(1, comp.max() + 1)])


def test_copy_is_networkx_copy():
    # the same graph, orders included (prune_spurs' merged paths follow each node's order of branches)
    import networkx as nx

    from topomap.core.skeleton import _copy, skeleton_graph, skeletonize

    def everything(G):
        return (dict(G.graph), list(G.nodes(data=True)),
                [(u, [(v, [(k, list(d.items())) for k, d in kd.items()]) for v, kd in nb.items()]) for u, nb in G.adj.items()])

    rng = np.random.default_rng(4)
    graphs = [skeleton_graph(skeletonize(rng.random((40, 40)) < 0.7), radius=np.ones((40, 40)), resolution=0.05)
              for _ in range(10)]
    G = nx.MultiGraph(name="x")
    G.add_edges_from([(3, 1), (1, 3), (2, 2), (0, 3, {"w": 1}), (3, 0, 7, {1: "a"})])
    G.add_node(9, kind="isolated")
    for G in graphs + [G]:
        H, want = _copy(G), G.copy()
        assert everything(H) == everything(want)
        for (_, a), (_, b) in zip(H.nodes(data=True), G.nodes(data=True)):
            assert a is not b
        for (*_, a), (*_, b) in zip(H.edges(keys=True, data=True), G.edges(keys=True, data=True)):
            assert a is not b
