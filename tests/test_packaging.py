"""The distribution's name, version and extras, and every install line users read.

"topomap" on the Python Package Index is an unrelated project: this one is
published as pyproject's [project] name. Every ``pip install`` line in the
README, the docs, the notebooks, the examples and the messages of the code
must install this project (a clone's ``-e .`` / ``".[extra]"``, or that
name), never the other one.
"""

import json
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
#: The name on the package index that belongs to another project.
TAKEN = "topomap"


@pytest.fixture(scope="module")
def project():
    """pyproject.toml's ``[project]`` table."""
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover
        tomllib = pytest.importorskip("tomli")
    return tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]


def _texts():
    """``(file name, text)`` of everything a user reads install lines in."""
    paths = [ROOT / "README.md", ROOT / "benchmarks" / "README.md", *sorted((ROOT / "docs").glob("*.md")),
             *sorted((ROOT / "examples").glob("*.py")), *sorted((ROOT / "topomap").glob("*.py"))]
    for p in paths:
        if p.is_file():
            yield p.relative_to(ROOT).as_posix(), p.read_text(encoding="utf-8")
    for p in sorted((ROOT / "notebooks").glob("*.ipynb")):
        cells = json.loads(p.read_text(encoding="utf-8"))["cells"]
        yield p.relative_to(ROOT).as_posix(), "\n".join("".join(c["source"]) for c in cells)


#: ``pip install`` and its arguments: options, quoted strings, bare words (up
#: to the first thing that is none of these: ``&&``, a backtick, a comment).
_INSTALL = re.compile(r"pip install((?:[ \t]+(?:-[-\w]+|'[^'\n]*'|\"[^\"\n]*\"|[\w.\[\],/=<>-]+))+)")
_TOKEN = re.compile(r"-[-\w]+|'[^'\n]*'|\"[^\"\n]*\"|[\w.\[\],/=<>-]+")


def _install_lines():
    """``(file, line, [requirement, ...])`` of every ``pip install`` in what users read."""
    for name, text in _texts():
        for m in _INSTALL.finditer(text):
            reqs = [t.strip("'\"") for t in _TOKEN.findall(m.group(1)) if not t.startswith("-")]
            yield name, m.group(0), reqs


def _split(req):
    """``"topomap-rooms[ros,dask]>=0.1"`` -> ``("topomap-rooms", {"ros", "dask"})``; ``(None, extras)``
    for a local path (``.``, ``".[ros]"``)."""
    m = re.match(r"([^\[<>=]*)(?:\[([^\]]*)\])?", req)
    target, extras = m.group(1), {e.strip() for e in (m.group(2) or "").split(",") if e.strip()}
    local = target in ("", ".") or target.startswith(("./", "/", "../"))
    return (None if local else target), extras


def test_the_name_is_not_the_taken_one(project):
    assert project["name"].lower() != TAKEN


def test_metadata_lookups_use_the_distribution_name(project):
    """``click.version_option(package_name=...)`` and every ``importlib.metadata``
    call in the package name pyproject's distribution, not the import name."""
    found = []
    for p in sorted((ROOT / "topomap").glob("*.py")):
        src = p.read_text(encoding="utf-8")
        found += [(p.name, n) for n in re.findall(r"package_name\s*=\s*[\"']([^\"']+)[\"']", src)]
        if re.search(r"importlib\.metadata|from importlib import metadata", src):
            found += [(p.name, n) for n in re.findall(
                r"\b(?:version|distribution|metadata|files|requires)\(\s*[\"']([^\"']+)[\"']\s*\)", src)]
    assert ("cli.py", project["name"]) in found, "cli.py: no version_option(package_name=<the distribution>)"
    wrong = [f for f in found if f[1] != project["name"]]
    assert not wrong, f"metadata looked up under another name than {project['name']!r}: {wrong}"


def test_every_install_line_installs_this_project(project):
    lines = list(_install_lines())
    assert any(name == "README.md" for name, *_ in lines)
    extras = set(project["optional-dependencies"])
    bad = []
    for name, line, reqs in lines:
        for req in reqs:
            target, wanted = _split(req)
            if target is not None and target.lower() == TAKEN:
                bad.append(f"{name}: {line!r} installs the unrelated {TAKEN!r} from the package index")
            ours = target is None or target.lower() == project["name"].lower()
            if ours and wanted - extras:
                bad.append(f"{name}: {line!r}: no extra {sorted(wanted - extras)} in pyproject.toml")
    assert not bad, "\n".join(bad)


def test_the_checker_catches_the_taken_name():
    """The line the docs had before the rename is caught, in each quoting."""
    for text in ('pip install "topomap[ros]"', "pip install topomap[ros]", "pip install 'topomap[dask]'",
                 "pip install -U topomap"):
        reqs = [t.strip("'\"") for t in _TOKEN.findall(_INSTALL.search(text).group(1)) if not t.startswith("-")]
        assert [_split(r)[0] for r in reqs] == ["topomap"], text
    assert _split(".[test,docs]") == (None, {"test", "docs"})


def test_readme_starts_with_the_fresh_machine_set_up():
    """The README's first two commands: the main job on the example map, and
    the tests as CI runs them."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    block = re.search(r"```bash\n(.*?)```", readme, re.S).group(1)
    first, second = [line.split("#")[0].strip() for line in block.splitlines()[:2]]
    assert first == "pip install -e . && topomap demo -o demo_out"
    assert second == 'pip install -e ".[test,docs]" && python -m pytest -q'


def test_extras_for_the_notebooks_and_the_tests(project):
    """``.[notebooks]`` gives ``jupyter nbconvert --execute``; ``.[test]`` holds
    what tests/test_notebooks.py needs to run them, and the optional libraries
    the tests exercise."""
    extras = project["optional-dependencies"]

    def names(extra):
        return {re.match(r"[A-Za-z0-9_.-]+", req).group(0).lower() for req in extras[extra]}

    assert {"jupyter", "nbconvert", "ipykernel"} <= names("notebooks")
    assert {"nbclient", "nbformat", "ipykernel"} <= names("test")
    assert names("ros") <= names("test") and names("dask") <= names("test")


def test_version_is_pyprojects(project):
    import topomap

    assert topomap.__version__ == project["version"]


def test_version_option_reads_the_installed_distribution(project):
    from importlib import metadata

    from click.testing import CliRunner

    from topomap.cli import main

    try:
        metadata.version(project["name"])
    except metadata.PackageNotFoundError:
        pytest.skip(f"{project['name']} is not installed (pip install -e .)")
    r = CliRunner().invoke(main, ["--version"], prog_name="topomap")
    assert r.exit_code == 0, r.output
    assert r.stdout.strip() == f"topomap, version {project['version']}"
