"""Draw ``docs/img/architecture.png``: the package's layers, from the import-linter contract in
pyproject.toml and the modules on disk (so the picture follows the code).

Run from the repository root::

    python docs/make_architecture_figure.py            # writes docs/img/architecture.png
    python docs/make_architecture_figure.py --out DIR  # somewhere else
"""

from __future__ import annotations

import argparse
import textwrap
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: What each layer is for, in a few words.
ROLES = {
    "topomap.cli": "the command line",
    "topomap.api": "topomap.segment with a previous result from a file",
    "topomap.bench": "benchmarks, scores, data sets, simulated maps",
    "topomap.run": "one map to its output files; batches; editing output folders",
    "topomap.io": "maps, graphs, label images, pictures, ROS messages, Nav2 files: read and write",
    "topomap.planning": "routes, tours and route graphs over the room graph",
    "topomap.core": "the algorithms: skeletons, walls, doors, rooms, room graph, methods, result",
    "topomap.options": "the methods' options",
    "topomap.grid": "the occupancy grid and the size limit",
    "topomap.errors": "every exception",
    "topomap._fast": "numeric kernels",
}


def layers() -> list:
    """The layers of the contract, top first, each a list of module names."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]["contracts"]
    contract = next(c for c in config if c["type"] == "layers")
    return [[m.strip() for m in layer.split("|")] for layer in contract["layers"]]


def members(module: str) -> str:
    """The modules of a package, or '' for a module."""
    folder = ROOT / Path(*module.split("."))
    if not folder.is_dir():
        return ""
    names = sorted(p.stem for p in folder.glob("*.py") if p.stem != "__init__")
    return ", ".join(names)


def main(out: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import FancyBboxPatch

    rows = layers()
    fig, ax = plt.subplots(figsize=(11, 1.15 * len(rows) + 0.6))
    ax.set_xlim(0, 1.05)
    ax.set_ylim(0, len(rows))
    ax.axis("off")
    for i, layer in enumerate(rows):
        y = len(rows) - 1 - i
        width = 0.96 / len(layer)
        for j, module in enumerate(layer):
            x = 0.02 + j * width
            ax.add_patch(FancyBboxPatch((x + 0.005, y + 0.12), width - 0.01, 0.76, boxstyle="round,pad=0.005",
                                        facecolor=plt.cm.Blues(0.15 + 0.6 * i / len(rows)), edgecolor="navy"))
            ax.text(x + width / 2, y + 0.72, module, ha="center", va="center", fontsize=10, weight="bold")
            text = ROLES.get(module, "")
            inner = members(module)
            if inner:
                text += "\n" + "\n".join(textwrap.wrap(inner, int(120 * width)))
            ax.text(x + width / 2, y + 0.62, text, ha="center", va="top", fontsize=8.5)
    ax.annotate("", xy=(1.01, 0.2), xytext=(1.01, len(rows) - 0.2),
                arrowprops=dict(arrowstyle="->", color="gray", lw=1.5))
    ax.text(1.025, len(rows) / 2, "a module imports from its own layer and those below it", rotation=90,
            ha="left", va="center", color="gray")
    out.mkdir(parents=True, exist_ok=True)
    path = out / "architecture.png"
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "img")
    print(main(parser.parse_args().out))
