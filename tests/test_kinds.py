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


def test_kind_rules_of_the_place_in_the_graph():
    # a 1 m x 3 m strip with two doors: a corridor when every route between its two neighbours
    # passes through it and neither is a dead end ...
    assert room_kind(3.0, 1.0, 3.0, 2) == "corridor"
    assert room_kind(3.0, 1.0, 3.0, 2, cut=True, dead_ends=0, widest_door=0.9) == "corridor"
    # ... not when one of them has no other door (the washroom before a bath) ...
    assert room_kind(3.0, 1.0, 3.0, 2, dead_ends=1) == "room"
    assert room_kind(2.0, 1.0, 2.0, 2, dead_ends=1) == "doorway"   # a small one: a lobby
    # ... unless it is a long strip (the end of a corridor, six widths long or more)
    assert room_kind(8.0, 1.0, 8.0, 2, dead_ends=1) == "corridor"
    # a strip beside two rooms joined otherwise too, through doors much wider than itself: a balcony
    assert room_kind(3.0, 1.0, 3.0, 2, cut=False, widest_door=2.0) == "room"
    assert room_kind(3.0, 1.0, 3.0, 2, cut=False, widest_door=0.9) == "corridor"  # a corridor of a loop
    assert room_kind(8.0, 1.0, 8.0, 2, cut=False, widest_door=2.0) == "room"
    # three doors or more: a hallway, however short; one door: never a corridor; none: by its shape
    assert room_kind(1.5, 1.0, 1.5, 3) == "corridor"
    assert room_kind(3.0, 1.0, 3.0, 3, cut=False, dead_ends=2) == "corridor"
    assert room_kind(4.0, 1.0, 4.0, 1) == "room"
    assert room_kind(4.0, 1.0, 4.0, 0) == "corridor"
    assert room_kind(2.2, 1.0, 2.2, 0) == "room"   # not three widths long
    # wider than a home's hallway: the wide-corridor rule alone, with the same place in the graph
    assert room_kind(5.0, 1.6, 3.1, 3) == "room"


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
    """The room graph of ``labels`` with these doors ``(a, b)`` or ``(a, b, width)``, annotated."""
    import networkx as nx

    from topomap.core.kinds import annotate_kinds

    G = nx.MultiGraph()
    G.add_nodes_from(int(v) for v in np.unique(labels) if v)
    for k, (a, b, *w) in enumerate(doors):
        G.add_edge(a, b, key=k, width=w[0] if w else 0.8)
    annotate_kinds(G, labels, res)
    return G


def _flat():
    """A small flat at 0.05 m: a 1 m x 4 m hallway (1) below two bedrooms (2, 3), a 1 m x 4 m
    balcony (4) above them, a 1 m x 3.2 m washroom (5) below the hallway and a bath (6) below it."""
    L = np.zeros((180, 120), np.int32)
    L[100:120, 20:100] = 1
    L[20:100, 20:60] = 2
    L[20:100, 60:100] = 3
    L[0:20, 20:100] = 4
    L[120:140, 20:84] = 5
    L[140:180, 20:84] = 6
    return L


def test_the_place_in_the_graph_tells_the_narrow_rooms_of_a_flat_apart():
    L = _flat()
    doors = [(1, 2), (1, 3), (1, 5), (5, 6), (2, 4, 1.8), (3, 4, 1.8)]
    G = _kinds_of(L, doors)
    kinds = {n: d["room_kind"] for n, d in G.nodes(data=True)}
    # hallway, balcony and washroom are all about 1 m wide and three to four widths long
    for n in (1, 4, 5):
        assert G.nodes[n]["width"] == pytest.approx(1.0, abs=0.15)
        assert G.nodes[n]["length"] >= 3.0 * G.nodes[n]["width"]
    assert kinds[1] == "corridor"       # three rooms open onto it
    assert kinds[4] == "room"           # beside the bedrooms, through their 1.8 m glass doors
    assert kinds[5] == "room"           # the anteroom of the bath, which has no other door
    assert kinds[2] == kinds[3] == kinds[6] == "room"
    # a second door of the bath to the hallway: the washroom is a passage of a loop, with doors
    G = _kinds_of(L, doors + [(6, 1)])
    assert G.nodes[5]["room_kind"] == "corridor"
    # the balcony's doors as narrow as ordinary doors: a passage between the bedrooms
    G = _kinds_of(L, doors[:4] + [(2, 4), (3, 4)])
    assert G.nodes[4]["room_kind"] == "corridor"


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


def test_a_strip_too_narrow_to_walk_along_is_no_corridor():
    """0.6 m, about a person's shoulders and a margin: a narrower strip is a gap between walls."""
    assert room_kind(1.1, 0.44, 2.6, 0) == "room"        # a sliver with no door (seen on a real map)
    assert room_kind(1.5, 0.6, 2.5, 0) == "corridor"     # as narrow as a corridor gets
    assert room_kind(2.0, 0.5, 4.0, 3) == "doorway"      # three doors do not make a gap a hallway


@pytest.mark.parametrize("seed", range(8))
def test_the_patches_filled_are_those_of_the_rule(seed):
    """A room's cells with its enclosed patches filled, against the rule with scipy's labelling: the
    4-connected pieces of its box's other cells that reach neither the box's border nor another room's
    cell, up to FURNITURE_MAX_AREA; on blocky random rooms with specks of no room."""
    from scipy import ndimage as ndi

    from topomap.core.kinds import FURNITURE_MAX_AREA, _without_furniture

    rng = np.random.default_rng(seed)
    for _ in range(40):
        h, w = (int(v) for v in rng.integers(1, 40, 2))
        f = int(rng.integers(1, 6))
        L = np.kron(rng.integers(0, 4, (h // f + 1, w // f + 1)), np.ones((f, f), int))[:h, :w]
        L = np.where(rng.random((h, w)) < rng.random() * 0.3, 0, L)
        res = float(rng.choice([0.05, 0.2, 0.5]))
        for n in range(1, 4):
            m = L == n
            holes, k = ndi.label(~m)
            size = np.bincount(holes.ravel(), minlength=k + 1)
            fill = size * res ** 2 <= FURNITURE_MAX_AREA
            fill[0] = False
            fill[np.concatenate([holes[0], holes[-1], holes[:, 0], holes[:, -1]])] = False
            fill[holes[(L != 0) & ~m]] = False
            np.testing.assert_array_equal(_without_furniture(L, n, res), m | fill[holes])
