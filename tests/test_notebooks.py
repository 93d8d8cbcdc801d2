"""Every notebook in notebooks/ runs from top to bottom without an error."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
TIMEOUT = 120  # seconds per cell


def _need_kernel():
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    from jupyter_client.kernelspec import KernelSpecManager, NoSuchKernel

    try:
        KernelSpecManager().get_kernel_spec("python3")
    except NoSuchKernel:
        pytest.skip("no 'python3' Jupyter kernel installed")
    return nbformat, nbclient


def _run(path, tmp_path, monkeypatch):
    """``path`` executed in a fresh kernel (cwd ``tmp_path``); the executed notebook."""
    nbformat, nbclient = _need_kernel()
    monkeypatch.setenv("MPLBACKEND", "Agg")
    nb = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(nb, timeout=TIMEOUT, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])
              if o.get("output_type") == "error"]
    assert not errors, errors
    return nb


def _printed(nb) -> str:
    return "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code"
                   for o in c.get("outputs", []) if o.get("output_type") == "stream")


@pytest.mark.skipif(not NOTEBOOKS, reason="no notebooks")
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_runs(path, tmp_path, monkeypatch):
    _run(path, tmp_path, monkeypatch)


def test_real_map_notebook_without_the_data_runs_on_the_example(tmp_path, monkeypatch):
    """Without the ROSE² maps the notebook says so and runs every step on the
    shipped example office (no cell skipped: the scores are printed)."""
    empty = tmp_path / "no_maps"
    empty.mkdir()
    monkeypatch.setenv("TOPOMAP_REAL_MAPS_DIR", str(empty))
    out = _printed(_run(ROOT / "notebooks" / "real_slam_map.ipynb", tmp_path, monkeypatch))
    assert "running on the example office shipped with topomap" in out
    assert "example office: 280 x 400 cells at 0.05 m" in out
    m = re.search(r"precision ([\d.]+) %, recall ([\d.]+) %, (\d+) rooms found, (\d+) true rooms", out)
    assert m, out
    assert int(m.group(4)) == 8   # the example's seven rooms and corridor


def test_real_map_notebook_names_its_data_set():
    """The notebook says which public data set the map is from, its licence and where to get it."""
    nbformat = pytest.importorskip("nbformat")
    intro = nbformat.read(ROOT / "notebooks" / "real_slam_map.ipynb", as_version=4).cells[0].source
    for needed in ("ROSE²", "Luperto et al.", "2022", "MIT licence", "goldleaf3i/declutter-reconstruct",
                   "TOPOMAP_REAL_MAPS_DIR", "topomap.example_map_path()"):
        assert needed in intro, f"real_slam_map.ipynb's introduction does not say {needed!r}"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_outputs_stripped(path):
    nbformat = pytest.importorskip("nbformat")
    nb = nbformat.read(path, as_version=4)
    for c in nb.cells:
        if c.cell_type == "code":
            assert c.get("outputs", []) == [] and c.get("execution_count") is None, \
                f"{path.name}: outputs are not stripped"
