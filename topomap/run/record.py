"""The run record, ``topomap_run.json``: what an output folder holds and what made it.

Every output folder of ``topomap segment`` gets one (see the rules of
:mod:`topomap.run.batch`): the map it holds (absolute path), size and
modification time of the input files, the options, the topomap version,
size and modification time of every output file, the map's summary row and,
after ``topomap edit``, the edits made, and the Nav2 route graphs exported from
its room graph (``topomap export OUT/rooms.graphml --nav2 FILE``), which
``topomap edit`` rewrites with the rest. It is written first as
``"status": "incomplete"`` and rewritten as ``"complete"`` after the last
output file, always atomically; a failed run puts the earlier record back.
A batch skips a map whose record is complete and still true
(:func:`up_to_date`); ``topomap edit`` (:mod:`topomap.run.editing`) reads
the map back through it and adds its edits.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Optional

from .. import __version__
from ..errors import ParameterError
from ..io.export import OUTPUT_FILES
from ..io.files import atomic_write, same_file
from ..io.metadata import image_named

__all__ = ["RECORD", "INCOMPLETE", "COMPLETE", "OUTPUT_NAMES", "file_stamp", "input_files", "fingerprint",
           "output_stamps", "read_record", "write_record", "restore_record", "up_to_date", "add_nav2_export",
           "nav2_exports", "check_nav2_target"]

#: Name of the run record in every output folder.
RECORD = "topomap_run.json"
#: ``status`` of a run record: being written (the map must run again), or complete.
INCOMPLETE, COMPLETE = "incomplete", "complete"
#: Output files a map's folder may hold (what ``topomap segment`` writes).
OUTPUT_NAMES = tuple(OUTPUT_FILES.values())


def file_stamp(path) -> Optional[list]:
    """``[size, modification time in ns]`` of the file ``path``, or None when it cannot be read (missing)."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return [st.st_size, st.st_mtime_ns]


def input_files(path: Path) -> list:
    """The map file and, for a YAML, the image it names; for an image, a YAML beside it of the same stem
    (read or not: see :func:`topomap.io.yaml_beside`) (absolute paths)."""
    files = [Path(os.path.abspath(path))]
    if path.suffix.lower() not in (".yaml", ".yml"):
        for suffix in (".yaml", ".yml"):
            if path.with_suffix(suffix).is_file():
                files.append(Path(os.path.abspath(path.with_suffix(suffix))))
    if path.suffix.lower() in (".yaml", ".yml"):
        # read as load_map reads it (bounded, never a FIFO); a bad YAML fails in load_map with its own message
        image = image_named(path)
        if image is not None:
            files.append(image)
    return files


def fingerprint(path: Path) -> dict:
    """``{input file: file_stamp}`` of the map ``path`` (:func:`input_files`): the record's ``inputs``."""
    return {str(f): file_stamp(f) for f in input_files(path)}


def output_stamps(folder: Path) -> dict:
    """``{name: file_stamp}`` of the output files (and ``changes.json``) that ``folder`` holds: the record's
    ``files``."""
    return {n: file_stamp(folder / n) for n in (*OUTPUT_NAMES, "changes.json") if (folder / n).exists()}


def read_record(folder: Path) -> Optional[dict]:
    """The run record of ``folder``: None when it has none, ``{}`` when it cannot be read or is no record."""
    try:
        rec = json.loads((folder / RECORD).read_text())
    except FileNotFoundError:
        return None
    except (OSError, ValueError):
        return {}
    return rec if isinstance(rec, dict) else {}


def write_record(folder: Path, record: dict) -> None:
    """Write ``record`` as the run record of ``folder``, atomically (this also removes the temporaries a
    killed run left there: :func:`topomap.io.atomic_write`)."""
    with atomic_write(folder / RECORD, "w") as fh:
        fh.write(json.dumps(record, indent=1, sort_keys=True, allow_nan=False) + "\n")


def restore_record(folder: Path, previous: Optional[str], existed: bool) -> None:
    """Put back the run record of ``folder`` as it was before a failed run: the text ``previous``, or no
    record when it had none (and no folder either when it did not exist, ``existed`` False, and is empty).
    Never raises for a file that cannot be written."""
    try:
        if previous is None:
            (folder / RECORD).unlink()
            if not existed:
                folder.rmdir()  # only if empty
        else:
            with atomic_write(folder / RECORD, "w") as fh:
                fh.write(previous)
    except OSError:
        pass


def up_to_date(record: dict, settings: dict, folder: Path) -> bool:
    """Whether ``record`` (of ``folder``) is complete, made by this version with ``settings``, and its input
    and output files are unchanged since: the map need not run again."""
    if record.get("status") != COMPLETE or record.get("settings") != settings or record.get("topomap") != __version__:
        return False
    inputs, files = record.get("inputs") or {}, record.get("files") or {}
    if not files or any(file_stamp(f) != v for f, v in inputs.items()):
        return False
    return all(file_stamp(folder / name) == v for name, v in files.items())


def check_nav2_target(graph_path, nav2_path, output=None) -> None:
    """Refuse a Nav2 route graph file ``nav2_path`` that would replace what the export reads or what its
    folder holds: the room graph ``graph_path``, the label files beside it, a file ``topomap segment``
    writes into that folder (the outputs, the run record, ``changes.json``), or ``output``, the room graph
    the same export writes.

    Raises
    ------
    ParameterError
        Naming ``--nav2 nav2_path`` and the file it would replace.
    """
    folder = Path(os.path.abspath(graph_path)).parent
    taken = [Path(graph_path)] + ([Path(output)] if output is not None else [])
    taken += [folder / n for n in (*OUTPUT_NAMES, RECORD, "changes.json")]
    for t in taken:
        if same_file(nav2_path, t):
            what = "the room graph it is made from" if t == Path(graph_path) else \
                "OUTPUT" if output is not None and t == Path(output) else f"the folder's {t.name}"
            raise ParameterError(f"--nav2 {nav2_path}: would replace {what} ({t}); choose another file")


def add_nav2_export(graph_path, nav2_path, clearance: Optional[float]) -> bool:
    """Note in the run record of the folder of ``graph_path`` that a Nav2 route graph was exported from it
    to ``nav2_path`` with ``clearance`` (m; None: the default), so that ``topomap edit`` rewrites it.

    Nothing is noted (False) when ``graph_path`` is not a room graph file of an output folder with a
    complete run record. The path is kept relative to the folder when it lies in it, else absolute; a
    later export to the same file replaces the earlier note.
    """
    folder = Path(os.path.abspath(graph_path)).parent
    rec = read_record(folder)
    if not rec or rec.get("status") != COMPLETE or Path(graph_path).name not in OUTPUT_NAMES:
        return False
    target = Path(os.path.abspath(nav2_path))
    try:
        where = str(target.relative_to(folder))
    except ValueError:
        where = str(target)
    notes = [n for n in nav2_exports(rec) if n["path"] != where]
    write_record(folder, dict(rec, nav2=notes + [{"path": where, "clearance": clearance}]))
    return True


def nav2_exports(record: dict) -> list:
    """The Nav2 exports a run record notes (:func:`add_nav2_export`): ``[{"path": str, "clearance": float or
    None}, ...]`` (a path relative to the folder or absolute); malformed notes are left out."""
    notes = record.get("nav2") if isinstance(record, dict) else None
    out = []
    for n in notes if isinstance(notes, list) else []:
        if isinstance(n, dict) and isinstance(n.get("path"), str) and n["path"] \
                and (n.get("clearance") is None or isinstance(n.get("clearance"), (int, float))):
            out.append({"path": n["path"], "clearance": n.get("clearance")})
    return out
