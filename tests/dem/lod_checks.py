"""Shared check of a two-level terrain's outer level against a reference grid."""

from __future__ import annotations

from typing import Any

import numpy as np


def assert_outer_matches(outer: Any, ref: np.ndarray, post_m: float, min_kept: int) -> None:
    """The outer level equals ``ref`` (south-up rows, datum removed) to 2 mm at every post
    beyond the blend band (8 m + one outer post outside the focus square)."""
    xs, ys = outer.heightfield.grid_xy()
    fx0, fy0, fx1, fy1 = outer.focus_bounds_xy_m
    dist = np.maximum.outer(np.maximum(fy0 - ys, ys - fy1), np.maximum(fx0 - xs, xs - fx1))
    keep = dist > 8.0 + post_m  # beyond the blend band
    assert keep.sum() > min_kept
    np.testing.assert_allclose(outer.heightfield.z_m[keep], ref[keep], atol=2e-3)
