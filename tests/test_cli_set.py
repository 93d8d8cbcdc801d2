"""``topomap segment --set OPTION=VALUE``: the method's options from the command line, checked before any
map runs, kept in the run record."""

import json

import pytest
from click.testing import CliRunner

import _testdata as T
from test_bad_input import png
from topomap import cli
from topomap.cli import main, parse_settings
from topomap.errors import ParameterError


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def _two_rooms(tmp_path):
    return png(tmp_path, "two.png", T.gray(T.two_rooms().array))


def _rooms(folder):
    return len(json.loads((folder / "rooms.json").read_text())["nodes"])


def test_an_option_changes_the_rooms_and_is_recorded(tmp_path):
    m = _two_rooms(tmp_path)
    assert invoke("segment", m, "-o", tmp_path / "a").exit_code == 0
    assert _rooms(tmp_path / "a") == 2
    # a 0.9 m door is no door when doors are at most 0.6 m wide: one room
    r = invoke("segment", m, "-o", tmp_path / "b", "--set", "max_door_width=0.6")
    assert r.exit_code == 0, r.output
    assert _rooms(tmp_path / "b") == 1
    record = json.loads((tmp_path / "b" / "topomap_run.json").read_text())
    assert record["settings"]["options"] == {"max_door_width": 0.6}
    assert "options" not in json.loads((tmp_path / "a" / "topomap_run.json").read_text())["settings"]


def test_other_options_run_the_map_again_the_same_ones_skip_it(tmp_path):
    m = _two_rooms(tmp_path)
    out = tmp_path / "o"
    assert invoke("segment", m, "-o", out).exit_code == 0
    r = invoke("segment", m, "-o", out, "--set", "max_door_width=0.6")
    assert "skipped" not in r.stdout and _rooms(out) == 1
    r = invoke("segment", m, "-o", out, "--set", "max_door_width=0.6")
    assert "up to date" in r.stdout
    r = invoke("segment", m, "-o", out)
    assert "skipped" not in r.stdout and _rooms(out) == 2


@pytest.mark.parametrize("args, words", [
    (["--set", "nope=1"], ["unknown option 'nope'", "max_door_width"]),
    (["--set", "max_door_width=-1"], ["max_door_width", "-1"]),
    (["--set", "gaps=maybe"], ["gaps", "maybe"]),
    (["--set", "max_door_width"], ["OPTION=VALUE"]),
    (["--set", "=2"], ["OPTION=VALUE"]),
    (["--set", "gaps=on", "--set", "gaps=off"], ["gaps", "twice"]),
    (["--method", "watershed", "--set", "min_distance=nan"], ["min_distance", "not a finite number"]),
    (["--set", "max_door_width=inf"], ["max_door_width", "inf"]),
    (["--method", "watershed", "--set", "max_door_width=2"], ["unknown option 'max_door_width'", "min_distance"]),
])
def test_bad_options_one_line_nothing_written(tmp_path, args, words):
    m = _two_rooms(tmp_path)
    out = tmp_path / "o"
    r = invoke("segment", m, "-o", out, *args)
    assert r.exit_code == cli.EXIT_INPUT
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: ")
    assert all(w in lines[0] for w in words), lines[0]
    assert not out.exists()


def test_values_are_read_as_booleans_numbers_none_or_text():
    got = parse_settings(["gaps=False", "mouths=yes", "max_door_width=2.5", "furniture_size=none",
                          "rule= paper ", "min_room_area=1e0"])
    assert got == {"gaps": False, "mouths": True, "max_door_width": 2.5, "furniture_size": None,
                   "rule": "paper", "min_room_area": 1.0}
    with pytest.raises(ParameterError):
        parse_settings(["no_equals_sign"])
