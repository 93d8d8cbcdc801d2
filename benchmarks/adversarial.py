"""Peak memory and time of the whole `topomap segment` job on adversarial maps.

Long thin corridors, checkerboards, mostly-free giants, scan specks, noise, a building-like
grid of rooms and tiny resolutions: each map is generated into a temporary
folder and segmented by ``topomap segment MAP -o OUT`` in its own process
(the whole CLI job, overlay included), whose peak RSS (``wait4``) and wall
time are measured. Bytes per cell are ``(peak - constant) / cells``, the
constant being the peak of a 1-cell map's job. Writes
``benchmarks/sections/80_adversarial.md``. Not a test: run it by hand
(``--scale 0.5`` for a quicker, smaller run).

    python benchmarks/adversarial.py [--scale S] [--out FILE]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from PIL import Image

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _section import HERE, _commit, _machine, write  # noqa: E402

FREE, WALL = 254, 0
#: The bound stated in docs/errors.md: 150 bytes per map cell + 25 kB per room + 250 MB.
BOUND_PER_CELL, BOUND_PER_ROOM, BOUND_CONSTANT = 150, 25 * 2**10, 250 * 2**20


def corridor(n):
    """3 x n: one free row between two walls (the length-growing kernel case)."""
    a = np.full((3, n), WALL, np.uint8)
    a[1, 1:-1] = FREE
    return a, 0.05


def corridor_wide(n):
    """12 x n: a 0.5 m corridor with a door-like gap every 10 m."""
    a = np.full((12, n), WALL, np.uint8)
    a[1:-1, 1:-1] = FREE
    a[1:-1, 200::200] = WALL
    a[4:8, 200::200] = FREE
    return a, 0.05


def checkerboard(n):
    """n x n checkerboard of 2 x 2 blocks (free blocks touch at corners only)."""
    i = np.arange(n) // 2
    a = np.where((i[:, None] + i[None, :]) % 2 == 0, FREE, WALL).astype(np.uint8)
    return a, 0.05


def checkerboard_1px(n):
    """n x n checkerboard of single cells: a piece of outline for every other cell."""
    i = np.arange(n)
    a = np.where((i[:, None] + i[None, :]) % 2 == 0, FREE, WALL).astype(np.uint8)
    return a, 0.05


def mostly_free(n):
    """n x n free square inside a wall (one room, nothing to find)."""
    a = np.full((n, n), FREE, np.uint8)
    a[[0, -1], :] = WALL
    a[:, [0, -1]] = WALL
    return a, 0.05


def specks(n):
    """n x n free square with 1 % of its cells occupied at random (seed 0): scan noise everywhere."""
    a, res = mostly_free(n)
    rng = np.random.default_rng(0)
    a[rng.random(a.shape) < 0.01] = WALL
    return a, res


def noise(n):
    """n x n square with a quarter of its cells occupied at random (seed 0): noise, not a building."""
    a, res = mostly_free(n)
    rng = np.random.default_rng(0)
    a[rng.random(a.shape) < 0.25] = WALL
    return a, res


def rooms_grid(n):
    """n x n grid of 5 m rooms (100 px) with a 0.9 m door in every wall: a big building."""
    a = np.full((n, n), FREE, np.uint8)
    a[::100, :] = WALL
    a[:, ::100] = WALL
    a[[0, 1, -2, -1], :] = WALL
    a[:, [0, 1, -2, -1]] = WALL
    for k in range(100, n - 1, 100):
        for m in range(50, n - 50, 100):
            a[k, m - 9:m + 9] = FREE  # doors in horizontal walls
            a[m - 9:m + 9, k] = FREE  # doors in vertical walls
    a[[0, -1], :] = WALL
    a[:, [0, -1]] = WALL
    return a, 0.05


def two_rooms_fine(n):
    """Two rooms and a door, n px wide, at 1 mm per cell (the smallest resolution accepted)."""
    h = n // 2
    a = np.full((h, n), WALL, np.uint8)
    t = max(n // 100, 2)
    a[t:h - t, t:n // 2 - t // 2] = FREE
    a[t:h - t, n // 2 + t // 2:n - t] = FREE
    a[h // 2 - n // 25:h // 2 + n // 25, n // 2 - t:n // 2 + t] = FREE
    return a, 0.001


def single_cell_rooms(n):
    """n x n checkerboard of single cells read at 1 m per cell: every free cell (1 m², the smallest room)
    is a room touching its neighbours at its corners: as many rooms as a map of this size can have."""
    a, _ = checkerboard_1px(n)
    return a, 1.0


def one_cell(n):
    return np.full((1, 1), FREE, np.uint8), 0.05


#: name, builder, size at scale 1
CASES = [
    ("1 cell (constant)", one_cell, 1),
    ("corridor 3 x n", corridor, 60000),
    ("corridor 12 x n, doors", corridor_wide, 40000),
    ("checkerboard 2 px", checkerboard, 600),
    ("checkerboard 2 px, larger", checkerboard, 1500),
    ("checkerboard 1 px", checkerboard_1px, 1500),
    ("mostly free n x n", mostly_free, 4000),
    ("mostly free, 1 % specks", specks, 2000),
    ("mostly free, 1 % specks, larger", specks, 3000),
    ("noise, 25 % occupied", noise, 1500),
    ("rooms grid n x n", rooms_grid, 4000),
    ("two rooms at 1 mm", two_rooms_fine, 2000),
    ("single-cell rooms at 1 m", single_cell_rooms, 300),
]


def run_case(builder, n, workdir: Path):
    """(cells, peak RSS bytes, seconds, exit code, last stderr line, whether an outline was simplified)
    of one job in a fresh process."""
    a, res = builder(n)
    img = workdir / f"{builder.__name__}.png"
    Image.fromarray(a).save(img)
    out = workdir / f"{builder.__name__}_out"
    cmd = [sys.executable, "-m", "topomap.cli", "segment", str(img), "-o", str(out), "--resolution", repr(res),
           "--overwrite"]
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    err = p.stderr.read().decode("utf-8", "replace")
    _, status, ru = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    p.returncode = os.waitstatus_to_exitcode(status)
    last = [ln for ln in err.splitlines() if ln.strip()][-1:] or [""]
    rooms = 0
    if (out / "rooms.json").is_file():
        import json

        rooms = len(json.loads((out / "rooms.json").read_text())["nodes"])
    return (a.size, ru.ru_maxrss * 1024, wall, p.returncode, last[0], "more detail than its outline holds" in err,
            rooms)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scale", type=float, default=1.0, help="linear size factor of every case (default 1)")
    ap.add_argument("--out", type=Path, default=HERE / "sections" / "80_adversarial.md")
    ap.add_argument("--only", default=None, metavar="TEXT", help="run only the cases whose name contains TEXT "
                                                                   "(and the constant)")
    args = ap.parse_args()
    t_all = time.perf_counter()
    rows = []
    with tempfile.TemporaryDirectory(prefix="topomap_adversarial_") as tmp:
        for name, builder, n in CASES:
            if args.only and builder is not one_cell and args.only not in name:
                continue
            size = max(int(round(n * args.scale)), 1) if builder is not one_cell else 1
            cells, peak, wall, code, last, simplified, rooms = run_case(builder, size, Path(tmp))
            rows.append((name, size, cells, peak, wall, code, last, simplified, rooms))
            print(f"{name:28s} n={size:6d} {cells:>12,} cells {rooms:>7,} rooms  {peak / 2**20:8.0f} MB  "
                  f"{wall:6.1f} s  exit {code}" + (f"  {last}" if code else ""), flush=True)
    write(args.out, _text(args, rows), _table(rows)[0], time.perf_counter() - t_all)


def _table(rows) -> tuple:
    """The section's table, and the rows over the memory bound."""
    const = rows[0][3]
    lines = ["| case | n | cells | rooms | exit | peak MB | bytes per cell above the constant | within the bound | s "
             "| µs per cell |",
             "|---|---:|---:|---:|---:|---:|---:|---|---:|---:|"]
    over = []
    for name, size, cells, peak, wall, code, last, _, rooms in rows:
        bpc = f"{(peak - const) / cells:.0f}" if cells > 1 else "—"
        us = f"{wall / cells * 1e6:.2f}" if cells > 1 else "—"
        ok = peak <= BOUND_CONSTANT + BOUND_PER_CELL * cells + BOUND_PER_ROOM * rooms
        if not ok:
            over.append(name)
        lines.append(f"| {name} | {size} | {cells:,} | {rooms:,} | {code} | {peak / 2**20:.0f} | {bpc} | "
                     f"{'yes' if ok else 'NO'} | {wall:.1f} | {us} |")
    return "\n".join(lines) + "\n", over


def _text(args, rows) -> str:
    """The section's text."""
    table, over = _table(rows)
    verdict = ("every row is within it" if not over else
               "these rows exceed it: " + "; ".join(f"'{n}'" for n in over))
    simple = [r[0] for r in rows if r[7]]
    simple = ("The room outlines of the rows " + "; ".join(f"'{n}'" for n in simple) + " exceed their detail "
              "limit: they are simplified, with a warning." if simple else "No room outline exceeds its detail limit.")
    load = os.getloadavg()
    cmd = "python benchmarks/adversarial.py" + (f" --scale {args.scale:g}" if args.scale != 1 else "")
    text = (f"## Adversarial maps: peak memory and time of the whole job\n\n"
            f"`{cmd}` at commit {_commit()}; {_machine()}; load average {load[0]:.1f} / {load[1]:.1f} at the "
            f"end. Each row is one `topomap segment MAP -o OUT` (overlay and every file included) in its own "
            f"process: peak resident memory (`wait4`), wall time and exit code. The constant is the first row "
            f"(a 1-cell map: interpreter, libraries, warm caches). The memory bound stated in "
            f"[Errors, bad input and exit codes](errors.md#memory-and-time) (150 bytes per cell + 25 kB per room "
            f"+ 250 MB) is checked against every row: {verdict}. {simple}{_per_room(rows)}\n\n" + table)
    return text


def _per_room(rows) -> str:
    """A sentence on the cost of a room, from the row of single-cell rooms (empty when it did not run)."""
    const = rows[0][3]
    many = [r for r in rows if r[1] > 1 and r[8] > 1000]
    if not many:
        return ""
    name, _, _, peak, wall, _, _, _, rooms = max(many, key=lambda r: r[8])
    return (f" A map of many rooms costs more than its cells: each room has its outline, its doors, its travel "
            f"distances and its entries in every file ('{name}': {rooms:,} rooms, "
            f"{(peak - const) / rooms / 1024:.0f} kB and {wall / rooms * 1e3:.1f} ms a room).")


if __name__ == "__main__":
    main()
