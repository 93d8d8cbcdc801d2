"""The ``topomap`` command line: a thin layer over the public functions.

Exit codes: 0 success; 1 a map or input could not be processed (one line on
stderr, the other maps of a batch still complete); 2 bad usage (unknown
option, missing argument); 3 an unexpected internal error. ``--debug`` prints
the traceback of any error.
"""

from __future__ import annotations

import logging
import sys
import traceback
from pathlib import Path

import click

EXIT_OK, EXIT_INPUT, EXIT_USAGE, EXIT_INTERNAL = 0, 1, 2, 3

log = logging.getLogger("topomap")


def _method_names():
    # kept in sync with topomap.segmentation.METHODS (a test checks) without importing numpy at start-up
    return ["topomap", "paper", "watershed", "morphological", "distance", "voronoi"]


class _State:
    debug = False


def _fail(exc, what="") -> int:
    """Print one line for ``exc`` on stderr; return the exit code to use."""
    from .errors import TopomapError

    if _State.debug:
        traceback.print_exception(exc)
    prefix = f"{what}: " if what else ""
    if isinstance(exc, (TopomapError, OSError, ValueError)):
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        click.echo(f"error: {prefix}{msg}", err=True)
        return EXIT_INPUT
    click.echo(f"internal error: {prefix}{type(exc).__name__}: {exc} (rerun with --debug for the traceback)",
               err=True)
    return EXIT_INTERNAL


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.option("--debug", is_flag=True, help="Print tracebacks of errors.")
@click.option("-v", "--verbose", count=True, help="More log output (-v info, -vv debug).")
@click.version_option(package_name="topomap")
def main(debug, verbose):
    """Rooms, doors and a room-door graph from occupancy grid maps."""
    _State.debug = debug
    level = logging.WARNING - 10 * min(verbose, 2)
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s")


def write_segmentation(seg, outdir, *, overlay: bool = True, skeletons: bool = False, geojson: bool = True,
                       timings: dict | None = None) -> dict:
    """The files ``topomap segment`` writes for ``seg`` into ``outdir``.

    Computes what is saved — the travel graph
    (:func:`topomap.planning.travel_graph`: the room–door graph with
    in-room door-to-door distances, so ``topomap plan`` works from
    ``rooms.graphml`` or ``rooms.json`` alone) and, unless ``overlay`` is
    False, the overlay picture (:func:`topomap.plot.overlay_png`) — then
    writes everything with :func:`topomap.export.write_outputs` (all files
    or none; ``rooms.geojson`` only when ``geojson``).

    ``timings``, when given, receives the seconds of each step: ``travel``,
    ``overlay`` and ``write_<file>`` per file.

    Returns
    -------
    dict
        ``{name: path}`` of the files written.
    """
    import time

    from .export import write_outputs
    from .planning import travel_graph

    t = {} if timings is None else timings
    t0 = time.perf_counter()
    G = travel_graph(seg)
    t["travel"] = time.perf_counter() - t0
    png = None
    if overlay:
        from .plot import overlay_png

        t0 = time.perf_counter()
        png = overlay_png(seg, skeletons=skeletons)
        t["overlay"] = time.perf_counter() - t0
    return write_outputs(seg, outdir, G, overlay_png=png, geojson=geojson, timings=t)


#: Modules the segment command uses, imported up front (their import time is the
#: ``import`` stage of ``--profile``, not hidden in the first map's stages).
_PRELOAD = ("numpy", "scipy.ndimage", "scipy.sparse.csgraph", "scipy.spatial", "cv2", "PIL.Image",
            "PIL.PngImagePlugin", "yaml", "networkx", "shapely", "shapely.geometry", "shapely.ops", "skimage.draw",
            "skimage.graph", "skimage.morphology", "skimage.segmentation", "topomap.io", "topomap.segmentation",
            "topomap.roomgraph", "topomap.planning", "topomap.export", "topomap.plot")


def _preload() -> float:
    """Import :data:`_PRELOAD`; returns the seconds it took."""
    import importlib
    import time

    t0 = time.perf_counter()
    for name in _PRELOAD:
        importlib.import_module(name)
    return time.perf_counter() - t0


def _warm_up(method) -> float:
    """Run the whole job once on a tiny map in memory (nothing written); returns the seconds.

    First calls pay one-off costs (lazy imports inside libraries, caches,
    font set-up); paid here they are the ``warmup`` stage of ``--profile``
    instead of hiding in the first map's stages.
    """
    import time

    import numpy as np

    from .io import from_array
    from .planning import travel_graph
    from .plot import overlay_png
    from .segmentation import segment

    t0 = time.perf_counter()
    free = np.zeros((60, 100), bool)
    free[4:56, 4:48] = True
    free[4:56, 52:96] = True
    free[24:36, 48:52] = True
    seg = segment(from_array(free, resolution=0.05), method=method)
    seg.room_graph
    travel_graph(seg)
    overlay_png(seg)
    return time.perf_counter() - t0


def _process_age() -> float | None:
    """Seconds since this process started (Linux ``/proc``), or None."""
    import os

    try:
        with open("/proc/self/stat") as fh:
            start = int(fh.read().rsplit(")", 1)[1].split()[19])
        with open("/proc/uptime") as fh:
            up = float(fh.read().split()[0])
        return max(up - start / os.sysconf("SC_CLK_TCK"), 0.0)
    except (OSError, ValueError, IndexError):
        return None


def _segment_one(path, outdir, resolution, method, skeletons, *, overlay=True, geojson=True):
    import time

    from . import io
    from .segmentation import segment

    t0 = time.perf_counter()
    grid = io.load_map(path, resolution=resolution)
    t1 = time.perf_counter()
    seg = segment(grid, method=method)
    seg.room_graph  # built here so its time is its own stage (timings["room_graph"])
    t2 = time.perf_counter()
    write_segmentation(seg, outdir, skeletons=skeletons, overlay=overlay, geojson=geojson, timings=seg.timings)
    seg.timings["load"] = t1 - t0
    seg.timings["write"] = time.perf_counter() - t2
    seg.timings["job"] = time.perf_counter() - t0
    return seg


def _summary(seg) -> str:
    """"12 rooms, 11 doors", and ", 40 fragments (1.3 m²)" when free regions
    too small to be a room (scan specks) were set apart."""
    text = f"{seg.n_rooms} rooms, {len(seg.doors)} doors"
    nf = seg.n_fragments
    if nf:
        text += f", {nf} fragment{'s' if nf > 1 else ''} ({seg.fragment_area:.4g} m²)"
    return text


#: Stages of ``--profile`` in the order of the job. ``total`` is the segmentation call (its
#: stages before it); ``write`` is travel distances, overlay and every ``write_<file>``;
#: ``job`` is the map from loading to the last file.
PROFILE_ORDER = ["start", "import", "warmup", "load", "preprocess", "skeletons", "graphs", "doors", "rooms", "segment",
                 "total", "room_graph", "travel", "overlay", "write_labels", "write_graphml", "write_json",
                 "write_geojson", "write_overlay", "write", "job"]


def _print_profile(path, seg):
    """One line per stage on stderr: where the time of a map went."""
    t = seg.timings
    stages = [k for k in PROFILE_ORDER if k in t] + sorted(k for k in t if k not in PROFILE_ORDER)
    click.echo(f"{path}: " + ", ".join(f"{k} {t[k] * 1000:.0f} ms" for k in stages), err=True)


@main.command("segment")
@click.argument("maps", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("-o", "--out", "outdir", required=True, type=click.Path(path_type=Path),
              help="Output directory (one subfolder per map stem when several maps are given).")
@click.option("--resolution", type=float, default=None,
              help="Metres per pixel for image maps without YAML (default 0.05).")
@click.option("--method", type=click.Choice(_method_names()), default=None,
              help="Segmentation method (default: the library's default).")
@click.option("--skeletons", is_flag=True, help="Draw both skeleton graphs in overlay.png.")
@click.option("--no-overlay", "no_overlay", is_flag=True, help="Do not draw or write overlay.png (batch runs).")
@click.option("--no-geojson", "no_geojson", is_flag=True, help="Do not write rooms.geojson.")
@click.option("--profile", is_flag=True,
              help="Print the time of every stage (start, imports, warm-up, load, segmentation stages, room "
                   "graph, travel distances, overlay, each file written) on stderr.")
def segment_cmd(maps, outdir, resolution, method, skeletons, no_overlay, no_geojson, profile):
    """Segment MAP files (ROS YAML, PGM or PNG) into rooms and doors.

    Writes labels.png (16-bit, 0 = not a room), rooms.graphml, rooms.json
    (node-link), rooms.geojson and overlay.png per map.
    """
    from .errors import ParameterError

    start = _process_age()
    imported = _preload()
    warm = None
    if profile:  # one-off first-call costs as a stage of their own, not inside the first map's
        try:
            warm = _warm_up(method)
        except Exception:  # noqa: BLE001 - a failed warm-up only leaves those costs in the first map
            warm = None

    if resolution is not None and not resolution > 0:
        sys.exit(_fail(ParameterError(f"--resolution must be > 0 m/px, got {resolution!r}")))
    many = len(maps) > 1
    failed = 0
    code = EXIT_OK
    items = list(maps)
    with click.progressbar(items, label="segmenting", file=sys.stderr,
                           show_pos=True, item_show_func=lambda p: p and p.name) if many else _nullbar(items) as bar:
        for path in bar:
            target = outdir / path.stem if many else outdir
            try:
                seg = _segment_one(path, target, resolution, method, skeletons, overlay=not no_overlay,
                                   geojson=not no_geojson)
                log.info("%s: %d rooms, %d doors -> %s", path, seg.n_rooms, len(seg.doors), target)
                if profile:
                    if imported is not None:  # the process's start and imports: once, with the first map
                        if start is not None:
                            seg.timings["start"] = start
                        seg.timings["import"] = imported
                        if warm is not None:
                            seg.timings["warmup"] = warm
                        imported = None
                    _print_profile(path, seg)
                if not many:
                    click.echo(f"{path}: {_summary(seg)} -> {target}")
            except Exception as exc:  # noqa: BLE001 - reported, batch goes on
                failed += 1
                code = max(code, _fail(exc))
    if many:
        click.echo(f"{len(items) - failed} of {len(items)} maps segmented -> {outdir}")
    sys.exit(code)


class _nullbar:
    def __init__(self, items):
        self.items = items

    def __enter__(self):
        return self.items

    def __exit__(self, *a):
        return False


@main.command("demo")
@click.option("-o", "--out", "outdir", default="demo_out", show_default=True, type=click.Path(path_type=Path),
              help="Output directory.")
@click.option("--method", type=click.Choice(_method_names()), default=None)
def demo_cmd(outdir, method):
    """Segment the embedded example office map and write the outputs."""
    from ._example import example_map_path

    try:
        seg = _segment_one(example_map_path(), outdir, None, method, True)
    except Exception as exc:  # noqa: BLE001
        sys.exit(_fail(exc))
    click.echo(f"example office: {seg.n_rooms} rooms, {len(seg.doors)} doors "
               f"(threshold {seg.threshold if seg.threshold is not None else float('nan'):.2f} m) -> {outdir}")
    for d in seg.doors:
        click.echo(f"  door {d.id}: rooms {d.rooms[0]}-{d.rooms[1]}, width {d.width:.2f} m, "
                   f"midpoint ({d.midpoint[0]:.2f}, {d.midpoint[1]:.2f}) m")


@main.command("benchmark")
@click.argument("dataset_dir", type=click.Path(path_type=Path))
@click.option("--methods", default=None,
              help="Comma-separated methods (default: every method of topomap.segmentation.METHODS).")
@click.option("--variant", type=click.Choice(["unfurnished", "furnished", "both"]), default="both",
              show_default=True, help="Which maps: without furniture, with furniture, or both.")
@click.option("--jobs", type=click.IntRange(min=1), default=1, show_default=True,
              help="Parallel worker processes (timings are only fully comparable with 1).")
@click.option("--out", "out", type=click.Path(path_type=Path), default=None,
              help="Write per-map rows to this .csv or .json file.")
@click.option("--maps", "maps", default=None,
              help="Comma-separated map names or shell patterns (e.g. 'office_*,lab_a_scan'); "
                   "default every map.")
def benchmark_cmd(dataset_dir, methods, variant, jobs, out, maps):
    """Run every method on the maps of DATASET_DIR and print the score table.

    DATASET_DIR holds either NAME.png, NAME_furnitures.png and
    NAME_gt_segmentation.png per map (the layout of Bormann et al. 2016), or
    NAME.png, NAME.yaml and NAME_gt.png (a map_server map and its label
    image; --variant is then ignored). Each map is loaded as `topomap
    segment` loads it; runtimes are of loading plus segmentation.
    """
    from .benchmark import _check_methods, format_table, run_benchmark, write_rows

    try:
        names = _check_methods(methods)
        if out is not None and out.suffix.lower() not in (".csv", ".json"):
            from .errors import ParameterError

            raise ParameterError(f"--out must end in .csv or .json, got {out.name!r}")
    except Exception as exc:  # noqa: BLE001
        sys.exit(_fail(exc))
    variants = ("unfurnished", "furnished") if variant == "both" else (variant,)
    state = {}

    def progress(done, total, row):
        bar = state.get("bar")
        if bar is None:
            bar = state["bar"] = click.progressbar(length=total, label="benchmark", file=sys.stderr,
                                                   show_pos=True, item_show_func=lambda s: s)
            bar.__enter__()
        bar.current_item = f"{row['method']} {row['variant']} {row['map']}"
        bar.update(1)
        if row.get("error"):
            log.warning("%s %s %s: %s", row["method"], row["variant"], row["map"], row["error"])

    try:
        rows = run_benchmark(dataset_dir, methods=names, variants=variants, jobs=jobs, progress=progress,
                             maps=maps)
    except Exception as exc:  # noqa: BLE001
        if state.get("bar") is not None:
            state["bar"].__exit__(None, None, None)
        sys.exit(_fail(exc))
    if state.get("bar") is not None:
        state["bar"].__exit__(None, None, None)
    click.echo(format_table(rows), nl=False)
    failed = sum(1 for r in rows if r.get("error"))
    if out is not None:
        try:
            write_rows(rows, out)
        except Exception as exc:  # noqa: BLE001
            sys.exit(_fail(exc))
        click.echo(f"{len(rows)} rows -> {out}")
    if failed:
        click.echo(f"error: {failed} of {len(rows)} runs failed (see the 'error' column)", err=True)
        sys.exit(EXIT_INPUT)


@main.command("plan")
@click.argument("graph", type=click.Path(path_type=Path))
@click.option("--from", "start", nargs=2, type=float, required=True, metavar="X Y",
              help="Start point, map-frame metres.")
@click.option("--to", "goal", nargs=2, type=float, required=True, metavar="X Y",
              help="Goal point, map-frame metres.")
@click.option("--robot-width", type=float, default=0.0, show_default=True,
              help="Doors narrower than this (m) are not used.")
@click.option("--json", "as_json", is_flag=True, help="Print the route as JSON.")
def plan_cmd(graph, start, goal, robot_width, as_json):
    """Plan a route through rooms and doors of GRAPH.

    GRAPH is rooms.graphml, rooms.json or rooms.geojson as written by
    ``topomap segment``: it holds the room outlines and the in-room
    door-to-door travel distances, so no map is needed. Prints the room
    sequence, the doors with their midpoints (m) and the travel length.
    """
    import json

    from .export import load_graph
    from .planning import plan_path

    try:
        G = load_graph(graph)
        route = plan_path(G, tuple(start), tuple(goal), robot_width=robot_width)
    except Exception as exc:  # noqa: BLE001
        sys.exit(_fail(exc))
    if as_json:
        out = dict(route, waypoints=route["waypoints"].tolist())
        click.echo(json.dumps(out))
        return
    doors = {int(d.get("door", k)): (a, b, d) for a, b, k, d in G.edges(keys=True, data=True)}
    click.echo("rooms: " + " -> ".join(str(r) for r in route["rooms"]))
    click.echo(f"length: {route['length']:.2f} m")
    wp = route["waypoints"]
    click.echo(f"  start   ({wp[0, 0]:.2f}, {wp[0, 1]:.2f}) m  room {route['start_room']}")
    for i, did in enumerate(route["doors"], start=1):
        a, b, d = doors[did]
        click.echo(f"  door {did:<3d}({wp[i, 0]:.2f}, {wp[i, 1]:.2f}) m  rooms {a}-{b}, width {d['width']:.2f} m")
    click.echo(f"  goal    ({wp[-1, 0]:.2f}, {wp[-1, 1]:.2f}) m  room {route['goal_room']}")


@main.command("export")
@click.argument("source", metavar="INPUT", type=click.Path(path_type=Path))
@click.argument("target", metavar="OUTPUT", type=click.Path(path_type=Path))
def export_cmd(source, target):
    """Convert a room graph between GraphML, JSON and GeoJSON.

    The formats follow the extensions: .graphml (or .xml), .json (node-link
    data) and .geojson (map-frame metres).
    """
    from .export import _format, load_graph, save_graph

    try:
        _format(target)
        G = load_graph(source)
        save_graph(G, target)
    except Exception as exc:  # noqa: BLE001
        sys.exit(_fail(exc))
    click.echo(f"{source} -> {target}: {G.number_of_nodes()} rooms, {G.number_of_edges()} doors")


if __name__ == "__main__":
    main()
