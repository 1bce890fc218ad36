"""Folders a test session builds once for all its xdist workers: a scene, a run, a world.

:func:`shared_folder` keys each folder by a name and a JSON-able description of what goes into
it (a config dict, seeds, sizes): the first worker to ask builds it under an exclusive file lock
(``fcntl.flock``) and marks it finished with a sibling ``.done`` file (built in place, so the
absolute paths a run records stay true); every other worker waits on the lock and reads the
finished folder. The folders live under the session's base temporary
folder, which all workers of one run share (``pytest-N/`` above each worker's ``popen-gwK/``),
so a new run starts empty and nothing survives between runs. Builders must only write inside
the folder they are given; users of the folder only read it.
"""

from __future__ import annotations

import fcntl
import hashlib
import json
import os
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

__all__ = ["session_root", "shared_folder"]


def session_root(factory: pytest.TempPathFactory) -> Path:
    """The folder every worker of this test session shares (created on first use)."""
    base = factory.getbasetemp()
    root = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base
    shared = root / "shared-session"
    shared.mkdir(exist_ok=True)
    return shared


def shared_folder(factory: pytest.TempPathFactory, name: str, key: Any,
                  build: Callable[[Path], object]) -> Path:
    """The folder ``name`` for ``key``, built once per session by ``build(folder)``.

    ``key`` is anything :func:`json.dumps` takes (sorted); two calls with equal keys share one
    folder. A build that raises leaves no folder behind: the next caller builds it again (and a
    ``pytest.skip`` inside ``build`` skips each caller in turn).
    """
    digest = hashlib.sha256(json.dumps(key, sort_keys=True, default=str).encode()).hexdigest()
    root = session_root(factory)
    target = root / f"{name}-{digest[:12]}"
    with open(root / f"{target.name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        done = root / f"{target.name}.done"
        if done.is_file():
            return target
        shutil.rmtree(target, ignore_errors=True)  # a build that failed before
        target.mkdir()
        try:
            build(target)
        except BaseException:
            shutil.rmtree(target, ignore_errors=True)
            raise
        done.touch()
    return target
