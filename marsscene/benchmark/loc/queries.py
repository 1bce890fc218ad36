"""Query places and dead-reckoning priors, seeded (pure).

A scene's queries lie at arc lengths drawn uniformly along its route (after the first short
drive's length, so every query has its drive); each query's prior is the truth moved by a
distance drawn uniformly in ``prior.position_error_m`` in a uniform direction, and turned by a
heading error uniform in +- ``prior.heading_error_deg``: what dead reckoning gives after an
unknown drive (no GNSS). Both come from the stream ``SeedSequence(seed, spawn_key=(LOC_STAGE,
crc32(scene name)))``: the same queries and priors for every tau and method, a different draw per
scene.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["LOC_STAGE", "Prior", "draw_priors", "query_arc_lengths", "query_rng",
           "segment_before"]

#: Spawn key of the benchmark's own stream (outside the scene build's stage ids).
LOC_STAGE = 67


def query_rng(seed: int, scene: str) -> np.random.Generator:
    """The stream of a scene's query places and priors."""
    key = (LOC_STAGE, zlib.crc32(scene.encode("utf-8")))
    return np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=key))


def query_arc_lengths(route_length_m: float, n: int, drive_m: float, *,
                      rng: np.random.Generator) -> NDArray[np.float64]:
    """``n`` sorted arc lengths uniform in ``[drive_m + 1, route_length_m - 1]`` (in m)."""
    lo, hi = drive_m + 1.0, route_length_m - 1.0
    if hi <= lo:
        from marsscene.errors import ConfigError

        raise ConfigError(f"the route ({route_length_m:.1f} m) is shorter than a query's drive "
                          f"({drive_m:.1f} m) plus 2 m; lengthen route.length_m")
    return np.sort(rng.uniform(lo, hi, n))


@dataclass(frozen=True)
class Prior:
    """A prior's error: horizontal offset (m) and heading offset (rad) from the truth."""

    dx_m: float
    dy_m: float
    dyaw_rad: float

    @property
    def distance_m(self) -> float:
        return math.hypot(self.dx_m, self.dy_m)


def draw_priors(n: int, position_error_m: tuple[float, float], heading_error_deg: float, *,
                rng: np.random.Generator) -> list[Prior]:
    """``n`` prior errors: distance uniform in the range, direction uniform, heading uniform in
    +- ``heading_error_deg``."""
    d = rng.uniform(position_error_m[0], position_error_m[1], n)
    a = rng.uniform(-math.pi, math.pi, n)
    h = np.radians(rng.uniform(-heading_error_deg, heading_error_deg, n))
    return [Prior(float(d[i] * math.cos(a[i])), float(d[i] * math.sin(a[i])), float(h[i]))
            for i in range(n)]


def segment_before(xy_m: NDArray[np.float64], s_end_m: float, length_m: float
                   ) -> NDArray[np.float64]:
    """The route's points from arc length ``s_end_m - length_m`` to ``s_end_m`` (ends
    interpolated): the short drive that ends at a query place."""
    seg = np.linalg.norm(np.diff(xy_m, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    s0 = max(s_end_m - length_m, 0.0)
    inner = (s > s0) & (s < s_end_m)
    at = [np.interp(s0, s, xy_m[:, k]) for k in (0, 1)], \
        [np.interp(s_end_m, s, xy_m[:, k]) for k in (0, 1)]
    return np.vstack([np.asarray(at[0])[None], xy_m[inner], np.asarray(at[1])[None]])
