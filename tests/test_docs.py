"""The documentation builds, the graph-attributes page matches the code, the
index and the site's navigation list every page, and the command outputs the
pages show are what the commands print.

``python tests/test_docs.py`` rewrites those outputs (after a change to what a
command prints).
"""

import importlib.util
import os
import re
import shlex
import subprocess
import sys
import tempfile
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
    from topomap.core.segmentation import METHODS, segment

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
    the statuses are the constants of :mod:`topomap.core.doors`."""
    from topomap.core import doors

    for path in sorted((ROOT / "topomap").glob("*.py")):
        src = path.read_text(encoding="utf-8")
        bad = re.findall(r"status\s*(?:==|!=|=)\s*\"[^\"]+\"", src)
        assert not bad, f"{path.name}: {bad}"
    assert len(set(doors.STATUSES)) == len(doors.STATUSES)


def test_every_candidate_status_is_explained():
    """Each ``status`` string the code gives a candidate is on how-it-works.md."""
    from topomap.core import doors

    page = (ROOT / "docs" / "how-it-works.md").read_text(encoding="utf-8")
    statuses = set(doors.STATUSES) - {doors.CANDIDATE}
    assert len(statuses) == 17
    missing = [s for s in sorted(statuses) if f"`{s}`" not in page]
    assert not missing, f"how-it-works.md does not explain candidate status {missing}"


# --------------------------------------------------------------------------
# The index and the navigation

def _pages():
    return sorted(p.name for p in (ROOT / "docs").glob("*.md"))


def test_every_page_is_in_the_nav_and_on_the_index():
    yaml = pytest.importorskip("yaml")
    nav = yaml.safe_load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"))["nav"]
    in_nav = [page for item in nav for page in item.values()]
    assert sorted(in_nav) == _pages(), "mkdocs.yml nav: not every page of docs/ exactly once"
    index = (ROOT / "docs" / "index.md").read_text(encoding="utf-8")
    linked = set(re.findall(r"\]\(([\w-]+\.md)\)", index))
    missing = set(_pages()) - {"index.md"} - linked
    assert not missing, f"docs/index.md links no {sorted(missing)}"


def test_every_command_is_on_the_index_and_on_the_cli_page():
    from topomap.cli import main

    index = (ROOT / "docs" / "index.md").read_text(encoding="utf-8")
    row = next(line for line in index.splitlines() if line.startswith("| [Command line]"))
    cli_page = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
    for name in main.commands:
        assert f"`{name}`" in row or f"`topomap {name}`" in row, f"docs/index.md: command {name} not listed"
        assert f"## `topomap {name}`" in cli_page, f"docs/cli.md: no section for topomap {name}"


# --------------------------------------------------------------------------
# Command outputs shown on the pages

#: A shown session: a ```text block whose first line is "$ topomap ...".
_SESSION = re.compile(r"^```text\n(\$ topomap .*?)^```$", re.M | re.S)
#: Pages with such sessions; each page's sessions run in order in one fresh folder.
SESSION_PAGES = ("cli.md",)


def _run_session(block: str) -> str:
    """``block`` with the output under each ``$ topomap ...`` line replaced by what it prints now."""
    from click.testing import CliRunner

    from topomap.cli import main

    out = []
    for line in block.splitlines():
        if not line.startswith("$ "):
            continue
        argv = shlex.split(line[2:])
        assert argv[0] == "topomap", line
        r = CliRunner().invoke(main, argv[1:])
        assert r.exit_code == 0, f"{line}: exit {r.exit_code}\n{r.output}"
        out.append(f"{line}\n{r.stdout}")
    return "".join(out)


def _render(page: Path) -> str:
    """The text of ``page`` with every shown session re-run, in a fresh folder."""
    text = page.read_text(encoding="utf-8")
    here = os.getcwd()
    with tempfile.TemporaryDirectory() as tmp:
        os.chdir(tmp)
        try:
            return _SESSION.sub(lambda m: "```text\n" + _run_session(m.group(1)) + "```", text)
        finally:
            os.chdir(here)


@pytest.mark.parametrize("name", SESSION_PAGES)
def test_shown_command_output_is_what_the_commands_print(name):
    page = ROOT / "docs" / name
    text = page.read_text(encoding="utf-8")
    shown = _SESSION.findall(text)
    assert shown, f"docs/{name}: no shown command output"
    rendered = _render(page)
    for old, new in zip(shown, _SESSION.findall(rendered)):
        assert old == new, (f"docs/{name}: the output shown differs from what the command prints "
                            f"(python tests/test_docs.py rewrites it):\n--- shown\n{old}--- printed\n{new}")


def test_cli_page_shows_the_demo_plan_tour_and_export():
    commands = {shlex.split(line)[2] for block in _SESSION.findall((ROOT / "docs" / "cli.md").read_text("utf-8"))
                for line in block.splitlines() if line.startswith("$ ")}
    assert {"demo", "plan", "tour", "export"} <= commands


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    for name in SESSION_PAGES:
        page = ROOT / "docs" / name
        page.write_text(_render(page), encoding="utf-8")
        print(f"docs/{name}: shown command output rewritten")
