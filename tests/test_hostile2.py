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
