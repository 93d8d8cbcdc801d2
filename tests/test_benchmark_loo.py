"""The fold logic of benchmarks/leave_one_out.py: options tuned on the training maps only, the
held-out figure of the held-out maps only, the section naming its command and commit."""

import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
import leave_one_out as loo  # noqa: E402

from topomap.errors import ParameterError  # noqa: E402

SPACE = {"min_room_area": [0.5, 1.0, 2.0]}


def _site(d: Path, name: str, closet_is_room: bool) -> None:
    """A labelled map (NAME.png + NAME.yaml + NAME_gt.png): a 3 x 3.5 m room and, walled off from it,
    a 0.9 x 1.0 m closet (0.9 m², under the default ``min_room_area`` of 1 m²) that the ground truth
    calls a room or not."""
    g = np.zeros((80, 120), np.uint8)
    labels = np.zeros(g.shape, np.uint16)
    g[5:65, 5:75] = 254
    labels[5:65, 5:75] = 1
    g[10:28, 85:105] = 254
    if closet_is_room:
        labels[10:28, 85:105] = 2
    Image.fromarray(g).save(d / f"{name}.png")
    (d / f"{name}.yaml").write_text(f"image: {name}.png\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\n"
                                    "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n")
    Image.fromarray(labels).save(d / f"{name}_gt.png")


@pytest.fixture
def sites(tmp_path):
    """Two "buildings": in freiburg079_* the closets are rooms, in bremen_cartesium_* they are not."""
    d = tmp_path / "real"
    d.mkdir()
    for n in ("freiburg079_a", "freiburg079_b"):
        _site(d, n, True)
    _site(d, "bremen_cartesium_a", False)
    return d


def _direct(refs, options):
    """Mean P / R of ``refs`` segmented with ``options``, computed here without the script's scorer."""
    from topomap.bench.datasets import load_labelled
    from topomap.bench.evaluation import score_segmentation
    from topomap.core.segmentation import segment

    p, r = [], []
    for ref in refs:
        bm = load_labelled(ref.directory, names=[ref.name])[0]
        grid = bm.load()
        sc = score_segmentation(segment(grid, **options).room_labels, bm.gt_rooms, scored=grid.free)
        p.append(sc["precision"])
        r.append(sc["recall"])
    return np.mean(p), np.mean(r)


def test_tuned_on_training_maps_scored_on_held_out_maps(sites):
    folds = loo.real_folds(sites)
    assert [f.train_label for f in folds] == ["Freiburg 079", "Bremen Cartesium"]
    assert {r.name for r in folds[0].train} == {"freiburg079_a", "freiburg079_b"}
    assert {r.name for r in folds[0].test} == {"bremen_cartesium_a"}
    scorer = loo.Scorer(jobs=1)
    res = [loo.run_fold(scorer, f, SPACE, sweeps=2) for f in folds]
    # Freiburg's closets are rooms: keeping them needs the smaller min_room_area; Bremen's are not
    assert res[0]["tuned"] == {"min_room_area": 0.5}
    assert res[1]["tuned"] == {}
    # the held-out figures are the held-out maps', segmented with the options tuned without them
    for fold, r in zip(folds, res):
        got = r["test"]["all"]
        assert got["n"] == len(fold.test)
        assert got["tuned"] == pytest.approx(_direct(fold.test, r["tuned"]))
        assert got["defaults"] == pytest.approx(_direct(fold.test, {}))
        assert r["train"]["all"]["tuned"] == pytest.approx(_direct(fold.train, r["tuned"]))
    # tuned on Freiburg, Bremen loses precision (its closet becomes a room with no true room in it)
    assert res[0]["test"]["all"]["tuned"][0] < res[0]["test"]["all"]["defaults"][0]
    assert res[0]["train"]["all"]["tuned"][1] > res[0]["train"]["all"]["defaults"][1]


def test_tuning_looks_only_at_the_training_maps(sites, monkeypatch):
    """Every options set other than the defaults and the result was tried on training maps only."""
    calls = []
    real = loo.score_task

    def spy(ref, keys):
        calls.append((ref.name, tuple(keys)))
        return real(ref, keys)

    monkeypatch.setattr(loo, "score_task", spy)
    fold = loo.real_folds(sites)[1]  # tuned on Bremen
    scorer = loo.Scorer(jobs=1)
    loo.tune(scorer, fold.train, SPACE, sweeps=2)
    assert {name for name, _ in calls} == {"bremen_cartesium_a"}
    tried = {k for _, keys in calls for k in keys}
    assert tried == {(), (("min_room_area", 0.5),), (("min_room_area", 2.0),)}


def test_tuning_follows_the_training_objective(monkeypatch):
    """Coordinate ascent with a scorer whose best options are known: each fold finds its training
    side's optimum, the held-out side's figure is that side's score at it."""
    best = {"x": {"facing": 1.0, "wall_gap": 0.3}, "y": {"facing": 0.8, "wall_gap": 0.7}}
    base = loo.defaults()

    def fake(ref, keys):
        out = []
        for key in keys:
            o = {**{k: base[k] for k in best["x"]}, **dict(key)}
            miss = sum(abs(o[k] - v) for k, v in best[ref.name[0]].items())
            out.append((1.0 - miss / 4, 1.0, 0.0, ""))
        return out

    monkeypatch.setattr(loo, "score_task", fake)
    x = [loo.MapRef("d", "nowhere", "map", n) for n in ("x1", "x2")]
    y = [loo.MapRef("d", "nowhere", "map", n) for n in ("y1",)]
    space = {"facing": [0.8, 0.9, 1.0], "wall_gap": [0.3, 0.5, 0.7]}
    for train, test in ((x, y), (y, x)):
        scorer = loo.Scorer(jobs=1)
        r = loo.run_fold(scorer, loo.Fold("d", "a", "b", train, test), space, sweeps=2)
        assert r["tuned"] == best[train[0].name[0]]
        want = fake(test[0], [loo.opt_key(r["tuned"])])[0][0]
        assert r["test"]["all"]["tuned"] == pytest.approx((want, 1.0))
        assert {name for name, key in scorer.requests if key not in ((), loo.opt_key(r["tuned"]))} \
            <= {m.key for m in train}


def test_plan_split_is_stable_and_halves_the_cases():
    names = [f"{i:02x}_{(i * 7919) % 256:02x}_case_{i:04d}" for i in range(200)]
    halves = loo.corpus_halves(names)
    assert sorted(halves[0] + halves[1]) == sorted(names)
    assert not set(halves[0]) & set(halves[1])
    assert 60 <= len(halves[0]) <= 140
    assert [loo.plan_split(n) for n in names] == [loo.plan_split(n) for n in names]
    # a smaller sample is the start of the same order, whatever other cases exist
    few = loo.corpus_halves(names, 10)
    assert few == [h[:10] for h in halves]
    assert loo.corpus_halves(names[::-1][:150], 5)[0] == [n for n in halves[0] if n in names[::-1][:150]][:5]


def test_space_is_checked():
    assert loo.check_space({"min_room_area": [0.5, 0.5, 1.0]}) == {"min_room_area": [0.5, 1.0]}
    with pytest.raises(ParameterError, match="no_such_option"):
        loo.check_space({"no_such_option": [1.0]})
    with pytest.raises(ParameterError, match="-1"):
        loo.check_space({"wall_gap": [-1]})
    assert set(loo.check_space({"no_such_option": [1.0], "wall_gap": [0.4]}, strict=False)) == {"wall_gap"}
    assert set(loo.read_space(None)) <= set(loo.defaults())


def test_section_names_command_commit_and_protocol(sites, tmp_path, capsys):
    out = tmp_path / "section.md"
    assert loo.main(["--real", str(sites), "--no-defaults", "--space", '{"min_room_area": [0.5, 1.0, 2.0]}',
                     "--jobs", "1", "--out", str(out)]) == 0
    text = out.read_text()
    assert "`python benchmarks/leave_one_out.py --real REAL_DIR --space" in text
    assert f"commit `{loo._commit()}`" in text
    assert "original protocol" in text
    assert "training figures" in text
    assert "| `min_room_area` | 1 | 0.5, 1, 2 | **0.5** | 1 |" in text
    assert "The ipa plans not given: not measured." in text
    assert "hurts** Bremen Cartesium" in text


def test_bad_space_is_one_line_error(sites, tmp_path):
    with pytest.raises(SystemExit, match="wall_gap"):
        loo.main(["--real", str(sites), "--no-defaults", "--space", '{"wall_gap": ["wide"]}',
                  "--out", str(tmp_path / "s.md")])
    assert not (tmp_path / "s.md").exists()


def test_disk_cache_scores_each_map_and_options_once(tmp_path, monkeypatch):
    calls = []

    def fake(ref, keys):
        calls.extend((ref.name, k) for k in keys)
        return [(0.5, 0.75, 0.0, "") for _ in keys]

    monkeypatch.setattr(loo, "score_task", fake)
    maps = [loo.MapRef("d", "nowhere", "map", n) for n in ("m1", "m2")]
    first = loo.Scorer(jobs=1, cache_dir=tmp_path)
    assert first.scores(maps, [{}, {"wall_gap": 0.4}, {}]) == [[(0.5, 0.75)] * 2] * 3
    first.save()
    assert len(calls) == 4
    again = loo.Scorer(jobs=1, cache_dir=tmp_path)
    assert again.scores(maps, [{"wall_gap": 0.4}]) == [[(0.5, 0.75)] * 2]
    assert len(calls) == 4 and again.n_segmented == 0
    assert len(again.used & again.from_disk) == 2
    # the cache file is named after the code that scored: another version of topomap starts afresh
    assert [p.name for p in tmp_path.iterdir()] == [f"scores_{loo.code_version()}.json"]
