"""Cross-track error: each point's distance to a route polyline.

A drive's summary measures it on every ground-truth pose (a 631 m route has about 6,300
segments, a 21-minute drive 64,000 poses at 50 Hz), so each point is measured exactly against
its nearest segments only: the segments whose midpoints are nearest (a k-d tree). A segment
outside those lies no nearer than the farthest candidate's midpoint distance less the longest
half-segment, so the answer is exact wherever the nearest candidate is inside that bound; the
few points where it is not are measured against every segment.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

__all__ = ["cross_track_m"]


class _Polyline(Protocol):
    """A route: its vertices ``xy_m`` (N, 2) in m (:class:`marsscene.sim.route.Route`)."""

    @property
    def xy_m(self) -> NDArray[np.float64]: ...

_CANDIDATES = 8  # nearest segment midpoints measured exactly for each point
_CHUNK = 256  # points a chunk against every segment (memory: chunk x segments)


def _to_segments_m(p: NDArray[np.float64], a: NDArray[np.float64],
                   ab: NDArray[np.float64]) -> NDArray[np.float64]:
    """Distances (in m) from points ``p`` (..., 1 or K, 2) to segments ``a + t ab``, t in [0, 1]."""
    denom = np.maximum((ab**2).sum(-1), 1e-12)
    t = np.clip(((p - a) * ab).sum(-1) / denom, 0.0, 1.0)
    return np.linalg.norm(p - (a + t[..., None] * ab), axis=-1)


def _to_all_segments_m(p: NDArray[np.float64], a: NDArray[np.float64],
                       ab: NDArray[np.float64]) -> NDArray[np.float64]:
    """The distance (in m) from each point (M, 2) to its nearest segment, by brute force."""
    out = np.zeros(len(p))
    for k in range(0, len(p), _CHUNK):
        out[k : k + _CHUNK] = _to_segments_m(p[k : k + _CHUNK, None, :], a, ab).min(axis=1)
    return out


def cross_track_m(route: _Polyline, xy: ArrayLike) -> NDArray[np.float64]:
    """Distance (in m) from each point (M, 2) to the route polyline."""
    p = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    vertices = np.asarray(route.xy_m, dtype=np.float64).reshape(-1, 2)
    if len(vertices) < 2:
        return np.linalg.norm(p - vertices[:1], axis=1)
    a, ab = vertices[:-1], np.diff(vertices, axis=0)
    if len(a) <= _CANDIDATES or len(p) == 0:
        return _to_all_segments_m(p, a, ab)
    mid_dist, idx = cKDTree(a + 0.5 * ab).query(p, k=_CANDIDATES)
    best = _to_segments_m(p[:, None, :], a[idx], ab[idx]).min(axis=1)
    longest_half_m = 0.5 * float(np.sqrt((ab**2).sum(1).max()))
    unsure = best > mid_dist[:, -1] - longest_half_m  # a segment outside might be nearer
    if unsure.any():
        best[unsure] = _to_all_segments_m(p[unsure], a, ab)
    return best
