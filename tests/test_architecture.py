"""The package's structure: its layers, no import circles, no private names across modules, short functions,
and the import paths users already have (docs/architecture.md)."""

import ast
import importlib
import itertools
import subprocess
import sys
from pathlib import Path

import networkx as nx
import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "topomap"
#: Longest function, in code lines (blank, comment and docstring lines not counted).
MAX_FUNCTION_LINES = 80


def _modules():
    """``(dotted name, path)`` of every module of the package."""
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(ROOT).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        yield name, path


def _imports(name, path):
    """``(module imported, names imported from it, line)`` of every import of the package's modules in
    ``path``, at any depth (inside functions too)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")[:len(package.split(".")) - node.level + 1]
                base = ".".join(parts + ([base] if base else []))
            if base.split(".")[0] == "topomap":
                yield base, [a.name for a in node.names], node.lineno
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] == "topomap":
                    yield a.name, [], node.lineno


def test_the_layers_hold():
    """``lint-imports`` with the contracts of pyproject.toml: no module imports from a layer above its own
    (even inside a function), and the algorithms import no file, picture or user-interface library."""
    # in a process of its own: import-linter sets up logging, which would silence the package's loggers
    # for the tests that run after it
    code = ("import sys; from importlinter.cli import lint_imports; "
            f"sys.exit(lint_imports(config_filename={str(ROOT / 'pyproject.toml')!r}, no_cache=True))")
    proc = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-4000:]


def test_no_import_circles():
    """No two modules import each other, directly or through others (imports inside functions count):
    a package ``__init__`` that re-exports its modules is not part of a circle through them."""
    names = dict(_modules())
    graph = nx.DiGraph()
    for name, path in names.items():
        for target, imported, _ in _imports(name, path):
            targets = [f"{target}.{n}" for n in imported if f"{target}.{n}" in names] or [target]
            for t in targets:
                if t in names and t != name and not name.startswith(t + "."):
                    graph.add_edge(name, t)
    circles = list(itertools.islice(nx.simple_cycles(graph), 10))
    assert not circles, "\n".join(" -> ".join(c + c[:1]) for c in circles)


def test_no_private_name_is_imported_from_another_module():
    names = dict(_modules())
    found = []
    for name, path in names.items():
        for target, imported, line in _imports(name, path):
            for n in imported:
                if n.startswith("_") and not n.startswith("__") and f"{target}.{n}" not in names:
                    found.append(f"{path.relative_to(ROOT)}:{line}: {n} from {target}")
    assert not found, "\n".join(found)


def _code_lines(source_lines, node):
    body = node.body
    doc = set()
    if body and isinstance(body[0], ast.Expr) and isinstance(getattr(body[0], "value", None), ast.Constant) \
            and isinstance(body[0].value.value, str):
        doc = set(range(body[0].lineno, body[0].end_lineno + 1))
    return sum(1 for i in range(node.lineno, node.end_lineno + 1)
               if i not in doc and source_lines[i - 1].strip() and not source_lines[i - 1].strip().startswith("#"))


def test_no_function_is_longer_than_80_code_lines():
    long = []
    for path in sorted([*PACKAGE.rglob("*.py"), *(ROOT / "benchmarks").glob("*.py")]):
        text = path.read_text()
        lines = text.splitlines()
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = _code_lines(lines, node)
                if n > MAX_FUNCTION_LINES:
                    long.append(f"{path.relative_to(ROOT)}:{node.lineno} {node.name}: {n} code lines")
    assert not long, "\n".join(long)


def test_the_line_counter_counts_code_lines_only():
    src = 'def f():\n    """Doc\n\n    string."""\n    # a comment\n\n    a = 1\n    return a\n'
    node = ast.parse(src).body[0]
    assert _code_lines(src.splitlines(), node) == 3  # def, a = 1, return


@pytest.mark.parametrize("path, name, home", [
    ("topomap", "load_map", "topomap.io.maps"),
    ("topomap", "segment", "topomap.api"),
    ("topomap", "OccupancyGrid", "topomap.grid"),
    ("topomap", "room_graph", "topomap.core.roomgraph"),
    ("topomap", "segment_many", "topomap.run.batch"),
    ("topomap", "example_map_path", "topomap.io.example"),
    ("topomap.io", "load_map", "topomap.io.maps"),
    ("topomap.io", "save_map", "topomap.io.maps"),
    ("topomap.io", "OccupancyGrid", "topomap.grid"),
    ("topomap.io", "cell_limit", "topomap.grid"),
    ("topomap.io", "atomic_write", "topomap.io.files"),
    ("topomap.planning", "plan_path", "topomap.planning.paths"),
    ("topomap.planning", "travel_graph", "topomap.planning.paths"),
    ("topomap.planning", "door_graph", "topomap.planning.paths"),
    ("topomap.planning", "room_at", "topomap.planning.paths"),
    ("topomap.planning", "plan_tour", "topomap.planning.tour"),
    # the modules that moved keep their old paths
    ("topomap.segmentation", "segment", "topomap.core.segmentation"),
    ("topomap.segmentation", "Segmentation", "topomap.core.result"),
    ("topomap.export", "load_graph", "topomap.io.export"),
    ("topomap.plot", "save_overlay", "topomap.io.plot"),
    ("topomap.identity", "match_rooms", "topomap.core.identity"),
    ("topomap.tour", "plan_tour", "topomap.planning.tour"),
    ("topomap.batch", "segment_many", "topomap.run.batch"),
    ("topomap.skeleton", "skeleton_graph", "topomap.core.skeleton"),
    ("topomap.doors", "wall_threshold", "topomap.core.doors"),
    ("topomap.datasets", "plan_split", "topomap.bench.datasets"),
])
def test_public_import_paths_keep_working(path, name, home):
    obj = getattr(importlib.import_module(path), name)
    assert obj is getattr(importlib.import_module(home), name)
    exec(f"from {path} import {name}", {})  # the from-import form too


def test_the_command_line_entry_point():
    import tomllib

    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    module, _, attr = scripts["topomap"].partition(":")
    assert callable(getattr(importlib.import_module(module), attr))


def test_topomap_io_max_cells_sets_the_limit_every_grid_checks(monkeypatch):
    import topomap.io
    from topomap import grid

    monkeypatch.setattr(topomap.io, "MAX_CELLS", 12)
    assert grid.MAX_CELLS == 12 and grid.cell_limit()[0] == 12
