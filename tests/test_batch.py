"""Batches: ``topomap.segment_many`` and ``topomap segment MAP... -o OUT``.

Output folders that never collide, refusal to replace results the run did
not write, summary.csv (also for failed maps), resume after a kill, and the
same outputs from one process, two processes and a 2-worker Dask
LocalCluster.
"""

import csv
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

import _testdata as T
from test_bad_input import png
from topomap.run import batch
from topomap import cli
from topomap.run.batch import RECORD, output_dirs, read_summary, segment_many
from topomap.cli import main
from topomap.errors import MissingDependencyError, OutputExistsError, ParameterError
from topomap.io import from_array, save_map


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


@pytest.fixture(autouse=True)
def _reset_debug():
    yield
    cli._State.debug = False


def ros_map(path: Path, test_map) -> Path:
    """A map_server pair ``path.yaml`` + ``path.pgm``; returns the YAML."""
    path.parent.mkdir(parents=True, exist_ok=True)
    save_map(from_array(test_map.free, resolution=test_map.resolution), path)
    return path.with_suffix(".yaml")


def four_maps(d: Path) -> list:
    """Four small maps, two of them called ``map.yaml`` (ROS style)."""
    return [ros_map(d / "ros" / "floor1" / "map", T.two_rooms()),
            ros_map(d / "ros" / "floor2" / "map", T.corridor_with_rooms()),
            png(d / "ros", "plan.png", T.gray(T.one_room().array)),
            png(d / "ros", "lshape.png", T.gray(T.l_shaped_room().array))]


def outputs(out: Path) -> dict:
    """Every output file below ``out`` (relative path -> bytes), run records and summary aside."""
    return {str(p.relative_to(out)): p.read_bytes() for p in sorted(out.rglob("*"))
            if p.is_file() and p.name not in (RECORD, "summary.csv")}


def summary_without_times(out: Path) -> list:
    return [{k: v for k, v in r.items() if k != "seconds" and not k.startswith("t_")}
            for r in read_summary(out / "summary.csv")]


# --------------------------------------------------------------------------
# Output folders
# --------------------------------------------------------------------------

def test_output_dirs_follow_the_path_below_the_common_parent(tmp_path):
    out = tmp_path / "out"
    maps = ["ros/floor1/map.yaml", "ros/floor2/map.yaml", "ros/plan.png"]
    assert output_dirs(maps, out) == [out / "floor1/map", out / "floor2/map", out / "plan"]
    assert output_dirs(["maps/a.png", "maps/b.pgm"], out) == [out / "a", out / "b"]
    assert output_dirs(["m/a.png", "m/a.yaml"], out) == [out / "a_png", out / "a_yaml"]
    assert output_dirs(["only/map.yaml"], out) == [out]  # one map: straight into out


def test_output_dirs_refuse_a_map_given_twice_and_the_summary_name(tmp_path):
    with pytest.raises(ParameterError, match="given twice"):
        output_dirs(["m/a.png", "m/../m/a.png"], tmp_path)
    with pytest.raises(ParameterError, match="summary.csv"):
        output_dirs(["m/summary.csv.png", "m/b.png"], tmp_path)


def test_maps_with_the_same_name_keep_their_own_results(tmp_path):
    """The motivating case: two ``map.yaml`` of different floors no longer overwrite each other."""
    maps = four_maps(tmp_path)[:2]
    out = tmp_path / "out"
    r = invoke("segment", *maps, "-o", out)
    assert r.exit_code == 0, r.output
    assert "2 of 2 maps segmented" in r.stdout
    n1 = np.asarray(Image.open(out / "floor1" / "map" / "labels.png")).max()
    n2 = np.asarray(Image.open(out / "floor2" / "map" / "labels.png")).max()
    assert (n1, n2) == (T.two_rooms().n_rooms, T.corridor_with_rooms().n_rooms)


# --------------------------------------------------------------------------
# Refusal
# --------------------------------------------------------------------------

def test_refuses_to_replace_another_batchs_results(tmp_path):
    first = [ros_map(tmp_path / "a" / f / "map", m) for f, m in (("f1", T.two_rooms()), ("f2", T.one_room()))]
    other = [ros_map(tmp_path / "b" / f / "map", m) for f, m in (("f1", T.one_room()), ("f2", T.two_rooms()))]
    out = tmp_path / "out"
    assert invoke("segment", *first, "-o", out).exit_code == 0
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    with pytest.raises(OutputExistsError, match="holds the results of"):
        segment_many(other, out)
    r = invoke("segment", *other, "-o", out)
    assert r.exit_code == 1
    (line,) = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert line.startswith("error: ") and "--overwrite" in line and "and 1 more" in line
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before
    rows = segment_many(other, out, overwrite=True)
    assert [r["status"] for r in rows] == ["ok", "ok"]
    assert np.asarray(Image.open(out / "f1" / "map" / "labels.png")).max() == T.one_room().n_rooms


def test_refuses_output_files_without_a_run_record(tmp_path):
    a, b = (png(tmp_path, f"{s}.png", T.gray(T.two_rooms().array)) for s in "ab")
    (tmp_path / "out" / "a").mkdir(parents=True)
    (tmp_path / "out" / "a" / "labels.png").write_bytes(b"someone else's")
    with pytest.raises(OutputExistsError, match="labels.png but no topomap_run.json"):
        segment_many([a, b], tmp_path / "out")
    assert not (tmp_path / "out" / "b").exists()
    assert (tmp_path / "out" / "a" / "labels.png").read_bytes() == b"someone else's"


# --------------------------------------------------------------------------
# Summary and failures
# --------------------------------------------------------------------------

def test_bad_map_in_the_middle(tmp_path):
    good1, good2 = four_maps(tmp_path)[:2]
    bad = tmp_path / "ros" / "bad.png"
    bad.write_text("not a picture")
    maps = [good1, bad, good2]
    out = tmp_path / "out"
    r = invoke("segment", *maps, "-o", out)
    assert r.exit_code == 1
    assert "2 of 3 maps segmented" in r.stdout
    rows = read_summary(out / "summary.csv")
    assert [(r["map"], r["status"]) for r in rows] == [(str(good1), "ok"), (str(bad), "failed"), (str(good2), "ok")]
    assert "not an image" in rows[1]["error"] and rows[1]["rooms"] is None
    assert [r["rooms"] for r in rows[::2]] == [2, 4] and rows[0]["error"] is None
    for row in rows[::2]:
        labels = np.asarray(Image.open(Path(row["output"]) / "labels.png"))
        assert row["rooms"] == labels.max()
        assert row["room_area_m2"] == pytest.approx((labels > 0).sum() * T.RES ** 2)
        assert row["t_load"] > 0 and row["t_write"] > 0 and row["seconds"] >= row["t_load"]
    assert not (out / "bad").exists()
    assert [p.name for p in out.iterdir() if p.name.startswith(".")] == []
    # the columns the summary promises, in order
    with open(out / "summary.csv") as fh:
        header = next(csv.reader(fh))
    assert header[:len(batch.SUMMARY_COLUMNS)] == list(batch.SUMMARY_COLUMNS) and header[-1] == "error"
    # a rerun retries only the failed map
    rows2 = segment_many(maps, out)
    assert [r["status"] for r in rows2] == ["skipped", "failed", "skipped"]


def test_internal_error_in_a_batch_exits_3(tmp_path, monkeypatch):
    def bug(*a, **k):
        raise ZeroDivisionError("oops")

    from topomap.core.segmentation import METHODS

    monkeypatch.setitem(METHODS, "topomap", bug)
    maps = [png(tmp_path, f"{s}.png", T.gray(T.two_rooms().array)) for s in "ab"]
    r = invoke("segment", *maps, "-o", tmp_path / "out")
    assert r.exit_code == 3
    lines = [ln for ln in r.stderr.splitlines() if ln.startswith("internal error")]
    assert len(lines) == 2 and "ZeroDivisionError: oops" in lines[0] and "a.png" in lines[0]
    assert {r["status"] for r in read_summary(tmp_path / "out" / "summary.csv")} == {"error"}


def test_scheduler_without_dask_is_a_clear_error(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)
    maps = [png(tmp_path, f"{s}.png", T.gray(T.two_rooms().array)) for s in "ab"]
    with pytest.raises(MissingDependencyError, match=r"topomap-rooms\[dask\]"):
        segment_many(maps, tmp_path / "out", scheduler="tcp://127.0.0.1:1")
    r = invoke("segment", *maps, "-o", tmp_path / "out", "--scheduler", "tcp://127.0.0.1:1")
    assert r.exit_code == 1 and r.stderr.startswith("error: ") and "topomap-rooms[dask]" in r.stderr


def test_bad_options(tmp_path):
    maps = [png(tmp_path, f"{s}.png", T.gray(T.two_rooms().array)) for s in "ab"]
    for kw, msg in (({"jobs": 0}, "jobs"), ({"jobs": 2, "scheduler": "tcp://x:1"}, "scheduler"),
                    ({"method": "magic"}, "unknown method"), ({"resolution": -1}, "resolution")):
        with pytest.raises(ParameterError, match=msg):
            segment_many(maps, tmp_path / "out", **kw)
    assert not (tmp_path / "out").exists()


# --------------------------------------------------------------------------
# Resume
# --------------------------------------------------------------------------

def test_rerun_skips_up_to_date_maps_and_redoes_changed_ones(tmp_path):
    maps = four_maps(tmp_path)[:3]
    out = tmp_path / "out"
    first = segment_many(maps, out)
    assert [r["status"] for r in first] == ["ok"] * 3
    stamps = {p: p.stat().st_mtime_ns for p in out.rglob("*") if p.is_file() and p.name != "summary.csv"}
    again = segment_many(maps, out)
    assert [r["status"] for r in again] == ["skipped"] * 3
    assert [r["rooms"] for r in again] == [r["rooms"] for r in first]
    assert {p: p.stat().st_mtime_ns for p in stamps} == stamps  # nothing rewritten
    assert [r["status"] for r in read_summary(out / "summary.csv")] == ["skipped"] * 3
    # a map whose image changed (the PGM a YAML names) runs again, the others not
    pgm = maps[0].with_suffix(".pgm")
    save_map(from_array(T.one_room().free, resolution=T.RES), maps[0].with_suffix(""))
    assert pgm.exists()
    rows = segment_many(maps, out)
    assert [r["status"] for r in rows] == ["ok", "skipped", "skipped"]
    assert rows[0]["rooms"] == T.one_room().n_rooms
    # an output file changed or removed since: that map runs again
    (out / "floor2" / "map" / "rooms.json").unlink()
    assert [r["status"] for r in segment_many(maps, out)] == ["skipped", "ok", "skipped"]
    # other options, or --overwrite: every map runs again
    assert [r["status"] for r in segment_many(maps, out, skeletons=True)] == ["ok"] * 3
    r = invoke("segment", *maps, "-o", out, "--skeletons")
    assert r.exit_code == 0 and "3 of 3 maps segmented, 3 of them up to date and skipped" in r.stdout
    assert [r["status"] for r in segment_many(maps, out, skeletons=True, overwrite=True)] == ["ok"] * 3


def test_single_map_rerun_is_skipped(tmp_path):
    p = png(tmp_path, "a.png", T.gray(T.two_rooms().array))
    assert invoke("segment", p, "-o", tmp_path / "o").exit_code == 0
    r = invoke("segment", p, "-o", tmp_path / "o")
    assert r.exit_code == 0 and "2 rooms, 1 door" in r.stdout and "up to date" in r.stdout


_KILLER = textwrap.dedent("""
    import os, signal, sys
    from topomap.io import export
    from topomap.cli import main

    real, seen = export.save_json, []

    def save_json_then_die(G, path):
        seen.append(path)
        if len(seen) == int(sys.argv[1]):   # the labels and GraphML of this map are written, JSON not
            os.kill(os.getpid(), signal.SIGKILL)
        return real(G, path)

    export.save_json = save_json_then_die
    main(sys.argv[2:])
""")


def test_resume_after_a_kill(tmp_path):
    maps = four_maps(tmp_path)
    out = tmp_path / "out"
    script = tmp_path / "killer.py"
    script.write_text(_KILLER)
    args = [sys.executable, str(script), "3", "segment", *map(str, maps), "-o", str(out)]
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1]))  # this checkout's topomap
    p = subprocess.run(args, capture_output=True, text=True, timeout=300, env=env)
    assert p.returncode == -signal.SIGKILL, p.stderr
    # killed while writing the third map: the first two complete, no half-written file under a final name
    third = out / "plan"
    assert (third / RECORD).exists() and '"incomplete"' in (third / RECORD).read_text()
    assert not any((third / n).exists() for n in batch.OUTPUT_NAMES)
    assert list(third.glob(".*.tmp")), "the kill left the temporary files behind (the test needs them)"
    rows = segment_many(maps, out)
    assert [r["status"] for r in rows] == ["skipped", "skipped", "ok", "ok"]
    assert not list(out.rglob(".*.tmp"))
    clean = tmp_path / "clean"
    segment_many(maps, clean)
    assert outputs(out) == outputs(clean)
    assert summary_without_times(out) == [dict(r, output=r["output"].replace(str(clean), str(out)),
                                               status=s) for r, s in
                                          zip(summary_without_times(clean), ["skipped", "skipped", "ok", "ok"])]


def test_progress_is_a_line_per_map_without_a_terminal(tmp_path):
    maps = [png(tmp_path, f"{s}.png", T.gray(T.two_rooms().array)) for s in "abc"]
    p = subprocess.run([sys.executable, "-m", "topomap.cli", "segment", *map(str, maps), "-o", str(tmp_path / "o")],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    lines = [ln for ln in p.stderr.splitlines() if "topomap.run.batch" in ln]
    assert len(lines) == 3 and all(f"[{i}/3]" in ln for i, ln in enumerate(lines, 1))
    assert "\r" not in p.stderr  # no bar


# --------------------------------------------------------------------------
# Same outputs in one process, two processes and on a Dask cluster
# --------------------------------------------------------------------------

@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                  silence_logs=40) as c:
        yield c


def test_jobs_and_cluster_give_the_same_outputs(tmp_path, cluster):
    from distributed import Client

    maps = four_maps(tmp_path)[:3]
    bad = tmp_path / "ros" / "broken.png"
    bad.write_bytes(b"\x89PNG\r\n\x1a\n truncated")
    maps.insert(2, bad)
    runs = {}
    for name, extra in (("jobs1", []), ("jobs2", ["--jobs", "2"]),
                        ("cluster", ["--scheduler", cluster.scheduler_address])):
        r = invoke("segment", *maps, "-o", tmp_path / name, *extra)
        assert r.exit_code == 1, r.output
        assert "3 of 4 maps segmented" in r.stdout
        runs[name] = tmp_path / name
    with Client(cluster) as client:
        rows = segment_many(maps, tmp_path / "api", scheduler=client)
    runs["api"] = tmp_path / "api"
    assert [r["status"] for r in rows] == ["ok", "ok", "failed", "ok"]
    ref = outputs(runs["jobs1"])
    assert len(ref) == 3 * len(batch.OUTPUT_NAMES)
    ref_rows = summary_without_times(runs["jobs1"])
    for name, d in runs.items():
        assert outputs(d) == ref, name
        got = summary_without_times(d)
        assert [dict(r, output=Path(r["output"]).relative_to(d)) for r in got] == \
               [dict(r, output=Path(r["output"]).relative_to(runs["jobs1"])) for r in ref_rows], name


def test_interrupted_batch_writes_the_summary_with_pending_maps(tmp_path, monkeypatch):
    maps = [png(tmp_path, f"{s}.png", T.gray(T.two_rooms().array)) for s in "abc"]
    real, calls = batch._run_one, []

    def ctrl_c_on_the_second(task):
        calls.append(task)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(task)

    monkeypatch.setattr(batch, "_run_one", ctrl_c_on_the_second)
    with pytest.raises(KeyboardInterrupt):
        segment_many(maps, tmp_path / "out")
    assert [r["status"] for r in read_summary(tmp_path / "out" / "summary.csv")] == ["ok", "pending", "pending"]
    monkeypatch.setattr(batch, "_run_one", real)
    assert [r["status"] for r in segment_many(maps, tmp_path / "out")] == ["skipped", "ok", "ok"]


def test_progress_bar_when_asked(tmp_path, capsys):
    maps = [png(tmp_path, f"{s}.png", T.gray(T.two_rooms().array)) for s in "ab"]
    segment_many(maps, tmp_path / "out", progress=True)
    err = capsys.readouterr().err
    assert "segmenting" in err and "2/2" in err


_FAULTS = textwrap.dedent("""
    import resource, sys
    import numpy as np
    if sys.argv[1] == "keep":
        from topomap._fast import keep_freed_memory
        assert keep_freed_memory()
    rng = np.random.default_rng(0)
    def work():  # arrays of 0.25-24 MB, a few alive at a time, as a map's stages make them
        held = []
        for s in rng.integers(1 << 18, 24 << 20, 40):
            held.append(np.ones(int(s), np.uint8))
            if len(held) > 4:
                held.pop(0)
    def beside():  # half of the work on a second thread, as a map's stages do (topomap._fast.BackgroundCall)
        from topomap._fast import BackgroundCall

        BackgroundCall(work).result()
        work()
    run = beside if sys.argv[2:] == ["thread"] else work
    run()
    r0 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    for _ in range(5):
        run()
    print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - r0)
""")


@pytest.mark.skipif(not sys.platform.startswith("linux") or __import__("platform").libc_ver()[0] != "glibc",
                    reason="glibc's mallopt")
def test_keep_freed_memory_reuses_pages_instead_of_touching_new_ones():
    # the segment command and batch workers call it: maps after the first reuse the pages freed
    def faults(mode):
        out = subprocess.run([sys.executable, "-c", _FAULTS, mode], capture_output=True, text=True, check=True)
        return int(out.stdout)

    default, kept = faults("default"), faults("keep")
    assert kept * 4 < default, (kept, default)


@pytest.mark.skipif(not sys.platform.startswith("linux") or __import__("platform").libc_ver()[0] != "glibc",
                    reason="glibc's mallopt")
def test_keep_freed_memory_shares_the_pages_between_threads():
    # a map's second thread frees arrays the main thread then reuses (one arena for all threads:
    # with an arena per thread, measured, the same work touched 2.2-2.5 times the pages of one thread)
    def faults(*mode):
        out = subprocess.run([sys.executable, "-c", _FAULTS, *mode], capture_output=True, text=True, check=True)
        return int(out.stdout)

    default, kept, one = faults("default", "thread"), faults("keep", "thread"), faults("keep")
    assert kept * 4 < default, (kept, default)
    assert kept < 1.5 * one, (kept, one)


def test_summary_floats_are_rounded(tmp_path):
    rows = [{"map": "a.png", "output": "o/a", "status": "ok", "rooms": 2, "doors": 1, "fragments": 0,
             "room_area_m2": 154.39500000000004, "fragment_area_m2": 0.1 + 0.2, "seconds": 1.5, "error": ""}]
    batch._write_summary(rows, tmp_path / "summary.csv")
    text = (tmp_path / "summary.csv").read_text()
    assert "154.395," in text and ",0.3," in text and "00000" not in text
    assert read_summary(tmp_path / "summary.csv")[0]["room_area_m2"] == 154.395


def test_output_dirs_stay_inside_out(tmp_path):
    out = tmp_path / "out"
    dirs = output_dirs(["m/...png", "m/..png", "m/b.png"], out)
    assert dirs == [out / "__", out / "_", out / "b"]
    for d in dirs:
        assert d.resolve().parent == out.resolve()


def test_rerun_after_the_previous_graph_changed_runs_again(tmp_path):
    p = png(tmp_path, "a.png", T.gray(T.two_rooms().array))
    assert invoke("segment", p, "-o", tmp_path / "o1").exit_code == 0
    prev = tmp_path / "prev.graphml"
    prev.write_bytes((tmp_path / "o1" / "rooms.graphml").read_bytes())
    assert invoke("segment", p, "-o", tmp_path / "o2", "--previous", prev).exit_code == 0
    assert "up to date" in invoke("segment", p, "-o", tmp_path / "o2", "--previous", prev).stdout
    prev.write_bytes(prev.read_bytes() + b"\n")  # changed
    r = invoke("segment", p, "-o", tmp_path / "o2", "--previous", prev)
    assert r.exit_code == 0 and "up to date" not in r.stdout
    (tmp_path / "o2" / "changes.json").unlink()
    r = invoke("segment", p, "-o", tmp_path / "o2", "--previous", prev)
    assert "up to date" not in r.stdout and (tmp_path / "o2" / "changes.json").exists()


def test_an_input_is_never_an_output(tmp_path):
    m = ros_map(tmp_path / "labels", T.two_rooms())  # labels.yaml + labels.pgm, -o their folder
    before = m.read_bytes()
    r = invoke("segment", m, "-o", tmp_path)
    assert r.exit_code == 1 and "is an input of this run" in r.stderr and m.read_bytes() == before
    p = png(tmp_path, "a.png", T.gray(T.two_rooms().array))
    with pytest.raises(ParameterError, match="--bag .*is an input of this run"):
        segment_many([p], tmp_path / "o", write_options={"bag": str(p)})
    assert not (tmp_path / "o").exists()


def test_inputs_and_outputs_are_compared_in_time_linear_in_the_maps(tmp_path, monkeypatch):
    # each file is looked up once (its resolved path, its device and inode), not once per pair of an
    # output and an input: a fleet's batch of thousands of maps would make millions of pairs
    calls = []
    real = batch.file_keys
    monkeypatch.setattr(batch, "file_keys", lambda p: calls.append(p) or real(p))
    tiny = np.zeros((24, 24), bool)
    tiny[2:22, 2:22] = True
    maps = [png(tmp_path, f"m{k}.png", T.gray(tiny)) for k in range(12)]
    rows = segment_many(maps, tmp_path / "o", resolution=0.05, progress=False)
    assert all(r["status"] == "ok" for r in rows)
    outputs = len(batch.OUTPUT_NAMES) + 2  # a folder's files, its run record and changes.json
    assert len(calls) <= len(maps) * (1 + outputs)  # 12 x 12 pairs x 10 outputs before
    # an input named as an output is still refused, through a link as well
    link = tmp_path / "o2"
    link.mkdir()
    os.symlink(maps[0], link / "labels.png")
    with pytest.raises(ParameterError, match="is an input of this run"):
        segment_many([maps[0]], link, resolution=0.05, progress=False)  # link/labels.png would replace m0.png
