"""Room kinds: the shape measures and the kind each room gets."""

from __future__ import annotations

import numpy as np
import pytest

import topomap
from topomap.io.export import load_graph, save_graph
from topomap.core.kinds import KINDS, room_kind, room_shape

from _testdata import corridor_with_rooms


def test_width_and_length_of_a_strip_and_a_square():
    strip = np.zeros((30, 230), bool)
    strip[5:25, 5:225] = True  # 1 m x 11 m at 0.05 m
    s = room_shape(strip, 0.05)
    assert s["area"] == pytest.approx(11.0)
    assert s["width"] == pytest.approx(1.0, abs=0.1)
    assert s["length"] == pytest.approx(11.0, rel=0.1)
    assert s["elongation"] == pytest.approx(11.0, rel=0.2)
    square = np.ones((60, 60), bool)  # 3 m x 3 m: mean width 2 m on this measure, elongation 2.25
    q = room_shape(square, 0.05)
    assert q["width"] == pytest.approx(2.0, abs=0.1)
    assert q["elongation"] == pytest.approx(2.25, abs=0.15)
    # the measure does not depend on the cell size
    fine = room_shape(np.kron(strip, np.ones((2, 2), bool)), 0.025)
    assert fine["width"] == pytest.approx(s["width"], abs=0.06)


def test_kind_rules():
    assert room_kind(12.0, 1.0, 12.0, 4) == "corridor"
    assert room_kind(12.0, 1.0, 12.0, 1) == "room"        # a strip with one door leads nowhere
    assert room_kind(30.0, 1.6, 18.0, 6) == "corridor"    # a wide office corridor, 11 widths long
    assert room_kind(8.0, 1.6, 5.0, 2) == "room"          # as wide but short: a room
    assert room_kind(1.5, 0.9, 1.6, 2) == "doorway"       # a small passage between two doors
    assert room_kind(1.5, 0.9, 1.6, 1) == "room"          # a closet
    assert room_kind(80.0, 6.0, 13.0, 3) == "hall"
    assert room_kind(16.0, 3.0, 5.0, 1) == "room"


def test_rooms_of_a_map_get_their_kind_and_keep_it_in_files(tmp_path):
    seg = topomap.segment(topomap.from_array(corridor_with_rooms().array))
    G = seg.room_graph
    kinds = {n: d["room_kind"] for n, d in G.nodes(data=True)}
    assert set(kinds.values()) <= set(KINDS)
    # the 1.5 m x 12.4 m corridor with three doors; the three 4 m x 3 m offices
    corridor = max(G.nodes, key=G.degree)
    assert kinds[corridor] == "corridor"
    assert all(k == "room" for n, k in kinds.items() if n != corridor)
    assert G.nodes[corridor]["width"] == pytest.approx(1.5, abs=0.15)
    for ext in ("graphml", "json", "geojson"):
        save_graph(G, tmp_path / f"g.{ext}")
        H = load_graph(tmp_path / f"g.{ext}")
        assert {n: d["room_kind"] for n, d in H.nodes(data=True)} == kinds


def _kinds_of(labels, doors, res=0.05):
    import networkx as nx

    from topomap.core.kinds import annotate_kinds

    G = nx.MultiGraph()
    G.add_nodes_from(int(v) for v in np.unique(labels) if v)
    for k, (a, b) in enumerate(doors):
        G.add_edge(a, b, key=k)
    annotate_kinds(G, labels, res)
    return G


def test_furniture_does_not_narrow_a_room_but_a_block_of_walls_does():
    L = np.zeros((120, 120), np.int32)
    L[10:110, 10:110] = 1                     # a 5 m x 5 m room ...
    plain = _kinds_of(L, []).nodes[1]["width"]
    L[50:70, 40:80] = 0                       # ... with a 1 m x 2 m desk in the middle
    assert _kinds_of(L, []).nodes[1]["width"] == pytest.approx(plain)
    # a 1 m wide ring corridor around a 3 m x 3 m block (9 m², not furniture): a corridor
    R = np.zeros((120, 120), np.int32)
    R[10:110, 10:110] = 1
    R[30:90, 30:90] = 0
    R[0:10, 50:60] = 2                        # rooms outside it, through two doors
    R[110:120, 50:60] = 3
    G = _kinds_of(R, [(1, 2), (1, 3)])
    assert G.nodes[1]["width"] == pytest.approx(1.0, abs=0.1)
    assert G.nodes[1]["room_kind"] == "corridor"
    # an enclosed patch that holds another room is never filled, however small
    C = np.zeros((120, 120), np.int32)
    C[10:110, 10:110] = 1
    C[50:70, 50:70] = 0                       # a 1 m x 1 m wall box ...
    filled = _kinds_of(C, []).nodes[1]["width"]
    C[55:65, 55:65] = 2                       # ... around a closet of another room
    assert _kinds_of(C, []).nodes[1]["width"] < filled - 0.1
