"""Draw ``docs/img/edit_before_after.png``: the example office before and after ``topomap edit``.

Run from the repository root::

    python docs/make_edit_figure.py            # writes docs/img/edit_before_after.png
    python docs/make_edit_figure.py --out DIR  # somewhere else

It segments the embedded example office (``topomap/data/example_office.yaml``)
into a temporary output folder, runs the edits the "Editing rooms" page shows
(``topomap edit OUT --split 4 2 -2 2 2 --merge 7 8 --name 7 lab --no-go 1``) and
draws the ``overlay.png`` of the folder before and after side by side, with the
room names and no-go rooms from the edited ``rooms.graphml``.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
EDITS = ["--split", "4", "2", "-2", "2", "2", "--merge", "7", "8", "--name", "7", "lab", "--no-go", "1"]


def main(out: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from click.testing import CliRunner
    from PIL import Image

    import topomap
    from topomap.cli import main as cli
    from topomap.io.export import load_graph

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "office"
        run = CliRunner().invoke
        r = run(cli, ["segment", str(topomap.example_map_path()), "-o", str(folder)])
        assert r.exit_code == 0, r.output
        before = Image.open(folder / "overlay.png").convert("RGB")
        G0 = load_graph(folder / "rooms.graphml")
        r = run(cli, ["edit", str(folder), *EDITS])
        assert r.exit_code == 0, r.output
        after = Image.open(folder / "overlay.png").convert("RGB")
        G1 = load_graph(folder / "rooms.graphml")
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6))
    for ax, img, G, title in ((axes[0], before, G0, "topomap segment"),
                              (axes[1], after, G1, "topomap edit " + " ".join(EDITS))):
        ax.imshow(img, interpolation="nearest")
        H = img.size[1]
        ox, oy, _ = G.graph["origin"]
        res = G.graph["resolution"]
        for n, d in G.nodes(data=True):
            label = d.get("name") or ""
            if d.get("no_go"):
                ax.add_patch(plt.Polygon([((x - ox) / res, H - (y - oy) / res) for x, y in
                                          d["polygon"].exterior.coords], fill=False, hatch="xx", color="0.35",
                                         lw=0))
                label = (label + " " if label else "") + "no-go"
            if label:
                ax.annotate(label, ((d["x"] - ox) / res, H - (d["y"] - oy) / res + 16), ha="center", fontsize=8,
                            color="black", bbox={"boxstyle": "round,pad=0.2", "fc": "white", "ec": "none"})
        ax.set_title(title, fontsize=8)
        ax.set_axis_off()
    out.mkdir(parents=True, exist_ok=True)
    path = out / "edit_before_after.png"
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path


if __name__ == "__main__":
    import sys

    sys.path.insert(0, str(HERE.parent))  # this repository's topomap, not another installed one
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=HERE / "img")
    print(main(ap.parse_args().out))
