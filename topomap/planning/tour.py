"""Room tours: the order in which to visit rooms, and the doors to pass.

:func:`plan_tour` (also ``topomap.planning.plan_tour``) answers "in which
order should the robot visit these rooms?" for room-by-room cleaning or
inspection. It works on the same travel distances as
:func:`topomap.planning.plan_path`: the in-room door-to-door geodesic
distances a room graph carries after :func:`topomap.planning.travel_graph`
(every saved ``rooms.graphml`` / ``rooms.json``), plus the in-room legs from
the start point and to each room's point.

Visiting a room means reaching its point: its interior point (node
attributes ``interior_x``, ``interior_y``: a cell of the room as far from its
edge as any), the point ``plan_path`` uses for a room ID. The start room counts as visited at the
start. The distance between two stops is the shortest route through doors
(Dijkstra on the door graph), so the distances are a metric and every tour
is a sequence of real routes through free space.

Solvers
-------
Up to ``exact_limit`` rooms (12 by default) the order is the optimum, by the
Held–Karp dynamic programme over subsets (``O(2^n n^2)``). Above that, a
heuristic: the nearest-neighbour tour improved by 2-opt (reversing a stretch of the tour) and Or-opt (moving
one, two or three consecutive stops elsewhere) until no move shortens it,
then rounds of iterated local search, with at most :data:`MOVES_BASE` +
:data:`MOVES_PER_STOP` moves per room in all and kicks only up to
:data:`KICK_LIMIT` rooms; :func:`tour_lower_bound` (a minimum spanning tree
of the stops) bounds how far from the optimum it can be. Above
:data:`TREE_LIMIT` rooms (1,000) no distance matrix is made: the rooms are
visited in the order of a depth-first walk of a minimum spanning tree of the
door graph (at most twice the tree's weight), in time about linear in the
rooms and doors.
"""

from __future__ import annotations

import logging
import math

import numpy as np
import networkx as nx

from ..core.roommap import RoomMap
from ..errors import NoPathError, NotInRoomError, PlanningError
from ..options import check_length
from .paths import annotated_graph, attach_to_doors, door_graph, locate_endpoint

log = logging.getLogger("topomap")

__all__ = ["plan_tour", "tour_length", "solve_order", "tour_lower_bound", "stop_distances", "EXACT_LIMIT",
           "TREE_LIMIT"]

#: Largest number of rooms to visit for which the order is computed exactly.
EXACT_LIMIT = 12
#: Rounds of iterated local search (double-bridge kicks) of the heuristic.
KICKS = 30
#: Improving moves (2-opt or Or-opt) the heuristic makes at most over its local search and all its
#: kicks together: ``MOVES_BASE + MOVES_PER_STOP * n`` for ``n`` rooms to visit, each move a scan of
#: ``O(n^2)`` pairs at most (the local search of the benchmark tours makes far fewer).
MOVES_BASE = 1000
#: See :data:`MOVES_BASE`.
MOVES_PER_STOP = 2
#: The kicks of the iterated local search run only up to this many rooms to visit (each ends with a
#: full scan of ``O(n^2)`` pairs that finds no move).
KICK_LIMIT = 200
#: Above this many rooms to visit, no distance matrix (``n^2`` distances) is made and the order is a
#: depth-first walk of a minimum spanning tree of the door graph (:func:`_tree_walk`): time
#: ``O(N log N)`` in the doors and rooms of the graph, a tour at most twice the tree's weight.
TREE_LIMIT = 1000


# --------------------------------------------------------------------------
# The order of the stops, on a distance matrix
# --------------------------------------------------------------------------

def tour_length(D: np.ndarray, order, *, closed: bool = False) -> float:
    """Length of visiting stops ``order`` (indices into ``D``, starting at stop 0)."""
    seq = [0] + [int(i) for i in order] + ([0] if closed else [])
    return float(sum(D[a, b] for a, b in zip(seq[:-1], seq[1:])))


def _held_karp(D, closed):
    n = D.shape[0] - 1  # stops 1..n to visit, 0 is the start
    if n == 0:
        return []
    full = (1 << n) - 1
    dp = np.full((1 << n, n), np.inf)
    parent = np.full((1 << n, n), -1, np.int64)
    d = D[1:, 1:]
    for j in range(n):
        dp[1 << j, j] = D[0, j + 1]
    bits = np.array([1 << j for j in range(n)])
    for mask in sorted(range(1, full + 1), key=lambda m: bin(m).count("1")):
        row = dp[mask]
        if not np.isfinite(row).any():
            continue
        cand = row[:, None] + d  # from last stop i (in mask) to j
        best = cand.argmin(0)
        val = cand[best, np.arange(n)]
        for j in np.nonzero((mask & bits) == 0)[0]:
            m2 = mask | (1 << j)
            if val[j] < dp[m2, j]:
                dp[m2, j] = val[j]
                parent[m2, j] = best[j]
    last = dp[full] + (D[1:, 0] if closed else 0.0)
    j = int(np.argmin(last))
    order, mask = [], full
    while j >= 0:
        order.append(j + 1)
        j, mask = int(parent[mask, j]), mask & ~(1 << j)
    return order[::-1]


def _nearest_neighbour(D):
    """From stop 0, always on to the nearest stop not yet visited (of equals the first): ``n`` scans of a row."""
    n = D.shape[0]
    left = np.ones(n, bool)
    left[0] = False
    at, order = 0, []
    for _ in range(n - 1):
        row = np.where(left, D[at], np.inf)
        at = int(np.argmin(row)) if np.isfinite(row).any() else int(np.flatnonzero(left)[0])
        order.append(at)
        left[at] = False
    return order


def _as_cycle(D, order, closed):
    """Distance matrix and cycle of the closed-tour form: an open tour from stop 0
    is a closed tour through one more stop that is glued to stop 0 (distance
    ``-big``, so no improving move ever separates them) and 0 from every other stop."""
    if closed:
        return D, np.array([0] + list(order))
    n = D.shape[0]
    big = 10.0 * (float(np.abs(D).sum()) + 1.0)
    E = np.zeros((n + 1, n + 1))
    E[:n, :n] = D
    E[n, 0] = E[0, n] = -big
    return E, np.array([0] + list(order) + [n])


def _two_opt_move(D, t):
    """Apply the best improving 2-opt move (reverse a stretch) of cycle ``t``; False if none."""
    n = len(t)
    for i in range(n - 2):
        a, b = t[i], t[i + 1]
        c = t[i + 2:]
        d = t[np.r_[i + 3:n, 0]]
        delta = D[a, c] + D[b, d] - D[a, b] - D[c, d]
        if i == 0:
            delta[-1] = 0.0  # the edge closing the cycle touches a
        k = int(np.argmin(delta))
        if delta[k] < -1e-9:
            t[i + 1:i + 3 + k] = t[i + 1:i + 3 + k][::-1]
            return True
    return False


def _or_opt_move(D, t):
    """Apply an improving Or-opt move (a run of 1-3 stops moved, maybe reversed); False if none."""
    n = len(t)
    for size in (1, 2, 3):
        if n < size + 3:
            break
        for i in range(n):
            r = np.roll(t, -i)
            run, rest = r[:size], r[size:]
            s0, se, p, q = run[0], run[-1], rest[-1], rest[0]
            gain = D[p, s0] + D[se, q] - D[p, q]
            x, y = rest[:-1], rest[1:]
            fwd = D[x, s0] + D[se, y] - D[x, y]
            rev = D[x, se] + D[s0, y] - D[x, y]
            add = np.minimum(fwd, rev)
            j = int(np.argmin(add))
            if add[j] - gain < -1e-9:
                piece = run if fwd[j] <= rev[j] else run[::-1]
                t[:] = np.concatenate([rest[:j + 1], piece, rest[j + 1:]])
                return True
    return False


def _cycle_length(E, t):
    return float(E[t, np.roll(t, -1)].sum())


def _local_search(E, t, budget):
    """2-opt and Or-opt moves until none shortens the cycle ``t`` or ``budget[0]`` moves are spent."""
    while budget[0] > 0 and (_two_opt_move(E, t) or _or_opt_move(E, t)):
        budget[0] -= 1
    return t


def _improve(D, order, closed, kicks=KICKS, stats=None):
    """2-opt and Or-opt moves until none shortens the tour, then ``kicks`` rounds
    of iterated local search: a random double-bridge move (three cuts, two
    stretches swapped; seeded, so the result is reproducible) followed by the
    same local search, kept when the tour got shorter. At most
    :data:`MOVES_BASE` + :data:`MOVES_PER_STOP` moves per stop in all (the
    kicks stop when they are spent), kicks only up to :data:`KICK_LIMIT`
    stops; ``stats`` (a dict), when given, gets the ``moves`` made and the
    ``searches`` run."""
    E, t = _as_cycle(np.asarray(D, float), order, closed)
    m = len(t)
    total = MOVES_BASE + MOVES_PER_STOP * m
    budget = [total]
    t = _local_search(E, t, budget)
    searches = 1
    best = _cycle_length(E, t)
    rng = np.random.default_rng(0)
    for _ in range(kicks if 8 <= m <= KICK_LIMIT + 1 else 0):
        if budget[0] <= 0:
            break
        a, b, c = np.sort(rng.choice(np.arange(1, m), 3, replace=False))
        cand = _local_search(E, np.concatenate([t[:a], t[b:c], t[a:b], t[c:]]), budget)
        searches += 1
        L = _cycle_length(E, cand)
        if L < best - 1e-9:
            t, best = cand, L
    if stats is not None:
        stats.update(moves=total - budget[0], searches=searches, budget=total)
    k = int(np.nonzero(t == 0)[0][0])
    t = list(np.roll(t, -k))
    if not closed:
        glue = D.shape[0]
        if t[1] == glue:  # the glued stop after 0: walk the cycle the other way
            t = [0] + t[1:][::-1]
        t = [v for v in t if v != glue]
    return [int(v) for v in t[1:]]


def solve_order(D: np.ndarray, *, closed: bool = False, exact_limit: int = EXACT_LIMIT):
    """The order in which to visit stops ``1..n`` of distance matrix ``D`` from stop 0.

    Parameters
    ----------
    D : (n + 1, n + 1) ndarray of float
        Distances (m), stop 0 the start; finite.
    closed : bool
        Come back to stop 0 at the end.
    exact_limit : int
        Up to this many stops the optimum (Held–Karp), above it the
        nearest-neighbour tour improved by 2-opt and Or-opt.

    Returns
    -------
    order : list of int
        Stop indices ``1..n`` in visiting order.
    method : str
        ``"held-karp"`` (optimal) or ``"nearest-neighbour+2-opt+or-opt"``.
    """
    D = np.asarray(D, float)
    n = D.shape[0] - 1
    if n <= exact_limit:
        return _held_karp(D, closed), "held-karp"
    return _improve(D, _nearest_neighbour(D), closed), "nearest-neighbour+2-opt+or-opt+kicks"


def tour_lower_bound(D: np.ndarray) -> float:
    """Weight of a minimum spanning tree of all stops: no tour (open or closed) is shorter."""
    D = np.asarray(D, float)
    n = D.shape[0]
    if n < 2:
        return 0.0
    inside = np.zeros(n, bool)
    inside[0] = True
    best = D[0].copy()
    total = 0.0
    for _ in range(n - 1):
        j = int(np.argmin(np.where(inside, np.inf, best)))
        total += best[j]
        inside[j] = True
        best = np.minimum(best, D[j])
    return float(total)


# --------------------------------------------------------------------------
# Stops on the room graph
# --------------------------------------------------------------------------

def _stop_graph(seg_or_G, start, rooms, robot_width):
    """The door graph with the start and the rooms to visit joined to their rooms' doors:
    ``(graph, names, stops, points, start_room)``; ``names[0]`` is the start's node, ``names[k]`` stop
    ``k`` (room ``stops[k - 1]``); ``points`` their map-frame points."""
    robot_width = check_length("robot_width", robot_width)
    room_map = RoomMap(seg_or_G)
    G = annotated_graph(seg_or_G)
    rs, ps, pxs = locate_endpoint(room_map, G, start, "start")
    if rooms is None:
        stops = sorted(int(r) for r in G.nodes)
    else:
        try:
            stops = sorted({int(r) for r in rooms})
        except (TypeError, ValueError, OverflowError):
            raise PlanningError(f"rooms must be room IDs, got {rooms!r}") from None
        missing = [r for r in stops if r not in G]
        if missing:
            raise NotInRoomError(f"no room {', '.join(map(str, missing[:20]))}"
                                 f"{' ...' if len(missing) > 20 else ''} in the graph")
    stops = [r for r in stops if r != rs]  # the start room is visited at the start
    graph = door_graph(G, min_width=robot_width)
    names = [("start",)] + [("room", r) for r in stops]
    points, pixels = [ps], [pxs]
    for r in stops:
        _, p, px = locate_endpoint(room_map, G, r, "room")
        points.append(p)
        pixels.append(px)
    spaces = {}
    for name, room, px in zip(names, [rs] + stops, pixels):
        graph.add_node(name)
        space = attach_to_doors(room_map, graph, name, room, px)
        if room == rs and space is not None:
            spaces[name] = (space, px)
    # the start and the stops in the start room's free space: direct legs
    if ("start",) in spaces:
        space, px0 = spaces[("start",)]
        src = space.local(*px0)
        for name, px in zip(names[1:], pixels[1:]):
            q = space.local(*px)
            if q is not None:
                (L,) = space.distances(src, [q])
                if math.isfinite(L):
                    graph.add_edge(("start",), name, length=L, room=rs)
    return graph, names, stops, points, rs


def _sparse(graph):
    """``(nodes, index, lengths)``: the nodes of ``graph``, each node's index, and the symmetric sparse
    matrix of its edge lengths (an edge of length 0 kept as a tiny length: a sparse matrix has no explicit zero)."""
    from scipy.sparse import coo_matrix

    nodes = list(graph.nodes)
    index = {v: i for i, v in enumerate(nodes)}
    u = np.array([index[a] for a, b in graph.edges], np.int64)
    v = np.array([index[b] for a, b in graph.edges], np.int64)
    w = np.array([max(float(d["length"]), 1e-12) for _, _, d in graph.edges(data=True)], float)
    lengths = coo_matrix((np.r_[w, w], (np.r_[u, v], np.r_[v, u])), shape=(len(nodes), len(nodes))).tocsr()
    return nodes, index, lengths


def _route(nodes, pred, i, j):
    """The nodes from ``nodes[i]`` to ``nodes[j]`` along a predecessor row of a search from ``i``."""
    out = [j]
    while out[-1] != i:
        out.append(int(pred[out[-1]]))
    return [nodes[k] for k in out[::-1]]


def stop_distances(seg_or_G, start, rooms=None, *, robot_width: float = 0.0):
    """Travel distances between a start and the rooms to visit.

    Parameters
    ----------
    seg_or_G : Segmentation or networkx.MultiGraph
    start : (float, float) or int
        Map-frame point (m) or room ID.
    rooms : iterable of int, optional
        Rooms to visit (default every room of the graph).
    robot_width : float
        Doors narrower than this (m) are not used.

    Returns
    -------
    dict
        ``D`` ((n + 1, n + 1) ndarray, m; stop 0 the start, ``inf`` where
        unreachable), ``stops`` (the n room IDs), ``points`` (n + 1 map-frame
        points), ``paths`` (``(i, j) -> list of door IDs`` along the shortest
        route, made when first read), ``start_room``, ``graph`` (the door graph with the stops).
        Memory ``O(n N)`` for ``N`` doors (one search from every stop, in
        :func:`scipy.sparse.csgraph.dijkstra`).
    """
    from scipy.sparse.csgraph import dijkstra

    graph, names, stops, points, rs = _stop_graph(seg_or_G, start, rooms, robot_width)
    nodes, index, lengths = _sparse(graph)
    src = np.array([index[v] for v in names], np.int64)
    dist, pred = dijkstra(lengths, directed=False, indices=src, return_predecessors=True)
    D = dist[:, src]
    return {"D": D, "stops": stops, "points": points, "paths": _Paths(nodes, src, pred, D),
            "start_room": rs, "graph": graph}


class _Paths(dict):
    """``(i, j) -> route`` (the nodes of the door graph from stop ``i`` to stop ``j``), each drawn
    from the searches' predecessors when first read; a missing key: no route."""

    def __init__(self, nodes, src, pred, D):
        super().__init__()
        self._args = (nodes, src, pred, D)

    def __missing__(self, key):
        nodes, src, pred, D = self._args
        i, j = key
        if not np.isfinite(D[i, j]):
            raise KeyError(key)
        self[key] = r = _route(nodes, pred[i], int(src[i]), int(src[j]))
        return r

    def __contains__(self, key):
        nodes, src, pred, D = self._args
        i, j = key
        return bool(np.isfinite(D[i, j]))


def _tree_walk(seg_or_G, start, rooms, robot_width, closed):
    """A tour of many rooms without a distance matrix: the rooms in the order a depth-first walk of
    a minimum spanning tree of the door graph (with the start and the rooms joined to their doors,
    branches to no room cut off) from the start meets them, each leg the way along the tree.

    Every tree edge is walked at most twice (once more back to the start when ``closed``), so the
    tour is at most twice the weight of the tree. Time ``O(N log N)`` in the graph's doors and
    rooms. Returns ``(graph, names, stops, points, start_room, visits, legs, routes, unreachable)``."""
    from scipy.sparse.csgraph import breadth_first_order, depth_first_order, dijkstra, minimum_spanning_tree

    graph, names, stops, points, rs = _stop_graph(seg_or_G, start, rooms, robot_width)
    nodes, index, lengths = _sparse(graph)
    tree = minimum_spanning_tree(lengths)
    tree = (tree + tree.T).tocsr()
    s0 = index[names[0]]
    order, pred = depth_first_order(tree, s0, directed=False, return_predecessors=True)
    stop_of = {index[v]: k for k, v in enumerate(names)}
    reach = {k for k in (stop_of.get(int(i)) for i in order) if k is not None}
    unreachable = [stops[k - 1] for k in range(1, len(names)) if k not in reach]
    # depth and distance from the start along the tree, in breadth-first order (parents first)
    bfs = breadth_first_order(tree, s0, directed=False, return_predecessors=False)
    depth = np.zeros(len(nodes), np.int64)
    for v, p in zip(bfs[1:].tolist(), pred[bfs[1:]].tolist()):
        depth[v] = depth[p] + 1
    along = dijkstra(tree, directed=False, indices=s0)
    visits = [0] + [stop_of[int(i)] for i in order if int(i) in stop_of and stop_of[int(i)] != 0]
    if closed:
        visits.append(0)
    legs, routes = [], []
    for a, b in zip(visits[:-1], visits[1:]):
        i, j = index[names[a]], index[names[b]]
        up, down = [i], [j]
        while up[-1] != down[-1]:  # climb from the deeper end until the two meet
            if depth[up[-1]] >= depth[down[-1]]:
                up.append(int(pred[up[-1]]))
            else:
                down.append(int(pred[down[-1]]))
        top = up[-1]
        legs.append(float(along[i] + along[j] - 2 * along[top]))
        routes.append([nodes[k] for k in up + down[-2::-1]])
    return graph, names, stops, points, rs, visits, legs, routes, unreachable


def _unreachable(rooms, start_room, robot_width) -> NoPathError:
    why = f" with doors at least {robot_width:g} m wide" if robot_width else ""
    more = " ..." if len(rooms) > 20 else ""
    return NoPathError(f"rooms {', '.join(map(str, rooms[:20]))}{more} cannot be reached from room {start_room}{why}")


def _graph_size(seg_or_G) -> int:
    """Number of rooms of a segmentation or a room graph (the stops of a tour of every room)."""
    if isinstance(seg_or_G, nx.Graph):
        return seg_or_G.number_of_nodes()
    return int(getattr(seg_or_G, "n_rooms", 0))


def plan_tour(seg_or_G, start, *, rooms=None, return_to_start: bool = False, robot_width: float = 0.0,
              exact_limit: int = EXACT_LIMIT) -> dict:
    """The order in which to visit rooms from ``start``, with the doors to pass.

    Parameters
    ----------
    seg_or_G : Segmentation or networkx.MultiGraph
        A segmentation or a room–door graph (best one saved by ``topomap
        segment``, which carries the in-room door-to-door distances).
    start : (float, float) or int
        A map-frame point ``(x, y)`` in metres, or a room ID (its point).
    rooms : iterable of int, optional
        The rooms to visit. Default: every room that can be reached from
        the start (the others are listed in ``unreachable``).
    return_to_start : bool
        End the tour back at the start point.
    robot_width : float
        Doors narrower than this (m) are not used.
    exact_limit : int
        Up to this many rooms to visit the order is optimal (Held–Karp);
        above it, nearest neighbour improved by 2-opt and Or-opt.

    Returns
    -------
    dict
        ``order`` (list of int): the rooms in visiting order, the start room
        first; ``doors`` (list of int): every door passed, in order;
        ``rooms`` (list of int): every room passed, in order (rooms crossed
        on the way included); ``legs`` (list of float, m): the travel
        distance to each room of ``order`` after the first (and back to the
        start when ``return_to_start``); ``length`` (float, m): their sum;
        ``waypoints`` ((K, 2) ndarray, m): the start, the door midpoints and
        the room points in order; ``method`` (str): ``"held-karp"``
        (optimal), the heuristic's name, or ``"spanning-tree-walk"`` (above
        :data:`TREE_LIMIT` rooms to visit); ``start_room`` (int);
        ``unreachable`` (list of int).

    Raises
    ------
    NotInRoomError
        The start is not in a room, or an unknown room ID.
    NoPathError
        A room given in ``rooms`` cannot be reached from the start.
    ParameterError
        ``robot_width`` is not a length >= 0 m.
    """
    try:
        exact_limit = int(exact_limit)
    except (TypeError, ValueError):
        raise PlanningError(f"exact_limit must be an integer, got {exact_limit!r}") from None
    n_stops = (len(rooms) if rooms is not None and hasattr(rooms, "__len__")
               else _graph_size(seg_or_G) if rooms is None else None)
    if n_stops is not None and n_stops > max(TREE_LIMIT, exact_limit):
        graph, names, stops, points, rs, visits, legs, routes, unreachable = _tree_walk(
            seg_or_G, start, rooms, robot_width, return_to_start)
        seq = visits[1:-1] if return_to_start else visits[1:]
        method = "spanning-tree-walk"
    else:
        sd = stop_distances(seg_or_G, start, rooms, robot_width=robot_width)
        D, stops, rs, graph, points = sd["D"], sd["stops"], sd["start_room"], sd["graph"], sd["points"]
        reach = [k for k in range(1, len(stops) + 1) if np.isfinite(D[0, k])]
        unreachable = [stops[k - 1] for k in range(1, len(stops) + 1) if not np.isfinite(D[0, k])]
        idx = [0] + reach
        if unreachable and rooms is not None:
            raise _unreachable(unreachable, rs, robot_width)
        sub = D[np.ix_(idx, idx)]
        local, method = solve_order(sub, closed=return_to_start, exact_limit=exact_limit)
        seq = [idx[k] for k in local]
        visits = [0] + seq + ([0] if return_to_start else [])
        legs = [float(D[a, b]) for a, b in zip(visits[:-1], visits[1:])]
        routes = [sd["paths"][(a, b)] for a, b in zip(visits[:-1], visits[1:])]
    if unreachable and rooms is not None:
        raise _unreachable(unreachable, rs, robot_width)
    doors, passed, pts = [], [rs], [points[0]]
    for b, route in zip(visits[1:], routes):
        for u, v in zip(route[:-1], route[1:]):
            room = int(graph.edges[u, v]["room"])
            if room != passed[-1]:
                passed.append(room)
            if isinstance(v, int):
                doors.append(int(v))
                pts.append((graph.nodes[v]["x"], graph.nodes[v]["y"]))
        end_room = rs if b == 0 else stops[b - 1]
        if end_room != passed[-1]:
            passed.append(end_room)
        pts.append(points[b])
    log.info("tour of %d rooms from room %d: %.2f m (%s)", len(seq) + 1, rs, sum(legs), method)
    return {"order": [rs] + [stops[k - 1] for k in seq], "doors": doors, "rooms": passed, "legs": legs,
            "length": float(sum(legs)), "waypoints": np.asarray(pts, float).reshape(-1, 2), "method": method,
            "start_room": rs, "unreachable": unreachable}
