"""The cross-track error of a long drive's summary: k-d tree candidates against every segment.

Run: ``python perf/run.py cross_track [--route-m M]`` (full: 631 m, the grand-canyon route).
An out-and-back route resampled every 0.1 m with lanes 20 m apart, and a drive along it at
0.5 m/s logged at 50 Hz, 2 cm off the route: the poses a drive's summary measures. Printed: the
sizes, both methods' seconds and their largest difference (0: both are exact).
"""

from __future__ import annotations

import time

import numpy as np

from marsscene.sim.cross_track import _to_all_segments_m, cross_track_m
from marsscene.sim.route import Route
from perf.suite import Param

PARAMS = (Param("route_m", float, "length of the out-and-back route (m)", quick=100.0,
                full=631.0),)


def out_and_back(route_m: float, spacing_m: float = 0.1) -> np.ndarray:
    """A lane out along +x, a half-circle of 10 m radius, and a lane back 20 m to the side."""
    leg_m = (route_m - np.pi * 10.0) / 2.0
    x = np.arange(0.0, leg_m, spacing_m)
    turn = np.linspace(-np.pi / 2, np.pi / 2, int(np.pi * 10.0 / spacing_m))
    return np.vstack([np.column_stack([x, np.zeros_like(x)]),
                      np.column_stack([leg_m + 10.0 * np.cos(turn), 10.0 + 10.0 * np.sin(turn)]),
                      np.column_stack([x[::-1], np.full_like(x, 20.0)])])


def main(route_m: float) -> dict[str, float]:
    vertices = out_and_back(route_m)
    seg = np.linalg.norm(np.diff(vertices, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    poses = int(s[-1] / 0.5 * 50)
    at = np.linspace(0.0, s[-1], poses)
    xy = np.column_stack([np.interp(at, s, vertices[:, 0]), np.interp(at, s, vertices[:, 1])])
    xy += np.random.default_rng(0).normal(0.0, 0.02, xy.shape)
    t0 = time.perf_counter()
    fast = cross_track_m(Route(vertices), xy)
    t_fast = time.perf_counter() - t0
    t0 = time.perf_counter()
    brute = _to_all_segments_m(xy, vertices[:-1], np.diff(vertices, axis=0))
    t_brute = time.perf_counter() - t0
    print(f"route {s[-1]:.0f} m, {len(vertices) - 1:,} segments; {poses:,} poses")
    print(f"k-d tree candidates: {t_fast:.3f} s   every segment: {t_brute:.1f} s   "
          f"({t_brute / t_fast:.0f}x)   largest difference {np.abs(fast - brute).max():.1e} m")
    return {"route_m": float(s[-1]), "segments": len(vertices) - 1, "poses": poses,
            "kdtree_s": t_fast, "every_segment_s": t_brute,
            "largest_difference_m": float(np.abs(fast - brute).max())}

