"""Cross-track error: the k-d tree's candidate segments give the brute-force distance exactly."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from marsscene.sim.cross_track import _to_all_segments_m, cross_track_m
from marsscene.sim.route import Route


def _brute_m(vertices: np.ndarray, xy: np.ndarray) -> np.ndarray:
    return _to_all_segments_m(xy, vertices[:-1], np.diff(vertices, axis=0))


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n_vertices=st.integers(2, 400),
       long_leg=st.booleans(), spread_m=st.floats(0.01, 50.0))
def test_cross_track_equals_brute_force(seed: int, n_vertices: int, long_leg: bool,
                                        spread_m: float) -> None:
    """Random walks of short steps (a resampled route), some with one long leg (sparse
    waypoints) and repeated vertices, and points near and far from them."""
    rng = np.random.default_rng(seed)
    steps = rng.normal(0.0, 0.1, (n_vertices - 1, 2))
    if long_leg:
        steps[rng.integers(len(steps))] = rng.normal(0.0, 30.0, 2)
        steps[rng.integers(len(steps))] = 0.0  # a zero-length segment
    vertices = np.vstack([[0.0, 0.0], np.cumsum(steps, axis=0)])
    xy = vertices[rng.integers(n_vertices, size=300)] + rng.normal(0.0, spread_m, (300, 2))
    got = cross_track_m(Route(vertices), xy)
    np.testing.assert_allclose(got, _brute_m(vertices, xy), rtol=0, atol=1e-12)


def test_cross_track_of_a_loop_back_route() -> None:
    """An out-and-back route whose lanes lie 0.3 m apart: a point between the lanes is measured
    to the nearer one, also where the farther lane's vertices are nearer to it."""
    x = np.arange(0.0, 100.0, 0.1)
    vertices = np.vstack([np.column_stack([x, np.zeros_like(x)]),
                          np.column_stack([x[::-1], np.full_like(x, 0.3)])])
    got = cross_track_m(Route(vertices), [[50.05, 0.1], [50.0, 0.2], [-1.0, 0.0]])
    np.testing.assert_allclose(got, [0.1, 0.1, 1.0], atol=1e-12)
