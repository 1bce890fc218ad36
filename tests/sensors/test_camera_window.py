"""The camera's far terrain window follows the camera up to the heightfield's edge.

Regression: with a 240 m window on a 1000 m scene the window was re-placed only once its
*clamped* origin had moved ``step`` posts; near the east edge the clamped origin moves less than
the camera, the window stayed put and the camera drove out of it (featureless frames).
Regression 2: the fix for that re-placed the window at every post the camera moved along the
edge (the clamped axis's distance counted), re-baking a 240 m texture every half metre: the
full-size VPR route ran eight times slower once its window reached the scene's east edge.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from marsscene.sensors.camera_ground import far_window_bounds, window_posts
from marsscene.terrain.heightfield import Heightfield


def _check_window_follows(hf: Heightfield, window_m: float, xy: np.ndarray) -> None:
    _, nr, nc, step = window_posts(hf, window_m)
    cell = hf.cell_size_m
    (ax, ay), (bx, by) = hf.xy_of(0, 0), hf.xy_of(hf.shape[0] - 1, hf.shape[1] - 1)
    hf_lo, hf_hi = np.minimum([ax, ay], [bx, by]), np.maximum([ax, ay], [bx, by])
    bounds = far_window_bounds(hf, window_m, xy)
    half = np.array([(nc - 1) / 2, (nr - 1) / 2]) * cell
    margin = half - (step + 1) * cell  # how close the camera may come to a movable window edge
    for p, b in zip(xy, bounds, strict=True):
        lo, hi = b[:2], b[2:]
        # on each side: the window's edge keeps its margin, or it is the heightfield's edge
        assert np.all((p - lo >= margin - 1e-9) | (np.abs(lo - hf_lo) < 1e-9)), (p, b)
        assert np.all((hi - p >= margin - 1e-9) | (np.abs(hi - hf_hi) < 1e-9)), (p, b)
        assert np.all(p >= lo - 1e-9) and np.all(p <= hi + 1e-9), (p, b)
    # each re-place needs the camera to move `step` posts (rounded to posts: step - 1 at least)
    moved_posts = float(np.abs(np.diff(xy, axis=0)).max(axis=1, initial=0.0).sum()) / cell
    replaced = int(np.any(np.diff(bounds, axis=0) != 0, axis=1).sum())
    if step >= 2:
        assert replaced <= moved_posts / (step - 1) + 1e-9, (replaced, moved_posts, step)


def test_240m_window_follows_to_the_scene_edge() -> None:
    """The failing case: mars-base's 1000 m, 0.5 m heightfield, the VPR route's east end."""
    hf = Heightfield(np.zeros((2001, 2001), np.float32), 0.5, (-500.0, -500.0))
    x = np.arange(280.0, 475.0, 0.1)
    xy = np.stack([x, np.full_like(x, -209.0)], axis=-1)
    _check_window_follows(hf, 240.0, xy)
    # ... and the window is still re-placed only rarely (each re-place re-bakes its texture)
    bounds = far_window_bounds(hf, 240.0, xy)
    assert len({tuple(b) for b in bounds}) <= 5


def test_240m_window_moves_rarely_along_the_scene_edge() -> None:
    """The route's east end as driven: along the edge with the lane's wobble of a few posts
    across it, out and back 30 m over."""
    hf = Heightfield(np.zeros((2001, 2001), np.float32), 0.5, (-500.0, -500.0))
    x = np.arange(380.0, 475.0, 0.1)
    wobble = 1.5 * np.sin(x / 3.0)
    out = np.stack([x, -209.0 + wobble], axis=-1)
    back = np.stack([x[::-1], -179.0 + wobble[::-1]], axis=-1)
    xy = np.concatenate([out, back])
    _check_window_follows(hf, 240.0, xy)
    bounds = far_window_bounds(hf, 240.0, xy)
    assert len({tuple(b) for b in bounds}) <= 3


@settings(max_examples=60, deadline=None)
@given(
    size_posts=st.integers(41, 801),
    cell_m=st.sampled_from([0.25, 0.5, 1.0]),
    window_frac=st.floats(0.1, 1.5),
    start=st.tuples(st.floats(0.0, 1.0), st.floats(0.0, 1.0)),
    heading_rad=st.floats(-np.pi, np.pi),
    step_frac=st.floats(0.001, 0.02),
)
def test_window_follows_any_path(size_posts, cell_m, window_frac, start, heading_rad,
                                 step_frac) -> None:
    """Any straight drive across any heightfield, window size and frame spacing."""
    hf = Heightfield(np.zeros((size_posts, size_posts), np.float32), cell_m)
    (ax, ay), (bx, by) = hf.xy_of(0, 0), hf.xy_of(size_posts - 1, size_posts - 1)
    lo, hi = np.minimum([ax, ay], [bx, by]), np.maximum([ax, ay], [bx, by])
    side = float(hi[0] - lo[0])
    p0 = lo + np.asarray(start) * (hi - lo)
    d = np.array([np.cos(heading_rad), np.sin(heading_rad)])
    t = np.arange(0.0, 2.0 * side, step_frac * side)
    xy = np.clip(p0 + t[:, None] * d, lo, hi)
    _check_window_follows(hf, window_frac * side, xy)
