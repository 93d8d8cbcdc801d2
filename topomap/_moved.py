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

#: old module (under ``topomap``) -> the module that holds it now
MOVED = {
    "_example": "io.example", "export": "io.export", "plot": "io.plot", "ros": "io.ros",
    "geometry": "core.geometry", "skeleton": "core.skeleton", "walls": "core.walls", "doors": "core.doors",
    "rooms": "core.rooms", "roomgraph": "core.roomgraph", "kinds": "core.kinds", "outside": "core.outside",
    "baselines": "core.baselines", "identity": "core.identity", "segmentation": "core.segmentation",
    "edit": "core.edit", "tour": "planning.tour", "nav2": "planning.nav2", "batch": "run.batch",
    "benchmark": "bench.benchmark", "evaluation": "bench.evaluation", "datasets": "bench.datasets",
    "simulate": "bench.simulate", "floorplan": "bench.floorplan", "corpus": "bench.corpus",
}


class _Forward(types.ModuleType):
    """A module whose attributes are those of the module that now holds its code."""

    def __init__(self, name: str, target: str):
        super().__init__(name, f"Moved to {target}.")
        self.__dict__["_target"] = target

    def __getattr__(self, attr):
        return getattr(importlib.import_module(self.__dict__["_target"]), attr)

    def __dir__(self):
        return dir(importlib.import_module(self.__dict__["_target"]))


class _Finder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    def find_spec(self, fullname, path=None, target=None):
        head, _, old = fullname.partition(".")
        if head == "topomap" and old in MOVED:
            return importlib.util.spec_from_loader(fullname, self)
        return None

    def create_module(self, spec):
        return _Forward(spec.name, "topomap." + MOVED[spec.name.partition(".")[2]])

    def exec_module(self, module):
        pass


def install() -> None:
    """Put the finder of the old paths on ``sys.meta_path`` (once)."""
    if not any(isinstance(f, _Finder) for f in sys.meta_path):
        sys.meta_path.append(_Finder())
