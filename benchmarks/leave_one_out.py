#!/usr/bin/env python
"""Leave-one-out figures: the default method's options tuned on some maps, scored on the others.

Run (not a test)::

    python benchmarks/leave_one_out.py [--real REAL_DIR] [--ipa IPA_DIR] [--corpus CORPUS]
        [--space SPACE.json] [--sweeps 2] [--corpus-cases 100] [--jobs 2] [--cache DIR]
        [--out benchmarks/sections/90_leave_one_out.md]
    python benchmarks/leave_one_out.py --sensitivity [--real ...] [--ipa ...] [--corpus ...]

A guard against rules that fit the files they were developed on. Each
*fold* splits a data set into training maps and held-out maps:

* ``rose2_real``: tuned on the Freiburg 079 maps (``freiburg079_*``),
  scored on the Bremen Cartesium maps (``bremen_cartesium_*``), and the
  other way round;
* the ipa plans (``ipa_room_segmentation``): the maps in name order split
  into the even and the odd ones (both variants, unfurnished and
  furnished, of a map on the same side); tuned on one half, scored on the
  other, both ways;
* the simulated corpus (one folder per case, variants ``plan`` and
  ``scan``): the cases split into two halves by a stable hash of the case
  name (:func:`plan_split`), ``--corpus-cases`` of each half (the first in
  the order of that hash) used; tuned on one half, scored on the other,
  both ways.

**Tuning** is coordinate ascent over a small search space of options of
:class:`topomap.options.TopomapOptions` (``--space``: a JSON object
``{"option": [values...]}``, physical values: lengths in m, areas in m²,
fractions), starting from the defaults: for each option in turn every
candidate value is tried with the other options at their current values,
and the best is kept if it beats the current one (ties keep the current
value); ``--sweeps`` rounds, stopping early when a round changes nothing.
The objective is the F1 of the training maps' mean precision and mean
recall (Bormann et al., **original protocol**, as ``topomap benchmark``
scores them: true rooms whole, segments on the free cells of the map as
loaded, segments and rooms of 100 cells or fewer ignored). Every map is
loaded as the user loads it (``load_map`` of the image and
``--resolution 0.05``, or of its YAML) and segmented with
``topomap.segment(grid, **options)``, only the options that differ from
the defaults passed.

Per fold the section gives: the defaults and the tuned options on the
training maps (training figures: the tuned one is in-sample), the
defaults and the tuned options on the held-out maps (the held-out
figure), and the defaults on every map of the data set (the figures on
everything). A tuned figure on the held-out maps far below the in-sample
one, or below the defaults', means the options fit the training files.

``--sensitivity`` instead measures how much the objective moves when one
option at a time is set to 0.7 and 1.4 times its default, on a few maps of
each data set, and prints the table (the default search space holds the
options that moved it most).

Segmentations are cached per (map, options) in memory, and on disk under
``--cache DIR`` (one file per version of the ``topomap`` package's code,
so a changed method is never scored from a stale cache).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import logging
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

# the topomap of this checkout (the commit the section names), not another installed copy
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))
import _section  # noqa: E402
from _section import _commit, _machine  # noqa: E402

log = logging.getLogger("benchmarks.leave_one_out")

#: The default search space: the six options the objective moved most with (``--sensitivity``:
#: each option alone at 0.7 and 1.4 times its default, on a few maps of each data set, changed the
#: F1 of one data set by 1.7 to 3.9 points; most other options by less than 1.5), each at a few
#: physical values around its default (lengths in m, fractions; the default is always a candidate).
DEFAULT_SPACE = {
    "facing": [0.7, 0.8, 0.9, 1.0, 1.1],
    "min_wall_length": [0.6, 0.8, 1.0, 1.2, 1.5],
    "alcove_depth": [0.8, 1.0, 1.2, 1.5, 1.8],
    "wall_gap": [0.3, 0.4, 0.5, 0.6, 0.7],
    "straight_walls": [0.5, 0.6, 0.7, 0.8, 0.9],
    "protrusion_min": [0.6, 0.65, 0.7, 0.75, 0.8],
}

#: The rose2_real folds: (name, training maps, held-out maps) as shell patterns of map names.
BUILDINGS = (("Freiburg 079", "freiburg079_*"), ("Bremen Cartesium", "bremen_cartesium_*"))

_EPS = 1e-9


# --------------------------------------------------------------------------
# maps and folds
# --------------------------------------------------------------------------

@dataclass(frozen=True)
class MapRef:
    """One map of a data set, as a user loads it: ``load_dataset(directory, variant=variant, names=[name])``."""

    dataset: str
    directory: str
    variant: str
    name: str

    @property
    def key(self) -> str:
        return f"{self.dataset}/{self.variant}/{self.name}"


@dataclass
class Fold:
    """Tuned on ``train``, scored on ``test`` (both lists of :class:`MapRef`)."""

    dataset: str
    train_label: str
    test_label: str
    train: list
    test: list
    tuned: dict = field(default_factory=dict)
    history: list = field(default_factory=list)


def plan_split(name: str) -> int:
    """The half (0: dev, 1: held-out) a corpus case belongs to: :func:`topomap.bench.datasets.plan_split`,
    the split every user of a corpus makes."""
    from topomap.bench.datasets import SPLITS, plan_split as split

    return SPLITS.index(split(name))


def _hash_order(name: str) -> str:
    return hashlib.sha1(("order:" + name).encode("utf-8", "surrogateescape")).hexdigest()


def _refs(dataset, directory, variants, names) -> list:
    return [MapRef(dataset, str(directory), v, n) for v in variants for n in names]


def real_folds(directory) -> list:
    """The two leave-one-building-out folds of ``rose2_real`` (see :data:`BUILDINGS`)."""
    from topomap.bench.datasets import LABELLED_VARIANT, load_labelled

    names = {}
    for label, pattern in BUILDINGS:
        names[label] = [bm.name for bm in load_labelled(directory, names=[pattern])]
    (a, _), (b, _) = BUILDINGS
    refs = {k: _refs("rose2_real", directory, [LABELLED_VARIANT], v) for k, v in names.items()}
    return [Fold("rose2_real", a, b, refs[a], refs[b]), Fold("rose2_real", b, a, refs[b], refs[a])]


def ipa_folds(directory) -> list:
    """Two folds of the ipa plans: the even and the odd maps in name order (both variants each)."""
    from topomap.bench.datasets import VARIANTS, load_benchmark

    names = [bm.name for bm in load_benchmark(directory, variant=VARIANTS[0])]
    halves = [names[0::2], names[1::2]]
    refs = [_refs("ipa", directory, VARIANTS, h) for h in halves]
    return [Fold("ipa", "even maps", "odd maps", refs[0], refs[1]),
            Fold("ipa", "odd maps", "even maps", refs[1], refs[0])]


def corpus_halves(names, per_half=None) -> list:
    """The corpus cases ``names`` in two halves (:func:`plan_split`), each in a stable hash order,
    cut to its first ``per_half`` (None: all)."""
    halves = [sorted((n for n in names if plan_split(n) == h), key=_hash_order) for h in (0, 1)]
    return [h if per_half is None else h[:per_half] for h in halves]


def corpus_folds(directory, per_half=None) -> list:
    """Two folds of the simulated corpus: tuned on one half of the cases, scored on the other."""
    from topomap.bench.datasets import SIMULATED_VARIANTS, _simulated_cases

    halves = corpus_halves(_simulated_cases(Path(directory)), per_half)
    refs = [_refs("corpus", directory, SIMULATED_VARIANTS, h) for h in halves]
    return [Fold("corpus", "dev half", "held-out half", refs[0], refs[1]),
            Fold("corpus", "held-out half", "dev half", refs[1], refs[0])]


# --------------------------------------------------------------------------
# options and the search space
# --------------------------------------------------------------------------

def defaults() -> dict:
    """Every option of the default method and its default value."""
    from topomap.options import TopomapOptions

    return dataclasses.asdict(TopomapOptions())


def opt_key(options: dict, base=None) -> tuple:
    """``options`` as a canonical, hashable key: the (name, value) pairs that differ from the defaults."""
    base = defaults() if base is None else base
    return tuple(sorted((k, v) for k, v in options.items() if base[k] != v))


def check_space(space, *, strict: bool = True) -> dict:
    """The search space with every value checked (one line naming the option and the value).

    ``strict=False`` leaves out, with a warning, options the method no longer has (the default space
    outliving a renamed option); with ``strict=True`` an unknown option is an error.
    """
    from topomap.errors import ParameterError
    from topomap.options import TopomapOptions

    if not isinstance(space, dict) or not space:
        raise ParameterError(f"search space must be a non-empty JSON object {{option: [values]}}, got {space!r}")
    base = defaults()
    out = {}
    for name, values in space.items():
        if name not in base:
            if strict:
                raise ParameterError(f"search space: {name!r} is not an option of the default method")
            log.warning("search space: option %r no longer exists, left out", name)
            continue
        if not isinstance(values, list) or not values:
            raise ParameterError(f"search space: {name} needs a non-empty list of values, got {values!r}")
        for v in values:
            TopomapOptions(**{name: v})  # raises ParameterError naming the option and the value
        out[name] = list(dict.fromkeys(values))
    if not out:
        raise ParameterError("search space: no option of the default method in it")
    return out


def read_space(text):
    """The search space of ``--space``: a JSON file's path or a JSON object given inline."""
    from topomap.errors import ParameterError

    if text is None:
        return check_space(DEFAULT_SPACE, strict=False)
    src = Path(text).read_text(encoding="utf-8") if Path(text).is_file() else text
    try:
        space = json.loads(src)
    except json.JSONDecodeError as exc:
        raise ParameterError(f"--space {text}: not a JSON object or a JSON file ({exc.msg})") from None
    return check_space(space)


# --------------------------------------------------------------------------
# scoring, cached
# --------------------------------------------------------------------------

_LOADED: dict = {}
_LOADED_CELLS = 80_000_000  # cells of loaded maps one process keeps


def _load(ref: MapRef):
    """``(bm, grid)``: the benchmark map and its grid loaded as a user loads it (kept per process)."""
    from topomap.bench.datasets import load_dataset

    got = _LOADED.get(ref)
    if got is None:
        bm = load_dataset(ref.directory, variant=ref.variant, names=[ref.name])[0]
        got = (bm, bm.load())
        while _LOADED and sum(g.free.size for _, g in _LOADED.values()) + got[1].free.size > _LOADED_CELLS:
            _LOADED.pop(next(iter(_LOADED)))
        _LOADED[ref] = got
    return got


def score_task(ref: MapRef, keys) -> list:
    """Segment ``ref`` with each options key of ``keys``: ``[(precision, recall, seconds, error)]``.

    The scores are the original protocol's (:func:`topomap.bench.evaluation.score_segmentation` of the rooms
    a user gets, on the free cells of the grid as loaded, the true rooms whole); a failure scores 0 / 0
    with its one-line error.
    """
    from topomap.bench.evaluation import score_segmentation
    from topomap.core.segmentation import segment

    out = []
    try:
        bm, grid = _load(ref)
    except Exception as exc:  # noqa: BLE001 - reported, scored as nothing found
        return [(0.0, 0.0, 0.0, f"{type(exc).__name__}: {exc}"[:200]) for _ in keys]
    for key in keys:
        t0 = time.perf_counter()
        try:
            seg = segment(grid, **dict(key))
            sc = score_segmentation(seg.room_labels, bm.gt_rooms, scored=grid.free)
            out.append((float(sc["precision"]), float(sc["recall"]), time.perf_counter() - t0, ""))
        except Exception as exc:  # noqa: BLE001 - an option set that breaks a map loses on it
            out.append((0.0, 0.0, time.perf_counter() - t0, f"{type(exc).__name__}: {exc}"[:200]))
    return out


def code_version() -> str:
    """A hash of the source of the ``topomap`` package that runs (the cache's file name)."""
    import topomap

    h = hashlib.sha256()
    root = Path(topomap.__file__).resolve().parent
    for p in sorted(root.rglob("*.py")):
        h.update(str(p.relative_to(root)).encode())
        h.update(p.read_bytes())
    return h.hexdigest()[:16]


class Scorer:
    """Precision / recall of (map, options) pairs, each segmented once.

    ``requests`` records every (map key, options key) asked for, in order: what a fold looked at.
    """

    def __init__(self, jobs: int = 1, cache_dir=None):
        self.jobs = int(jobs)
        self.memo = {}
        self.requests = []
        self.errors = {}
        self.seconds = 0.0
        self.n_segmented = 0
        self.from_disk = set()
        self.used = set()
        self.cache_path = None
        self._pool = None
        if cache_dir is not None:
            self.cache_path = Path(cache_dir) / f"scores_{code_version()}.json"
            if self.cache_path.is_file():
                for k, v in json.loads(self.cache_path.read_text(encoding="utf-8")).items():
                    self.memo[k] = tuple(v)
            self.from_disk = set(self.memo)

    @staticmethod
    def _mkey(ref: MapRef, key: tuple) -> str:
        return json.dumps([ref.dataset, ref.variant, ref.name, [list(kv) for kv in key]])

    def scores(self, maps, option_sets) -> list:
        """``[[(precision, recall) per map] per options]`` for ``option_sets`` (dicts of changed options)."""
        base = defaults()
        keys = [opt_key(o, base) for o in option_sets]
        todo = {}
        for ref in maps:
            for key in keys:
                self.requests.append((ref.key, key))
                self.used.add(self._mkey(ref, key))
                if self._mkey(ref, key) not in self.memo:
                    todo.setdefault(ref, [])
                    if key not in todo[ref]:
                        todo[ref].append(key)
        if todo:
            self._run(todo)
        return [[self.memo[self._mkey(ref, key)][:2] for ref in maps] for key in keys]

    def _run(self, todo: dict) -> None:
        items = list(todo.items())
        if self.jobs > 1:
            if self._pool is None:
                self._pool = ProcessPoolExecutor(max_workers=self.jobs)
            results = self._pool.map(score_task, [r for r, _ in items], [k for _, k in items])
        else:
            results = (score_task(r, k) for r, k in items)
        for (ref, keys), res in zip(items, results):
            for key, (p, r, secs, err) in zip(keys, res):
                self.memo[self._mkey(ref, key)] = (p, r)
                self.seconds += secs
                self.n_segmented += 1
                if err:
                    self.errors[(ref.key, key)] = err

    def save(self) -> None:
        """Write the disk cache (a temporary file renamed over the old one)."""
        if self.cache_path is None:
            return
        self.cache_path.parent.mkdir(parents=True, exist_ok=True)
        tmp = self.cache_path.with_name(self.cache_path.name + ".tmp")
        tmp.write_text(json.dumps(self.memo), encoding="utf-8")
        tmp.replace(self.cache_path)

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None


def mean_pr(pairs) -> tuple:
    """Mean precision and mean recall of ``[(p, r)]``."""
    a = np.array(pairs, float).reshape(-1, 2)
    return (float(a[:, 0].mean()), float(a[:, 1].mean())) if len(a) else (math.nan, math.nan)


def f1(p: float, r: float) -> float:
    return 2 * p * r / (p + r) if p + r > 0 else 0.0


def objective(pairs) -> float:
    """The tuning objective: the F1 of the mean precision and the mean recall of ``[(p, r)]``."""
    return f1(*mean_pr(pairs))


# --------------------------------------------------------------------------
# tuning and folds
# --------------------------------------------------------------------------

def tune(scorer: Scorer, train, space: dict, *, sweeps: int = 2) -> tuple:
    """Coordinate ascent from the defaults on the maps ``train`` only.

    Returns
    -------
    (dict, float, list)
        The options that differ from the defaults, the objective they reach on ``train``, and the
        steps ``[(sweep, option, value, objective)]`` of every candidate tried.
    """
    base = defaults()
    current = {}
    best = objective(scorer.scores(train, [current])[0])
    history = []
    for sweep in range(1, sweeps + 1):
        changed = False
        for name, values in space.items():
            now = current.get(name, base[name])
            cands = [v for v in values if v != now]
            trials = [_with(current, name, v, base) for v in cands]
            for v, trial, res in zip(cands, trials, scorer.scores(train, trials)):
                obj = objective(res)
                history.append((sweep, name, v, obj))
                if obj > best + _EPS:
                    best, current, changed = obj, trial, True
            log.info("  sweep %d %s = %s: %.4f", sweep, name, current.get(name, base[name]), best)
        if not changed:
            break
    return current, best, history


def _with(options: dict, name: str, value, base: dict) -> dict:
    out = {k: v for k, v in options.items() if k != name}
    if base[name] != value:
        out[name] = value
    return out


def _variants(refs) -> list:
    return list(dict.fromkeys(r.variant for r in refs))


def run_fold(scorer: Scorer, fold: Fold, space: dict, *, sweeps: int = 2) -> dict:
    """Tune on ``fold.train``, then score the defaults and the tuned options on both sides.

    Returns
    -------
    dict
        ``tuned`` (options that differ from the defaults), ``train`` and ``test``: per variant
        ``{"defaults": (P, R), "tuned": (P, R), "n": maps}``, and ``objective`` (the tuned one on
        the training maps).
    """
    log.info("%s: tuned on %s (%d maps), scored on %s (%d maps)", fold.dataset, fold.train_label,
             len(fold.train), fold.test_label, len(fold.test))
    tuned, obj, history = tune(scorer, fold.train, space, sweeps=sweeps)
    fold.tuned, fold.history = tuned, history
    out = {"tuned": tuned, "objective": obj}
    for side, refs in (("train", fold.train), ("test", fold.test)):
        d, t = scorer.scores(refs, [{}, tuned])
        per = {}
        for v in _variants(refs) + ["all"]:
            idx = [i for i, r in enumerate(refs) if v in ("all", r.variant)]
            per[v] = {"defaults": mean_pr([d[i] for i in idx]), "tuned": mean_pr([t[i] for i in idx]),
                      "n": len(idx)}
        out[side] = per
    return out


def everything(scorer: Scorer, refs) -> dict:
    """The defaults on every map of ``refs``: per variant (and ``all``) ``((P, R), n)``."""
    d = scorer.scores(refs, [{}])[0]
    out = {}
    for v in _variants(refs) + ["all"]:
        idx = [i for i, r in enumerate(refs) if v in ("all", r.variant)]
        out[v] = (mean_pr([d[i] for i in idx]), len(idx))
    return out


# --------------------------------------------------------------------------
# the section
# --------------------------------------------------------------------------

def _pr(pr) -> str:
    p, r = pr
    return "–" if not np.isfinite(p) else f"{100 * p:.1f} / {100 * r:.1f}"


def _f1(pr) -> float:
    return 100 * f1(*pr) if np.isfinite(pr[0]) else math.nan


def _value(v) -> str:
    return "map-dependent" if v is None else (f"{v:g}" if isinstance(v, float) else str(v))


def fold_table(results) -> str:
    """One line per fold and variant of the held-out maps."""
    lines = ["| data set | tuned on | scored on | variant | maps train / held out "
             "| train: defaults P / R | train: tuned P / R (in-sample) | held out: defaults P / R "
             "| held out: tuned P / R | tuned - defaults, held out (F1) | held out - in-sample (F1) |",
             "| --- | --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for fold, res in results:
        for v, te in res["test"].items():
            if v == "all" and len(res["test"]) == 2:
                continue  # one variant: its line is the whole
            tr = res["train"].get(v, res["train"]["all"])
            gain = _f1(te["tuned"]) - _f1(te["defaults"])
            gap = _f1(te["tuned"]) - _f1(tr["tuned"])
            lines.append(f"| {fold.dataset} | {fold.train_label} | {fold.test_label} | {v} | {tr['n']} / {te['n']} "
                         f"| {_pr(tr['defaults'])} | {_pr(tr['tuned'])} | {_pr(te['defaults'])} "
                         f"| **{_pr(te['tuned'])}** | {gain:+.1f} | {gap:+.1f} |")
    return "\n".join(lines) + "\n"


def everything_table(whole) -> str:
    lines = ["| data set | variant | maps | defaults P / R (%) | F1 (%) |", "| --- | --- | ---: | ---: | ---: |"]
    for dataset, per in whole.items():
        for v, (pr, n) in per.items():
            if v == "all" and len(per) == 2:
                continue
            lines.append(f"| {dataset} | {v} | {n} | {_pr(pr)} | {_f1(pr):.1f} |")
    return "\n".join(lines) + "\n"


def tuned_table(results, space) -> str:
    base = defaults()
    head = "| option | default | candidates | " + " | ".join(
        f"{f.dataset}: tuned on {f.train_label}" for f, _ in results) + " |"
    lines = [head, "| --- | ---: | --- |" + " ---: |" * len(results)]
    for name, values in space.items():
        cells = []
        for _, res in results:
            v = res["tuned"].get(name, base[name])
            cells.append(f"**{_value(v)}**" if name in res["tuned"] else _value(v))
        lines.append(f"| `{name}` | {_value(base[name])} | {', '.join(_value(v) for v in values)} | "
                     + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def findings(results) -> str:
    """One sentence per fold whose tuning hurts the held-out maps or falls far below its in-sample figure."""
    out = []
    for fold, res in results:
        for v, te in res["test"].items():
            if v != "all":
                continue
            tr = res["train"]["all"]
            gain = _f1(te["tuned"]) - _f1(te["defaults"])
            gap = _f1(te["tuned"]) - _f1(tr["tuned"])
            if not res["tuned"]:
                out.append(f"- {fold.dataset}, tuned on {fold.train_label}: the defaults are already the best "
                           f"of the search space there; on {fold.test_label} they score {_pr(te['defaults'])}.")
            elif gain < -0.5:
                out.append(f"- {fold.dataset}, tuned on {fold.train_label}: the tuning helps the training maps "
                           f"({_f1(tr['tuned']) - _f1(tr['defaults']):+.1f} F1) and **hurts** {fold.test_label} "
                           f"({gain:+.1f} F1): these options fit the training files.")
            else:
                out.append(f"- {fold.dataset}, tuned on {fold.train_label}: {gain:+.1f} F1 on {fold.test_label} "
                           f"against the defaults ({_f1(tr['tuned']) - _f1(tr['defaults']):+.1f} on the training "
                           f"maps); held out {gap:+.1f} F1 from in-sample.")
    return "\n".join(out) + "\n"


def command(a) -> str:
    cmd = "python benchmarks/leave_one_out.py"
    for flag, arg in (("--real", a.real), ("--ipa", a.ipa), ("--corpus", a.corpus)):
        if arg:
            cmd += f" {flag} {flag[2:].upper()}_DIR"
    if a.space:
        cmd += f" --space {Path(a.space).name if Path(a.space).is_file() else repr(a.space)}"
    cmd += f" --sweeps {a.sweeps}" + (f" --corpus-cases {a.corpus_cases}" if a.corpus else "") + f" --jobs {a.jobs}"
    return cmd


def _cpu_minutes() -> float:
    """CPU time (min) of this process and its finished worker processes."""
    import os

    t = os.times()
    return (t.user + t.system + t.children_user + t.children_system) / 60


def section(a, results, whole, space, scorer, wall, skipped) -> tuple:
    ftab, etab, ttab = fold_table(results), everything_table(whole), tuned_table(results, space)
    n_err = len(scorer.errors)
    err = (f"\n{n_err} segmentation{'s' if n_err != 1 else ''} failed (scored 0 / 0), e.g. "
           f"{next(iter(scorer.errors.values()))}.\n") if n_err else ""
    skip = "".join(f"\n{s}\n" for s in skipped)
    n_disk = len(scorer.used & scorer.from_disk)
    cached = f"; {n_disk} scores read from the disk cache of an earlier run" if n_disk else ""
    text = f"""## Leave-one-out: options tuned on some maps, scored on others

`{command(a)}`, commit `{_commit()}`; {_machine()}; {wall / 60:.1f} min with {a.jobs} job{"s" if a.jobs > 1 else ""},
{_cpu_minutes():.1f} min of CPU ({scorer.n_segmented} segmentations{cached}).

A guard against rules that fit the files they were developed on. Each data
set is split into two sides; the default method's options are tuned on one
side (coordinate ascent from the defaults over the search space below, at
most {a.sweeps} sweeps, on the F1 of the mean precision and the mean recall)
and scored on the other. rose2_real: tuned on one building, scored on the
other. ipa plans: the maps in name order, even against odd (both variants
of a map on one side). Simulated corpus: the cases split in two halves by a
hash of the case name, {a.corpus_cases} cases of each half, both variants
(plan, scan). P / R: mean precision / recall of Bormann et al. (%), the
**original protocol** (true rooms whole; segments on the free cells of the
map as loaded; segments and rooms of 100 cells or fewer ignored), each map
loaded as `topomap segment` loads it.

The **train** columns are training figures: the tuned one is in-sample
(the options were chosen on those maps). The **held out** columns are
the leave-one-out figures: options chosen without those maps. "tuned -
defaults, held out" is the F1 the tuning gains (or loses) on maps it did
not see; "held out - in-sample" how far the held-out figure falls below
the training one.

{ftab}
The figures on everything: the defaults on every map used above.

{etab}
Tuned values per fold (bold: changed from the default):

{ttab}
{findings(results)}{err}{skip}"""
    return text, ftab + "\n" + etab + "\n" + ttab


# --------------------------------------------------------------------------
# sensitivity
# --------------------------------------------------------------------------

def sensitivity_options() -> list:
    """The numeric options with a default value that the segmentation of one map uses (not the
    ``prior_*`` ones, which need a previous result)."""
    from topomap.options import TopomapOptions

    out = []
    for f in dataclasses.fields(TopomapOptions):
        v = getattr(TopomapOptions(), f.name)
        if f.name.startswith("prior_") or isinstance(v, (bool, str)) or v is None or v == 0:
            continue
        out.append(f.name)
    return out


def sensitivity(scorer: Scorer, groups: dict, factors=(0.7, 1.4)) -> str:
    """A table: per option and factor, the objective's change (F1 points) on each group of maps."""
    from topomap.options import TopomapOptions

    base = defaults()
    rows = []
    names = sensitivity_options()
    ref = {g: objective(scorer.scores(maps, [{}])[0]) for g, maps in groups.items()}
    for name in names:
        cells, worst = [], 0.0
        for fac in factors:
            v = round(base[name] * fac, 4)
            kind = [f for f in dataclasses.fields(TopomapOptions) if f.name == name][0].metadata["kind"]
            if kind == "fraction":
                v = min(v, 1.0)
            for g, maps in groups.items():
                d = 100 * (objective(scorer.scores(maps, [{name: v}])[0]) - ref[g])
                worst = max(worst, abs(d))
                cells.append(f"{d:+.1f}")
        rows.append((worst, name, cells))
        log.info("%s: %s", name, " ".join(cells))
    rows.sort(key=lambda x: -x[0])
    head = "| option | default | " + " | ".join(f"{g} x{fac}" for fac in factors for g in groups) + " | max abs |"
    lines = [head, "| --- | ---: |" + " ---: |" * (len(factors) * len(groups) + 1)]
    for worst, name, cells in rows:
        lines.append(f"| `{name}` | {_value(base[name])} | " + " | ".join(cells) + f" | {worst:.1f} |")
    base_line = "Objective at the defaults: " + ", ".join(f"{g} {100 * v:.1f}" for g, v in ref.items())
    return base_line + "\n\n" + "\n".join(lines) + "\n"


def _sensitivity_groups(folds) -> dict:
    """A few maps of each data set: every third of a side, at most 8 per side and variant."""
    groups = {}
    for fold in folds:
        if fold.dataset in groups and fold.dataset != "rose2_real":
            continue
        label = fold.dataset if fold.dataset != "rose2_real" else fold.train_label
        if label in groups:
            continue
        pick = []
        for v in _variants(fold.train):
            pick += [r for r in fold.train if r.variant == v][::3][:8]
        groups[label] = pick
    return groups


# --------------------------------------------------------------------------

def main(argv=None) -> int:
    from topomap.bench.datasets import benchmark_dir, real_maps_dir
    from topomap.errors import TopomapError

    import argparse

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=_section.HERE / "sections" / "90_leave_one_out.md",
                    help="section file to write (default benchmarks/sections/90_leave_one_out.md)")
    ap.add_argument("--real", default=None, help="rose2_real directory (default: found as benchmarks/README.md says)")
    ap.add_argument("--ipa", default=None, help="ipa_room_segmentation directory (default: found likewise)")
    ap.add_argument("--corpus", default=None, help="simulated corpus directory (default: none)")
    ap.add_argument("--space", default=None, help="search space: a JSON file or inline JSON {option: [values]}")
    ap.add_argument("--sweeps", type=int, default=2)
    ap.add_argument("--corpus-cases", type=int, default=100, help="cases of each corpus half (default 100)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--cache", type=Path, default=None, help="directory of a disk cache of the scores")
    ap.add_argument("--no-defaults", action="store_true",
                    help="use only the data sets given (do not look for rose2_real and the ipa plans)")
    ap.add_argument("--sensitivity", action="store_true", help="print the sensitivity table and stop")
    a = ap.parse_args(argv)
    logging.basicConfig(level=logging.WARNING, format="%(message)s")
    log.setLevel(logging.INFO)
    if not a.no_defaults:
        a.real = a.real or real_maps_dir()
        a.ipa = a.ipa or benchmark_dir()
    if a.sweeps < 1 or a.corpus_cases < 1 or a.jobs < 1:
        sys.exit(f"error: --sweeps, --corpus-cases and --jobs must be >= 1, got {a.sweeps}, {a.corpus_cases}, {a.jobs}")
    t0 = time.perf_counter()
    try:
        space = read_space(a.space)
        folds, skipped = [], []
        for label, d, make in (("rose2_real", a.real, real_folds), ("The ipa plans", a.ipa, ipa_folds),
                               ("The simulated corpus", a.corpus,
                                lambda d: corpus_folds(d, a.corpus_cases))):
            if d is None:
                skipped.append(f"{label} not given: not measured.")
                continue
            folds += make(d)
    except TopomapError as exc:
        sys.exit(f"error: {exc}")
    if not folds:
        sys.exit("error: no data set (pass --real, --ipa or --corpus)")
    scorer = Scorer(a.jobs, a.cache)
    try:
        if a.sensitivity:
            sys.stdout.write(sensitivity(scorer, _sensitivity_groups(folds)))
            scorer.save()
            log.info("%.0f s, %d segmentations", time.perf_counter() - t0, scorer.n_segmented)
            return 0
        results, whole = [], {}
        for fold in folds:
            results.append((fold, run_fold(scorer, fold, space, sweeps=a.sweeps)))
            scorer.save()
        for fold in folds:
            if fold.dataset not in whole:
                refs = list(dict.fromkeys(f for g in folds if g.dataset == fold.dataset for f in g.train + g.test))
                whole[fold.dataset] = everything(scorer, refs)
    finally:
        scorer.save()
        scorer.close()
    wall = time.perf_counter() - t0
    text, tab = section(a, results, whole, space, scorer, wall, skipped)
    _section.write(a.out, text, tab, wall)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
