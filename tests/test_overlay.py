"""The overlay picture drawn straight into the raster (topomap.io.plot.overlay_image / overlay_png)."""

import io
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

from topomap.io import plot
from topomap.io import load_map
from topomap.core.segmentation import segment


@pytest.fixture(scope="module")
def seg():
    from topomap.io.example import example_map_path

    s = segment(load_map(example_map_path()))
    s.room_graph
    return s


def test_overlay_png_is_the_map_at_its_own_resolution(seg):
    data = plot.overlay_png(seg)
    img = Image.open(io.BytesIO(data))
    assert img.format == "PNG" and img.size == (seg.grid.shape[1], seg.grid.shape[0])
    rgb = np.asarray(img.convert("RGB"))
    np.testing.assert_array_equal(rgb, plot.overlay_image(seg))


def test_rooms_walls_and_doors_have_their_colours(seg):
    img = plot.overlay_image(seg)
    labels = seg.labels
    # walls black, unknown grey, where no room is
    occ = seg.grid.occupied & (labels == 0)
    assert occ.any() and (img[occ] == 0).all(axis=1).mean() > 0.95
    # each room one colour (away from doors and numbers): its most common colour covers most of it
    colours = {}
    for r in range(1, seg.n_rooms + 1):
        px = img[labels == r]
        vals, counts = np.unique(px, axis=0, return_counts=True)
        assert counts.max() > 0.8 * len(px), r
        colours[r] = tuple(vals[np.argmax(counts)])
        assert colours[r] != (255, 255, 255) and colours[r] != (0, 0, 0)
    # neighbouring rooms (joined by a door) differ
    for d in seg.doors:
        a, b = d.rooms
        assert colours[a] != colours[b], d
        # the door segment is drawn in red
        r, c = np.rint(np.mean([d.p1, d.p2], axis=0)).astype(int)
        assert tuple(img[r, c]) == (255, 0, 0), d


def test_room_numbers_are_drawn(seg):
    plain = plot.overlay_image(seg)
    G = seg.room_graph
    r = max(G.nodes, key=lambda n: G.nodes[n]["area"])
    row, col = int(round(G.nodes[r]["interior_row"])), int(round(G.nodes[r]["interior_col"]))
    box = plain[row - 4:row + 5, col - 4:col + 5]
    assert (box == 0).all(axis=2).any()  # black digits at the room's interior point


def test_skeletons_and_graph_add_lines(seg):
    plain = plot.overlay_image(seg)
    more = plot.overlay_image(seg, skeletons=True, graph=True)
    green = (more == (50, 205, 50)).all(axis=2)
    navy = (more == (0, 0, 128)).all(axis=2)
    assert green.any() and navy.any()
    assert not (plain == (50, 205, 50)).all(axis=2).any()


def test_matplotlib_figure_on_request(seg):
    data = plot.overlay_png(seg, dpi=40)
    assert Image.open(io.BytesIO(data)).format == "PNG"


def test_raster_overlay_does_not_import_matplotlib():
    code = ("import sys\nfrom topomap.io.example import example_map_path\nfrom topomap.io import load_map\n"
            "from topomap.core.segmentation import segment\nfrom topomap.io.plot import overlay_png\n"
            "overlay_png(segment(load_map(example_map_path())))\nprint('matplotlib' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_room_colours_match_room_colors(seg):
    img = plot.overlay_image(seg, alpha=1.0)
    want = np.rint(255 * plot.room_colors(seg.n_rooms)[:, :3]).astype(np.uint8)
    labels = seg.labels
    for r in range(1, seg.n_rooms + 1):
        px = img[labels == r]
        vals, counts = np.unique(px, axis=0, return_counts=True)
        np.testing.assert_array_equal(vals[np.argmax(counts)], want[r])
