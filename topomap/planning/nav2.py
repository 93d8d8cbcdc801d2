"""Route graphs for the Nav2 Route Server (``nav2_route``), as GeoJSON.

:func:`route_graph` turns the rooms and doors of a segmentation into the
graph file the Route Server's GeoJSON loader reads;
:func:`topomap.io.nav2.write_route_graph` writes it (atomically).
``topomap export OUT_DIR/rooms.graphml --nav2 graph.geojson`` does both from a
segment output folder.

The file follows the loader of ``nav2_route`` (``GeoJsonGraphFileLoader``):

* a ``FeatureCollection`` whose ``features`` hold every node and edge (at
  least one of each, or the loader refuses the graph);
* a node is a Feature with a ``Point`` geometry ``[x, y]`` (metres in the map
  frame) and ``properties`` ``id`` (a non-negative integer, unique),
  ``frame`` (the frame the coordinates are in) and ``metadata`` (an object);
* an edge is a Feature with a ``MultiLineString`` geometry (the loader does
  not read it; it is the straight line between its nodes, for GIS tools) and
  ``properties`` ``id`` (a non-negative integer, unique among edges and
  nodes), ``startid``, ``endid`` (IDs of existing nodes), ``cost`` (the travel
  length in metres) and ``metadata``; an edge goes one way, so every link is
  written twice, once each way;
* IDs fit 16 bits (the route messages of ``nav2_msgs`` carry them so): at most
  :data:`MAX_IDS` nodes and edges in all;
* ``metadata`` values are numbers, booleans, strings, arrays of those or
  objects (never ``null``: the loader throws on it).

Nodes: one at each door the robot fits through (the widest point of the
door's opening), one inside each room (the room's ``interior_x`` /
``interior_y`` when the graph has them and they have the clearance, else the
room's cell farthest from any wall), and waypoints inside a room where the
way between them bends. The ways are the cheapest paths from the room's
point to each of its doors through the room's cells that keep the robot's
``clearance`` from every cell that is not free, cells near walls costing more
(so the paths keep to the middle of the room, as its skeleton does); the
paths from one room point form a tree, cut at its branch points; each branch
is straightened into as few straight edges as keep every point of every edge
``clearance`` metres clear of walls and unknown space (:func:`segment_clear`).
"""

from __future__ import annotations

import logging
import math

import numpy as np
import networkx as nx
from scipy import ndimage as ndi

from ..core.roommap import RoomMap
from ..errors import ParameterError, PlanningError
from ..options import check_length
from .paths import block_any

__all__ = ["route_graph", "free_clearance", "segment_clear", "DEFAULT_CLEARANCE", "FRAME", "SAMPLES_PER_CELL",
           "REACH", "MAX_IDS"]

log = logging.getLogger("topomap")

#: Default clearance (m): the distance every edge keeps from walls and unknown space. Nav2's sample
#: robots are 0.1 to 0.22 m in radius (``robot_radius`` of its parameter files), and an interior door
#: 0.7 m wide in the clear leaves a robot of radius 0.2 m 0.15 m on either side; pass your robot's
#: radius (or its inscribed radius plus a margin).
DEFAULT_CLEARANCE = 0.2
#: The frame the nodes' coordinates are in (``frame`` of every node), as map_server publishes the map.
FRAME = "map"
#: Node and edge IDs a route graph may use: ``nav2_msgs`` carries them as 16-bit integers
#: (``ComputeRoute``'s ``start_id`` / ``goal_id``, ``RouteEdge.edgeid``).
MAX_IDS = 65536
#: Points tested per cell of an edge's length by :func:`segment_clear`.
SAMPLES_PER_CELL = 10
#: Width (m) of the band along walls in which a cell costs more to cross (up to 3 times): the paths
#: keep this far from walls where the room is wide enough.
_PREFER = 1.0
#: Metres: every reachable cell of a room is at most this far from its tree of paths; the farthest
#: cell beyond it becomes a waypoint (a leaf) until none is (a large hall gets a tree through it).
REACH = 3.0
#: Cells around a door's cells a room's paths may use (the door line may run a cell or two into the
#: room on the other side).
_DOOR_REACH = 2


def free_clearance(free: np.ndarray, resolution: float) -> np.ndarray:
    """Distance (m) from each cell's centre to the nearest cell that is not free (to its edge).

    Parameters
    ----------
    free : (M, N) ndarray of bool
        Free cells (the cells of rooms and fragments: ``labels > 0``).
    resolution : float
        Metres per cell.

    Returns
    -------
    (M, N) ndarray of float
        ``0`` outside the free space; the map's border counts as not free.
    """
    free = np.pad(np.asarray(free, bool), 1)
    d = ndi.distance_transform_edt(free)[1:-1, 1:-1] * resolution - resolution / 2
    return np.maximum(d, 0.0)


def segment_clear(ok: np.ndarray, a, b) -> bool:
    """Whether every point of the segment from pixel ``a`` to pixel ``b`` lies in an ``ok`` cell.

    ``a`` and ``b`` are ``(row, col)`` (cell centres at integers). Points are taken every
    ``1 / SAMPLES_PER_CELL`` cell along the segment, and every cell within half that step of a
    point (along either axis) is tested: every cell the segment touches is among them.
    """
    (r0, c0), (r1, c1) = a, b
    n = int(math.ceil(max(abs(r1 - r0), abs(c1 - c0)) * SAMPLES_PER_CELL)) + 1
    t = np.linspace(0.0, 1.0, n + 1)
    r, c = r0 + (r1 - r0) * t, c0 + (c1 - c0) * t
    H, W = ok.shape
    h = 0.5 / SAMPLES_PER_CELL  # every point of the segment is within h (per axis) of a sample
    for dr in (-h, h):
        for dc in (-h, h):
            rr = np.floor(r + dr + 0.5).astype(np.int64)
            cc = np.floor(c + dc + 0.5).astype(np.int64)
            if rr.min() < 0 or cc.min() < 0 or rr.max() >= H or cc.max() >= W or not ok[rr, cc].all():
                return False
    return True


def _straighten(ok, path):
    """Indices into ``path`` (pixels) of the corners of a polyline from its first to its last pixel
    whose straight pieces stay in ``ok`` cells: split at the pixel farthest from the chord until every
    piece is clear (two 4-neighbours always are)."""
    keep = {0, len(path) - 1}
    stack = [(0, len(path) - 1)]
    P = np.asarray(path, float)
    while stack:
        i, j = stack.pop()
        if j - i < 2 or segment_clear(ok, path[i], path[j]):
            continue
        a, b = P[i], P[j]
        d = b - a
        seg = P[i + 1:j] - a
        L = math.hypot(*d)
        dist = np.abs(seg[:, 0] * d[1] - seg[:, 1] * d[0]) / L if L else np.hypot(seg[:, 0], seg[:, 1])
        k = i + 1 + int(np.argmax(dist))
        keep.add(k)
        stack += [(i, k), (k, j)]
    return sorted(keep)


def _door_line(p1, p2, shape):
    """Cells the segment between door end points ``p1``, ``p2`` (pixels) runs through or along (the
    cells on both sides where it runs along cell edges), without repeats."""
    (r0, c0), (r1, c1) = p1, p2
    n = int(math.ceil(max(abs(r1 - r0), abs(c1 - c0)) * 2)) + 1
    t = np.linspace(0, 1, n + 1)
    r, c = r0 + (r1 - r0) * t, c0 + (c1 - c0) * t
    out = []
    for fr, fc in ((np.floor, np.floor), (np.ceil, np.ceil)):  # a line along cell edges: the cells on both sides
        rr = np.clip(fr(r).astype(int), 0, shape[0] - 1)
        cc = np.clip(fc(c).astype(int), 0, shape[1] - 1)
        for p in zip(rr.tolist(), cc.tolist()):
            if p not in out:
                out.append(p)
    return out


def _plain(v):
    """``v`` as a metadata value the Nav2 loader takes (numbers, strings, booleans, lists of them), or None."""
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        return float(v) if math.isfinite(v) else None
    if isinstance(v, str):
        return v
    return None


def route_graph(seg_or_G, labels=None, *, clearance: float = DEFAULT_CLEARANCE, frame: str = FRAME) -> dict:
    """The Nav2 Route Server graph of a segmentation, as a GeoJSON dict.

    Parameters
    ----------
    seg_or_G : Segmentation or networkx.MultiGraph
        A segmentation, or its room graph (as :func:`topomap.io.export.load_graph` reads it), then with
        ``labels``.
    labels : (M, N) ndarray of int, optional
        The label image of the room graph (``labels.pgm`` / ``labels.png``): rooms and fragments are
        the free space. Required with a graph, ignored with a segmentation.
    clearance : float
        Metres every edge keeps from cells that are not free (walls, unknown space, the map's
        border); doors narrower than twice that get no node.
    frame : str
        The ``frame`` of every node.

    Returns
    -------
    dict
        A GeoJSON ``FeatureCollection`` as the module docstring describes: node metadata
        ``{"type": "room" | "door" | "waypoint", "room": id, "name", "room_kind"}`` (a door:
        ``"door"``, ``"rooms"``, ``"width"`` in m), edge metadata ``{"room", "name", "room_kind"}``
        of the room it runs through plus ``"door"`` and ``"door_width"`` (m) when it ends at a door;
        ``cost`` is the edge's length in metres.

    Raises
    ------
    ParameterError
        Bad ``clearance``, labels missing or of another shape than the graph's map.
    PlanningError
        No edge (no door has the clearance and no room is large enough for a way through it), or more than
        :data:`MAX_IDS` nodes and edges.
    """
    clearance = check_length("clearance", clearance)
    G, labels = _graph_and_labels(seg_or_G, labels)
    room_map = RoomMap(G)  # the map frame and the doors' ends, checked (PlanningError naming what is missing)
    if room_map.shape != tuple(labels.shape):
        raise ParameterError(f"labels of shape {tuple(labels.shape)} do not match the room graph's map "
                             f"(shape {room_map.shape})")
    clear = free_clearance(labels > 0, room_map.resolution)
    ok = clear >= clearance
    room_meta = _room_metadata(G)
    doors = _door_openings(room_map, labels, clear, ok, clearance)
    nodes = []  # (pixel, metadata)
    door_node = {}  # door id -> node index
    for did in sorted(doors):
        a, b, w, px, _ = doors[did]
        door_node[did] = len(nodes)
        nodes.append((px, {"type": "door", "door": did, "rooms": [_plain(a), _plain(b)], "width": w}))
    if not all(isinstance(r, (int, np.integer)) and not isinstance(r, bool) for r in G.nodes):
        raise PlanningError("room graph: room IDs must be integers (the labels of the label image), got "
                            f"{sorted(map(repr, G.nodes))[:5]}")
    edges = []  # (node a, node b, metadata)
    boxes = ndi.find_objects(np.where(labels > 0, labels, 0).astype(np.int64, copy=False))
    for r in sorted(G.nodes):
        ri = int(r)
        if ri < 1 or ri > len(boxes) or boxes[ri - 1] is None:
            continue
        mine = [did for did in sorted(doors) if r in doors[did][:2]]
        win, region, own = _room_window(labels, ok, r, boxes[ri - 1], [doors[did][4] for did in mine])
        if not region.any():
            log.info("room %s has no cell with a clearance of %.2f m: no node", r, clearance)
            continue
        off = (win[0].start, win[1].start)
        start = _room_point(G.nodes[r], own, clear[win], off, room_map.grid)
        if start is None:
            continue
        nodes.append(((start[0] + off[0], start[1] + off[1]), dict(room_meta[r], type="room")))
        key = {start: len(nodes) - 1}  # window pixel -> node index
        mcp, cum, targets = _room_paths(region, clear[win], start, off, {did: doors[did][3] for did in mine},
                                        door_node, key, r, clearance)
        targets += _far_points(mcp, cum, start, targets, own, room_map.resolution)
        _tree_edges(mcp, start, targets, key, ok[win], nodes, edges, off, room_meta[r], doors, door_node)
    if not edges:
        raise PlanningError(f"no route graph: no door has a clearance of {clearance:g} m on both sides and no "
                            f"room is more than {REACH:g} m across at that clearance")
    if len(nodes) + 2 * len(edges) > MAX_IDS:
        raise PlanningError(f"route graph of {len(nodes)} nodes and {2 * len(edges)} edges: more IDs than the "
                            f"{MAX_IDS} Nav2's messages hold (16-bit node and edge IDs); a larger clearance "
                            "gives fewer")
    return _collection(nodes, edges, room_map.grid.pixel_to_world, frame)


def _graph_and_labels(seg_or_G, labels):
    """``(room graph, label image)`` of :func:`route_graph`'s input; ParameterError when a graph comes
    without its labels or the labels are not 2-D."""
    if isinstance(seg_or_G, nx.Graph):
        G = seg_or_G
        if labels is None:
            raise ParameterError("a room graph needs its labels (the label image) for a route graph")
    else:
        G, labels = seg_or_G.room_graph, seg_or_G.labels
    labels = np.asarray(labels)
    if labels.ndim != 2:
        raise ParameterError(f"labels must be a 2-D array, got shape {labels.shape}")
    return G, labels


def _room_metadata(G) -> dict:
    """``room -> metadata`` of the nodes and edges in that room: ``room`` (its ID) and its ``name`` and
    ``room_kind`` when it has them."""
    room_meta = {}
    for r, d in G.nodes(data=True):
        m = {"room": _plain(r)}
        for key in ("name", "room_kind"):
            v = _plain(d.get(key))
            if v is not None and v != "":
                m[key] = v
        room_meta[r] = m
    return room_meta


def _door_openings(room_map, labels, clear, ok, clearance) -> dict:
    """``door id -> (room a, room b, width, cell, line)`` of the doors with a cell of clearance
    ``clearance`` on their line (the ``line`` of cells, :func:`_door_line`): ``cell`` the one of
    largest clearance (``clear``), where the door's node goes. Narrower doors are left out."""
    doors = {}
    for did, (a, b, p1, p2, width, _) in sorted(room_map.doors.items()):
        line = _door_line(p1, p2, labels.shape)
        cells = [p for p in line if ok[p]]
        if not cells:
            log.info("door %d (%.2f m) is too narrow for a clearance of %.2f m: no node", did, width, clearance)
            continue
        best = max(cells, key=lambda p: clear[p])
        doors[did] = (a, b, width, best, line)
    return doors


def _room_window(labels, ok, r, box, lines):
    """``(window, region, own)`` of room ``r`` (its bounding box ``box`` in ``labels``) and the lines
    of cells of its doors (``lines``): ``window`` the slices of the box grown to hold every door cell
    and :data:`_DOOR_REACH` cells around it; ``region`` the window's cells a way in the room may use
    (the room's and, around its doors' cells, any free cell, all of them ``ok``); ``own`` those of
    ``region`` in the room."""
    H, W = labels.shape
    r0, r1, c0, c1 = box[0].start, box[0].stop, box[1].start, box[1].stop
    g = _DOOR_REACH
    for line in lines:
        for p in line:
            r0, r1 = max(min(r0, p[0] - g), 0), min(max(r1, p[0] + g + 1), H)
            c0, c1 = max(min(c0, p[1] - g), 0), min(max(c1, p[1] + g + 1), W)
    win = (slice(r0, r1), slice(c0, c1))
    region = labels[win] == r
    for line in lines:  # the door's cells and the free cells around them: the way through the opening
        for p in line:
            a = slice(max(p[0] - g, 0) - r0, p[0] + g + 1 - r0)
            b = slice(max(p[1] - g, 0) - c0, p[1] + g + 1 - c0)
            region[a, b] |= labels[win][a, b] > 0
    region &= ok[win]
    return win, region, region & (labels[win] == r)


def _room_paths(region, clear, start, off, door_cells, door_node, key, r, clearance):
    """``(mcp, cum, targets)``: the cheapest paths over ``region`` from window pixel ``start`` (cells
    near walls cost more, up to 3 times within :data:`_PREFER` m of one: ``clear`` is each cell's
    clearance), their cumulative costs, and the window pixels of the doors they reach
    (``door_cells``: door id -> map pixel), each put in ``key`` as its door's node."""
    from skimage.graph import MCP_Geometric

    cost = np.where(region, 1.0 + 2.0 * np.clip(1.0 - clear / _PREFER, 0.0, 1.0), np.inf)
    mcp = MCP_Geometric(cost, fully_connected=False)
    cum, _ = mcp.find_costs([start])
    targets = []
    for did, px in door_cells.items():
        q = (px[0] - off[0], px[1] - off[1])
        if not np.isfinite(cum[q]):
            log.info("door %d cannot be reached from the middle of room %s with a clearance of %.2f m",
                     did, r, clearance)
            continue
        key[q] = door_node[did]
        targets.append(q)
    return mcp, cum, targets


def _room_point(d, own, clear, off, grid):
    """The room's node pixel (window coordinates): its interior point if set and clear, else its
    cell of largest clearance (the first in row-major order among equals)."""
    if d.get("interior_x") is not None and d.get("interior_y") is not None:
        row, col = grid.world_to_pixel(float(d["interior_x"]), float(d["interior_y"]))
        q = (int(round(float(row))) - off[0], int(round(float(col))) - off[1])
        if 0 <= q[0] < own.shape[0] and 0 <= q[1] < own.shape[1] and own[q]:
            return q
    if not own.any():
        return None
    k = int(np.argmax(np.where(own, clear, -1.0)))
    return divmod(k, own.shape[1])


def _far_points(mcp, cum, start, targets, own, res):
    """Cells of a large room to add to its tree: the cell of ``own`` (reachable) farthest from the
    paths to ``targets`` while that is more than :data:`REACH` m, so that the tree reaches within
    :data:`REACH` m of every part of the room (its way along a long corridor, into the aisles of a hall).

    Distances are taken on blocks of about 0.25 m (one block of the tree's cells or the room's
    reachable cells: any of its cells), a tenth of the reach."""
    reach = np.isfinite(cum) & own
    if not reach.any():
        return []
    f = max(1, int(round(0.25 / res)))
    H, W = own.shape
    Hf, Wf = -(-H // f) * f, -(-W // f) * f
    tree = np.zeros((Hf, Wf), bool)
    tree[start] = True
    for t in targets:
        p = mcp.traceback(t)
        tree[tuple(np.asarray(p).T)] = True
    big = np.zeros((Hf, Wf), bool)
    big[:H, :W] = reach
    reach_b = block_any(big, f)
    out = []
    limit = int(reach.sum() * res * res / (REACH * REACH)) + 1  # never more than the room has REACH-squares
    while len(out) < limit:
        d = ndi.distance_transform_edt(~block_any(tree, f)) * (res * f)
        d[~reach_b] = 0.0
        k = int(np.argmax(d))
        if d.flat[k] <= REACH:
            break
        br, bc = divmod(k, d.shape[1])
        cells = np.argwhere(reach[br * f:(br + 1) * f, bc * f:(bc + 1) * f])
        q = (int(cells[0][0]) + br * f, int(cells[0][1]) + bc * f)
        out.append(q)
        tree[tuple(np.asarray(mcp.traceback(q)).T)] = True
    return out


def _tree_edges(mcp, start, targets, key, ok, nodes, edges, off, meta, doors, door_node):
    """Edges of the tree of cheapest paths from ``start`` to ``targets`` (window pixels), cut at its
    branch points and at ``key`` pixels, each branch straightened (:func:`_straighten`)."""
    parent, children = {}, {}
    for t in targets:
        path = [tuple(p) for p in mcp.traceback(t)]
        for a, b in zip(path[:-1], path[1:]):
            if b not in parent:
                parent[b] = a
                children.setdefault(a, set()).add(b)
    door_of = {v: did for did, v in door_node.items()}

    def node_at(p):
        if p not in key:
            key[p] = len(nodes)
            nodes.append(((p[0] + off[0], p[1] + off[1]), dict(meta, type="waypoint")))
        return key[p]

    # walk down from the root: a branch ends at a key pixel, a branch point or a leaf
    stack = [start]
    while stack:
        top = stack.pop()
        for c in sorted(children.get(top, ())):
            branch = [top, c]
            while c not in key and len(children.get(c, ())) == 1:
                c = next(iter(children[c]))
                branch.append(c)
            stack.append(c)
            corners = _straighten(ok, branch)
            ids = [node_at(branch[i]) for i in corners]
            for a, b in zip(ids[:-1], ids[1:]):
                em = dict(meta)
                for n in (a, b):
                    if n in door_of:
                        em["door"] = door_of[n]
                        em["door_width"] = doors[door_of[n]][2]
                edges.append((a, b, em))


def _collection(nodes, edges, to_world, frame):
    """The GeoJSON dict of ``nodes`` (pixel, metadata) and ``edges`` (a, b, metadata), both ways."""
    px = np.array([p for p, _ in nodes], float)
    x, y = to_world(px[:, 0], px[:, 1])
    xy = [(float(a), float(b)) for a, b in zip(np.atleast_1d(x), np.atleast_1d(y))]
    feats = []
    for i, (_, m) in enumerate(nodes):
        feats.append({"type": "Feature", "properties": {"id": i, "frame": frame, "metadata": m},
                      "geometry": {"type": "Point", "coordinates": list(xy[i])}})
    eid = len(nodes)
    for a, b, m in edges:
        length = math.dist(xy[a], xy[b])
        for s, e in ((a, b), (b, a)):
            feats.append({"type": "Feature",
                          "properties": {"id": eid, "startid": s, "endid": e, "cost": length, "metadata": m},
                          "geometry": {"type": "MultiLineString", "coordinates": [[list(xy[s]), list(xy[e])]]}})
            eid += 1
    return {"type": "FeatureCollection", "name": "graph",
            "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::3857"}},
            "features": feats}
