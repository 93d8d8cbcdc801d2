"""Exception hierarchy of topomap.

Every error topomap raises on bad input is a :class:`TopomapError`. The
subclasses also derive from the matching built-in exception, so callers that
already catch ``ValueError`` or ``OSError`` keep working.

The message is always one line that names the offending file (or ``<array>``)
and what is wrong with it.
"""

from __future__ import annotations

__all__ = [
    "TopomapError",
    "MapError",
    "MapFileError",
    "MapFileNotFoundError",
    "MapTooLargeError",
    "PlanFormatError",
    "ParameterError",
    "GraphFormatError",
    "BenchmarkNotFoundError",
    "PlanningError",
    "EditError",
    "NotInRoomError",
    "NoPathError",
    "BagError",
    "OutputExistsError",
    "MissingDependencyError",
    "first_line",
]


def one_line(text) -> str:
    """Collapse whitespace (newlines included) and cap the length."""
    text = " ".join(str(text).split())
    return text if len(text) <= 300 else text[:297] + "..."


def named(name, text) -> str:
    """``"name: text"`` on one line (:func:`one_line`): how every error names its file or value."""
    return one_line(f"{name}: {text}")


def first_line(exc) -> str:
    """The first line of ``exc``'s message, or its type's name when that is empty:
    what a one-line error report says of an exception."""
    text = str(exc).splitlines()[0] if str(exc) else ""
    return text or type(exc).__name__


class TopomapError(Exception):
    """Base class of every error raised by topomap."""


class MapError(TopomapError, ValueError):
    """A map (image, YAML or array) exists but cannot be used."""


class MapFileError(TopomapError, OSError):
    """A map file cannot be read: missing, a directory, unreadable."""


class MapTooLargeError(MapError):
    """The map has more cells than the limit of :func:`topomap.io.cell_limit` (the memory available)."""


class PlanFormatError(MapError):
    """A vector floor plan file cannot be used: a bad line, no walls, no doors to take its scale from."""


class ParameterError(TopomapError, ValueError):
    """An option has an invalid value (the message echoes the value)."""


class GraphFormatError(TopomapError, ValueError):
    """A saved room graph (GraphML, JSON, GeoJSON) cannot be loaded."""


class MapFileNotFoundError(MapFileError, FileNotFoundError):
    """A map file (or the image a YAML names) does not exist."""


class BenchmarkNotFoundError(MapFileError, FileNotFoundError):
    """No benchmark maps in a directory (or the directory does not exist)."""


class PlanningError(TopomapError, ValueError):
    """A query or plan cannot be answered (base of the planning errors)."""


class NotInRoomError(PlanningError):
    """A start or goal point is not in the free space of any room, or a room ID does not exist."""


class NoPathError(PlanningError):
    """No route joins the start and the goal (walls, or every door too narrow)."""


class BagError(MapError):
    """A ROS bag cannot be read or holds no usable map: corrupt, empty, no such topic, another type."""


class OutputExistsError(TopomapError, FileExistsError):
    """An output folder holds results this run did not write (another map's, or files of unknown origin)."""


class MissingDependencyError(TopomapError, ImportError):
    """An optional dependency a feature needs is not installed (the message says which extra to install)."""


class EditError(TopomapError, ValueError):
    """An edit of the rooms cannot be made: an unknown room ID, a bad name, a split line
    outside the map or one that does not cut the room in two (see :mod:`topomap.core.edit`)."""
