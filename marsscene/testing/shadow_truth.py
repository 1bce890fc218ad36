"""A penumbra-aware truth for terrain shadows, independent of the renderer: the terrain's
horizon toward the sun by a ray march over the heightfield, and the visible share of the sun's
disc above it. ``tests/sensors/test_camera_low_sun.py`` judges rendered frames with it and
``perf/fidelity/bench_shadow_accuracy.py`` prints how far they are from it. Core dependencies
only."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from marsscene.terrain.heightfield import Heightfield

__all__ = ["disc_visible", "horizon_excess_deg"]


def horizon_excess_deg(hf: Heightfield, p: NDArray[np.float64], sun: NDArray[np.float64], *,
                       step_m: float = 0.05, growth: float = 0.01,
                       reach_m: float = 100.0) -> NDArray[np.float64]:
    """Largest elevation of the terrain seen from points ``p`` (N, 3, on the heightfield's
    surface) toward the sun's azimuth, minus the sun's elevation (deg): a ray march in steps of
    ``step_m`` growing by ``growth`` of the distance, to ``reach_m``."""
    flat = sun[:2] / np.hypot(sun[0], sun[1])
    elevation = math.degrees(math.atan2(sun[2], math.hypot(sun[0], sun[1])))
    z0 = hf.sample(p[:, 0], p[:, 1])
    best = np.full(len(p), -90.0)
    t = step_m
    while t < reach_m:
        x, y = p[:, 0] + t * flat[0], p[:, 1] + t * flat[1]
        inside = hf.contains(x, y)
        angle = np.degrees(np.arctan2(hf.sample(x, y) - z0, t))
        best = np.where(inside, np.maximum(best, angle), best)
        t += max(step_m, growth * t)
    return np.asarray(best - elevation)


def disc_visible(excess_deg: NDArray[np.float64], radius_deg: float) -> NDArray[np.float64]:
    """Visible fraction of a uniform disc of ``radius_deg`` above a straight horizon
    ``excess_deg`` above its centre (a circular segment)."""
    t = np.clip(excess_deg / radius_deg, -1.0, 1.0)
    return np.asarray((np.arccos(t) - t * np.sqrt(1.0 - t * t)) / math.pi)
