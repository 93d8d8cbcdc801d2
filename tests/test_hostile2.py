"""Hostile and odd inputs, second part: concurrent batches, outputs that land together, inputs bounded by
their own size, messages that name the right file. Each test failed before its fix."""

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from topomap import io
from topomap.cli import main

ROOT = Path(__file__).resolve().parents[1]


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def _one_error_line(res, name, code=1):
    """The CLI's output is one error line naming ``name``, exit ``code``."""
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert res.exit_code == code, res.output
    assert len(lines) == 1 and lines[0].startswith("error: ") and str(name) in lines[0], res.output
    assert "internal" not in res.output and " object at 0x" not in res.output
    return lines[0]


def _two_rooms():
    a = np.zeros((60, 100), bool)
    a[4:56, 4:48] = True
    a[4:56, 52:96] = True
    a[24:36, 48:52] = True
    return a


def _maps(tmp_path, names=("a", "b", "c")):
    return [io.save_map(_two_rooms(), tmp_path / n) for n in names]


# --------------------------------------------------------------------------
# Two batches into one -o at once: the second is refused, the first's results stay
# --------------------------------------------------------------------------

_HOLDER = textwrap.dedent("""
    import sys
    import topomap.batch as b
    run = b._run_one
    def held(task):  # the batch is running: it waits here until told to go on
        print("running", flush=True)
        sys.stdin.readline()
        return run(task)
    b._run_one = held
    rows = b.segment_many(sys.argv[2:], sys.argv[1])
    print(" ".join(r["status"] for r in rows), flush=True)
""")


def test_two_batches_into_one_folder_the_second_is_refused(tmp_path):
    maps = _maps(tmp_path)
    out = tmp_path / "out"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    first = subprocess.Popen([sys.executable, "-c", _HOLDER, str(out), *map(str, maps)], stdin=subprocess.PIPE,
                             stdout=subprocess.PIPE, text=True, env=env, cwd=tmp_path)
    try:
        assert first.stdout.readline().strip() == "running"
        before = sorted(p.relative_to(out) for p in out.rglob("*"))
        res = _run("segment", *maps, "-o", out)  # a second process-wide batch into the same folder
        line = _one_error_line(res, out)
        assert "another topomap run" in line, line
        assert sorted(p.relative_to(out) for p in out.rglob("*")) == before  # it wrote nothing
    finally:
        out_text, _ = first.communicate("go\ngo\ngo\n", timeout=120)
    assert first.returncode == 0 and out_text.splitlines()[-1] == "ok ok ok", out_text
    assert not (out / ".topomap.lock").exists()  # the lock goes with the batch
    res = _run("segment", *maps, "-o", out)  # the folder is free again: up to date
    assert res.exit_code == 0 and "3 of them up to date" in res.output, res.output


# --------------------------------------------------------------------------
# A map's outputs, the --bag included, land together or not at all
# --------------------------------------------------------------------------

def _tree(folder):
    """Every file of ``folder``: its bytes, and its size and time (the run record: its bytes only)."""
    return {p.name: (p.read_bytes(), None if p.name == "topomap_run.json" else (p.stat().st_size, p.stat().st_mtime_ns))
            for p in folder.iterdir()}


def test_a_bag_that_fails_writes_no_other_output(tmp_path):
    pytest.importorskip("rosbags")
    from topomap.batch import FAILED, OK, SKIPPED, segment_many

    (m,) = _maps(tmp_path, ["a"])
    out = tmp_path / "out"
    blocked = tmp_path / "taken.mcap"
    blocked.mkdir()  # the bag's name is a folder now: writing the bag fails
    (row,) = segment_many([m], out, write_options={"bag": str(blocked)})
    assert row["status"] == FAILED and "taken.mcap" in row["error"]
    assert not out.exists()  # no output without its bag, no run record missing beside outputs
    good = tmp_path / "good.mcap"
    (row,) = segment_many([m], out, write_options={"bag": str(good)})  # the folder is not refused
    assert row["status"] == OK and good.is_file()
    earlier, bag_bytes = _tree(out), good.read_bytes()
    # a rerun whose bag fails leaves the earlier outputs, the bag and the run record as they were
    (row,) = segment_many([m], out, overwrite=True, write_options={"bag": str(blocked)})
    assert row["status"] == FAILED
    assert _tree(out) == earlier and good.read_bytes() == bag_bytes
    (row,) = segment_many([m], out, write_options={"bag": str(good)})
    assert row["status"] == SKIPPED


def test_outputs_that_fail_write_no_bag(tmp_path, monkeypatch):
    pytest.importorskip("rosbags")
    from topomap import export
    from topomap.batch import FAILED, segment_many

    (m,) = _maps(tmp_path, ["a"])

    def broken(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(export, "save_geojson", broken)
    bag = tmp_path / "a.mcap"
    (row,) = segment_many([m], tmp_path / "out", write_options={"bag": str(bag)})
    assert row["status"] == FAILED and "rooms.geojson" in row["error"], row["error"]
    assert not bag.exists() and not (tmp_path / "out").exists()
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []  # no temporary left
