"""The documentation builds, and the graph-attributes page matches the code."""

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PAGE = ROOT / "docs" / "graph-attributes.md"


def _sections(text):
    """``{(h2, h3): set of attribute names}`` from the tables of the page.

    An attribute is the back-quoted first cell of a table row under an
    ``###`` heading.
    """
    out = {}
    h2 = h3 = None
    for line in text.splitlines():
        if line.startswith("## "):
            h2, h3 = line[3:].strip(), None
        elif line.startswith("### "):
            h3 = line[4:].strip()
        else:
            m = re.match(r"\|\s*`([^`]+)`\s*\|", line)
            if m and h2 and h3:
                out.setdefault((h2, h3), set()).add(m.group(1))
    return out


def _find(sections, h2, h3_prefix):
    hits = [v for (a, b), v in sections.items() if a == h2 and b.startswith(h3_prefix)]
    assert len(hits) == 1, f"graph-attributes.md: no unique section '## {h2}' / '### {h3_prefix}...'"
    return hits[0]


def _attrs(G):
    graph = set(G.graph)
    nodes = {k for _, d in G.nodes(data=True) for k in d}
    edges = {k for *_, d in G.edges(data=True) for k in d}
    return graph, nodes, edges


@pytest.fixture(scope="module")
def actual():
    """Attributes the code puts on every kind of graph, over the example map."""
    import topomap
    from topomap import planning
    from topomap.segmentation import METHODS, segment

    grid = topomap.load_map(topomap.example_map_path())
    room = [set(), set(), set()]
    door = [set(), set(), set()]
    skel = [set(), set(), set()]
    for method in METHODS:
        seg = segment(grid, method=method)
        for G, acc in ((seg.room_graph, room), (planning.travel_graph(seg), room),
                       (planning.door_graph(seg), door), (seg.free_graph, skel), (seg.occupied_graph, skel)):
            if G is None:
                continue
            for a, s in zip(acc, _attrs(G)):
                a |= s
    return {"Room graph": room, "Door graph": door, "Skeleton graphs": skel}


@pytest.mark.parametrize("graph", ["Room graph", "Door graph", "Skeleton graphs"])
def test_graph_attributes_page_matches_code(actual, graph):
    sections = _sections(PAGE.read_text(encoding="utf-8"))
    for kind, have in zip(("Graph attributes", "Node attributes", "Edge attributes"), actual[graph]):
        documented = _find(sections, graph, kind)
        missing = have - documented
        assert not missing, f"graph-attributes.md, {graph} / {kind}: undocumented {sorted(missing)}"
        stale = documented - have
        assert not stale, f"graph-attributes.md, {graph} / {kind}: documented but not set {sorted(stale)}"


def test_figures_exist_and_are_referenced():
    pages = "".join(p.read_text(encoding="utf-8") for p in (ROOT / "docs").glob("*.md"))
    for ref in set(re.findall(r"\(img/([\w.-]+\.png)\)", pages)):
        assert (ROOT / "docs" / "img" / ref).is_file(), f"docs/img/{ref} is referenced but missing"
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert "docs/img/example_overlay.png" in readme
    assert (ROOT / "docs" / "img" / "example_overlay.png").is_file()


@pytest.mark.skipif(importlib.util.find_spec("mkdocs") is None
                    or importlib.util.find_spec("mkdocstrings") is None
                    or importlib.util.find_spec("material") is None,
                    reason="docs extra not installed (pip install -e '.[docs]')")
def test_mkdocs_build_strict(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-d", str(tmp_path / "site")],
                          cwd=ROOT, capture_output=True, text=True, timeout=300,
                          env={**__import__("os").environ, "NO_MKDOCS_2_WARNING": "1"})
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert (tmp_path / "site" / "graph-attributes" / "index.html").is_file()


def test_statuses_are_named_constants_only():
    """No module compares or sets a candidate status with a string literal:
    the statuses are the constants of :mod:`topomap.doors`."""
    from topomap import doors

    for path in sorted((ROOT / "topomap").glob("*.py")):
        src = path.read_text(encoding="utf-8")
        bad = re.findall(r"status\s*(?:==|!=|=)\s*\"[^\"]+\"", src)
        assert not bad, f"{path.name}: {bad}"
    assert len(set(doors.STATUSES)) == len(doors.STATUSES)


def test_every_candidate_status_is_explained():
    """Each ``status`` string the code gives a candidate is on how-it-works.md."""
    from topomap import doors

    page = (ROOT / "docs" / "how-it-works.md").read_text(encoding="utf-8")
    statuses = set(doors.STATUSES) - {doors.CANDIDATE}
    assert len(statuses) == 16
    missing = [s for s in sorted(statuses) if f"`{s}`" not in page]
    assert not missing, f"how-it-works.md does not explain candidate status {missing}"
