"""Every valid level-of-detail configuration builds, or fails with a one-line error: property
tests over footprints, posts, focus squares, tiles, seeds and crater ranges (issue 15)."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import marsscene as ms
from marsscene.errors import MarsSceneError

_SETTINGS = settings(max_examples=30, deadline=None, derandomize=True,
                     suppress_health_check=[HealthCheck.too_slow])


@_SETTINGS
@given(
    size_m=st.floats(30.0, 260.0),
    post_m=st.sampled_from([0.5, 1.0, 2.0]),
    focus_post_m=st.sampled_from([0.25, 0.5]),
    focus_frac=st.floats(0.05, 0.8),
    focus_uv=st.tuples(st.floats(-1.0, 1.0), st.floats(-1.0, 1.0)),
    tile_m=st.floats(2.0, 200.0),
    seed=st.integers(0, 2**31 - 1),
    craters=st.booleans(),
    rocks=st.booleans(),
)
def test_any_lod_configuration_builds_or_gives_a_one_line_error(
        size_m: float, post_m: float, focus_post_m: float, focus_frac: float,
        focus_uv: tuple[float, float], tile_m: float, seed: int, craters: bool,
        rocks: bool) -> None:
    # the focus centre anywhere its square fits, up to its edge (|u|, |v| = 1: on the border)
    room = (1.0 - focus_frac) * size_m / 2.0
    focus_xy = [focus_uv[0] * room, focus_uv[1] * room]
    cfg = {"terrain": {"source": "procedural", "size_m": [size_m, size_m], "post_m": post_m,
                       "lod": True, "focus_post_m": focus_post_m,
                       "focus_size_m": focus_frac * size_m, "focus_xy_m": focus_xy,
                       "tile_m": tile_m, "lod_blend_m": 10.0},
           "craters": {"enabled": craters, "d_min_m": 1.0, "d_max_m": 30.0},
           "rocks": {"enabled": rocks, "d_min_m": 0.5, "outer_d_min_m": 1.0},
           "lighting": {"enabled": False}}
    try:
        scene = ms.build_scene(ms.SceneConfig.from_dict(cfg), seed=seed)
    except MarsSceneError as err:
        assert "\n" not in str(err)
        assert "focus square" in str(err) or "whole multiple" in str(err)
        return
    fine, outer = scene.heightfield, scene.outer
    assert outer is not None and np.isfinite(fine.z_m).all()
    assert np.isfinite(outer.heightfield.z_m).all()
    lod = scene.provenance.extra["lod"]
    n = lod["focus_tiles"][0]
    assert n >= 1 and lod["focus_tile_m"] * (n - 1) < fine.size_m[0] + 1e-9
    # the outer grid equals the focus on every shared post (no seam)
    k = round(post_m / focus_post_m)
    x0, y0, x1, y1 = fine.bounds_xy_m
    xs, ys = outer.heightfield.grid_xy()
    cols = np.flatnonzero((xs >= x0 - 1e-9) & (xs <= x1 + 1e-9))
    rows = np.flatnonzero((ys >= y0 - 1e-9) & (ys <= y1 + 1e-9))
    np.testing.assert_array_equal(outer.heightfield.z_m[np.ix_(rows, cols)], fine.z_m[::k, ::k])
    if scene.rocks is not None and len(scene.rocks):
        assert np.isfinite(scene.rocks.position_xyz_m).all()


@settings(max_examples=12, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(
    post_m=st.sampled_from([None, 1.0, 2.0, 3.0, 4.0]),
    focus_size_m=st.floats(10.0, 320.0),
    focus_uv=st.tuples(st.floats(-1.0, 1.0), st.floats(-1.0, 1.0)),
    tile_m=st.floats(5.0, 300.0),
    seed=st.integers(0, 2**31 - 1),
)
def test_any_lod_configuration_on_the_bundled_dtm_builds_or_gives_a_one_line_error(
        post_m: float | None, focus_size_m: float, focus_uv: tuple[float, float], tile_m: float,
        seed: int) -> None:
    """The bundled Gale DTM (1 m posts): the outer level at its posts or read averaged to
    ``post_m``, the focus from its own posts (the crop is 347 m x 336 m)."""
    room = max(330.0 - focus_size_m, 0.0) / 2.0
    cfg = {"terrain": {"lod": True, "post_m": post_m, "focus_size_m": focus_size_m,
                       "focus_xy_m": [focus_uv[0] * room, focus_uv[1] * room],
                       "tile_m": tile_m, "lod_blend_m": 10.0},
           "craters": {"enabled": False}, "rocks": {"enabled": False},
           "lighting": {"enabled": False}}
    try:
        scene = ms.build_scene(ms.SceneConfig.from_dict(cfg), seed=seed)
    except MarsSceneError as err:
        assert "\n" not in str(err) and "focus square" in str(err)
        return
    assert scene.outer is not None and np.isfinite(scene.heightfield.z_m).all()
    assert scene.outer.heightfield.cell_size_m == (post_m or 1.0)
    assert scene.heightfield.cell_size_m == 0.25
