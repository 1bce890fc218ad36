"""Atomic outputs: files and folders are built under a temporary name, then renamed in.

Two helpers for every writer: :func:`write_atomic` for a file written in one go (JSON, tables,
trajectories, PLY scans, caches) and :func:`replacing_dir` for a folder (scene folders, sweep
cells, ROS bags and dataset exports). A reader never sees a half-written output, and a failure
leaves the previous one untouched. Files inside a :func:`replacing_dir` folder need no more.

A killed writer leaves its ``.<name>.<8 random chars>.tmp`` behind, so each write of ``<name>``
first sweeps those whose owner is provably gone. Each names its owner in ``owner.json`` (pid,
host, start time from ``/proc/<pid>/stat`` against pid reuse) and holds ``owner.lock`` with
``flock`` for the whole block; the kernel drops the lock however the process dies. Removed: a
folder of this host whose lock can be taken (without ``flock``: whose pid is dead or reused);
one of another host or without owner information (older versions) only when its lock is free
and it was idle for :data:`STALE_AFTER_S` (a lock may be local to one host). If the dead writer
had moved the previous output aside (``old``) and the output is missing, it is put back first.
Cleanup never fails a write.
"""

from __future__ import annotations

import json
import logging
import os
import re
import shutil
import socket
import stat
import tempfile
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager, nullcontext, suppress
from pathlib import Path

from marsscene.errors import ExportError

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows: the pid check alone
    fcntl = None  # type: ignore[assignment]

__all__ = ["STALE_AFTER_S", "probe_writable", "replacing_dir", "write_atomic"]

log = logging.getLogger("marsscene")
STALE_AFTER_S = 24 * 3600.0  # foreign or ownerless temporary folders: removed after this idle
_RANDOM = re.compile(r"[a-z0-9_]{8}")  # tempfile.mkdtemp's random part (no dots)
_OPEN = os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOFOLLOW", 0)  # no fifo hangs, no links


def _start_time(pid: int) -> int | None:
    """The start time of ``pid`` in clock ticks since boot (``/proc/<pid>/stat`` field 22)."""
    try:
        return int(Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[19])
    except (OSError, ValueError, IndexError):
        return None


def _pid_gone(pid: int, start: int | None) -> bool:
    """Whether process ``pid`` of this host (started at ``start``) provably no longer runs."""
    if os.name == "nt":  # os.kill(pid, 0) would terminate it there
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except OSError:  # another user's process: alive
        pass
    now = _start_time(pid)
    return None not in (start, now) and now != start  # the pid was reused


def _open_regular(path: Path) -> int | None:
    """A read-only descriptor of ``path`` if it is a regular file (not a link, fifo, ...)."""
    with suppress(OSError):
        fd = os.open(path, _OPEN)
        if stat.S_ISREG(os.fstat(fd).st_mode):
            return fd
        os.close(fd)
    return None


def _claim(tmp: Path) -> int | None:
    """Name this process the owner of ``tmp``; return the descriptor holding its lock."""
    me, fd = os.getpid(), None
    try:
        (tmp / "owner.json").write_text(
            json.dumps({"pid": me, "host": socket.gethostname(), "start": _start_time(me)}))
        if fcntl is not None:
            fd = os.open(tmp / "owner.lock.part", os.O_RDWR | os.O_CREAT, 0o644)
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            os.rename(tmp / "owner.lock.part", tmp / "owner.lock")  # appears already locked
        return fd
    except OSError as err:  # e.g. no flock on this filesystem: the pid check alone
        log.debug("cannot record the owner of %s: %s", tmp, err)
        if fd is not None:
            os.close(fd)
        return None


def _reap(tmp: Path, final: Path) -> None:
    """Remove the temporary folder ``tmp`` of ``final`` if its owner is provably gone."""
    pid, host, start = 0, "", None
    if (fd := _open_regular(tmp / "owner.json")) is not None:
        with os.fdopen(fd, "rb") as f, suppress(ValueError, KeyError, TypeError):
            owner = json.loads(f.read(4096))
            pid, host, start = int(owner["pid"]), str(owner["host"]), owner.get("start")
    lock = _open_regular(tmp / "owner.lock") if fcntl is not None else None
    with os.fdopen(lock, "rb") if lock is not None else nullcontext():
        if lock is not None:  # held (a live writer) or no flock here: raises, the folder stays
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        if host == socket.gethostname() and pid > 0:
            gone = lock is not None or _pid_gone(pid, start)
        else:
            newest = max(p.lstat().st_mtime for p in (tmp, tmp / "new", tmp / "new" / final.name)
                         if os.path.lexists(p))
            gone = time.time() - newest > STALE_AFTER_S
        if not gone:
            return
        if (tmp / "old").is_dir() and not os.path.lexists(final):  # killed between the renames
            (tmp / "old").rename(final)
            log.info("restored %s from an interrupted write", final)
        shutil.rmtree(tmp, ignore_errors=True)
        log.info("removed the stale temporary folder %s of an interrupted write", tmp)


def _sweep(final: Path) -> None:
    """Remove the stale temporary folders of ``final`` (never raises)."""
    prefix = f".{final.name}."
    try:
        with os.scandir(final.parent) as entries:
            stale = [Path(e.path) for e in entries if e.name.startswith(prefix)
                     and e.name.endswith(".tmp") and _RANDOM.fullmatch(e.name[len(prefix):-4])
                     and e.is_dir(follow_symlinks=False)]
    except OSError:
        return
    for tmp in stale:
        try:
            _reap(tmp, final)
        except Exception as err:  # a live owner's lock, or cleanup failed: the write goes on
            log.debug("left the temporary folder %s: %s", tmp, err)


def write_atomic(path: str | os.PathLike[str], data: bytes | str) -> Path:
    """Write ``data`` (``str`` as UTF-8) to ``path`` whole or not at all.

    The bytes go to a temporary sibling named for this process and thread
    (``.<name>.<pid>.<thread>.part``: concurrent writers never share one) and are renamed over
    ``path``; on any error the sibling is removed and ``path`` is untouched. Returns the path.
    """
    final = Path(path)
    blob = data.encode("utf-8") if isinstance(data, str) else data
    tmp = final.with_name(f".{final.name}.{os.getpid()}.{threading.get_ident()}.part")
    try:
        with open(tmp, "wb") as fh:
            fh.write(blob)
        os.replace(tmp, final)
    except BaseException:
        with suppress(OSError):
            tmp.unlink()
        raise
    return final


def _temp_beside(final: Path) -> Path:
    """A fresh temporary folder beside ``final`` (same filesystem: the final rename is atomic)."""
    try:
        final.parent.mkdir(parents=True, exist_ok=True)
        return Path(tempfile.mkdtemp(prefix=f".{final.name}.", suffix=".tmp", dir=final.parent))
    except OSError as err:
        reason = err.strerror or type(err).__name__
        raise ExportError(f"cannot write the output folder {final}: {reason}") from None


def probe_writable(final: Path) -> None:
    """Raise :class:`ExportError` now (before a long job) if ``final`` could not be written."""
    _sweep(final)
    if final.exists() and not final.is_dir():
        raise ExportError(f"the output {final} exists and is not a folder")
    shutil.rmtree(_temp_beside(final), ignore_errors=True)


@contextmanager
def replacing_dir(final: Path, *, overwrite: bool = True, create: bool = True) -> Iterator[Path]:
    """Yield a folder (named like ``final``, inside a temporary sibling) that replaces
    ``final`` when the block succeeds; on any error nothing is left behind.

    An existing ``final`` is refused unless ``overwrite``. With ``create=False`` the yielded
    path does not exist yet (for writers that insist on creating their folder, e.g. rosbags).
    Stale temporary folders of ``final`` left by killed writers are removed first.
    """
    _sweep(final)
    if final.exists() and not overwrite:
        raise ExportError(f"{final} exists; pass --overwrite (overwrite=True) to replace it")
    tmp = _temp_beside(final)
    lock = _claim(tmp)
    try:
        out = tmp / "new" / final.name  # same name: rosbags names its storage file after it
        out.parent.mkdir()
        if create:
            out.mkdir()
        yield out
        if final.exists():
            final.rename(tmp / "old")
        out.rename(final)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
        if lock is not None:
            os.close(lock)
