"""The ``topomap`` command line: a thin layer over the public functions.

Exit codes: 0 success; 1 a map or input could not be processed (one line on
stderr, the other maps of a batch still complete); 2 bad usage (unknown
option, missing argument); 3 an unexpected internal error. ``--debug`` prints
the traceback of any error.
"""

from __future__ import annotations

# The commands import what they use inside their functions, so that ``topomap --help`` starts fast.

import logging
import sys
import traceback
from pathlib import Path

import click

EXIT_OK, EXIT_INPUT, EXIT_USAGE, EXIT_INTERNAL = 0, 1, 2, 3

log = logging.getLogger("topomap")


def __getattr__(name):
    # ``topomap.cli.write_segmentation``, its earlier place, imported on first use (start-up stays fast)
    if name == "write_segmentation":
        from .run.job import write_segmentation

        return write_segmentation
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _method_names():
    # kept in sync with topomap.core.segmentation.METHODS (a test checks) without importing numpy at start-up
    return ["topomap", "paper", "watershed", "morphological", "distance", "voronoi"]


class _State:
    debug = False


def _naming(path, exc) -> str:
    """``path`` as the prefix of ``exc``'s error line, or "" when the message already names it."""
    return "" if str(path) in str(exc) else str(path)


def parse_settings(pairs) -> dict:
    """``--set OPTION=VALUE`` pairs as keyword options: ``true``/``false`` (also yes/no, on/off) as booleans,
    ``none`` as None, numbers as floats, any other value as text (the method checks them all).

    Raises
    ------
    ParameterError
        A pair without ``=`` or without a name, or an option given twice.
    """
    from .errors import ParameterError

    words = {"true": True, "yes": True, "on": True, "false": False, "no": False, "off": False,
             "none": None, "null": None}
    out = {}
    for pair in pairs:
        name, eq, text = pair.partition("=")
        name, text = name.strip(), text.strip()
        if not eq or not name:
            raise ParameterError(f"--set {pair!r}: expected OPTION=VALUE, e.g. --set max_door_width=2.5")
        if name in out:
            raise ParameterError(f"--set {name}: given twice")
        if text.lower() in words:
            out[name] = words[text.lower()]
        else:
            try:
                out[name] = float(text)
            except ValueError:
                out[name] = text
    return out


def _fail(exc, what="") -> int:
    """Print one line for ``exc`` on stderr; return the exit code to use."""
    from .errors import TopomapError, first_line

    if _State.debug:
        traceback.print_exception(exc)
    prefix = f"{what}: " if what else ""
    if isinstance(exc, (TopomapError, OSError, ValueError)):
        click.echo(f"error: {prefix}{first_line(exc)}", err=True)
        return EXIT_INPUT
    click.echo(f"internal error: {prefix}{type(exc).__name__}: {exc} (rerun with --debug for the traceback)",
               err=True)
    return EXIT_INTERNAL


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.option("--debug", is_flag=True, help="Print tracebacks of errors.")
@click.option("-v", "--verbose", count=True, help="More log output (-v info, -vv debug).")
@click.version_option(package_name="topomap-rooms")
def main(debug, verbose):
    """Rooms, doors and a room-door graph from occupancy grid maps."""
    _State.debug = debug
    level = logging.WARNING - 10 * min(verbose, 2)
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s")


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


def _id_changes(path) -> str:
    """One line on the room-ID changes recorded in ``path`` (changes.json)."""
    import json

    from .core.identity import RoomChanges

    return RoomChanges.from_dict(json.loads(Path(path).read_text(encoding="utf-8"))).summary()


def _count(n, noun) -> str:
    """``"1 room"``, ``"0 rooms"``, ``"2 rooms"``: ``n`` and ``noun``, plural unless ``n`` is 1."""
    return f"{n} {noun}{'' if n == 1 else 's'}"


def _summary(row) -> str:
    """"12 rooms, 11 doors", and ", 40 fragments (1.3 m²)" when free regions
    too small to be a room (scan specks) were set apart, ", 4 fragments (15.2 m²,
    13.8 m² of it outside the building)" when some of them lie outside the
    building (``row``: a summary row of :func:`topomap.segment_many`)."""
    text = f"{_count(row['rooms'], 'room')}, {_count(row['doors'], 'door')}"
    nf = row.get("fragments") or 0
    if nf:
        outside = row.get("outside_area_m2") or 0
        of_it = f", {outside:.4g} m² of it outside the building" if outside else ""
        text += f", {_count(nf, 'fragment')} ({row['fragment_area_m2']:.4g} m²{of_it})"
    return text


def _print_profile(path, row):
    """One line per stage on stderr (``row``: a summary row, ``t_<stage>`` seconds): where the time of a map went."""
    from .run.job import STAGES

    t = {k[2:]: v for k, v in row.items() if k.startswith("t_") and v is not None and v == v}
    stages = [k for k in STAGES if k in t] + sorted(k for k in t if k not in STAGES)
    click.echo(f"{path}: " + ", ".join(f"{k} {t[k] * 1000:.0f} ms" for k in stages), err=True)


def _report_failure(row) -> int:
    """The one-line message of a failed map of a batch; its exit code."""
    if _State.debug and row.get("traceback"):
        click.echo(row["traceback"], err=True, nl=False)
    msg = row["error"]
    if Path(row["map"]).name not in msg:
        msg = f"{row['map']}: {msg}"
    from .run.batch import ERROR

    if row["status"] == ERROR:
        click.echo(f"internal error: {msg} (rerun with --debug for the traceback)", err=True)
        return EXIT_INTERNAL
    click.echo(f"error: {msg}", err=True)
    return EXIT_INPUT


def _check_outdir(outdir):
    """ParameterError / MapFileError for an ``-o`` that cannot be an output folder (empty, a file)."""
    from .errors import MapFileError, ParameterError

    if not str(outdir).strip():
        raise ParameterError(f"-o/--out must name an output folder, got {str(outdir)!r}")
    outdir = Path(outdir)
    if outdir.exists() and not outdir.is_dir():
        raise MapFileError(f"-o {outdir}: exists and is not a folder")
    return outdir


@main.command("segment")
@click.argument("maps", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("-o", "--out", "outdir", required=True, type=click.Path(path_type=str),
              help="Output directory (several maps: a folder per map, from its path below the maps' "
                   "common folder, and summary.csv).")
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
@click.option("--topic", default=None, metavar="TOPIC",
              help="Bag maps: the nav_msgs/OccupancyGrid topic (default: the bag's only one).")
@click.option("--time", "at", type=float, default=None, metavar="SECONDS",
              help="Bag maps: the last map message at or before SECONDS after the bag's start "
                   "(default: the last one).")
@click.option("--bag", type=click.Path(path_type=Path), default=None, metavar="OUT",
              help="Also write the map, the rooms (MarkerArray) and the labels (mono16 Image) into a new bag: "
                   "OUT.mcap (ROS 2), OUT.bag (ROS 1) or OUT (ROS 2 sqlite3 directory). One map only.")
@click.option("-j", "--jobs", type=click.IntRange(min=1), default=1, show_default=True,
              help="Run maps in this many local processes.")
@click.option("--scheduler", metavar="ADDRESS", default=None,
              help="Run maps on this Dask distributed cluster (e.g. tcp://host:8786); needs topomap[dask].")
@click.option("--overwrite", is_flag=True,
              help="Segment every map again (no skipping of up-to-date outputs) and replace results "
                   "this run did not write.")
@click.option("--previous", type=click.Path(path_type=Path), default=None, metavar="GRAPH",
              help="Room graph of an earlier map of the same place (rooms.graphml, .json or .geojson): "
                   "rooms keep its IDs and names; writes changes.json.")
@click.option("--set", "settings", multiple=True, metavar="OPTION=VALUE",
              help="An option of the method (lengths in metres, areas in m²; see the options of "
                   "topomap.segment), e.g. --set max_door_width=2.5 --set gaps=false; repeatable. Kept in "
                   "topomap_run.json: a folder segmented with other options is run again.")
def segment_cmd(maps, outdir, resolution, method, skeletons, no_overlay, no_geojson, profile, topic, at, bag, jobs,
                scheduler, overwrite, previous, settings):
    """Segment MAP files (ROS YAML, PGM, PNG or a ROS bag) into rooms and doors.

    Writes labels.png (16-bit, 0 = not a room), labels.pgm + labels.yaml
    (the labels as a map_server raw-mode map), rooms.graphml, rooms.json
    (node-link), rooms.geojson, overlay.png and topomap_run.json per map.
    Maps whose outputs are complete and newer than the map are skipped.
    With --previous also changes.json (kept, new, vanished, split and
    merged room IDs).
    """
    start = _process_age()  # before any import below: those are the "import" stage
    from ._fast import keep_freed_memory

    keep_freed_memory()  # a batch reuses the pages of the maps before (see there)
    import time

    t0 = time.perf_counter()  # the import stage: the modules of the job, then the rest of preload's list
    from .run.batch import ERROR, FAILED, OK, SKIPPED, segment_many
    from .run.job import preload, warm_up

    preload(maps)
    imported = time.perf_counter() - t0
    from .errors import ParameterError

    warm = None
    if profile:  # one-off first-call costs as a stage of their own, not inside the first map's
        try:
            warm = warm_up(method)
        except Exception:  # noqa: BLE001 - a failed warm-up only leaves those costs in the first map
            warm = None
    # the modules just imported (hundreds of thousands of objects) live as long as the command:
    # the garbage collector's full passes need not walk them again while the maps run
    import gc

    gc.freeze()

    try:
        outdir = _check_outdir(outdir)
        options = parse_settings(settings)
        if resolution is not None:
            from .io.metadata import check_resolution

            check_resolution(resolution, name="--resolution")
        if at is not None and not 0 <= at < float("inf"):  # nan too
            raise ParameterError(f"--time must be seconds >= 0 after the start of the bag, got {at!r}")
    except Exception as exc:  # noqa: BLE001
        sys.exit(_fail(exc))
    if bag is not None:
        from .io.ros import check_bag_path

        try:
            if len(maps) > 1:
                raise ParameterError(f"--bag {bag}: writes the results of one map; {len(maps)} maps given")
            check_bag_path(bag)
        except Exception as exc:  # noqa: BLE001
            sys.exit(_fail(exc))
    if previous is not None:
        from .io.export import load_graph

        try:
            load_graph(previous)  # a bad file stops the run before anything is written
        except Exception as exc:  # noqa: BLE001
            sys.exit(_fail(exc, "--previous"))
    many = len(maps) > 1
    batch_log = logging.getLogger("topomap.run.batch")
    if many and not sys.stderr.isatty() and batch_log.getEffectiveLevel() > logging.INFO:
        batch_log.setLevel(logging.INFO)  # no progress bar: a line per map
    try:
        extra = {k: v for k, v in (("topic", topic), ("at", at), ("bag", None if bag is None else str(bag)),
                                   ("previous", None if previous is None else str(previous)),
                                   ("overlay", False if no_overlay else None),
                                   ("geojson", False if no_geojson else None)) if v is not None}
        rows = segment_many(maps, outdir, jobs=jobs, scheduler=scheduler, overwrite=overwrite,
                            resolution=resolution, method=method, skeletons=skeletons, options=options,
                            write_options=extra)
    except Exception as exc:  # noqa: BLE001 - nothing ran
        sys.exit(_fail(exc))
    code = EXIT_OK
    for row in rows:
        if row["status"] in (FAILED, ERROR):
            code = max(code, _report_failure(row))
            continue
        log.info("%s: %d rooms, %d doors -> %s", row["map"], row["rooms"], row["doors"], row["output"])
        if profile:
            if imported is not None:  # the process's start and imports: once, with the first map
                row = dict(row, t_start=start, t_import=imported, t_warmup=warm)
                imported = None
            _print_profile(row["map"], row)
        if not many:
            done = " (up to date, skipped)" if row["status"] == SKIPPED else ""
            click.echo(f"{row['map']}: {_summary(row)} -> {row['output']}{done}")
            if previous is not None and row["status"] == OK:
                click.echo(f"{row['map']}: room IDs: {_id_changes(Path(row['output']) / 'changes.json')}")
    if many:
        good = sum(r["status"] in (OK, SKIPPED) for r in rows)
        skipped = sum(r["status"] == SKIPPED for r in rows)
        note = f", {skipped} of them up to date and skipped" if skipped else ""
        click.echo(f"{good} of {len(rows)} maps segmented{note} -> {outdir} (summary.csv)")
    sys.exit(code)


@main.command("demo")
@click.option("-o", "--out", "outdir", default="demo_out", show_default=True, type=click.Path(path_type=Path),
              help="Output directory.")
@click.option("--method", type=click.Choice(_method_names()), default=None)
def demo_cmd(outdir, method):
    """Segment the embedded example office map and write the outputs."""
    from .io.example import example_map_path
    from .run.job import segment_file

    try:
        seg = segment_file(example_map_path(), outdir, None, method, True)
    except Exception as exc:  # noqa: BLE001
        sys.exit(_fail(exc))
    click.echo(f"example office: {_count(seg.n_rooms, 'room')}, {_count(len(seg.doors), 'door')} "
               f"(threshold {seg.threshold if seg.threshold is not None else float('nan'):.2f} m) -> {outdir}")
    for d in seg.doors:
        click.echo(f"  door {d.id}: rooms {d.rooms[0]}-{d.rooms[1]}, width {d.width:.2f} m, "
                   f"midpoint ({d.midpoint[0]:.2f}, {d.midpoint[1]:.2f}) m")


@main.command("benchmark")
@click.argument("dataset_dir", type=click.Path(path_type=Path))
@click.option("--methods", default=None,
              help="Comma-separated methods (default: every method of topomap.core.segmentation.METHODS).")
@click.option("--variant", type=click.Choice(["unfurnished", "furnished", "plan", "scan", "both"]), default="both",
              show_default=True, help="Which maps: without furniture, with furniture, or both; of a simulated "
                                      "corpus: the floor plan, the simulated scan, or both.")
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
    image; --variant is then ignored), or one folder per simulated case
    (map.yaml, plan.yaml, gt_rooms.png, gt_doors.json). Each map is loaded
    as `topomap segment` loads it; runtimes are of loading plus segmentation.
    """
    from .bench.benchmark import check_methods, format_table, run_benchmark, write_rows

    try:
        names = check_methods(methods)
        if out is not None and out.suffix.lower() not in (".csv", ".json"):
            from .errors import ParameterError

            raise ParameterError(f"--out must end in .csv or .json, got {out.name!r}")
    except Exception as exc:  # noqa: BLE001
        sys.exit(_fail(exc))
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
        rows = run_benchmark(dataset_dir, methods=names, variants=variant, jobs=jobs, progress=progress,
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


def _place(point, room, name: str):
    """The start or goal of ``plan`` / ``tour``: the point ``(x, y)`` of ``--NAME`` or the room ID of
    ``--NAME-room``, exactly one of them."""
    if (point is None) == (room is None):
        raise click.UsageError(f"give one of --{name} X Y (a point, m) or --{name}-room ID (a room)")
    return tuple(point) if point is not None else int(room)


@main.command("plan")
@click.argument("graph", type=click.Path(path_type=Path))
@click.option("--from", "start", nargs=2, type=float, default=None, metavar="X Y",
              help="Start point, map-frame metres.")
@click.option("--from-room", "start_room", type=int, default=None, metavar="ID",
              help="Start in this room (at its interior point), instead of --from.")
@click.option("--to", "goal", nargs=2, type=float, default=None, metavar="X Y",
              help="Goal point, map-frame metres.")
@click.option("--to-room", "goal_room", type=int, default=None, metavar="ID",
              help="Go to this room (to its interior point), instead of --to.")
@click.option("--robot-width", type=float, default=0.0, show_default=True,
              help="Doors narrower than this (m) are not used.")
@click.option("--json", "as_json", is_flag=True, help="Print the route as JSON.")
def plan_cmd(graph, start, start_room, goal, goal_room, robot_width, as_json):
    """Plan a route through rooms and doors of GRAPH.

    GRAPH is rooms.graphml, rooms.json or rooms.geojson as written by
    ``topomap segment``: it holds the room outlines and the in-room
    door-to-door travel distances, so no map is needed. Prints the room
    sequence, the doors with their midpoints (m) and the travel length.
    A room given by its ID stands for its interior point (a point inside
    the room, as far from its walls as any).
    """
    import json

    from .io.export import load_graph
    from .planning.paths import plan_path

    start, goal = _place(start, start_room, "from"), _place(goal, goal_room, "to")
    try:
        G = load_graph(graph)
        route = plan_path(G, start, goal, robot_width=robot_width)
    except Exception as exc:  # noqa: BLE001
        sys.exit(_fail(exc, _naming(graph, exc)))
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


@main.command("tour")
@click.argument("graph", type=click.Path(path_type=Path))
@click.option("--from", "start", nargs=2, type=float, default=None, metavar="X Y",
              help="Start point, map-frame metres.")
@click.option("--from-room", "start_room", type=int, default=None, metavar="ID",
              help="Start in this room (at its interior point), instead of --from.")
@click.option("--rooms", default=None, metavar="IDS",
              help="Comma-separated room IDs to visit (default: every room reachable from the start).")
@click.option("--return", "return_to_start", is_flag=True, help="End the tour back at the start.")
@click.option("--robot-width", type=float, default=0.0, show_default=True,
              help="Doors narrower than this (m) are not used.")
@click.option("--json", "as_json", is_flag=True, help="Print the tour as JSON.")
def tour_cmd(graph, start, start_room, rooms, return_to_start, robot_width, as_json):
    """The order in which to visit the rooms of GRAPH, and the doors to pass.

    GRAPH is rooms.graphml, rooms.json or rooms.geojson as written by
    ``topomap segment``. Optimal for up to 12 rooms, a heuristic above (see
    topomap.planning.plan_tour). Prints the rooms in order with the travel
    distance to each, the doors passed and the total length. A room is
    visited at its interior point (a point inside the room, as far from its
    walls as any); --from-room starts there.
    """
    import json

    from .errors import ParameterError
    from .io.export import load_graph
    from .planning.tour import plan_tour

    start = _place(start, start_room, "from")
    try:
        ids = None
        if rooms is not None:
            try:
                ids = [int(t) for t in rooms.split(",") if t.strip()]
            except ValueError:
                raise ParameterError(f"--rooms must be comma-separated room IDs, got {rooms!r}") from None
        G = load_graph(graph)
        tour = plan_tour(G, start, rooms=ids, return_to_start=return_to_start, robot_width=robot_width)
    except Exception as exc:  # noqa: BLE001
        sys.exit(_fail(exc, _naming(graph, exc)))
    if as_json:
        click.echo(json.dumps(dict(tour, waypoints=tour["waypoints"].tolist())))
        return
    click.echo("order: " + " -> ".join(str(r) for r in tour["order"]) + (" -> start" if return_to_start else ""))
    click.echo(f"length: {tour['length']:.2f} m ({tour['method']})")
    stops = tour["order"][1:] + (["start"] if return_to_start else [])
    for r, leg in zip(stops, tour["legs"]):
        click.echo(f"  {'room ' + str(r) if r != 'start' else 'start':<10} +{leg:.2f} m")
    click.echo("doors: " + " ".join(str(d) for d in tour["doors"]))
    if tour["unreachable"]:
        click.echo("unreachable rooms: " + ", ".join(str(r) for r in tour["unreachable"]))


@main.command("simulate")
@click.argument("plans", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("-o", "--out", "outdir", required=True, type=click.Path(path_type=str),
              help="Output folder (several plans: a folder per plan, named as `segment` names them).")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Seed of the scan (several plans: each plan's seed is fixed by this seed and its name).")
@click.option("--explore", type=float, default=None, help="Share of the rooms the robot enters (default 1).")
@click.option("--glass", type=float, default=None, help="Share of the facade that is glass (default 0.15).")
@click.option("--closed-doors", "closed_doors", type=float, default=None,
              help="Share of the doors that are closed (default 0.1).")
@click.option("--no-drift", "no_drift", is_flag=True, help="No pose drift (walls drawn where they are).")
@click.option("--no-furniture", "no_furniture", is_flag=True, help="No furniture (neither the plan's nor random).")
@click.option("--no-people", "no_people", is_flag=True, help="No people (dynamic clutter) along the path.")
@click.option("--option", "extra", multiple=True, metavar="NAME=VALUE",
              help="Any other scan option of topomap.bench.simulate.ScanOptions (e.g. range_max=5.6); repeatable.")
@click.option("--resolution", type=float, default=0.05, show_default=True, help="Metres per cell of the map.")
@click.option("-j", "--jobs", type=click.IntRange(min=1), default=1, show_default=True,
              help="Simulate plans in this many local processes.")
@click.option("--overwrite", is_flag=True, help="Simulate again plans whose case folder is up to date.")
def simulate_cmd(plans, outdir, seed, explore, glass, closed_doors, no_drift, no_furniture, no_people, extra,
                 resolution, jobs, overwrite):
    """Simulate a robot's laser map of each vector floor PLAN, with its ground truth.

    Writes map.pgm + map.yaml (the map as ROS map_saver writes it),
    plan.pgm + plan.yaml (the drawn plan on the same grid), gt_rooms.png
    (16-bit room labels), gt_doors.json, gt_rooms_scan.png and
    gt_doors_scan.json (the rooms the scan shows, and their doors),
    gt_rooms.json and simulation.json per plan. The output folder of several plans reads as a data set:
    `topomap benchmark OUT --variant scan`.
    """
    from .run.batch import FAILED, SKIPPED
    from .bench.corpus import scan_options, simulate_many
    from .io.metadata import check_resolution

    try:
        check_resolution(resolution, name="--resolution")
        options = scan_options(explore=explore, glass_share=glass, closed_doors=closed_doors, no_drift=no_drift,
                               no_furniture=no_furniture, no_people=no_people, extra=extra)
        outdir = _check_outdir(outdir)
        rows = simulate_many(plans, outdir, seed=seed, options=options, resolution=resolution, jobs=jobs,
                             overwrite=overwrite)
    except Exception as exc:  # noqa: BLE001 - nothing ran
        sys.exit(_fail(exc))
    code = EXIT_OK
    for row in rows:
        if row["status"] == FAILED:
            click.echo(f"error: {row['error']}", err=True)
            code = EXIT_INPUT
        elif len(rows) == 1:
            done = " (up to date, skipped)" if row["status"] == SKIPPED else ""
            click.echo(f"{row['plan']}: {_count(row['rooms'], 'room')}, {_count(row['doors'], 'door')}, "
                       f"{row['area']:.1f} m², {100 * row['free_share']:.0f} % of it seen free -> "
                       f"{row['output']}{done}")
    if len(rows) > 1:
        good = sum(r["status"] != FAILED for r in rows)
        click.echo(f"{good} of {len(rows)} plans simulated -> {outdir}")
    sys.exit(code)


@main.command("export")
@click.argument("source", metavar="INPUT", type=click.Path(path_type=Path))
@click.argument("target", metavar="OUTPUT", required=False, type=click.Path(path_type=Path))
@click.option("--nav2", "nav2", type=click.Path(path_type=Path), default=None, metavar="GEOJSON",
              help="Write the Nav2 Route Server graph of INPUT's rooms to this file (needs labels.yaml + "
                   "labels.pgm or labels.png beside INPUT, as topomap segment writes them).")
@click.option("--clearance", type=float, default=None, metavar="M",
              help="With --nav2: metres every edge keeps from walls and unknown space (default 0.2; "
                   "your robot's radius).")
def export_cmd(source, target, nav2, clearance):
    """Convert a room graph between GraphML, JSON and GeoJSON, or export a Nav2 route graph.

    The formats follow the extensions: .graphml (or .xml), .json (node-link
    data) and .geojson (map-frame metres). With --nav2, writes the route
    graph Nav2's Route Server loads (OUTPUT may then be left out).
    """
    from .io.export import graph_format, load_graph, save_graph

    if clearance is not None and nav2 is None:
        click.echo("error: --clearance needs --nav2", err=True)
        sys.exit(EXIT_USAGE)
    if target is None and nav2 is None:
        click.echo("error: give OUTPUT, --nav2 GEOJSON or both", err=True)
        sys.exit(EXIT_USAGE)
    route = None
    try:
        if clearance is not None:
            from .options import check_length

            clearance = check_length("--clearance", clearance)
        if target is not None:
            graph_format(target)
        if nav2 is not None:
            from .run.record import check_nav2_target

            check_nav2_target(source, nav2, target)
        G = load_graph(source)
        if nav2 is not None:
            from .io.nav2 import labels_beside
            from .planning.nav2 import DEFAULT_CLEARANCE, route_graph

            route = route_graph(G, labels_beside(source), clearance=DEFAULT_CLEARANCE if clearance is None
                                else clearance)
    except Exception as exc:  # noqa: BLE001
        named = "--clearance" in str(exc) or any(str(p) in str(exc) for p in (target, nav2) if p is not None)
        sys.exit(_fail(exc, "" if named else _naming(source, exc)))
    try:
        if target is not None:
            save_graph(G, target)
        if route is not None:
            from .io.nav2 import write_route_graph
            from .run.record import add_nav2_export

            write_route_graph(route, nav2)
            add_nav2_export(source, nav2, clearance)  # so that topomap edit rewrites it
    except Exception as exc:  # noqa: BLE001
        sys.exit(_fail(exc, _naming(target or nav2, exc) and _naming(nav2 or target, exc)))
    if target is not None:
        click.echo(f"{source} -> {target}: {_count(G.number_of_nodes(), 'room')}, "
                   f"{_count(G.number_of_edges(), 'door')}")
    if route is not None:
        n = sum(f["geometry"]["type"] == "Point" for f in route["features"])
        click.echo(f"{source} -> {nav2}: Nav2 route graph, {_count(n, 'node')}, "
                   f"{_count(len(route['features']) - n, 'edge')}")


class _EditCommand(click.Command):
    """A command that keeps the order its options were given in (``ctx.meta["topomap.cli.edit.order"]``:
    one parameter name per occurrence), for edits applied in the order typed."""

    def make_parser(self, ctx):
        parser = super().make_parser(ctx)
        parse = parser.parse_args

        def parse_args(args):
            opts, rest, order = parse(args=args)
            ctx.meta["topomap.cli.edit.order"] = [p.name for p in order]
            return opts, rest, order

        parser.parse_args = parse_args
        return parser


@main.command("edit", cls=_EditCommand)
@click.argument("outdir", metavar="OUT_DIR", type=click.Path(path_type=Path))
@click.option("--merge", "merges", multiple=True, type=(int, int), metavar="A B",
              help="Merge room B into room A (they must share a door or touch); repeatable.")
@click.option("--split", "splits", multiple=True, type=(int, float, float, float, float), metavar="ROOM X1 Y1 X2 Y2",
              help="Split ROOM along the line from (X1, Y1) to (X2, Y2), map-frame metres, drawn from wall to "
                   "wall; it becomes a door. Repeatable.")
@click.option("--name", "names", multiple=True, type=(int, str), metavar="ROOM NAME",
              help="Name ROOM (quote a name with spaces); repeatable.")
@click.option("--no-go", "no_gos", multiple=True, type=int, metavar="ROOM",
              help="Mark ROOM as a room a robot must not enter; repeatable.")
def edit_cmd(outdir, merges, splits, names, no_gos):
    """Merge, split, name and mark rooms in OUT_DIR, the output folder of `topomap segment`.

    The edits apply in the order given (room IDs are those after the edits
    before). Every output in OUT_DIR is rewritten to agree (labels, room
    graph files, overlay), all files or none; a bad edit changes no file.
    The edits are added to the run record (topomap_run.json), and the room
    graph keeps names, no-go marks and merges for `topomap segment NEW_MAP
    --previous OUT_DIR/rooms.graphml`.
    """
    from .run.editing import edit_outputs

    given = {"merges": [("merge", *v) for v in merges], "splits": [("split", *v) for v in splits],
             "names": [("name", *v) for v in names], "no_gos": [("no_go", v) for v in no_gos]}
    if not any(given.values()):
        raise click.UsageError("nothing to edit: give --merge, --split, --name or --no-go")
    order = click.get_current_context().meta.get("topomap.cli.edit.order") or list(given)
    edits, taken = [], {k: 0 for k in given}
    for name in order:  # each option's values in the order typed, interleaved as typed
        if name in given and taken[name] < len(given[name]):
            edits.append(given[name][taken[name]])
            taken[name] += 1
    edits += [e for k, v in given.items() for e in v[taken[k]:]]
    try:
        seg, records = edit_outputs(outdir, edits)
    except Exception as exc:  # noqa: BLE001
        sys.exit(_fail(exc, _naming(outdir, exc)))
    done = []
    for r in records:
        if r["edit"] == "merge":
            done.append(f"merged {r['rooms'][1]} into {r['rooms'][0]}")
        elif r["edit"] == "split":
            done.append(f"split {r['room']} (new room {r['new_room']})")
        elif r["edit"] == "name":
            done.append(f"named {r['room']} {r['name']!r}")
        else:
            done.append(f"{r['room']} no-go")
    row = {"rooms": seg.n_rooms, "doors": len(seg.doors), "fragments": seg.n_fragments,
           "fragment_area_m2": seg.fragment_area}
    click.echo(f"{outdir}: {'; '.join(done)} -> {_summary(row)}")
    from .run.record import nav2_exports, read_record

    for note in nav2_exports(read_record(Path(outdir)) or {}):
        click.echo(f"{outdir}: Nav2 route graph {note['path']} rewritten")


if __name__ == "__main__":
    main()
