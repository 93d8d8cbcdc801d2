"""Hostile and odd inputs users met: each is bounded, refused in one line naming the file,
or read as it should be; never an internal error (exit 3)."""

import json

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from topomap import io
from topomap.cli import main


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def _one_error_line(res, name):
    """The CLI's output is one error line naming ``name``, exit 1."""
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert res.exit_code == 1, res.output
    assert len(lines) == 1 and lines[0].startswith("error: ") and str(name) in lines[0], res.output
    assert "internal" not in res.output and " object at 0x" not in res.output
    return lines[0]


# --------------------------------------------------------------------------
# 65,536 free specks: fragments share a label in the label files when they would not fit 16 bits
# --------------------------------------------------------------------------

def test_many_fragments_fit_the_label_files(tmp_path):
    from topomap.io.export import load_label_map

    a = np.zeros((600, 600), bool)
    a[1:513:2, 1:513:2] = True  # 256 x 256 = 65,536 free cells, each alone: fragments
    a[530:590, 20:580] = True  # one room
    yml = io.save_map(a, tmp_path / "specks")
    res = _run("segment", yml, "-o", tmp_path / "out")
    assert res.exit_code == 0, res.output
    png = np.asarray(Image.open(tmp_path / "out" / "labels.png"))
    pgm, _, _ = load_label_map(tmp_path / "out" / "labels.yaml")
    np.testing.assert_array_equal(png, pgm)
    G = json.loads((tmp_path / "out" / "rooms.json").read_text())
    top = max(n["id"] for n in G["nodes"])
    assert len(G["nodes"]) == 1 and G["graph"]["n_fragments"] == 65536
    # the room keeps its label, every fragment cell has the one label after it, nothing else changed
    assert np.all(png[530:590, 20:580] == top)
    assert np.all(png[1:513:2, 1:513:2] == top + 1) and png.max() == top + 1
    assert np.array_equal(png > 0, a)


def test_label_array_beyond_16_bits_is_one_line(tmp_path):
    from topomap.errors import ParameterError
    from topomap.io.export import save_labels

    import io as pyio

    with pytest.raises(ParameterError, match=r"^labels.png: room IDs up to 70000 do not fit a 16-bit PNG"):
        save_labels(np.array([[70000, 1]]), pyio.BytesIO())
