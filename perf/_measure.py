"""Wall time and peak memory of a call, measured in a child process (clean peak RSS)."""

from __future__ import annotations

import multiprocessing as mp
import resource
import time
from collections.abc import Callable
from typing import Any


def _child(fn: Callable[[], Any], queue: Any) -> None:
    t0 = time.perf_counter()
    extra = fn()
    wall = time.perf_counter() - t0
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    queue.put((wall, peak_mb, extra))


def measure(fn: Callable[[], Any]) -> tuple[float, float, Any]:
    """Run ``fn`` in a fresh process; return ``(wall_s, peak_rss_mb, fn's return value)``.

    ``fn`` must be a module-level function (picklable under the 'fork' start method too).
    """
    ctx = mp.get_context("fork")
    queue = ctx.Queue()
    proc = ctx.Process(target=_child, args=(fn, queue))
    proc.start()
    result = queue.get()
    proc.join()
    return result
