"""Exports and round trips of the room–door graph (issue 4): GraphML, JSON, GeoJSON, label map, CLI."""

import json

import numpy as np
import networkx as nx
import pytest

import topomap
from click.testing import CliRunner

from topomap.io import export as E
from topomap import planning as P
from topomap.errors import GraphFormatError, TopomapError
from topomap.io import FREE, OCCUPIED, OccupancyGrid, load_map
from topomap.core.segmentation import Segmentation, cut_rooms, segment

RES = 0.05


def hand_map():
    """Three rooms: west and east joined to a north hall; an L-shaped hall with a hole (a pillar)."""
    cells = np.full((60, 80), OCCUPIED, np.int8)
    cells[3:27, 3:77] = FREE      # north hall
    cells[30:57, 3:38] = FREE     # south-west room
    cells[30:57, 41:77] = FREE    # south-east room
    cells[12:16, 30:34] = OCCUPIED  # a pillar: a hole in the hall's polygon
    cells[27:30, 10:20] = FREE    # door hall - SW (0.5 m)
    cells[27:30, 50:70] = FREE    # door hall - SE (1.0 m)
    grid = OccupancyGrid(cells, RES, (-1.5, 2.25, 0.3))
    labels, doors, _ = cut_rooms(grid, [((28.0, 9.0), (28.0, 20.0)), ((28.0, 49.0), (28.0, 70.0))])
    return Segmentation(grid=grid, labels=labels, doors=doors, method="manual")


@pytest.fixture(scope="module")
def hand():
    return hand_map()


@pytest.fixture(scope="module")
def example():
    from topomap.io.example import example_map_path

    return segment(load_map(example_map_path()))


@pytest.fixture(scope="module", params=["hand", "example"])
def graph(request, hand, example):
    seg = hand if request.param == "hand" else example
    return P.travel_graph(seg)


def assert_graphs_equal(A, B):
    """Same graph attributes, nodes, edges (with keys) and attributes, with the same types."""
    assert A.graph == B.graph
    assert sorted(A.nodes) == sorted(B.nodes)
    assert all(type(n) is type(m) for n, m in zip(sorted(A.nodes), sorted(B.nodes)))
    ea = sorted((min(u, v), max(u, v), k) for u, v, k in A.edges(keys=True))
    eb = sorted((min(u, v), max(u, v), k) for u, v, k in B.edges(keys=True))
    assert ea == eb
    for n in A:
        da, db = A.nodes[n], B.nodes[n]
        assert da == db, n
        assert {k: type(v) for k, v in da.items()} == {k: type(v) for k, v in db.items()}
    for u, v, k in A.edges(keys=True):
        da, db = A.edges[u, v, k], B.edges[u, v, k]
        assert da == db
        assert {a: type(x) for a, x in da.items()} == {a: type(x) for a, x in db.items()}


def test_hand_map(hand):
    assert hand.n_rooms == 3 and [d.rooms for d in hand.doors] == [(1, 2), (1, 3)]
    assert len(list(hand.room_graph.nodes[1]["polygon"].interiors)) == 1  # the pillar


# --------------------------------------------------------------------------
# Round trips
# --------------------------------------------------------------------------

@pytest.mark.parametrize("ext", ["graphml", "json", "geojson"])
def test_round_trip(graph, tmp_path, ext):
    path = E.save_graph(graph, tmp_path / f"rooms.{ext}")
    back = E.load_graph(path)
    assert isinstance(back, nx.MultiGraph)
    assert_graphs_equal(graph, back)
    # and once more: stable
    again = E.load_graph(E.save_graph(back, tmp_path / f"again.{ext}"))
    assert_graphs_equal(graph, again)


def test_round_trip_plain_room_graph(hand, tmp_path):
    G = hand.room_graph  # without travel distances
    for ext in ("graphml", "json", "geojson"):
        assert_graphs_equal(G, E.load_graph(E.save_graph(G, tmp_path / f"g.{ext}")))


def test_restored_types(graph, tmp_path):
    G = E.load_graphml(E.save_graphml(graph, tmp_path / "g.graphml"))
    n = next(iter(G.nodes))
    assert isinstance(n, int)
    assert G.nodes[n]["polygon"].geom_type in ("Polygon", "MultiPolygon")
    assert isinstance(G.graph["origin"], tuple) and isinstance(G.graph["shape"], tuple)
    for u, v, k, d in G.edges(keys=True, data=True):
        assert k == d["door"] and isinstance(k, int)
        assert isinstance(d["p1"], tuple) and all(isinstance(t, float) for t in d["p1"])


def test_graphml_is_plain_for_other_readers(graph, tmp_path):
    from shapely import wkt

    path = E.save_graphml(graph, tmp_path / "g.graphml")
    H = nx.read_graphml(path)  # networkx's own reader, no topomap help
    assert H.number_of_nodes() == graph.number_of_nodes()
    assert H.number_of_edges() == graph.number_of_edges()
    for _, d in H.nodes(data=True):
        assert all(isinstance(v, (str, int, float, bool)) for v in d.values())
        assert wkt.loads(d["polygon"]).geom_type in ("Polygon", "MultiPolygon")
        json.loads(d["door_distances"])
    for _, _, d in H.edges(data=True):
        assert all(isinstance(v, (str, int, float, bool)) for v in d.values())
    text = path.read_text()
    assert 'attr.type="double"' in text and "<graphml" in text


def test_wkt_is_exact():
    from shapely import wkt
    from shapely.geometry import LineString, MultiPolygon, Point, Polygon

    p = Polygon([(0.1 + 1 / 3, 0.7), (1e-3 / 7, 2.123456789012345), (3.3, -1e-7)])
    for g in (p, MultiPolygon([p, Polygon([(10, 10), (11, 10), (11, 11)])]), LineString([(1 / 3, 2 / 3), (5, 6)]),
              Point(1 / 7, -2 / 9), Polygon()):
        assert wkt.loads(E.geometry_wkt(g)).equals_exact(g, 0) or (g.is_empty and wkt.loads(E.geometry_wkt(g)).is_empty)
    assert "e" not in E.geometry_wkt(p).replace("POLYGON", "")


def test_json_is_node_link(graph, tmp_path):
    data = json.loads(E.save_json(graph, tmp_path / "g.json").read_text())
    assert data["multigraph"] is True and len(data["nodes"]) == graph.number_of_nodes()
    assert len(data["edges"]) == graph.number_of_edges()
    assert all(isinstance(n["id"], int) for n in data["nodes"])


def test_geojson_feature_collection(graph):
    from shapely.geometry import shape

    from shapely.geometry import Polygon

    H, W = graph.graph["shape"]
    grid = OccupancyGrid(np.zeros((H, W), np.int8), graph.graph["resolution"], graph.graph["origin"])
    xs, ys = grid.pixel_to_world(np.array([-0.5, -0.5, H - 0.5, H - 0.5]), np.array([-0.5, W - 0.5, W - 0.5, -0.5]))
    extent = Polygon(list(zip(xs, ys))).buffer(1e-9)
    fc = E.to_geojson(graph)
    json.dumps(fc, allow_nan=False)  # plain JSON
    assert fc["type"] == "FeatureCollection"
    rooms = [f for f in fc["features"] if f["properties"]["kind"] == "room"]
    doors = [f for f in fc["features"] if f["properties"]["kind"] == "door"]
    assert len(rooms) == graph.number_of_nodes() and len(doors) == graph.number_of_edges()
    for f in rooms:
        assert f["type"] == "Feature"
        assert f["geometry"]["type"] in ("Polygon", "MultiPolygon")
        n = f["properties"]["room"]
        assert shape(f["geometry"]).equals_exact(graph.nodes[n]["polygon"], 0)
        assert f["properties"]["area"] == graph.nodes[n]["area"]
        # map-frame metres: the polygon lies within the map's extent
        assert shape(f["geometry"]).within(extent)
    for f in doors:
        p = f["properties"]
        assert f["geometry"]["type"] == "LineString"
        a, b = p["rooms"]
        d = graph.edges[a, b, p["door"]]
        assert f["geometry"]["coordinates"] == [[d["x1"], d["y1"]], [d["x2"], d["y2"]]]
        assert p["width"] == d["width"] and isinstance(p["p1"], list)


def test_load_errors(tmp_path):
    bad = tmp_path / "bad.graphml"
    bad.write_text("<graphml><not closed")
    with pytest.raises(GraphFormatError, match="bad.graphml"):
        E.load_graph(bad)
    js = tmp_path / "bad.json"
    js.write_text("{not json")
    with pytest.raises(GraphFormatError):
        E.load_graph(js)
    js.write_text('{"type": "Topology"}')
    with pytest.raises(GraphFormatError):
        E.load_json(js)
    gj = tmp_path / "bad.geojson"
    gj.write_text('{"type": "Feature"}')
    with pytest.raises(GraphFormatError, match="FeatureCollection"):
        E.load_graph(gj)
    with pytest.raises(GraphFormatError, match="unknown graph format"):
        E.load_graph(tmp_path / "x.txt")
    with pytest.raises(FileNotFoundError):
        E.load_graph(tmp_path / "missing.json")
    for e in (GraphFormatError,):
        assert issubclass(e, TopomapError) and issubclass(e, ValueError)


def test_geojson_in_a_json_file(graph, tmp_path):
    path = tmp_path / "g.json"
    path.write_text(json.dumps(E.to_geojson(graph)))
    assert_graphs_equal(graph, E.load_graph(path))


# --------------------------------------------------------------------------
# Atomic writes and write_outputs
# --------------------------------------------------------------------------

@pytest.mark.parametrize("ext", ["graphml", "json", "geojson"])
def test_failed_write_keeps_the_old_file(graph, tmp_path, monkeypatch, ext):
    path = E.save_graph(graph, tmp_path / f"g.{ext}")
    before = path.read_bytes()

    def boom(*a, **k):
        raise OSError("disk full")

    monkeypatch.setattr(json, "dump", boom)
    monkeypatch.setattr(json, "dumps", boom)  # the writers encode with json.dumps (the C encoder)
    monkeypatch.setattr(E, "graphml_bytes", boom)  # the GraphML text, made before the file is written
    with pytest.raises(OSError, match="disk full"):
        E.save_graph(nx.MultiGraph(), path)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == [path.name]


def test_write_outputs_only_writes(hand, tmp_path):
    """export.write_outputs saves the graph and picture it is given, as they are."""
    G = P.travel_graph(hand)
    G.graph["marker"] = "given"
    out = E.write_outputs(hand, tmp_path / "o", G, overlay_png=b"\x89PNG fake")
    assert out["overlay"].read_bytes() == b"\x89PNG fake"
    assert E.load_graph(out["json"]).graph["marker"] == "given"
    assert "overlay" not in E.write_outputs(hand, tmp_path / "p", G)


def test_write_outputs(hand, tmp_path):
    from topomap.run.job import write_segmentation

    out = write_segmentation(hand, tmp_path / "out", overlay=False)
    assert set(out) >= {"labels", "graphml", "json", "geojson"}
    assert out["geojson"].name == "rooms.geojson"
    for p in out.values():
        assert p.is_file()
    G = E.load_graph(out["graphml"])
    assert G.graph["travel_distances"] == "geodesic"
    assert all("door_distances" in d for _, d in G.nodes(data=True))
    assert_graphs_equal(G, E.load_graph(out["geojson"]))
    assert_graphs_equal(G, E.load_graph(out["json"]))


# --------------------------------------------------------------------------
# Label image as a ROS map pair
# --------------------------------------------------------------------------

def test_label_map_round_trip(hand, tmp_path):
    yml = E.save_label_map(hand, tmp_path / "labels")
    assert yml.name == "labels.yaml" and (tmp_path / "labels.pgm").is_file()
    labels, res, origin = E.load_label_map(yml)
    np.testing.assert_array_equal(labels, hand.labels)
    assert res == hand.grid.resolution and origin == hand.grid.origin
    assert (tmp_path / "labels.pgm").read_bytes().startswith(b"P5\n80 60\n255\n")
    # aligned with the input map: map_server-style loading gives the same frame
    grid = load_map(yml)
    assert grid.shape == hand.grid.shape and grid.resolution == hand.grid.resolution
    assert grid.origin == hand.grid.origin
    np.testing.assert_array_equal(grid.cells, hand.labels)  # mode raw: the value is the label
    assert "mode: raw" in yml.read_text()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["labels.pgm", "labels.yaml"]


def test_label_map_16_bit(tmp_path):
    labels = np.arange(20 * 30, dtype=np.int32).reshape(20, 30)
    yml = E.save_label_map(labels, tmp_path / "many.yaml", resolution=0.1, origin=(1, 2))
    assert (tmp_path / "many.pgm").read_bytes().startswith(b"P5\n30 20\n65535\n")
    back, res, origin = E.load_label_map(yml)
    np.testing.assert_array_equal(back, labels)
    assert res == 0.1 and origin == (1.0, 2.0, 0.0)


def test_label_map_example(example, tmp_path):
    labels, res, origin = E.load_label_map(E.save_label_map(example, tmp_path / "ex"))
    np.testing.assert_array_equal(labels, example.labels)
    assert (res, origin) == (example.grid.resolution, example.grid.origin)


# --------------------------------------------------------------------------
# CLI
# --------------------------------------------------------------------------

def _run(*args):
    from topomap.cli import main

    return CliRunner().invoke(main, [str(a) for a in args])


def _stderr(r):
    return getattr(r, "stderr", r.output)


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    """rooms.graphml / rooms.json of a corridor of five rooms (doors 0.8, 1.0, 0.6, 1.0 m)."""
    from test_planning import corridor_of_rooms, room_centre

    seg = corridor_of_rooms()
    d = tmp_path_factory.mktemp("saved")
    E.write_outputs(seg, d, P.travel_graph(seg))
    return d, room_centre(seg, 1), room_centre(seg, 5)


@pytest.mark.parametrize("name", ["rooms.graphml", "rooms.json", "rooms.geojson"])
def test_cli_plan(saved, name):
    d, s, g = saved
    r = _run("plan", d / name, "--from", s[0], s[1], "--to", g[0], g[1])
    assert r.exit_code == 0, _stderr(r)
    assert "rooms: 1 -> 2 -> 3 -> 4 -> 5" in r.stdout
    for i in range(4):
        assert f"door {i}" in r.stdout
    assert "length:" in r.stdout and " m" in r.stdout


def test_cli_plan_json(saved):
    d, s, g = saved
    r = _run("plan", d / "rooms.json", "--from", s[0], s[1], "--to", g[0], g[1], "--json")
    assert r.exit_code == 0, _stderr(r)
    out = json.loads(r.stdout)
    assert out["rooms"] == [1, 2, 3, 4, 5] and out["doors"] == [0, 1, 2, 3]
    assert len(out["waypoints"]) == 6 and out["length"] == pytest.approx(g[0] - s[0], abs=0.15)


def test_cli_plan_errors(saved, tmp_path):
    d, s, g = saved
    r = _run("plan", d / "rooms.graphml", "--from", s[0], s[1], "--to", g[0], g[1], "--robot-width", 0.7)
    assert r.exit_code == 1
    assert _stderr(r).strip().count("\n") == 0 and "no path" in _stderr(r)
    r = _run("plan", d / "rooms.graphml", "--from", -100, 0, "--to", g[0], g[1])
    assert r.exit_code == 1 and "outside the map" in _stderr(r)
    r = _run("plan", tmp_path / "missing.graphml", "--from", 0, 0, "--to", 1, 1)
    assert r.exit_code == 1 and _stderr(r).startswith("error: ")
    r = _run("plan", d / "rooms.graphml", "--from", 0, "--to", 1, 1)
    assert r.exit_code == 2


def test_cli_export(saved, tmp_path):
    d, _, _ = saved
    G = E.load_graph(d / "rooms.graphml")
    for src, dst in [("rooms.graphml", "a.geojson"), ("rooms.json", "b.graphml"), ("rooms.geojson", "c.json")]:
        r = _run("export", d / src, tmp_path / dst)
        assert r.exit_code == 0, _stderr(r)
        assert "5 rooms, 4 doors" in r.stdout
        assert_graphs_equal(G, E.load_graph(tmp_path / dst))
    r = _run("export", d / "rooms.graphml", tmp_path / "x.txt")
    assert r.exit_code == 1 and "unknown graph format" in _stderr(r)
    assert not (tmp_path / "x.txt").exists()
    bad = tmp_path / "bad.json"
    bad.write_text("[]")
    r = _run("export", bad, tmp_path / "y.graphml")
    assert r.exit_code == 1 and _stderr(r).startswith("error: ")


# --------------------------------------------------------------------------
# The direct writers give the documents of the generic ones
# --------------------------------------------------------------------------

def _odd_graph():
    """Attributes a GraphML writer must escape or type: markup, quotes, newlines, empty strings,
    bools, a key whose type changes between nodes, a MultiPolygon, a 3-D polygon, no polygon."""
    from shapely.geometry import MultiPolygon, Polygon

    G = nx.MultiGraph(name='a&<b>"q"', flag=True, f=1.5, empty="")
    square = Polygon([(0, 0), (1e-7, 0), (1, 1), (0, 1)], [[(0.2, 0.2), (0.4, 0.2), (0.4, 0.4)]])
    G.add_node('x"\n\t&<1>', text="a<&>\"'\r\n\tb", ok=False, i=3, polygon=square)
    G.add_node(2, i=2.5, polygon=MultiPolygon([square, Polygon([(5, 5), (6.25, 5), (6, 6e20)])]))
    G.add_node(3, polygon=Polygon([(0, 0, 1), (1, 0, 2), (1, 1, 3)]))
    G.add_node(4, polygon=None, note="é")
    G.add_node(5)
    G.add_edge('x"\n\t&<1>', 2, key='k"1', door=1, x1=0.0, y1=1.0, x2=2.0, y2=3.5)
    G.add_edge(2, 3, key=7, w=1, x1=-0.0, y1=1e-9, x2=2.0, y2=3.0)
    return G


@pytest.mark.parametrize("which", ["odd", "hand", "example", "empty", "directed"])
def test_graphml_bytes_is_networkx_document(which, hand, example):
    import io

    G = {"odd": _odd_graph, "hand": lambda: P.travel_graph(hand), "example": lambda: P.travel_graph(example),
         "empty": nx.MultiGraph, "directed": lambda: nx.DiGraph([(1, 2, {"w": 1}), (2, 3, {})])}[which]()
    H = E.to_graphml_graph(G)
    buf = io.BytesIO()
    nx.write_graphml_xml(H.copy(), buf)
    assert E.graphml_bytes(H) == buf.getvalue()
    back = nx.read_graphml(io.BytesIO(E.graphml_bytes(H)))
    assert back.number_of_nodes() == G.number_of_nodes() and back.number_of_edges() == G.number_of_edges()


@pytest.mark.parametrize("which", ["odd", "hand", "example"])
def test_geojson_file_is_json_of_to_geojson(which, hand, example, tmp_path):
    G = {"odd": _odd_graph, "hand": lambda: P.travel_graph(hand), "example": lambda: P.travel_graph(example)}[which]()
    path = E.save_geojson(G, tmp_path / "g.geojson")
    assert path.read_text() == json.dumps(E.to_geojson(G))


def test_write_outputs_files_as_the_single_writers(hand, tmp_path):
    """The outline texts shared by GraphML, JSON and GeoJSON in write_outputs give the files the
    single writers give."""
    G = P.travel_graph(hand)
    files = E.write_outputs(hand, tmp_path / "all", G)
    for kind, save in (("graphml", E.save_graphml), ("json", E.save_json), ("geojson", E.save_geojson)):
        alone = save(G, tmp_path / f"alone.{kind}")
        assert files[kind].read_bytes() == alone.read_bytes(), kind


@pytest.mark.parametrize("n_labels", [3, 600])
def test_write_outputs_label_map_as_save_label_map(n_labels, tmp_path):
    """write_outputs writes labels.pgm (its header and pixels apart, 8 or 16 bits) and labels.yaml
    as save_label_map does."""
    labels = (np.arange(20 * 30, dtype=np.int32).reshape(20, 30) % n_labels).astype(np.int32)
    grid = OccupancyGrid(np.full((20, 30), FREE, np.int8), 0.1, (1.0, 2.0, 0.5))
    seg = Segmentation(grid=grid, labels=labels, doors=[], method="manual")
    files = E.write_outputs(seg, tmp_path / "all", nx.MultiGraph())
    E.save_label_map(seg, tmp_path / "alone" / "labels")
    for kind, name in (("label_map_pgm", "labels.pgm"), ("label_map", "labels.yaml")):
        assert files[kind].read_bytes() == (tmp_path / "alone" / name).read_bytes(), kind
    assert files["label_map_pgm"].read_bytes() == E.label_map_bytes(seg, "labels.pgm")[0]
    back, _, _ = E.load_label_map(files["label_map"])
    np.testing.assert_array_equal(back, labels)


def test_json_text_is_json_dumps_of_node_link(hand, tmp_path):
    """rooms.json is json.dumps of the node-link data (the outlines' WKT copied in whole), also when
    an attribute holds the mark that stands for a WKT text there."""
    G = P.travel_graph(hand)
    n = next(iter(G.nodes))
    for mark in (None, E._MARK, E._MARK * 2):
        if mark is not None:
            G.nodes[n]["note"] = mark
        path = E.save_json(G, tmp_path / "g.json")
        assert path.read_text() == json.dumps(E.node_link(G), allow_nan=False)
        assert E.load_json(path).nodes[n].get("note") == mark


def test_wkt_of_odd_coordinates_reads_back_exactly():
    from shapely import wkt

    G = _odd_graph()
    for n in (2, 'x"\n\t&<1>'):
        g = G.nodes[n]["polygon"]
        text = E.geometry_wkt(g)
        assert "e" not in text.replace("POLYGON", "").replace("MULTI", "")
        assert wkt.loads(text).equals_exact(g, 0)


def test_json_writes_non_finite_numbers_as_null(tmp_path):
    """rooms.json stays valid JSON (no bare NaN / Infinity) and reads back as NaN."""
    import json
    import math

    import topomap
    from topomap.io.export import load_json, save_json

    G = topomap.segment(topomap.load_map(topomap.example_map_path())).room_graph.copy()
    n = next(iter(G.nodes))
    G.nodes[n]["area"] = float("nan")
    p = tmp_path / "g.json"
    save_json(G, p)
    text = p.read_text()
    json.loads(text, parse_constant=lambda c: pytest.fail(f"bare {c} in rooms.json"))
    assert math.isnan(load_json(p).nodes[n]["area"])


def test_graphml_of_a_non_utf8_source_name_loads(tmp_path):
    import networkx as nx
    from topomap.io.export import load_graphml, save_graphml

    G = nx.MultiGraph(source=b"caf\xe9\x01.png".decode("utf-8", "surrogateescape"))
    G.add_node(1, area=1.0)
    save_graphml(G, tmp_path / "g.graphml")
    assert load_graphml(tmp_path / "g.graphml").graph["source"] == "caf\\xe9\\x01.png"


def test_the_typed_room_attributes_are_the_computed_ones():
    """Every attribute room_graph computes has a type for the file round trip, and nothing else does: a
    user's own attribute (a name, a no-go mark) is carried as it is, and to the next map."""
    from topomap.core.result import ROOM_ATTRIBUTES
    from topomap.io.export import NODE_TYPES

    assert set(NODE_TYPES) == set(ROOM_ATTRIBUTES)
    seg = topomap.segment(topomap.load_map(topomap.example_map_path()))
    computed = {k for _, d in seg.room_graph.nodes(data=True) for k in d}
    assert computed | {"door_distances"} == set(ROOM_ATTRIBUTES)  # travel distances: topomap segment adds them
