"""What the benchmark scripts that write a section of docs/benchmarks.md share:
the command line (a data directory and ``--out``), the commit and machine lines,
and writing the section file in one piece."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from speed import _commit, _machine  # noqa: F401  (one copy of the commit and machine lines)

HERE = Path(__file__).resolve().parent


def parser(doc: str, data: str, section: str) -> argparse.ArgumentParser:
    """Arguments ``directory`` (``data``: what it holds) and ``--out`` (default ``sections/section``)."""
    ap = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    ap.add_argument("directory", nargs="?", default=None, help=f"{data} (default: found as benchmarks/README.md says)")
    ap.add_argument("--out", type=Path, default=HERE / "sections" / section,
                    help=f"section file to write (default benchmarks/sections/{section})")
    return ap


def directory(given, finder, env: str) -> Path:
    """``given``, else ``finder()``; exits with one line when neither is a directory."""
    d = given or finder()
    if d is None or not Path(d).is_dir():
        sys.exit(f"error: no data directory {given or ''} (pass it or set {env})")
    return Path(d)


def write(out: Path, text: str, table: str, wall: float) -> None:
    """Write ``text`` to ``out`` (a temporary name renamed at the end); print ``table``."""
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(out.name + ".tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(out)
    sys.stdout.write(table)
    print(f"-> {out} ({wall:.0f} s)")


def ros_cells(grid):
    """``grid``'s cells as map_server values: 0 free, 100 occupied, -1 every other cell (int8)."""
    import numpy as np

    cells = np.full(grid.free.shape, -1, np.int8)
    cells[grid.free] = 0
    cells[grid.occupied] = 100
    return cells
