"""Files written whole or not at all: every output of topomap goes through :func:`atomic_write`."""

from __future__ import annotations

import logging
import os
import re
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Optional

from ..errors import MapFileError, TopomapError, named

log = logging.getLogger(__name__)

__all__ = ["atomic_write", "write_bytes", "remove_stale_temporaries", "renamed_error", "file_keys", "same_file"]


#: Temporary files :func:`atomic_write` makes: ``.NAME.topomap-pPID.RANDOM.tmp`` (the ``topomap-`` marker:
#: a user's own ``.draft.p4000000.autosave.tmp`` is not ours).
_TMP_RE = re.compile(r"^\..+\.topomap-p(\d+)\.[A-Za-z0-9_]{8}\.tmp$")


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, OSError):
        return True
    return True


def remove_stale_temporaries(folder) -> int:
    """Remove the temporary files killed runs of :func:`atomic_write` left in ``folder``.

    A temporary is ours when its name is ``.NAME.topomap-pPID.RANDOM.tmp``;
    it is stale when process ``PID`` no longer runs. Other files (a user's
    own ``.notes.txt.download.tmp``) are never touched.

    Returns
    -------
    int
        How many files were removed.
    """
    removed = 0
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return 0
    for e in entries:
        name = e.name
        if not (name.startswith(".") and name.endswith(".tmp")):
            continue
        m = _TMP_RE.match(name)
        try:
            if not e.is_file(follow_symlinks=False):
                continue
            stale = m is not None and int(m.group(1)) != os.getpid() and not _pid_alive(int(m.group(1)))
            if stale:
                os.unlink(e.path)
                removed += 1
        except OSError:
            continue
    if removed:
        log.info("%s: removed %d stale temporary file(s) of killed runs", folder, removed)
    return removed


def renamed_error(exc, tmp: str, path: Path):
    """``exc`` with the final ``path`` in its message instead of the temporary ``tmp``, or None to keep it."""
    if isinstance(exc, OSError) and not isinstance(exc, TopomapError):
        return MapFileError(named(path, f"cannot write: {exc.strerror or exc}"))
    text = str(exc)
    if tmp in text:
        try:
            return type(exc)(text.replace(tmp, str(path)))
        except Exception:  # noqa: BLE001 - an exception type that takes other arguments: keep the original
            return None
    return None


@contextmanager
def atomic_write(path, mode: Optional[str] = "wb"):
    """Open a temporary file beside ``path``; rename it to ``path`` on success.

    On an exception the temporary file is removed and ``path`` is untouched
    (never a half-written output, never a clobbered earlier one). Yields the
    temporary file's path (``mode=None``, for writers that take a file name)
    or a file object open in ``mode``. The file gets the permissions of the
    file it replaces, or the umask's default for a new one.

    The temporary is named ``.NAME.topomap-pPID.RANDOM.tmp``; temporaries that killed
    runs left in the folder are removed first (:func:`remove_stale_temporaries`).
    Errors name ``path``, never the temporary: a failed write (a full disk)
    is a :class:`~topomap.errors.MapFileError`. Text modes write UTF-8, file
    names that are not UTF-8 as their original bytes.
    """
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise MapFileError(named(path.parent, f"cannot create the output folder: {exc.strerror or exc}")) from None
    remove_stale_temporaries(path.parent)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.topomap-p{os.getpid()}.", suffix=".tmp", dir=path.parent)
    except OSError as exc:
        raise MapFileError(named(path, f"cannot write: {exc.strerror or exc}")) from None
    os.close(fd)
    try:
        try:
            perm = os.stat(path).st_mode & 0o777
        except OSError:
            umask = os.umask(0)
            os.umask(umask)
            perm = 0o666 & ~umask
        os.chmod(tmp, perm)
        if mode is None:
            yield tmp
        else:
            text = "b" not in mode
            with open(tmp, mode, **({"encoding": "utf-8", "errors": "surrogateescape"} if text else {})) as fh:
                yield fh
                fh.flush()
                os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        new = renamed_error(exc, tmp, path) if isinstance(exc, Exception) else None
        if new is not None:
            raise new from None
        raise


def write_bytes(path: Path, data: bytes):
    """Write ``data`` to ``path`` through :func:`atomic_write` (all of it, or nothing)."""
    with atomic_write(path) as fh:
        fh.write(data)


def file_keys(path) -> tuple:
    """What names the file ``path`` is, for :func:`same_file`: ``(its path with links resolved, (device,
    inode) when it exists, else None)``; ``(None, None)`` for a name the system refuses (a NUL byte).
    Comparing the keys of many paths (a set of them) is linear in the paths, where comparing every pair
    is not."""
    try:
        real = os.path.realpath(path)
    except (OSError, ValueError):
        return None, None
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return real, None
    return real, (st.st_dev, st.st_ino)


def same_file(a, b) -> bool:
    """Whether the paths ``a`` and ``b`` name one file: the same path once links are resolved (either may
    not exist yet), or the same existing file (hard links); False for a name the system refuses (a NUL byte)."""
    (ra, ia), (rb, ib) = file_keys(a), file_keys(b)
    return ra is not None and rb is not None and (ra == rb or (ia is not None and ia == ib))
