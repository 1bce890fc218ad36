"""Every valid configuration builds (issue 13 part 1): property tests over sizes, posts, seeds,
crater ranges, ages and DEM crops, plus the exact regression cases that crashed in stamping."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import marsscene as ms
from marsscene.craters import CraterTable, stamp_craters
from marsscene.errors import MarsSceneError
from marsscene.terrain.heightfield import Heightfield

_FAST = {"rocks": {"enabled": False}, "lighting": {"enabled": False}}
_SETTINGS = settings(max_examples=40, deadline=None, derandomize=True,
                     suppress_health_check=[HealthCheck.too_slow])


def _procedural(size_m: float, post_m: float, craters: dict[str, object]) -> ms.SceneConfig:
    return ms.SceneConfig.from_dict({
        "terrain": {"source": "procedural", "size_m": [size_m, size_m], "post_m": post_m},
        "craters": craters, **_FAST,
    })


@pytest.mark.parametrize(("size_m", "seed"), [(200.0, 1), (292.55066452312906, 28),
                                              (109.31283390419827, 36)])
def test_regression_builds_that_crashed_in_stamping(size_m: float, seed: int) -> None:
    scene = ms.build_scene(_procedural(size_m, 0.25, {}), seed=seed)
    assert np.isfinite(scene.heightfield.z_m).all()
    assert len(scene.craters) > 0


@pytest.mark.parametrize("offset_m", [-9.7, -6.1, -3.3, 3.3, 6.1, 9.7, 10.4])
@pytest.mark.parametrize("diameter_m", [2.0, 4.5, 7.0])
def test_crater_centred_outside_equals_the_same_window_of_a_larger_grid(
    offset_m: float, diameter_m: float
) -> None:
    """On flat ground a crater stamped near or beyond the grid edge leaves the same heights as
    the matching window of a grid that contains it (the batched box holds the footprint)."""
    cs, n, big = 0.25, 41, 201
    small = Heightfield.centered(np.zeros((n, n), np.float32), cs)
    large = Heightfield.centered(np.zeros((big, big), np.float32), cs)
    x = small.bounds_xy_m[2] + offset_m  # east of the small grid's east edge (or inside it)
    t = CraterTable(np.array([[x, 1.3]]), [diameter_m], [0.15 * diameter_m],
                    [0.036 * diameter_m], [0.0], [0])
    a = stamp_craters(small, t).z_m
    b = stamp_craters(large, t).z_m
    r0 = c0 = (big - n) // 2
    np.testing.assert_allclose(a, b[r0:r0 + n, c0:c0 + n], atol=1e-5)


@_SETTINGS
@given(
    size_m=st.floats(20.0, 340.0),
    post_m=st.sampled_from([0.2, 0.25, 0.5, 1.0]),
    seed=st.integers(0, 2**31 - 1),
    d_min_m=st.floats(0.5, 8.0),
    span=st.floats(1.5, 40.0),
    age_ga=st.floats(0.01, 4.5),
    profile=st.sampled_from(["watters-2015", "fassett-thomson-2014", "ftmod"]),
    axis_ratio_min=st.sampled_from([1.0, 0.6]),
)
def test_any_valid_procedural_configuration_builds(
    size_m: float, post_m: float, seed: int, d_min_m: float, span: float, age_ga: float,
    profile: str, axis_ratio_min: float,
) -> None:
    craters = {"d_min_m": d_min_m, "d_max_m": d_min_m * span, "age_ga": age_ga,
               "profile": profile, "axis_ratio_min": axis_ratio_min}
    scene = ms.build_scene(_procedural(size_m, post_m, craters), seed=seed)
    z = scene.heightfield.z_m
    assert np.isfinite(z).all()
    # the stamped relief is bounded by the largest crater's depth + rim (plus the terrain)
    assert float(np.ptp(z)) < 60.0 + 0.6 * craters["d_max_m"]  # type: ignore[operator]


@_SETTINGS
@given(
    row=st.integers(0, 1300), col=st.integers(0, 1300),
    rows=st.integers(2, 260), cols=st.integers(2, 260),
    post_m=st.sampled_from([None, 0.25, 0.5, 2.0]),
    seed=st.integers(0, 2**31 - 1),
)
def test_any_crop_of_the_bundled_dem_builds_or_says_why(
    row: int, col: int, rows: int, cols: int, post_m: float | None, seed: int
) -> None:
    terrain: dict[str, object] = {"source": "default", "crop_px": [row, col, rows, cols]}
    if post_m is not None:
        terrain["post_m"] = post_m
    cfg = ms.SceneConfig.from_dict({"terrain": terrain, "craters": {"d_min_m": 1.0}, **_FAST})
    try:
        scene = ms.build_scene(cfg, seed=seed)
    except MarsSceneError as err:  # e.g. a crop outside the DEM: a one-line reason
        assert "\n" not in str(err) and "np." not in str(err)
        return
    assert np.isfinite(scene.heightfield.z_m).all()


_VALUES = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10, 10**7),
                    st.text(max_size=5), st.booleans(), st.none(),
                    st.lists(st.floats(-1e3, 1e3), max_size=3))


@settings(max_examples=60, deadline=None, derandomize=True)
@given(key=st.sampled_from(["d_min_m", "d_max_m", "age_ga", "system", "profile",
                            "depth_to_diameter", "rim_height_to_diameter", "axis_ratio_min",
                            "diffusivity_m2_per_myr", "equilibrium", "degradation",
                            "ejecta_reach", "no_such_key"]),
       value=_VALUES)
def test_any_crater_config_value_is_accepted_or_rejected_in_one_line(
    key: str, value: object
) -> None:
    try:
        cfg = ms.SceneConfig.from_dict({
            "terrain": {"source": "procedural", "size_m": [30.0, 30.0]},
            "craters": {key: value}, **_FAST})
    except MarsSceneError as err:
        assert "\n" not in str(err) and "np.float" not in str(err)
        return
    ms.build_scene(cfg, seed=0)
