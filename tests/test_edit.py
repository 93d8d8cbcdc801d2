"""Editing rooms (topomap.core.edit, topomap.run.editing, ``topomap edit``): merges, splits, names and no-go marks keep the
labels, the doors and the room graph consistent; bad edits change nothing; edits last through
``--previous``."""

import json
import math

import networkx as nx
import numpy as np
import pytest
from click.testing import CliRunner

from _testdata import corridor_with_rooms
from topomap.core import edit as E
from topomap.errors import EditError, GraphFormatError, MapFileNotFoundError
from topomap.io.export import load_graph, load_label_map, save_graph
from topomap.core.identity import match_rooms
from topomap.io import from_array, save_map
from topomap.core.segmentation import segment
from topomap.run.editing import load_segmentation

SPECKS = [(2, 20), (3, 100), (125, 40), (124, 200)]  # free 3 x 3 specks outside the building: fragments


def _array():
    """The corridor with three offices (tests/_testdata.py), a margin around it and free specks in it."""
    m = corridor_with_rooms()
    a = np.pad(m.array, 12, constant_values=False)
    for r, c in SPECKS:
        a[r:r + 3, c:c + 3] = True
    return a, m.resolution


@pytest.fixture(scope="module")
def base():
    a, res = _array()
    seg = segment(from_array(a, resolution=res))
    assert seg.n_rooms == 4 and len(seg.doors) == 3 and seg.n_fragments == len(SPECKS)
    return seg


@pytest.fixture
def out_dir(tmp_path):
    """An output folder of ``topomap segment`` of the corridor map (and the map's YAML)."""
    from topomap.cli import main

    a, res = _array()
    save_map(from_array(a, resolution=res), tmp_path / "map")
    r = CliRunner().invoke(main, ["segment", str(tmp_path / "map.yaml"), "-o", str(tmp_path / "out")])
    assert r.exit_code == 0, r.output
    return tmp_path / "out"


def _snapshot(folder):
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def _state(seg):
    return seg.labels.copy(), [(d.id, d.rooms, d.p1, d.p2) for d in seg.doors]


def _cells_of_door(shape, d):
    """The cells of door ``d``'s line and their 8-neighbours (an independent drawing of the line)."""
    n = int(math.ceil(max(abs(d.p1[0] - d.p2[0]), abs(d.p1[1] - d.p2[1])))) * 2 + 1
    t = np.linspace(0.0, 1.0, n)
    r = np.rint(d.p1[0] + t * (d.p2[0] - d.p1[0])).astype(int)
    c = np.rint(d.p1[1] + t * (d.p2[1] - d.p1[1])).astype(int)
    m = np.zeros(shape, bool)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            m[np.clip(r + dr, 0, shape[0] - 1), np.clip(c + dc, 0, shape[1] - 1)] = True
    return m


def check_consistent(seg, base):
    """Every free cell in exactly one room or fragment, the fragments as in ``base``, the room graph's
    nodes the rooms, as many components as ``base``'s, every door between two rooms that touch at it."""
    L = seg.labels
    free = seg.grid.free
    assert np.array_equal(L > 0, free), "a free cell without a label, or a label off the free space"
    top = seg.top_room_id
    assert np.array_equal(L > top, base.labels > base.top_room_id), "fragments changed"
    assert len(np.unique(L[L > top])) == base.n_fragments
    G = seg.room_graph
    rooms = sorted(int(i) for i in np.unique(L[(L > 0) & (L <= top)]))
    assert sorted(G.nodes) == rooms == list(getattr(seg, "room_ids", rooms))
    assert nx.number_connected_components(G) == nx.number_connected_components(base.room_graph)
    ids = [d.id for d in seg.doors]
    assert len(set(ids)) == len(ids)
    assert sorted((min(u, v), max(u, v), k) for u, v, k in G.edges(keys=True)) == \
        sorted((*d.rooms, d.id) for d in seg.doors)
    for d in seg.doors:
        a, b = d.rooms
        assert a != b and a in G and b in G
        near = L[_cells_of_door(L.shape, d)]
        assert (near == a).any() and (near == b).any(), f"door {d.id} {d.rooms}: the rooms do not touch at it"
    assert abs(sum(G.nodes[n]["area"] for n in G) + seg.fragment_area - free.sum() * seg.grid.resolution ** 2) < 1e-6


# --------------------------------------------------------------------------
# Each edit

def test_merge_joins_two_rooms_and_drops_their_door(base):
    before = _state(base)
    office, corridor = next(d.rooms for d in base.doors)
    out = E.merge(base, corridor, office)
    check_consistent(out, base)
    assert office not in out.room_graph and len(out.doors) == len(base.doors) - 1
    assert np.array_equal(out.labels == corridor, (base.labels == corridor) | (base.labels == office))
    assert out.room_graph.nodes[corridor]["merged"] == sorted([office, corridor])
    assert out.room_graph.number_of_nodes() == 3
    # the input is not changed
    assert np.array_equal(base.labels, before[0]) and _state(base)[1] == before[1]
    assert base.room_graph.number_of_nodes() == 4


def test_merge_refuses(base):
    offices = sorted(set(range(1, 5)) - {base.doors[0].rooms[1]})
    with pytest.raises(EditError, match="share no door and do not touch"):
        E.merge(base, offices[0], offices[1])
    with pytest.raises(EditError, match="with itself"):
        E.merge(base, 1, 1)
    with pytest.raises(EditError, match=r"no room 9 \(rooms: 1-4\)"):
        E.merge(base, 1, 9)
    with pytest.raises(EditError, match="not a room ID"):
        E.merge(base, 1, "2")


def _ids(seg):
    return sorted(seg.room_graph.nodes)


def _corridor(seg):
    return max(seg.room_graph.degree, key=lambda t: t[1])[0]


def test_split_makes_a_door_where_the_line_crosses(base):
    c = _corridor(base)
    before = _state(base)
    # across the corridor (rows 81..110, columns 17..264) at x = 4 m (column 80, between two office
    # doors), drawn from the wall above it to the margin below
    x = 4.0
    ys = [base.grid.pixel_to_world(r, 0)[1] for r in (75, 118)]
    out = E.split(base, c, (x, float(ys[0])), (x, float(ys[1])))
    check_consistent(out, base)
    new = out.next_room_id - 1
    assert new == 5 and set(out.room_ids) == {1, 2, 3, 4, 5}
    cut = [d for d in out.doors if set(d.rooms) == {c, new}]
    assert len(cut) == 1 and abs(cut[0].width - 1.55) < 1e-9  # the 1.5 m corridor, wall cell to wall cell
    assert abs(cut[0].midpoint[0] - x) < base.grid.resolution
    # the larger (east) part keeps the ID; each part keeps the doors beside it
    G = out.room_graph
    assert out.labels[95, 200] == c and out.labels[95, 40] == new
    assert G.nodes[c]["area"] > G.nodes[new]["area"] > 1.0
    for d in out.doors:
        if d is not cut[0]:
            assert (new if d.midpoint[0] < x else c) in d.rooms
    assert len(out.doors) == len(base.doors) + 1
    # merging the parts again gives the room back
    back = E.merge(out, c, new)
    assert np.array_equal(back.room_labels == c, base.room_labels == c)
    assert sorted(d.id for d in back.doors) == sorted(d.id for d in base.doors)
    assert np.array_equal(base.labels, before[0]) and _state(base)[1] == before[1]


def test_split_refuses(base):
    c = _corridor(base)
    y = [float(base.grid.pixel_to_world(r, 0)[1]) for r in (75, 118)]
    with pytest.raises(EditError, match="off the map"):
        E.split(base, c, (7.0, y[0]), (7.0, 500.0))
    with pytest.raises(EditError, match="does not cross room"):
        E.split(base, c, (0.1, y[0]), (0.1, y[1]))  # in the margin, left of the building
    with pytest.raises(EditError, match="into one part only"):  # ends inside the corridor: cuts nothing
        E.split(base, c, (7.0, 2.0), (7.0, 1.0))
    with pytest.raises(EditError, match="into no part"):
        E.split(base, c, (7.0, y[0]), (7.0, y[1]), min_area=1000.0)
    with pytest.raises(EditError, match="shorter than a cell"):
        E.split(base, c, (7.0, y[0]), (7.0, y[0]))
    with pytest.raises(EditError, match="not a point"):
        E.split(base, c, (7.0,), (7.0, y[0]))
    with pytest.raises(EditError, match="no room 7"):
        E.split(base, 7, (7.0, y[0]), (7.0, y[1]))
    # a slanted line from wall to wall
    out = E.split(base, c, (2.0, y[0]), (12.0, y[1]))
    check_consistent(out, base)
    assert len(out.doors) == 4 and out.doors[-1].width > 2.0


def test_rename_and_no_go(base):
    out = E.rename(base, 2, "  kitchen ")
    out = E.no_go(out, 3)
    G = out.room_graph
    assert G.nodes[2]["name"] == "kitchen" and G.nodes[3]["no_go"] is True
    assert "name" not in G.nodes[1] and "no_go" not in G.nodes[2]
    assert np.array_equal(out.labels, base.labels)
    assert E.no_go(out, 3, value=False).room_graph.nodes[3].get("no_go") is None
    assert "name" not in base.room_graph.nodes[2]
    for bad, msg in (("", "empty"), ("a\nb", "control character"), (5, "not text"), ("x" * 201, "more than 200")):
        with pytest.raises(EditError, match=msg):
            E.rename(base, 2, bad)
    with pytest.raises(EditError, match="True or False"):
        E.no_go(base, 2, value="yes")


def test_merged_room_takes_names_marks_and_ids(base):
    c = _corridor(base)
    o1, o2 = sorted(set(_ids(base)) - {c})[:2]
    seg = E.no_go(E.rename(base, o1, "lab"), c)
    m = E.merge(E.merge(seg, c, o1), c, o2)
    G = m.room_graph
    assert G.nodes[c]["name"] == "lab" and G.nodes[c]["no_go"] is True
    assert G.nodes[c]["merged"] == sorted([c, o1, o2])


def test_apply_edits_in_order_and_records(base):
    c = _corridor(base)
    y = [float(base.grid.pixel_to_world(r, 0)[1]) for r in (75, 118)]
    out, rec = E.apply_edits(base, [("split", c, 4.0, y[0], 4.0, y[1]), ("name", 5, "east"), ("no_go", 1)])
    assert rec == [{"edit": "split", "room": c, "line": [4.0, y[0], 4.0, y[1]], "new_room": 5},
                   {"edit": "name", "room": 5, "name": "east"}, {"edit": "no_go", "room": 1}]
    assert out.room_graph.nodes[5]["name"] == "east"
    with pytest.raises(EditError, match=r"^here: name 5 'east': no room 5"):  # no room 5 before the split
        E.apply_edits(base, [("name", 5, "east")], source="here")
    with pytest.raises(EditError, match="is not one of"):
        E.apply_edits(base, [("rotate", 1)])


# --------------------------------------------------------------------------
# Any sequence of edits

hypothesis = pytest.importorskip("hypothesis")
st = hypothesis.strategies


def _random_line(seg, room, data):
    """A line through a random cell of ``room`` at a random angle, as long as the map lets it be."""
    grid = seg.grid
    H, W = grid.shape
    rr, cc = np.nonzero(seg.labels == room)
    k = data.draw(st.integers(0, rr.size - 1), label="cell")
    ang = data.draw(st.floats(0, math.pi), label="angle")
    length = data.draw(st.floats(0.3, 8.0), label="half length (m)") / grid.resolution
    u = np.array([math.sin(ang), math.cos(ang)])
    p = np.array([rr[k], cc[k]], float)
    ends = []
    for s in (-1, 1):
        q = p + s * length * u
        q = np.clip(q, [0, 0], [H - 1, W - 1])
        x, y = grid.pixel_to_world(q[0], q[1])
        ends.append((float(x), float(y)))
    return ends


@hypothesis.settings(max_examples=30, deadline=None, derandomize=True,
                     suppress_health_check=list(hypothesis.HealthCheck))
@hypothesis.given(data=st.data())
def test_any_sequence_of_edits_keeps_rooms_doors_and_graph_consistent(base, data):
    seg = base
    for _ in range(data.draw(st.integers(1, 6), label="edits")):
        kind = data.draw(st.sampled_from(["merge", "split", "split", "name", "no_go"]), label="kind")
        before = _state(seg)
        n_doors = len(seg.doors)
        if kind == "merge":
            if not seg.doors:
                continue
            d = data.draw(st.sampled_from(seg.doors), label="door")
            a, b = d.rooms if data.draw(st.booleans(), label="order") else d.rooms[::-1]
            shared = sum(set(e.rooms) == {a, b} for e in seg.doors)
            new = E.merge(seg, a, b)
            assert len(new.doors) == n_doors - shared and b not in new.room_graph
            hypothesis.event("merge made")
        elif kind == "split":
            room = data.draw(st.sampled_from(_ids(seg)), label="room")
            p, q = _random_line(seg, room, data)
            try:
                new = E.split(seg, room, p, q)
            except EditError as exc:
                assert "\n" not in str(exc)
                new = None
                hypothesis.event("split refused")
            else:
                hypothesis.event("split made")
                assert len(new.doors) > n_doors and new.n_rooms == seg.n_rooms + 1
        elif kind == "name":
            room = data.draw(st.sampled_from(_ids(seg)), label="room")
            name = data.draw(st.text(st.characters(codec="utf-8", categories=["L", "N", "Zs"]), min_size=1,
                                     max_size=20).filter(str.strip), label="name")
            new = E.rename(seg, room, name)
            assert new.room_graph.nodes[room]["name"] == name.strip()
        else:
            room = data.draw(st.sampled_from(_ids(seg)), label="room")
            new = E.no_go(seg, room)
            assert new.room_graph.nodes[room]["no_go"] is True
        after = _state(seg)
        assert np.array_equal(before[0], after[0]) and before[1] == after[1], "the input changed"
        if new is not None:
            check_consistent(new, base)
            seg = new


# --------------------------------------------------------------------------
# Output folders and the command line

def test_load_segmentation_reads_back_what_segment_wrote(out_dir, base):
    seg = load_segmentation(out_dir)
    assert np.array_equal(seg.labels, base.labels) and np.array_equal(seg.grid.cells, base.grid.cells)
    assert [(d.id, d.rooms, d.p1, d.p2) for d in seg.doors] == [(d.id, d.rooms, d.p1, d.p2) for d in base.doors]
    G, H = seg.room_graph, base.room_graph
    assert sorted(G.nodes) == sorted(H.nodes)
    assert all(G.nodes[n]["cells"] == H.nodes[n]["cells"] for n in G)
    check_consistent(seg, base)


def test_load_segmentation_without_the_map(out_dir, caplog):
    (out_dir.parent / "map.pgm").unlink()
    seg = load_segmentation(out_dir)
    assert "map.yaml cannot be read" in caplog.text and "taken as the free space" in caplog.text
    assert np.array_equal(seg.grid.free, seg.labels > 0)


def test_load_segmentation_refuses(tmp_path, out_dir):
    with pytest.raises(MapFileNotFoundError, match="no such output folder"):
        load_segmentation(tmp_path / "nope")
    with pytest.raises(MapFileNotFoundError, match="holds no rooms.graphml"):
        load_segmentation(tmp_path)
    G = load_graph(out_dir / "rooms.graphml")
    G.remove_node(1)
    save_graph(G, out_dir / "rooms.graphml")
    with pytest.raises(GraphFormatError, match="disagree: room 1 is in one of them only"):
        load_segmentation(out_dir)


def _run(*args):
    from topomap.cli import main

    return CliRunner().invoke(main, [str(a) for a in args])


def test_cli_edit_rewrites_every_output(out_dir, base):
    c = _corridor(base)
    y = [float(base.grid.pixel_to_world(r, 0)[1]) for r in (75, 118)]
    office = next(d.rooms[0] if d.rooms[1] == c else d.rooms[1] for d in base.doors if d.midpoint[0] > 6)
    old = _snapshot(out_dir)
    r = _run("edit", out_dir, "--name", 5, "west wing", "--split", c, 4.0, y[0], 4.0, y[1], "--merge", c, office,
             "--no-go", 5)
    assert r.exit_code == 1 and "no room 5" in r.output  # applied in the order given: 5 is not there yet
    assert _snapshot(out_dir) == old
    r = _run("edit", out_dir, "--split", c, 4.0, y[0], 4.0, y[1], "--name", 5, "west wing", "--merge", c, office,
             "--no-go", 5)
    assert r.exit_code == 0, r.output
    assert r.output == (f"{out_dir}: split {c} (new room 5); named 5 'west wing'; merged {office} into {c}; 5 no-go "
                        f"-> 4 rooms, 3 doors, 4 fragments (0.09 m²)\n")
    new = _snapshot(out_dir)
    for name in ("labels.png", "labels.pgm", "rooms.graphml", "rooms.json", "rooms.geojson", "overlay.png"):
        assert new[name] != old[name], name
    seg = load_segmentation(out_dir)
    check_consistent(seg, base)
    from PIL import Image

    assert np.array_equal(np.asarray(Image.open(out_dir / "labels.png")), load_label_map(out_dir / "labels.yaml")[0])
    for f in ("rooms.graphml", "rooms.json", "rooms.geojson"):
        G = load_graph(out_dir / f)
        assert sorted(G.nodes) == sorted(seg.room_ids), f
        assert G.nodes[5]["name"] == "west wing" and G.nodes[5]["no_go"] is True, f
        assert E.merged_ids(G.nodes[c]["merged"]) == sorted([c, office]), f
        assert "door_distances" in G.nodes[c] and G.graph["next_room_id"] == 6, f
    rec = json.loads((out_dir / "topomap_run.json").read_text())
    assert rec["status"] == "complete"
    assert [e["edit"] for e in rec["edits"]] == ["split", "name", "merge", "no_go"]
    assert rec["row"]["rooms"] == 4 and rec["row"]["doors"] == 3
    # the same map again into the same folder: up to date, the edits stay
    r = _run("segment", out_dir.parent / "map.yaml", "-o", out_dir)
    assert r.exit_code == 0 and "up to date" in r.output, r.output
    assert _snapshot(out_dir) == new
    # a second edit appends to the record
    assert _run("edit", out_dir, "--name", c, "hall").exit_code == 0
    rec = json.loads((out_dir / "topomap_run.json").read_text())
    assert [e["edit"] for e in rec["edits"]] == ["split", "name", "merge", "no_go", "name"]


BAD = [
    (["--merge", 1, 99], "merge 1 99: no room 99 (rooms: 1-4)"),
    (["--merge", 2, 2], "cannot merge room 2 with itself"),
    (["--no-go", 0], "no room 0"),
    (["--name", 1, ""], "room name '' is empty"),
    (["--name", 1, "a\tb"], "control character"),
    (["--split", 4, 7.0, 2.0, 7.0, 900.0], "off the map"),
    (["--split", 4, 7.0, 4.0, 7.0, 4.5], "does not cross room 4"),
    (["--split", 4, 7.0, 2.0, 7.0, 1.0], "cuts room 4 into one part only"),
    (["--name", 1, "fine", "--merge", 1, 99], "no room 99"),  # a good edit before a bad one: nothing changes
]


@pytest.mark.parametrize("args, msg", BAD, ids=[str(i) for i in range(len(BAD))])
def test_cli_bad_edit_changes_no_file(out_dir, args, msg):
    seg = load_segmentation(out_dir)
    assert seg.room_graph.degree[4] == 3  # the corridor is room 4 (the lines above are drawn for it)
    old = _snapshot(out_dir)
    r = _run("edit", out_dir, *args)
    assert r.exit_code == 1, r.output
    lines = r.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {out_dir}: ") and msg in lines[0], r.stderr
    assert _snapshot(out_dir) == old


def test_cli_edit_usage_and_missing_folder(tmp_path):
    r = _run("edit", tmp_path)
    assert r.exit_code == 2 and "nothing to edit" in r.output
    r = _run("edit", tmp_path / "nope", "--no-go", 1)
    assert r.exit_code == 1 and r.stderr.startswith("error: ") and "nope" in r.stderr
    assert not (tmp_path / "nope").exists()


def test_failed_write_leaves_files_and_record(out_dir, monkeypatch):
    import topomap.io.export as X

    old = _snapshot(out_dir)

    def broken(G, path):
        raise OSError("disk full")

    monkeypatch.setattr(X, "save_geojson", broken)
    r = _run("edit", out_dir, "--name", 1, "kitchen")
    assert r.exit_code == 1 and "disk full" in r.stderr
    assert _snapshot(out_dir) == old


# --------------------------------------------------------------------------
# The next map of the same place

def _bigger(a, res):
    """The same building with 8 more columns of unknown on the left: another image, the same map frame."""
    from topomap.io import OccupancyGrid

    g = from_array(a, resolution=res)
    cells = np.full((g.shape[0], g.shape[1] + 8), -1, np.int8)
    cells[:, 8:] = g.cells
    return OccupancyGrid(cells, res, (g.origin[0] - 8 * res, g.origin[1], 0.0))


def test_previous_keeps_names_marks_merges_and_splits(out_dir, base, tmp_path):
    c = _corridor(base)
    office = next(d.rooms[0] if d.rooms[1] == c else d.rooms[1] for d in base.doors if d.midpoint[0] > 6)
    other = sorted(set(_ids(base)) - {c, office})[0]
    y = [float(base.grid.pixel_to_world(r, 0)[1]) for r in (75, 118)]
    assert _run("edit", out_dir, "--split", c, 4.0, y[0], 4.0, y[1], "--name", 5, "west",
                "--merge", c, office, "--name", c, "hall", "--no-go", other).exit_code == 0
    a, res = _array()
    save_map(_bigger(a, res), tmp_path / "new")
    r = _run("segment", tmp_path / "new.yaml", "-o", tmp_path / "next", "--previous", out_dir / "rooms.graphml")
    assert r.exit_code == 0, r.output
    G = load_graph(tmp_path / "next" / "rooms.graphml")
    assert G.nodes[c]["name"] == "hall" and G.nodes[other]["no_go"] is True
    assert E.merged_ids(G.nodes[c]["merged"]) == sorted([c, office]) and office not in G
    # the split's door is a door of the previous graph: the door prior cuts it again (default method)
    assert G.nodes[5]["name"] == "west" and G.has_edge(c, 5) and G.number_of_nodes() == 4
    assert json.loads((tmp_path / "next" / "changes.json").read_text())["split"] == {}


def test_a_merge_is_kept_where_the_new_map_agrees(out_dir, base):
    """Matching alone (no door prior): the new map's two rooms in the merged room are merged again;
    without the ``merged`` record they would be a split."""
    c = _corridor(base)
    office = next(d.rooms[0] if d.rooms[1] == c else d.rooms[1] for d in base.doors)
    merged = E.rename(E.merge(base, c, office), c, "hall")
    a, res = _array()
    fresh = segment(_bigger(a, res))
    assert fresh.n_rooms == 4
    out, ch = match_rooms(merged.room_graph, fresh)
    assert out.n_rooms == 3 and not ch.split and ch.kept == tuple(sorted(merged.room_ids))
    assert out.room_graph.nodes[c]["name"] == "hall" and len(out.doors) == 2
    check_consistent(out, fresh)
    # the same rooms, the merge record taken away: a split of the previous room
    G = merged.room_graph.copy()
    del G.nodes[c]["merged"]
    _, ch2 = match_rooms(G, fresh)
    assert c in ch2.split
    # the previous merged room without the office's east quarter (a room of its own): the new office lies
    # in it by three quarters, enough for a share of 0.5, not for 0.9
    rows, cols = np.nonzero(base.labels == office)
    col = cols.min() + 0.75 * (cols.max() - cols.min())
    line = [tuple(float(v) for v in merged.grid.pixel_to_world(r, col)) for r in (0, rows.max() + 3)]
    G = E.split(merged, c, *line).room_graph.copy()
    assert "merged" not in G.nodes[c]
    G.nodes[c]["merged"] = [c, office]
    assert match_rooms(G, fresh)[0].n_rooms == 3
    assert match_rooms(G, fresh, min_overlap=0.9)[0].n_rooms == 4


# --------------------------------------------------------------------------
# Nav2 route graphs exported from the folder's room graph
# --------------------------------------------------------------------------

def _cli(*args):
    from topomap.cli import main

    return CliRunner().invoke(main, [str(a) for a in args])


def _a_door(folder):
    """Two rooms of the folder's room graph that share a door (the first door)."""
    a, b, _ = next(iter(load_graph(folder / "rooms.graphml").edges(keys=True)))
    return sorted((a, b))


def test_edit_rewrites_the_nav2_route_graphs_exported_from_the_folder(out_dir, tmp_path):
    inside, outside = out_dir / "route.geojson", tmp_path / "nav" / "route.geojson"
    outside.parent.mkdir()
    assert _cli("export", out_dir / "rooms.graphml", "--nav2", inside).exit_code == 0
    r = _cli("export", out_dir / "rooms.json", "--nav2", outside, "--clearance", "0.15")
    assert r.exit_code == 0, r.output
    notes = json.loads((out_dir / "topomap_run.json").read_text())["nav2"]
    assert notes == [{"path": "route.geojson", "clearance": None}, {"path": str(outside), "clearance": 0.15}]
    before = inside.read_bytes(), outside.read_bytes()
    a, b = _a_door(out_dir)
    r = _cli("edit", out_dir, "--merge", a, b)
    assert r.exit_code == 0, r.output
    assert f"{out_dir}: Nav2 route graph route.geojson rewritten" in r.output
    assert (inside.read_bytes(), outside.read_bytes()) != before  # the merged rooms' route graphs changed
    # each is what exporting the edited room graph gives now, with the clearance it was exported with
    fresh = tmp_path / "fresh.geojson"
    assert _cli("export", out_dir / "rooms.graphml", "--nav2", fresh).exit_code == 0
    assert inside.read_bytes() == fresh.read_bytes()
    assert _cli("export", out_dir / "rooms.graphml", "--nav2", fresh, "--clearance", "0.15").exit_code == 0
    assert outside.read_bytes() == fresh.read_bytes()
    rooms = {f["properties"]["metadata"].get("room") for f in json.loads(inside.read_text())["features"]}
    assert b not in rooms and a in rooms


def test_an_edit_whose_nav2_route_graph_cannot_be_made_changes_no_file(out_dir):
    assert _cli("export", out_dir / "rooms.graphml", "--nav2", out_dir / "route.geojson").exit_code == 0
    record = json.loads((out_dir / "topomap_run.json").read_text())
    record["nav2"][0]["clearance"] = 50.0  # no door is 100 m wide: no route graph of any rooms
    (out_dir / "topomap_run.json").write_text(json.dumps(record))
    before = _snapshot(out_dir)
    r = _cli("edit", out_dir, "--merge", *_a_door(out_dir))
    assert r.exit_code == 1, r.output
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "route.geojson" in lines[0], lines
    assert _snapshot(out_dir) == before


def test_a_room_graph_outside_an_output_folder_notes_no_export(out_dir, tmp_path):
    import shutil

    elsewhere = tmp_path / "copy"
    elsewhere.mkdir()
    for name in ("rooms.graphml", "labels.png"):
        shutil.copy(out_dir / name, elsewhere / name)
    assert _cli("export", elsewhere / "rooms.graphml", "--nav2", elsewhere / "route.geojson").exit_code == 0
    assert not (elsewhere / "topomap_run.json").exists()
    assert "nav2" not in json.loads((out_dir / "topomap_run.json").read_text())


def test_segmenting_the_folder_again_rewrites_its_nav2_route_graphs(out_dir, tmp_path):
    """A changed map segmented into the same folder: the route graph exported from it follows the new rooms."""
    route = out_dir / "route.geojson"
    assert _cli("export", out_dir / "rooms.graphml", "--nav2", route).exit_code == 0
    before = route.read_bytes()
    a, res = _array()
    a[40:60, 120:135] = False  # a block of wall in the corridor: other rooms, another route graph
    save_map(from_array(a, resolution=res), tmp_path / "map")
    r = _cli("segment", tmp_path / "map.yaml", "-o", out_dir)
    assert r.exit_code == 0, r.output
    assert route.read_bytes() != before
    assert json.loads((out_dir / "topomap_run.json").read_text())["nav2"] == [{"path": "route.geojson",
                                                                              "clearance": None}]
    fresh = tmp_path / "fresh.geojson"
    assert _cli("export", out_dir / "rooms.graphml", "--nav2", fresh).exit_code == 0
    assert route.read_bytes() == fresh.read_bytes()
