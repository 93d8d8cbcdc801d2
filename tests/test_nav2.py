"""Nav2 route graphs: the file the Route Server's GeoJSON loader reads, edges in free space."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from scipy import ndimage as ndi

import topomap
from topomap.cli import main
from topomap.errors import ParameterError, PlanningError
from topomap.io.nav2 import write_route_graph
from topomap.planning.nav2 import DEFAULT_CLEARANCE, route_graph

from _testdata import corridor_with_rooms


class Nav2LoadError(Exception):
    pass


def _uint(v, what):
    # nlohmann::json's get<unsigned int>: an integer number; a bool or a string throws. The route
    # messages (ComputeRoute start_id / goal_id, RouteEdge edgeid) carry IDs as uint16.
    if isinstance(v, bool) or not isinstance(v, int) or v < 0 or v > 2 ** 16 - 1:
        raise Nav2LoadError(f"{what} must be an unsigned integer, got {v!r}")
    return v


def _metadata(props, key="metadata"):
    # convertMetaDataFromJson: objects recurse; numbers, bools, strings and arrays of them; anything
    # else (null) throws "Failed to convert"
    if key not in props:
        return {}
    out = {}
    obj = props[key]
    if not isinstance(obj, dict):
        raise Nav2LoadError(f"{key} must be an object, got {obj!r}")
    for k, v in obj.items():
        if isinstance(v, dict):
            out[k] = _metadata(obj, k)
            continue
        for x in (v if isinstance(v, list) else [v]):
            if not (isinstance(x, (bool, int, float, str))):
                raise Nav2LoadError(f"metadata {k!r}: cannot convert {x!r}")
            if isinstance(x, float) and not math.isfinite(x):
                raise Nav2LoadError(f"metadata {k!r}: {x!r} is not JSON")
        out[k] = v
    return out


def nav2_load(text: str) -> dict:
    """The graph nav2_route's GeoJsonGraphFileLoader builds from ``text``, or Nav2LoadError where it
    refuses the file (its rules, plus unique IDs: the loader keys nodes by ID and edges by ID)."""
    data = json.loads(text)  # Json::parse (strict JSON: no NaN)
    feats = data["features"]
    nodes, edges = [], []
    for f in feats:
        t = f["geometry"]["type"]
        if t == "Point":
            nodes.append(f)
        elif t in ("MultiLineString", "LineString"):
            edges.append(f)
    if not nodes or not edges:
        raise Nav2LoadError("the graph does not contain nodes or edges")
    graph = {}
    for f in nodes:
        p = f["properties"]
        nid = _uint(p["id"], "node id")
        if nid in graph:
            raise Nav2LoadError(f"node id {nid} twice")
        if "frame" in p and not isinstance(p["frame"], str):
            raise Nav2LoadError("frame must be a string")
        x, y = f["geometry"]["coordinates"][:2]
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in (x, y)):
            raise Nav2LoadError(f"node {nid}: bad coordinates")
        if "operations" in p and not isinstance(p["operations"], list):
            raise Nav2LoadError("operations must be a list")
        graph[nid] = {"x": float(x), "y": float(y), "frame": p.get("frame", ""), "metadata": _metadata(p),
                      "edges": []}
    ids = set(graph)
    for f in edges:
        p = f["properties"]
        eid = _uint(p["id"], "edge id")
        s, e = _uint(p["startid"], "startid"), _uint(p["endid"], "endid")
        if eid in ids:
            raise Nav2LoadError(f"edge id {eid} is not unique")
        ids.add(eid)
        if s not in graph:
            raise Nav2LoadError(f"Start id {s} does not exist for edge id {eid}")
        if e not in graph:
            raise Nav2LoadError(f"End id of {e} does not exist for edge id {eid}")
        cost = p.get("cost", 0.0)
        if isinstance(cost, bool) or not isinstance(cost, (int, float)):
            raise Nav2LoadError(f"edge {eid}: cost must be a number")
        if "overridable" in p and not isinstance(p["overridable"], bool):
            raise Nav2LoadError("overridable must be a boolean")
        graph[s]["edges"].append((e, float(cost), eid, _metadata(p)))
    return graph


def _check_loader_rejects():
    # the loader of this test refuses what the C++ loader refuses
    bad = [{"type": "FeatureCollection", "features": []},
           {"features": [{"geometry": {"type": "Point", "coordinates": [0, 0]}, "properties": {"id": -1}}]}]
    for b in bad:
        with pytest.raises((Nav2LoadError, KeyError)):
            nav2_load(json.dumps(b))


def test_loader_of_this_test_refuses_bad_graphs():
    _check_loader_rejects()
    node = {"type": "Feature", "geometry": {"type": "Point", "coordinates": [0, 0]}, "properties": {"id": 0}}
    edge = {"type": "Feature", "geometry": {"type": "MultiLineString", "coordinates": [[[0, 0], [0, 0]]]},
            "properties": {"id": 1, "startid": 0, "endid": 7}}
    with pytest.raises(Nav2LoadError, match="End id"):
        nav2_load(json.dumps({"features": [node, edge]}))
    edge["properties"]["endid"] = 0
    edge["properties"]["metadata"] = {"name": None}
    with pytest.raises(Nav2LoadError, match="convert"):
        nav2_load(json.dumps({"features": [node, edge]}))


def _clearance_of(grid):
    """Distance (m) from each cell centre to the nearest edge of a cell that is not free (or the border)."""
    free = np.pad(grid.free, 1)
    return ndi.distance_transform_edt(free)[1:-1, 1:-1] * grid.resolution - grid.resolution / 2


def _check(grid, R, clearance):
    """The route graph ``R`` of ``grid`` loads by Nav2's rules and keeps every edge ``clearance`` m
    from cells that are not free; returns the loaded graph."""
    g = nav2_load(json.dumps(R))
    clear = _clearance_of(grid)
    H, W = clear.shape
    res = grid.resolution
    for nid, n in g.items():
        assert n["frame"] == "map"
        assert n["metadata"]["type"] in ("room", "door", "waypoint")
        for e, cost, eid, meta in n["edges"]:
            m = g[e]
            assert cost == pytest.approx(math.dist((n["x"], n["y"]), (m["x"], m["y"])))
            assert any(e2 == nid for e2, *_ in m["edges"]), f"edge {eid} has no way back"
            assert "room" in meta
            # sample the segment every 1/20 cell: each point's cell keeps the clearance
            k = int(cost / res * 20) + 2
            t = np.linspace(0, 1, k)
            row, col = grid.world_to_pixel(n["x"] + (m["x"] - n["x"]) * t, n["y"] + (m["y"] - n["y"]) * t)
            rr, cc = np.floor(row + 0.5).astype(int), np.floor(col + 0.5).astype(int)
            assert rr.min() >= 0 and cc.min() >= 0 and rr.max() < H and cc.max() < W
            worst = clear[rr, cc].min()
            assert worst >= clearance - 1e-9, f"edge {eid} passes {worst:.3f} m from a wall (< {clearance} m)"
    return g


def _connected(g):
    seen, todo = set(), [next(iter(g))]
    while todo:
        n = todo.pop()
        if n in seen:
            continue
        seen.add(n)
        todo += [e for e, *_ in g[n]["edges"]]
    return len(seen) == len(g)


def test_hand_drawn_map():
    tm = corridor_with_rooms()
    grid = topomap.from_array(tm.array)
    seg = topomap.segment(grid)
    R = route_graph(seg)
    g = _check(grid, R, DEFAULT_CLEARANCE)
    types = [n["metadata"]["type"] for n in g.values()]
    assert types.count("room") == seg.room_graph.number_of_nodes() == 4
    assert types.count("door") == 3
    assert _connected(g)
    # the door nodes are in the door openings (the known door centres, within a cell or two)
    doors = [(n["x"], n["y"]) for n in g.values() if n["metadata"]["type"] == "door"]
    for x, y in tm.doors:
        assert min(math.dist((x, y), d) for d in doors) < 0.15
    # edge metadata: a door edge names the door and its width; the corridor edges its kind
    metas = [m for n in g.values() for *_, m in n["edges"]]
    assert any("door_width" in m and 0.7 < m["door_width"] < 1.2 for m in metas)
    assert {m["room_kind"] for m in metas} >= {"corridor", "room"}


def test_wide_clearance_drops_narrow_doors():
    tm = corridor_with_rooms()
    grid = topomap.from_array(tm.array)
    seg = topomap.segment(grid)
    # 0.45 m: only the 1.0 m door (0.95 m in the clear between its jamb cells) is wide enough
    g = _check(grid, route_graph(seg, clearance=0.45), 0.45)
    widest = max(seg.doors, key=lambda d: d.width)
    assert [n["metadata"]["door"] for n in g.values() if n["metadata"]["type"] == "door"] == [widest.id]
    # 0.6 m: no door, but a way along the 12 m corridor
    g = _check(grid, route_graph(seg, clearance=0.6), 0.6)
    assert {n["metadata"]["type"] for n in g.values()} == {"room", "waypoint"}
    # 1.6 m: no room is 3.2 m wide
    with pytest.raises(PlanningError, match="no door"):
        route_graph(seg, clearance=1.6)
    with pytest.raises(ParameterError, match="-1"):
        route_graph(seg, clearance=-1)


def l_corridor():
    """An L-shaped corridor (1 m wide, arms of 6 m) widening to 2 m x 2 m at the end of one arm, and
    a room off the far end of the other arm through a 0.9 m door."""
    a = np.zeros((150, 140), bool)
    a[10:30, 10:130] = True      # top arm
    a[10:140, 110:130] = True    # right arm ...
    a[100:140, 90:130] = True    # ... widening at its end
    a[40:90, 10:70] = True       # a room below the top arm (0.5 m wall) ...
    a[30:40, 20:38] = True       # ... through a 0.9 m door at the arm's far end
    return a


def test_l_shaped_corridor_needs_waypoints():
    grid = topomap.from_array(l_corridor())
    seg = topomap.segment(grid)
    assert seg.room_graph.number_of_edges() >= 1
    g = _check(grid, route_graph(seg), DEFAULT_CLEARANCE)
    assert _connected(g)
    # no straight edge joins the two arms: the way round the corner has a waypoint
    assert any(n["metadata"]["type"] == "waypoint" for n in g.values())


def test_write_and_cli(tmp_path):
    tm = corridor_with_rooms()
    grid = topomap.from_array(tm.array)
    out = tmp_path / "out"
    from topomap.run.job import write_segmentation

    seg = topomap.segment(grid)
    write_segmentation(seg, out, overlay=False)
    r = CliRunner().invoke(main, ["export", str(out / "rooms.graphml"), "--nav2", str(tmp_path / "g.geojson")])
    assert r.exit_code == 0, r.output
    assert "Nav2 route graph" in r.output
    text = (tmp_path / "g.geojson").read_text()
    assert nav2_load(text) == nav2_load(json.dumps(route_graph(seg)))  # the files give the API's graph
    # labels.png alone serves as well
    (out / "labels.yaml").unlink()
    r = CliRunner().invoke(main, ["export", str(out / "rooms.graphml"), "--nav2", str(tmp_path / "h.geojson")])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "h.geojson").read_text() == text
    # bad input: one line, exit 1, no file written or changed
    r = CliRunner().invoke(main, ["export", str(out / "rooms.graphml"), "--nav2", str(tmp_path / "g.geojson"),
                                  "--clearance", "5"])
    assert r.exit_code == 1 and r.output.count("\n") == 1 and "no door" in r.output
    assert (tmp_path / "g.geojson").read_text() == text
    (out / "labels.png").unlink()
    r = CliRunner().invoke(main, ["export", str(out / "rooms.graphml"), "--nav2", str(tmp_path / "k.geojson")])
    assert r.exit_code == 1 and "labels" in r.output and not (tmp_path / "k.geojson").exists()
    r = CliRunner().invoke(main, ["export", str(out / "rooms.graphml")])
    assert r.exit_code == 2
    p = write_route_graph(route_graph(seg), tmp_path / "w.geojson")
    assert p.read_text() == text.rstrip("\n")


@pytest.mark.parametrize("argv, code, words", [
    (["--nav2", "{t}/n.geojson", "--clearance", "-1"], 1, "--clearance must be a length >= 0 m, got -1.0"),
    (["--clearance", "0.3"], 2, "--clearance needs --nav2"),
    ([], 2, "give OUTPUT, --nav2"),
    (["--nav2", "{t}/n.geojson", "--clearance", "5"], 1, "no route graph"),
])
def test_export_bad_input(tmp_path, argv, code, words):
    seg = topomap.segment(topomap.from_array(corridor_with_rooms().array))
    from topomap.run.job import write_segmentation

    write_segmentation(seg, tmp_path / "out", overlay=False)
    (tmp_path / "n.geojson").write_text("earlier")
    r = CliRunner().invoke(main, ["export", str(tmp_path / "out" / "rooms.graphml"),
                                  *[a.format(t=tmp_path) for a in argv]])
    assert r.exit_code == code and words in r.output and r.output.count("\n") == 1, r.output
    assert (tmp_path / "n.geojson").read_text() == "earlier"


def test_graph_without_door_ends_is_a_one_line_error():
    seg = topomap.segment(topomap.from_array(corridor_with_rooms().array))
    G = seg.room_graph.copy()
    for *_, d in G.edges(data=True):
        del d["p1"]
    with pytest.raises(PlanningError, match="lacks the attribute 'p1'"):
        route_graph(G, seg.labels)
    with pytest.raises(ParameterError, match="needs its labels"):
        route_graph(G)


def test_export_labels_of_another_map(tmp_path):
    from topomap.run.job import write_segmentation

    write_segmentation(topomap.segment(topomap.from_array(corridor_with_rooms().array)), tmp_path / "a",
                       overlay=False)
    write_segmentation(topomap.segment(topomap.from_array(l_corridor())), tmp_path / "b", overlay=False)
    for name in ("labels.yaml", "labels.pgm"):
        (tmp_path / "a" / name).write_bytes((tmp_path / "b" / name).read_bytes())
    r = CliRunner().invoke(main, ["export", str(tmp_path / "a" / "rooms.graphml"), "--nav2",
                                  str(tmp_path / "n.geojson")])
    assert r.exit_code == 1 and "do not match the room graph's map" in r.output and str(tmp_path / "a") in r.output
    assert not (tmp_path / "n.geojson").exists()


def _real_nogt():
    from topomap.bench.datasets import _shared_dataset

    d = os.environ.get("TOPOMAP_REAL_NOGT_DIR")
    return Path(d) if d and Path(d).is_dir() else _shared_dataset("real_nogt")


REAL = _real_nogt()
REAL_MAPS = sorted(p for p in REAL.rglob("*.yaml")) if REAL else []


@pytest.mark.skipif(not REAL_MAPS, reason="real_nogt maps not available (set TOPOMAP_REAL_NOGT_DIR)")
@pytest.mark.parametrize("path", REAL_MAPS, ids=lambda p: f"{p.parent.name}-{p.stem}")
def test_real_maps(path):
    grid = topomap.load_map(path)
    seg = topomap.segment(grid)
    g = _check(grid, route_graph(seg), DEFAULT_CLEARANCE)
    assert sum(n["metadata"]["type"] == "room" for n in g.values()) >= 1
