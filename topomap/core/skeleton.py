"""Skeleton graphs: the Voronoi diagram of free or occupied space as a networkx graph.

A skeleton (one-pixel-wide medial axis, the paper's approximation of the
Voronoi diagram) becomes a :class:`networkx.MultiGraph`:

* nodes are junctions (3+ branches) and endpoints (1 branch) of the skeleton,
  keyed by consecutive integers, with ``row``, ``col`` (pixels), ``x``, ``y``
  (metres), ``radius`` (metres, clearance at the node), ``kind``
  (``"endpoint"``, ``"junction"`` or ``"loop"``);
* edges are branches with ``path`` ((K, 2) int array of pixel ``(row, col)``,
  ends included, starting at node ``start``), ``length`` (metres,
  along the path), ``radius`` ((K,) float array, metres, clearance along the
  path) and ``radius_min`` (metres).

The conversion is vectorised: pixels and branches are never visited in a Python
loop; the branches and the order of the pixels along each come from pointer
jumping over the steps between neighbouring branch pixels (:class:`_Branches`).
"""

from __future__ import annotations

import numpy as np
import networkx as nx
from scipy import sparse
from scipy.sparse import csgraph


__all__ = ["skeletonize", "skeleton_graph", "skeleton_topology", "graph_from_topology",
           "SkeletonTopology", "prune_spurs", "graph_endpoints", "graph_pixels", "downsample"]

_OFFSETS = np.array([(-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1)])


def skeletonize(mask: np.ndarray) -> np.ndarray:
    """One-pixel-wide, 8-connected skeleton of ``mask`` (bool, same shape).

    Uses :func:`skimage.morphology.skeletonize` (Zhang's method, the closest
    available equivalent of MATLAB's ``bwskel`` the paper uses) on the
    bounding box of the mask only; a large mask with wide areas gets the
    same thinning from :func:`_thin`, which visits only the pixels whose
    neighbourhood changed.
    """
    import skimage.morphology

    mask = np.asarray(mask, bool)
    out = np.zeros(mask.shape, bool)
    rows = np.flatnonzero(mask.any(axis=1))
    if rows.size == 0:
        return out
    cols = np.flatnonzero(mask.any(axis=0))
    r0, r1 = max(rows[0] - 1, 0), min(rows[-1] + 2, mask.shape[0])
    c0, c1 = max(cols[0] - 1, 0), min(cols[-1] + 2, mask.shape[1])
    box = mask[r0:r1, c0:c1]
    # a large mask with wide areas (free space: many passes, most of the image long finished)
    # is thinned pixel by pixel from the boundary inwards; skimage scans the whole box every pass
    wide = box.size >= _THIN_SPARSE_CELLS and np.count_nonzero(box) >= 0.15 * box.size
    out[r0:r1, c0:c1] = _thin(box) if wide else skimage.morphology.skeletonize(box)
    return out


#: Size (cells of its bounding box) from which a mask with wide areas is thinned by :func:`_thin`.
_THIN_SPARSE_CELLS = 300_000
#: The neighbourhood table of scikit-image's Zhang thinning (``skeletonize``): for the 8 neighbours
#: coded NW 1, N 2, NE 4, E 8, SE 16, S 32, SW 64, W 128, whether a pixel goes in the first pass (1),
#: the second (2) or both (3).
_ZHANG = np.frombuffer(bytes.fromhex(
    "0000000100000103000003010100010300000000000000000200020003000303000000000000000003000000000000000000"
    "0000000000000200000003000202000000000000000000000000000000000000000000000000000000000000000002000000"
    "0000000002000000020000000300000000000000030000000300020000000301000001030000000000000001000000000000"
    "0000000000000000000103010000000000000000000000000000020000000000000000000000000000000203010300000103"
    "0000000000000001000000000000000000000000000000000203000100000001000000000000000003030001000000000202"
    "000002000000"), np.uint8)
_KERNEL = np.array([[1, 2, 4], [128, 0, 8], [64, 32, 16]], np.float32)


def _thin(mask: np.ndarray) -> np.ndarray:
    """:func:`skimage.morphology.skeletonize` of ``mask`` (Zhang's two-pass thinning, its table),
    visiting only the pixels whose neighbourhood changed.

    Each pass removes, all at once, the set pixels whose neighbourhood code (kept up to date as
    pixels go) the pass's table marks; a pixel is looked at again in a pass of either kind only
    after one of its neighbours went, so the passes remove exactly what skimage's full scans
    remove, and the thinning ends when nothing can change any more.
    """
    import cv2

    H, W = mask.shape
    Wp = W + 2
    img = np.zeros((H + 2, W + 2), np.uint8)
    img[1:-1, 1:-1] = mask
    flat = img.ravel()
    code = cv2.filter2D(img, cv2.CV_8U, _KERNEL, borderType=cv2.BORDER_CONSTANT)
    start = np.flatnonzero((code != 255) & (img > 0))
    code = code.ravel()
    offs = np.array([-Wp - 1, -Wp, -Wp + 1, 1, Wp + 1, Wp, Wp - 1, -1])  # NW N NE E SE S SW W
    back = np.array([16, 32, 64, 128, 1, 2, 4, 8], np.uint8)  # a pixel's bit in that neighbour's code
    remove = (np.isin(_ZHANG, (1, 3)), np.isin(_ZHANG, (2, 3)))
    slot = np.zeros(flat.size, np.int32)
    queue = [start, start]  # per kind of pass, the pixels to look at in its next pass
    kind = 0
    while queue[0].size or queue[1].size:
        c, queue[kind] = queue[kind], start[:0]
        if c.size:
            k = np.arange(c.size, dtype=np.int32)
            slot[c] = k
            c = c[slot[c] == k]  # each pixel once
            c = c[flat[c] == 1]
            gone = c[remove[kind][code[c]]]
            if gone.size:
                flat[gone] = 0
                nb = gone[:, None] + offs
                for i in range(8):
                    code[nb[:, i]] -= back[i]
                nb = nb.ravel()
                nb = nb[flat[nb] == 1]
                queue = [np.concatenate([queue[0], nb]), np.concatenate([queue[1], nb])]
        kind ^= 1
    return img[1:-1, 1:-1].astype(bool)


def neighbour_count(mask: np.ndarray) -> np.ndarray:
    """Number of 8-neighbours of every cell that are True (int16; outside the
    image counts as False). On a skeleton: 1 at endpoints, 3+ at junctions."""
    import cv2

    k = np.ones((3, 3), np.float32)
    k[1, 1] = 0
    return cv2.filter2D(np.asarray(mask, np.uint8), cv2.CV_16S, k, borderType=cv2.BORDER_CONSTANT)


class _PixelGraph:
    """The 8-neighbour adjacency of the pixels of a skeleton, as index arrays.

    ``pr``, ``pc``: pixel rows / columns (row-major order); ``nb`` (npx, 8):
    index of each neighbour or -1; ``has``: ``nb >= 0``; ``deg``: neighbour
    count; ``src``, ``dst``: every (pixel, neighbour) pair; ``shape``: the
    skeleton image's.
    """

    def __init__(self, skel: np.ndarray):
        H, W = self.shape = skel.shape
        lin = np.flatnonzero(skel)
        self.pr, self.pc = np.divmod(lin, W)  # np.nonzero's order (row-major), faster
        self.npx = npx = self.pr.size
        # sparse pixel adjacency: one full-size index image (padded by one, flat), everything else O(pixels)
        pid = np.full((H + 2) * (W + 2), -1, np.int32)
        at = lin + 2 * self.pr + W + 3  # (row + 1) * (W + 2) + col + 1
        pid[at] = np.arange(npx, dtype=np.int32)
        self.nb = pid[at[:, None] + (_OFFSETS[:, 0] * (W + 2) + _OFFSETS[:, 1])]
        self.has = self.nb >= 0
        # the (pixel, neighbour) pairs from one scan of ``has`` (quicker than one scan per
        # direction), the degrees counted from them
        pair = np.flatnonzero(self.has)
        self.src = pair >> 3
        self.dst = self.nb.ravel()[pair]
        self.deg = np.bincount(self.src, minlength=npx)

    def components(self, mask_px: np.ndarray) -> np.ndarray:
        """Connected components of the pixels in ``mask_px`` (labels 1.., 0 =
        outside), numbered in row-major order of their first pixel.

        The pixels' 8-neighbour adjacency is the 8-connectivity of their image:
        OpenCV labels that image, then the labels are renumbered."""
        import cv2

        lab = np.zeros(self.npx, np.int64)
        idx = np.flatnonzero(mask_px)
        if idx.size:
            img = np.zeros(self.shape, np.uint8)
            rr, cc = self.pr[idx], self.pc[idx]
            img[rr, cc] = 1
            comp = cv2.connectedComponents(img, connectivity=8, ltype=cv2.CV_32S)[1][rr, cc]
            _, first, inv = np.unique(comp, return_index=True, return_inverse=True)
            rank = np.empty(first.size, np.int64)
            rank[np.argsort(first, kind="stable")] = np.arange(1, first.size + 1)
            lab[idx] = rank[inv]
        return lab

    def clusters(self, mask_px: np.ndarray) -> np.ndarray:
        """:meth:`components` of pixels that form small clusters (the junction pixels, a few in
        each), without an image: every pixel takes the least index over its pairs in the set
        (and that index's own) until nothing changes, which is each component's first pixel.

        Quicker than OpenCV's labelling on the skeletons of real maps; a set that has not
        settled after :data:`_CLUSTER_ROUNDS` rounds is labelled by :meth:`components`.
        """
        lab = np.zeros(self.npx, np.int64)
        idx = np.flatnonzero(mask_px)
        if not idx.size:
            return lab
        local = np.full(self.npx, -1, np.int64)
        local[idx] = np.arange(idx.size)
        m = mask_px[self.src] & mask_px[self.dst]
        s, d = local[self.src[m]], local[self.dst[m]]
        low = np.arange(idx.size)
        for _ in range(_CLUSTER_ROUNDS):
            new = low.copy()
            np.minimum.at(new, s, low[d])
            new = new[new]
            if np.array_equal(new, low):
                lab[idx] = np.cumsum(low == np.arange(idx.size))[low]  # numbered by first pixel
                return lab
            low = new
        return self.components(mask_px)


#: Rounds after which :meth:`_PixelGraph.clusters` leaves a set to OpenCV's labelling.
_CLUSTER_ROUNDS = 16


def _find_nodes(px: _PixelGraph):
    """Node label per pixel (0 = branch pixel), the node count and the branch
    pixels traced (:class:`_Branches`; None when there is none).

    Nodes are clusters of junction pixels (3+ neighbours) and single end or
    isolated pixels; a loop without any node gets its first pixel as node.
    """
    is_junc = px.deg >= 3
    node_of = px.clusters(is_junc)
    nj = int(node_of.max())
    single = np.flatnonzero(px.deg <= 1)
    node_of[single] = nj + 1 + np.arange(single.size)
    n_nodes = nj + single.size
    br = _Branches.of(px, node_of)
    if br is not None:
        # a branch pixel has two neighbours: a branch without an end pixel is a loop that
        # touches no node
        has_end = np.zeros(br.first.size + 1, bool)
        has_end[br.lab[br.bdeg <= 1]] = True
        loops = np.flatnonzero(~has_end[1:])
        if loops.size:
            node_of[br.bidx[br.first[loops]]] = n_nodes + 1 + np.arange(loops.size)
            n_nodes += loops.size
            br = _Branches.of(px, node_of)
    return node_of, n_nodes, br


class _Branches:
    """The branch pixels of a skeleton (the pixels of no node) and the paths they form.

    ``is_br``: per pixel; ``bidx``: the pixel of each branch pixel, in row-major order (their
    *local* indices ``0..n-1``); ``local``: per pixel, its local index or -1; ``s_l``,
    ``d_l``: every step from a branch pixel to a neighbouring one (local, sorted by ``s_l``);
    ``bdeg``: branch neighbours per branch pixel; ``lab``: the branch (component) of each
    branch pixel, ``1..K`` numbered in row-major order of their first pixels, which are
    ``first``; ``nxt``, ``rank``: per step, the last step of its list (the steps that follow
    it, each out of the pixel the one before goes to and not back) and the number of steps
    after it up to there.

    The labels are those of :meth:`_PixelGraph.components` of the branch pixels, found with
    the lists instead of an image: pointer jumping along the lists (each step's least pixel
    up to its list's end taken on) gives every branch pixel its branch's first pixel. The
    lists and the labels at once: quicker than the labelling and the lists apart.
    """

    @classmethod
    def of(cls, px: _PixelGraph, node_of: np.ndarray):
        """The branch pixels of the nodes ``node_of``; None when there is none."""
        is_br = node_of == 0
        bidx = np.flatnonzero(is_br)
        return cls(px, is_br, bidx) if bidx.size else None

    def __init__(self, px: _PixelGraph, is_br: np.ndarray, bidx: np.ndarray):
        self.is_br, self.bidx = is_br, bidx
        self.n = nbr = bidx.size
        self.local = local = np.full(px.npx, -1, np.int64)
        local[bidx] = np.arange(nbr)
        m = is_br[px.src] & is_br[px.dst]
        self.s_l, self.d_l = s_l, d_l = local[px.src[m]], local[px.dst[m]]
        self.bdeg = bdeg = np.bincount(s_l, minlength=nbr)
        # the step after each one; a last step is its own successor
        fb = np.r_[0, np.cumsum(bdeg)[:-1]][d_l]
        step = np.arange(s_l.size)
        nxt = np.where(bdeg[d_l] == 2, fb + (d_l[fb] == s_l), step)
        rank = (nxt != step).astype(np.int64)
        low = np.minimum(s_l, d_l)  # the least pixel of the steps from each one to its successor
        # the lists are done when every step's successor is a last step; a loop's lists never
        # are, but each of its steps has gone round it once 2 ** rounds >= nbr
        for _ in range(int(np.ceil(np.log2(max(nbr, 2)))) + 1):
            jump = nxt[nxt]
            if np.array_equal(jump, nxt):
                break
            rank += rank[nxt]
            np.minimum(low, low[nxt], out=low)
            nxt = jump
        np.minimum(low, low[nxt], out=low)  # and the last step's own pixels
        self.nxt, self.rank = nxt, rank
        least = np.arange(nbr)
        np.minimum.at(least, s_l, low)  # a pixel's steps go to both ends of its branch
        is_first = least == np.arange(nbr)
        self.lab = np.cumsum(is_first)[least]
        self.first = np.flatnonzero(is_first)


def _node_positions(px: _PixelGraph, node_of: np.ndarray, n_nodes: int):
    """Per node (1-based rows): the mean pixel ``mr``, ``mc`` of its cluster
    and its representative pixel ``rep`` (the cluster pixel nearest the mean)."""
    nidx = np.flatnonzero(node_of)
    nl = node_of[nidx]
    nr, nc = px.pr[nidx], px.pc[nidx]
    cnt = np.bincount(nl, minlength=n_nodes + 1).astype(float)
    cnt[cnt == 0] = 1
    mr = np.bincount(nl, weights=nr, minlength=n_nodes + 1) / cnt
    mc = np.bincount(nl, weights=nc, minlength=n_nodes + 1) / cnt
    d2 = (nr - mr[nl]) ** 2 + (nc - mc[nl]) ** 2
    order = np.lexsort((d2, nl))
    first_idx = order[np.r_[True, nl[order][1:] != nl[order][:-1]]]
    rep = np.zeros((n_nodes + 1, 2), int)
    rep[nl[first_idx]] = np.stack([nr[first_idx], nc[first_idx]], 1)
    return rep, mr, mc


def _ordered_branches(px: _PixelGraph, node_of, br: _Branches):
    """The pixels of every branch in order along it, and the nodes each
    branch pixel touches: ``(branch rows, cols, porder, bounds, en_p, en_n)``.

    Branch ``k`` (label ``k + 1``) is the branch pixels (local indices)
    ``porder[bounds[k]:bounds[k + 1]]`` in order, from its first end; ``(en_p,
    en_n)`` are the (branch pixel, node) pairs of touching pixels, sorted.
    """
    is_br, local, nbr, br_l, s_l, d_l = br.is_br, br.local, br.n, br.lab, br.s_l, br.d_l
    br_r, br_c = px.pr[br.bidx], px.pc[br.bidx]
    src, dst = px.src, px.dst
    # (branch pixel, node) pairs of touching pixels, sorted
    m2 = is_br[src] & (node_of[dst] > 0)
    nn = int(node_of.max()) + 1
    en = np.sort(local[src[m2]] * nn + node_of[dst[m2]])
    en_p, en_n = np.divmod(en[np.r_[True, en[1:] != en[:-1]]] if en.size else en, nn)
    # order along each branch (a path: at most two branch neighbours), from its first end
    ends = np.flatnonzero(br.bdeg <= 1)
    ends = ends[np.argsort(br_l[ends], kind="stable")]
    e_l = br_l[ends]
    starts = ends[np.r_[True, e_l[1:] != e_l[:-1]]] if ends.size else ends
    if starts.size != br.first.size:  # a branch without an end: order by distance from the ends
        w = np.hypot(br_r[s_l] - br_r[d_l], br_c[s_l] - br_c[d_l])
        A = sparse.csr_matrix((w, (s_l, d_l)), shape=(nbr, nbr))
        dist = csgraph.dijkstra(A, directed=False, indices=starts, min_only=True)
        porder = np.lexsort((dist, br_l))
    else:
        # a pixel's position is one more than the number of steps after its step towards the start
        pos = np.zeros(nbr, np.int64)
        back = d_l[br.nxt] == starts[br_l[s_l] - 1]
        pos[s_l[back]] = br.rank[back] + 1
        first = np.r_[0, np.cumsum(np.bincount(br_l))[:-1]]
        porder = np.empty(nbr, np.int64)
        porder[first[br_l] + pos] = np.arange(nbr)
    bounds = np.flatnonzero(np.r_[True, br_l[porder][1:] != br_l[porder][:-1], True])
    return br_r, br_c, porder, bounds, en_p, en_n


def _branch_edges(rc, porder, bounds, en_p, en_n, rep, mr, mc, n_nodes):
    """``(u, v, path)`` of every ordered branch (:func:`_ordered_branches`) and the node table
    with the endpoints added where a branch end touches no node: ``(edges, rep, mr, mc, n)``.

    A branch's end nodes are the first node its first pixel touches and the first its last
    pixel touches (the second, if that is the first end's); a one-pixel branch touching two
    nodes joins the two lowest. An end that touches no node becomes an endpoint of its own,
    numbered on from ``n_nodes`` branch by branch, its first end before its last. The path
    is the branch's pixels with the end nodes' pixels added; the paths are consecutive slices
    of one array. All branches at once: quicker than branch by branch.
    """
    nbr = rc.shape[0]
    size = np.diff(bounds)
    first_px, last_px = porder[bounds[:-1]], porder[bounds[1:] - 1]
    # the nodes an end pixel touches: how many, the first, the second (0: none)
    cnt = np.bincount(en_p, minlength=nbr)
    off = np.cumsum(cnt) - cnt
    nodes = np.r_[en_n, 0, 0]

    def touched(p):
        k, o = cnt[p], off[p]
        return k, np.where(k >= 1, nodes[o], 0), np.where(k >= 2, nodes[o + 1], 0)

    ka, a1, a2 = touched(first_px)
    kb, b1, b2 = touched(last_px)
    one = (size == 1) & (ka >= 2)  # one pixel between two nodes
    head = ka >= 1
    tail = one | ((kb >= 1) & (size > 1))
    u = a1
    v = np.where(one, a2, np.where(~one & (b1 == a1) & (kb > 1), b2, b1))
    new_u = ~head
    new_v = ~tail & ((size > 1) | head)
    new = np.stack([new_u, new_v], 1).ravel()  # in the order the ends are met
    if new.any():
        label = (n_nodes + np.cumsum(new)).reshape(-1, 2)
        u = np.where(new_u, label[:, 0], u)
        v = np.where(new_v, label[:, 1], v)
        ex = np.stack([rc[first_px], rc[last_px]], 1).reshape(-1, 2)[new].astype(int)
    v = np.where(~tail & ~new_v, u, v)  # a lone pixel touching nothing: from and to itself
    # every path in one array: [end node pixel] + branch pixels + [end node pixel]
    n_out = size + head + tail
    out = np.cumsum(n_out) - n_out
    P = np.empty((int(n_out.sum()), 2), np.result_type(rc, rep))
    P[np.repeat(out - bounds[:-1] + head, size) + np.arange(nbr)] = rc[porder]
    P[out[head]] = rep[u[head]]
    P[(out + n_out - 1)[tail]] = rep[v[tail]]
    paths = [P[a:b] for a, b in zip(out.tolist(), (out + n_out).tolist())]
    edges = list(zip(u.tolist(), v.tolist(), paths))
    if new.any():
        rep = np.vstack([rep, ex])
        mr = np.concatenate([mr, ex[:, 0].astype(float)])
        mc = np.concatenate([mc, ex[:, 1].astype(float)])
        n_nodes += ex.shape[0]
    return edges, rep, mr, mc, n_nodes


def _direct_edges(px: _PixelGraph, node_of, rep) -> list:
    """Edges between adjacent nodes with no branch pixel between them."""
    src, dst = px.src, px.dst
    m3 = (node_of[src] > 0) & (node_of[dst] > 0) & (node_of[src] < node_of[dst])
    return [(u, v, np.vstack([rep[u], rep[v]]))
            for u, v in sorted(set(zip(node_of[src[m3]].tolist(), node_of[dst[m3]].tolist())))]


class SkeletonTopology:
    """Nodes and branches of a skeleton in pixels, before attributes are added.

    Attributes
    ----------
    rep : (n + 1, 2) ndarray of int
        Representative pixel of node ``1..n`` (row 0 unused).
    mr, mc : (n + 1,) ndarray of float
        Mean pixel row / column of each node's cluster.
    n_nodes : int
    edges : list of (u, v, path)
        Branches between nodes ``u`` and ``v`` (1-based), ``path`` a (K, 2)
        int array of pixels from ``u`` to ``v``.
    """

    def __init__(self, rep, mr, mc, n_nodes, edges):
        self.rep, self.mr, self.mc, self.n_nodes, self.edges = rep, mr, mc, n_nodes, edges


def skeleton_topology(skel: np.ndarray) -> SkeletonTopology:
    """Junctions, endpoints and branches of a one-pixel-wide 8-connected
    skeleton (see :func:`skeleton_graph`), in pixels."""
    skel = np.asarray(skel, bool)
    px = _PixelGraph(skel)
    if px.npx == 0:
        return SkeletonTopology(np.zeros((1, 2), int), np.zeros(1), np.zeros(1), 0, [])
    node_of, n_nodes, br = _find_nodes(px)
    rep, mr, mc = _node_positions(px, node_of, n_nodes)
    edges = []
    if br is not None:
        br_r, br_c, porder, bounds, en_p, en_n = _ordered_branches(px, node_of, br)
        edges, rep, mr, mc, n_nodes = _branch_edges(np.stack([br_r, br_c], 1), porder, bounds, en_p, en_n,
                                                     rep, mr, mc, n_nodes)
    edges += _direct_edges(px, node_of, rep)
    return SkeletonTopology(rep, mr, mc, n_nodes, edges)


def graph_from_topology(topo: SkeletonTopology, *, radius: np.ndarray | None = None,
                        resolution: float = 1.0, to_world=None) -> nx.MultiGraph:
    """The :class:`networkx.MultiGraph` of a :class:`SkeletonTopology`, with
    the attributes the module docstring lists (``radius`` sampled from the
    clearance image ``radius``, in pixels, at every node and path pixel)."""
    G = nx.MultiGraph(resolution=float(resolution))
    n = topo.n_nodes
    if n == 0:
        return G
    res = float(resolution)
    rep = topo.rep[1:n + 1]
    seen_direct = set()  # the direct edges are listed twice
    edges, us, vs = [], [], []
    for u, v, path in topo.edges:
        if path.shape[0] == 2:
            key = (min(u, v), max(u, v))
            if key in seen_direct:
                continue
            seen_direct.add(key)
        if u > v:
            u, v = v, u
            path = path[::-1]
        edges.append((u, v, path))
        us.append(u)
        vs.append(v)
    # every node's attributes as columns of Python values (the same floats as float() of each
    # numpy value), its kind from the degrees the edges will give it
    keys, cols = ["row", "col", "pixel"], [np.asarray(topo.mr[1:n + 1], float).tolist(),
                                           np.asarray(topo.mc[1:n + 1], float).tolist(),
                                           list(zip(rep[:, 0].tolist(), rep[:, 1].tolist()))]
    if radius is not None:
        keys.append("radius")
        cols.append((radius[rep[:, 0], rep[:, 1]].astype(float) * res).tolist())
    if to_world is not None:
        wx, wy = to_world(topo.mr, topo.mc)
        keys += ["x", "y"]
        cols += [np.asarray(np.broadcast_to(w, topo.mr.shape), float)[1:n + 1].tolist() for w in (wx, wy)]
    ends = np.array([us, vs], np.int64).T - 1
    known = ends.size == 0 or (ends.min() >= 0 and ends.max() < n)  # else networkx adds bare nodes
    if known:
        keys.append("kind")
        cols.append(np.array(_KINDS, object)[np.minimum(np.bincount(ends.ravel(), minlength=n), 3)].tolist())
    G.add_nodes_from(range(n))
    for (_, attrs), vals in zip(G.nodes(data=True), zip(*cols)):
        attrs.update(zip(keys, vals))
    if edges:
        # every path's step lengths and clearances at once; each edge's length is still the sum
        # over its own steps (np.add.reduce of its slice: the same pairwise float sum as
        # ``.sum()`` on its own array; a batched reduceat sums in another order)
        P = np.concatenate([path for _, _, path in edges])
        first = np.cumsum([0] + [len(path) for _, _, path in edges]).tolist()
        d = np.diff(P, axis=0)
        step = np.sqrt((d * d).sum(1))
        add = np.add.reduce
        lengths = [float(add(step[a:b - 1]) if b > a else 0.0) * res for a, b in zip(first[:-1], first[1:])]
        add_edge = G.add_edge
        if radius is None:
            for (u, v, path), length in zip(edges, lengths):
                add_edge(u - 1, v - 1, path=path, start=u - 1, length=length)
        else:
            rad_all = radius[P[:, 0], P[:, 1]].astype(float) * res
            rad_min = np.minimum.reduceat(rad_all, first[:-1]).tolist()  # a minimum in any order
            for (u, v, path), length, a, b, rmin in zip(edges, lengths, first[:-1], first[1:], rad_min):
                add_edge(u - 1, v - 1, path=path, start=u - 1, length=length, radius=rad_all[a:b],
                         radius_min=rmin)
    if not known:
        _set_kinds(G)
    return G


def skeleton_graph(skel: np.ndarray, *, radius: np.ndarray | None = None,
                   resolution: float = 1.0, to_world=None) -> nx.MultiGraph:
    """Convert a skeleton image to a graph of junctions, endpoints and branches.

    Parameters
    ----------
    skel : (M, N) ndarray of bool
        One-pixel-wide skeleton (8-connected).
    radius : (M, N) ndarray of float, optional
        Clearance in *pixels* (a distance transform); stored on nodes and
        along edges in metres.
    resolution : float
        Metres per pixel, for ``length`` and ``radius``.
    to_world : callable, optional
        ``(rows, cols) -> (x, y)`` in metres; adds ``x``, ``y`` to nodes.

    Returns
    -------
    networkx.MultiGraph
        See the module docstring for the attributes. Graph attribute
        ``resolution`` (m/px).

    See Also
    --------
    skeleton_topology, graph_from_topology : the two steps, for callers that
        move the pixels in between (the default method's coarse skeleton,
        :func:`topomap.core.segmentation.coarse_skeleton_graph`).
    """
    return graph_from_topology(skeleton_topology(skel), radius=radius, resolution=resolution,
                               to_world=to_world)


def _set_kinds(G, degree=None):
    """Set node ``kind``: endpoint (degree 1), junction (3+), isolated (0), loop (2).

    ``degree``: every node's degree, when the caller knows them (``G.degree`` otherwise).
    """
    if degree is None:
        degree = dict(G.degree)  # one degree view for all nodes (G.degree(n) makes one per node)
    for n, attrs in G.nodes(data=True):
        attrs["kind"] = _KINDS[min(degree[n], 3)]


#: Node ``kind`` by degree: 0, 1, 2, 3 and more.
_KINDS = ("isolated", "endpoint", "loop", "junction")


def prune_spurs(G: nx.MultiGraph, min_length: float, *, copy: bool = True) -> nx.MultiGraph:
    """Remove end branches shorter than ``min_length`` metres, then merge
    the branches meeting at nodes left with two branches.

    One pass, as MATLAB's ``bwskel(..., 'MinBranchLength', L)`` which the
    paper uses: a spur is a branch with an endpoint (degree-1 node). Returns a
    new graph (``copy=False``: ``G`` itself, pruned in place, for a graph
    just made that nobody else holds); node keys are kept. A copy lists
    each node's branches in another order than ``G`` does, so where two
    branches are merged into one, which of them comes first (the direction
    of the merged path) can differ between the two.
    """
    H = _copy(G) if copy else G
    # the degrees counted once and kept up to date as branches go (networkx counts a node's
    # branches afresh on every degree asked: three passes over the nodes were most of the time)
    deg = dict(H.degree)
    spurs = [(u, v, k) for u, v, k, d in H.edges(keys=True, data=True)
             if d["length"] < min_length and u != v and (deg[u] == 1) != (deg[v] == 1)]
    for u, v, k in spurs:
        if H.has_edge(u, v, k):
            H.remove_edge(u, v, k)
            for n in (u, v):
                deg[n] -= 1
                if deg[n] == 0:
                    H.remove_node(n)
                    del deg[n]
    _contract(H, deg)
    _set_kinds(H, deg)
    return H


def _copy(G: nx.MultiGraph) -> nx.MultiGraph:
    """``G.copy()``: the same graph attributes, nodes, edges and keys, each attribute dict
    copied, every node's branches listed in the same order; faster.

    networkx's copy adds every edge from both of its ends (the second time changes nothing)
    and every node with its attributes through an exception; here the nodes come first,
    their attributes after, and the edges once each, in ``G.edges`` order: the order their
    first ends give them there, so every node lists its branches as in networkx's copy.
    """
    H = G.__class__()
    H.graph.update(G.graph)
    H.add_nodes_from(G)
    for (_, attrs), (_, d) in zip(H.nodes(data=True), G.nodes(data=True)):
        attrs.update(d)
    H.add_edges_from((u, v, k, d.copy()) for u, v, k, d in G.edges(keys=True, data=True))
    return H


def _contract(H: nx.MultiGraph, deg: dict):
    """Merge the two branches at every degree-2 node into one branch (``deg``: every node's
    degree, kept up to date)."""
    # a merge leaves every other node's degree as it was (two branches out, one in): the
    # degree-2 nodes can be listed at the start
    for n in sorted(n for n, d in deg.items() if d == 2):
        if n not in H:
            continue
        es = list(H.edges(n, keys=True, data=True))
        if len(es) != 2 or any(u == v for u, v, _, _ in es):
            continue
        (_, o1, k1, d1), (_, o2, k2, d2) = es
        # orient both branches to start at n (``start`` is the node at path[0])
        fwd1 = d1["start"] == n
        fwd2 = d2["start"] == n
        p1 = d1["path"] if fwd1 else d1["path"][::-1]
        p2 = d2["path"] if fwd2 else d2["path"][::-1]
        path = np.vstack([p1[::-1], p2[1:]])  # o1 ... n ... o2
        attrs = dict(path=path, start=o1, length=d1["length"] + d2["length"])
        if "radius" in d1:
            r1 = d1["radius"] if fwd1 else d1["radius"][::-1]
            r2 = d2["radius"] if fwd2 else d2["radius"][::-1]
            rad = np.concatenate([r1[::-1], r2[1:]])
            attrs["radius"] = rad
            attrs["radius_min"] = float(rad.min())
        u, v = o1, o2
        H.remove_node(n)
        del deg[n]
        H.add_edge(u, v, **attrs)


def graph_endpoints(G: nx.MultiGraph) -> np.ndarray:
    """(K, 2) float array of the pixel ``(row, col)`` of every degree-1 node."""
    # one degree view for all nodes (G.degree(n) makes a view per node)
    nodes = G.nodes
    pts = [nodes[n]["pixel"] for n, deg in G.degree if deg == 1]
    return np.array(pts, float).reshape(-1, 2)


def graph_pixels(G: nx.MultiGraph) -> np.ndarray:
    """(K, 2) int array of every pixel on the graph's branches (duplicates removed)."""
    paths = [d["path"] for _, _, d in G.edges(data=True)]
    if not paths:
        return np.zeros((0, 2), int)
    return _unique_pixels(np.vstack(paths))


def _unique_pixels(P: np.ndarray) -> np.ndarray:
    """``np.unique(P, axis=0)`` of a (K, 2) array of pixels: the same rows in the same (row, col) order.

    Signed integer pixels are sorted as one int64 key per pixel, much quicker (``np.unique``
    with an axis sorts structured rows, and on plain keys it is itself slower than a sort).
    """
    if P.ndim != 2 or P.shape[1] != 2 or P.dtype.kind != "i" or P.shape[0] == 0:
        return np.unique(P, axis=0)
    r, c = P[:, 0].astype(np.int64), P[:, 1].astype(np.int64)
    c0 = int(c.min())
    span = int(c.max()) - c0 + 1
    if (max(-int(r.min()), int(r.max())) + 1) * span >= 2 ** 62:  # the key would overflow
        return np.unique(P, axis=0)
    key = np.sort(r * span + (c - c0))
    key = key[np.r_[True, key[1:] != key[:-1]]]
    rr, cc = np.divmod(key, span)  # floor division: the row even where it is negative
    return np.stack([rr, cc + c0], 1).astype(P.dtype)


def downsample(mask: np.ndarray, factor: int, *, keep: str = "all") -> np.ndarray:
    """Block-reduce a bool mask by an integer ``factor``.

    ``keep="all"``: a coarse cell is True only if every fine cell is (free
    space: a one-cell wall survives as a wall); ``keep="any"``: True if any
    fine cell is (occupied space). The image is padded with False.
    """
    if factor <= 1:
        return np.asarray(mask, bool)
    H, W = mask.shape
    Hp, Wp = -(-H // factor) * factor, -(-W // factor) * factor
    m = np.zeros((Hp, Wp), bool)
    m[:H, :W] = mask
    # combine the factor**2 strided sub-grids (faster than a reduction over axes)
    out = m[0::factor, 0::factor].copy()
    for i in range(factor):
        for j in range(factor):
            if i or j:
                if keep == "all":
                    out &= m[i::factor, j::factor]
                else:
                    out |= m[i::factor, j::factor]
    return out
