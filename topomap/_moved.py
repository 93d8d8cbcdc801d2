"""The import paths of modules that moved when the package was laid out in layers.

``import topomap.export`` (and ``from topomap.export import load_graph``) still
work: the old name is a module that hands every attribute on to the module that
now holds it (``topomap.io.export``). New code should import the new paths.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import types

#: old module (under ``topomap``) -> the module that holds it now (or the modules its parts went to)
MOVED = {
    "_example": "io.example", "export": "io.export", "plot": "io.plot", "ros": "io.ros",
    "geometry": "core.geometry", "skeleton": "core.skeleton", "walls": "core.walls", "doors": "core.doors",
    "rooms": "core.rooms", "roomgraph": "core.roomgraph", "kinds": "core.kinds", "outside": "core.outside",
    "baselines": "core.baselines", "identity": "core.identity", "segmentation": "core.segmentation",
    "edit": ("core.edit", "run.editing"), "tour": "planning.tour", "nav2": ("planning.nav2", "io.nav2"),
    "batch": ("run.batch", "run.record", "run.job"),
    "benchmark": "bench.benchmark", "evaluation": "bench.evaluation", "datasets": "bench.datasets",
    "simulate": "bench.simulate", "floorplan": "bench.floorplan", "corpus": "bench.corpus",
}


class _Forward(types.ModuleType):
    """A module whose attributes are those of the module that now holds its code."""

    def __init__(self, name: str, targets: tuple):
        super().__init__(name, f"Moved to {', '.join(targets)}.")
        self.__dict__["_targets"] = targets

    def __getattr__(self, attr):
        for target in self.__dict__["_targets"]:
            module = importlib.import_module(target)
            if hasattr(module, attr):
                return getattr(module, attr)
        raise AttributeError(f"module {self.__name__!r} (moved to {', '.join(self.__dict__['_targets'])}) "
                             f"has no attribute {attr!r}")

    def __dir__(self):
        return sorted({n for t in self.__dict__["_targets"] for n in dir(importlib.import_module(t))})


class _Finder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    def find_spec(self, fullname, path=None, target=None):
        head, _, old = fullname.partition(".")
        if head == "topomap" and old in MOVED:
            return importlib.util.spec_from_loader(fullname, self)
        return None

    def create_module(self, spec):
        moved = MOVED[spec.name.partition(".")[2]]
        return _Forward(spec.name, tuple(f"topomap.{m}" for m in ((moved,) if isinstance(moved, str) else moved)))

    def exec_module(self, module):
        pass


def install() -> None:
    """Put the finder of the old paths on ``sys.meta_path`` (once)."""
    if not any(isinstance(f, _Finder) for f in sys.meta_path):
        sys.meta_path.append(_Finder())
