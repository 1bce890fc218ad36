"""A progress line for long drives: distance, simulated time, real-time factor and an ETA.

On a terminal the line is redrawn in place once per simulated second; in a log file (stderr not
a terminal) a line is printed once a minute of wall time, so CI logs and ``nohup`` files stay
short.
"""

from __future__ import annotations

import sys
import time
from contextlib import ExitStack
from typing import Any, TextIO

import click

__all__ = ["DriveMeter", "ProgressBar", "format_eta"]


def format_eta(seconds: float) -> str:
    """``1 h 02 min``, ``7 min 05 s`` or ``42 s``."""
    s = max(0, round(seconds))
    if s >= 3600:
        return f"{s // 3600} h {s % 3600 // 60:02d} min"
    if s >= 60:
        return f"{s // 60} min {s % 60:02d} s"
    return f"{s} s"


class DriveMeter:
    """Call with each :class:`~marsscene.sim.driver.DriveProgress`; :meth:`close` at the end."""

    def __init__(self, stream: TextIO | None = None, *, log_every_s: float = 60.0,
                 clock: Any = time.monotonic) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.clock, self.log_every_s = clock, log_every_s
        self.t0 = clock()
        self._last_log = self.t0
        self._width = 0

    def line(self, p: Any) -> str:
        wall = max(self.clock() - self.t0, 1e-9)
        f = p.fraction
        where = (f"{p.route_done_m:.1f} of {p.route_length_m:.1f} m" if p.route_length_m
                 else f"{p.distance_m:.1f} m")
        eta = format_eta(wall * (1.0 - f) / f) if f > 1e-3 else "--"
        return (f"driving: {where} ({100 * f:.0f}%) | sim {p.sim_time_s:.0f} s | "
                f"{p.sim_time_s / wall:.2f}x real time | ETA {eta}")

    def __call__(self, p: Any) -> None:
        now = self.clock()
        if self.tty:
            text = self.line(p)
            self.stream.write("\r" + text.ljust(self._width))
            self._width = len(text)
            self.stream.flush()
        elif now - self._last_log >= self.log_every_s:
            self._last_log = now
            self.stream.write(self.line(p) + "\n")
            self.stream.flush()

    def close(self) -> None:
        if self.tty and self._width:
            self.stream.write("\n")
            self.stream.flush()


class ProgressBar:
    """``progress(done, total)`` as a click progress bar on stderr, started at the first call
    (once the work's input proved valid)."""

    def __init__(self, stack: ExitStack, label: str) -> None:
        self.stack, self.label = stack, label
        self.bar: Any = None

    def __call__(self, done: int, total: int) -> None:
        if self.bar is None:
            self.bar = self.stack.enter_context(click.progressbar(
                length=total, label=self.label, file=sys.stderr))
        self.bar.update(done - self.bar.pos)
