"""``topomap benchmark --maps``: select maps by name or shell pattern."""

import csv

from click.testing import CliRunner

from topomap.cli import main
from test_benchmark import dataset  # noqa: F401  (the drawn three-map data set)


def test_cli_benchmark_maps(dataset, tmp_path):  # noqa: F811
    out = tmp_path / "r.csv"
    res = CliRunner().invoke(main, ["benchmark", str(dataset), "--methods", "watershed",
                                    "--variant", "unfurnished", "--maps", "t*_rooms",
                                    "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert "ORIGINAL protocol" in res.output
    assert sorted(r["map"] for r in csv.DictReader(open(out))) == ["three_rooms", "two_rooms"]
    bad = CliRunner().invoke(main, ["benchmark", str(dataset), "--maps", "nope*"])
    assert bad.exit_code == 1 and "no map matches 'nope*'" in bad.output
