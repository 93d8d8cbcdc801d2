"""Saving results: label image, room graph (GraphML, JSON), overlay picture.

Every file is written to a temporary name in the target directory and renamed
into place (:func:`atomic_write`), so a failed run never leaves a partial file
and never clobbers an earlier output.
"""

from __future__ import annotations

import json
import os
import tempfile
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import networkx as nx

__all__ = ["atomic_write", "save_labels", "save_graphml", "save_json", "to_graphml_graph",
           "node_link", "write_outputs"]


@contextmanager
def atomic_write(path, mode: str = "wb"):
    """Open a temporary file beside ``path``; rename it to ``path`` on success.

    On an exception the temporary file is removed and ``path`` is untouched.
    Yields the temporary file's path (``mode=None``) or an open file object.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)
    try:
        if mode is None:
            yield tmp
        else:
            with open(tmp, mode) as fh:
                yield fh
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def save_labels(labels: np.ndarray, path) -> Path:
    """Write the label image as a 16-bit PNG (0 = not a room), same size as the map."""
    from PIL import Image

    if labels.max(initial=0) > 65535:
        raise ValueError(f"{path}: {int(labels.max())} rooms do not fit a 16-bit PNG")
    img = Image.fromarray(labels.astype(np.uint16))
    with atomic_write(path) as fh:
        img.save(fh, format="PNG")
    return Path(path)


def _scalar(v):
    """GraphML-safe value: scalars stay, tuples/lists become JSON, geometry WKT."""
    if v is None:
        return ""
    if isinstance(v, (bool, int, float, str)):
        return v
    if isinstance(v, (np.integer,)):
        return int(v)
    if isinstance(v, (np.floating,)):
        return float(v)
    if hasattr(v, "wkt"):
        return v.wkt
    if isinstance(v, np.ndarray):
        return json.dumps(v.tolist())
    return json.dumps(v, default=float)


def to_graphml_graph(G: nx.Graph) -> nx.Graph:
    """A copy of ``G`` whose attributes are all GraphML scalars (str, int, float, bool)."""
    H = G.__class__()
    H.graph.update({k: _scalar(v) for k, v in G.graph.items()})
    for n, d in G.nodes(data=True):
        H.add_node(n, **{k: _scalar(v) for k, v in d.items()})
    if G.is_multigraph():
        for u, v, k, d in G.edges(keys=True, data=True):
            H.add_edge(u, v, key=k, **{a: _scalar(b) for a, b in d.items()})
    else:
        for u, v, d in G.edges(data=True):
            H.add_edge(u, v, **{a: _scalar(b) for a, b in d.items()})
    return H


def save_graphml(G: nx.Graph, path) -> Path:
    """Write the room graph as GraphML (geometry as WKT strings)."""
    H = to_graphml_graph(G)
    with atomic_write(path) as fh:
        nx.write_graphml(H, fh)
    return Path(path)


def node_link(G: nx.Graph) -> dict:
    """JSON-ready node-link data of ``G`` (geometry as WKT, arrays as lists)."""
    H = to_graphml_graph(G)
    return nx.node_link_data(H, edges="edges")


def save_json(G: nx.Graph, path) -> Path:
    """Write the room graph as node-link JSON."""
    data = node_link(G)
    with atomic_write(path, "w") as fh:
        json.dump(data, fh, indent=1)
    return Path(path)


def write_outputs(seg, outdir, *, overlay: bool = True, skeletons: bool = False) -> dict:
    """Write ``labels.png``, ``rooms.graphml``, ``rooms.json`` and ``overlay.png``.

    Returns ``{name: path}``. All files are first written to temporary names
    and renamed into place only once every one of them has been written, so
    a failure in any writer leaves no partial file and keeps every earlier
    output of ``outdir`` as it was.
    """
    from contextlib import ExitStack

    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    G = seg.room_graph
    names = {"labels": "labels.png", "graphml": "rooms.graphml", "json": "rooms.json"}
    if overlay:
        names["overlay"] = "overlay.png"
    with ExitStack() as stack:  # on success renames every temporary file; on error removes them all
        tmp = {k: stack.enter_context(atomic_write(outdir / f, None)) for k, f in names.items()}
        save_labels(seg.labels, tmp["labels"])
        save_graphml(G, tmp["graphml"])
        save_json(G, tmp["json"])
        if overlay:
            from .plot import save_overlay

            save_overlay(seg, tmp["overlay"], skeletons=skeletons)
    return {k: outdir / f for k, f in names.items()}
