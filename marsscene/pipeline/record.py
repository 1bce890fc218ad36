"""What a build records beside the scene: per-stage timings, the models used (with their
citations), notes (rules applied, warnings) and stage summaries (all go to the manifest)."""

from __future__ import annotations

import logging
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

from marsscene.scene import ModelRef

__all__ = ["BuildRecord"]

log = logging.getLogger("marsscene")


@dataclass
class BuildRecord:
    """Filled in stage by stage by :func:`marsscene.build_scene`."""

    models: list[ModelRef] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    summary: dict[str, object] = field(default_factory=dict)
    timings_s: dict[str, float] = field(default_factory=dict)

    @contextmanager
    def stage(self, name: str) -> Iterator[None]:
        """Time a stage (logged at INFO, rounded to 0.1 ms in the manifest)."""
        log.info("[%s] ...", name)
        t0 = time.perf_counter()
        yield
        dt = time.perf_counter() - t0
        self.timings_s[name] = round(dt, 4)
        log.info("[%s] done in %.2f s", name, dt)
