"""Atomic output folders: build in a temporary sibling, then swap it in with renames.

One mechanism for every writer (scene folders, sweep cells, ROS bags and dataset exports): a
reader never sees a half-written folder, and a failure leaves the previous folder untouched.
"""

from __future__ import annotations

import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from marsscene.errors import ExportError

__all__ = ["probe_writable", "replacing_dir"]


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
    if final.exists() and not final.is_dir():
        raise ExportError(f"the output {final} exists and is not a folder")
    shutil.rmtree(_temp_beside(final), ignore_errors=True)


@contextmanager
def replacing_dir(final: Path, *, overwrite: bool = True, create: bool = True) -> Iterator[Path]:
    """Yield a folder (named like ``final``, inside a temporary sibling) that replaces
    ``final`` when the block succeeds; on any error nothing is left behind.

    An existing ``final`` is refused unless ``overwrite``. With ``create=False`` the yielded
    path does not exist yet (for writers that insist on creating their folder, e.g. rosbags).
    """
    if final.exists() and not overwrite:
        raise ExportError(f"{final} exists; pass --overwrite (overwrite=True) to replace it")
    tmp = _temp_beside(final)
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
