"""Terrain shadows toward the sun over a whole heightfield (``marsscene.terrain.horizon``)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from marsscene.terrain.heightfield import Heightfield
from marsscene.terrain.horizon import SUN_RADIUS_RAD, sun_shadow, sun_visibility


def _sun(azimuth_deg: float, elevation_deg: float) -> tuple[float, float, float]:
    az, el = math.radians(azimuth_deg), math.radians(elevation_deg)
    return (math.sin(az) * math.cos(el), math.cos(az) * math.cos(el), math.sin(el))


def test_a_wall_casts_its_shadow_length() -> None:
    """A 1 m wall (x = 5 m) under a sun in the east at 5 deg: 11.4 m of shadow west of it."""
    z = np.zeros((81, 161), np.float32)
    hf = Heightfield.centered(z, 0.25)  # x from -20 to 20 m
    x = hf.grid_xy()[0]
    z[:, np.abs(x - 5.0) < 0.01] = 1.0
    shadow = sun_shadow(Heightfield.centered(z, 0.25), _sun(90.0, 5.0))
    length = 1.0 / math.tan(math.radians(5.0))
    vis = shadow.visibility()[40]
    behind = x[(vis < 0.5) & (x < 5.0)]
    assert abs((5.0 - behind.min()) - length) < 0.3, (behind.min(), length)
    assert np.all(vis[x > 5.1] == 1.0)  # toward the sun: lit
    assert np.all(vis[x < 5.0 - length - 1.0] == 1.0)  # beyond the shadow: lit
    d = shadow.distance_m[40][(x < 4.9) & (x > 5.0 - length + 1.0)]
    np.testing.assert_allclose(d, 5.0 - x[(x < 4.9) & (x > 5.0 - length + 1.0)], atol=0.26)


@pytest.mark.parametrize("azimuth_deg", [35.0, 160.0, 250.0])
def test_matches_a_ray_march_at_any_azimuth(azimuth_deg: float) -> None:
    from scipy.ndimage import gaussian_filter

    rng = np.random.default_rng(3)
    z = gaussian_filter(rng.standard_normal((161, 201)), 4.0)
    z = (z * (0.6 / z.std())).astype(np.float32)
    hf = Heightfield.centered(z, 0.25)
    sun = _sun(azimuth_deg, 4.0)
    shadow = sun_shadow(hf, sun)
    r = rng.integers(4, 157, 600)  # a metre inside the edges
    c = rng.integers(4, 197, 600)
    x, y = hf.xy_of(r, c)
    flat = np.array(sun[:2]) / math.hypot(sun[0], sun[1])
    tan_e = math.tan(math.radians(4.0))
    above = np.full(r.size, -np.inf)  # brute force, every 5 cm toward the sun: the terrain's
    for t in np.arange(0.05, 60.0, 0.05):  # largest height above the ray to the sun (m)
        px, py = x + t * flat[0], y + t * flat[1]
        rise = hf.sample(px, py) - z[r, c] - t * tan_e
        above = np.where(hf.contains(px, py), np.maximum(above, rise), above)
    vis = shadow.visibility()[r, c]
    clear = np.abs(above) > 0.02  # beyond the two bilinear resamplings' error (2 cm)
    assert clear.sum() > 400 and (above[clear] > 0).sum() > 50
    agree = (vis[clear] < 0.5) == (above[clear] > 0)
    assert agree.mean() >= 0.99, agree.mean()


def test_visibility_of_the_sun_disc() -> None:
    d = 100.0  # occluder distance (m): the sun's disc spans +-d tan(radius) of height
    half = d * math.tan(SUN_RADIUS_RAD) + 0.01
    vis = sun_visibility(np.array([-2 * half, -half, 0.0, half, 2 * half]), np.full(5, d))
    np.testing.assert_allclose(vis, [1.0, 1.0, 0.5, 0.0, 0.0], atol=1e-6)
    ramp = sun_visibility(np.linspace(-half, half, 50), np.full(50, d))
    assert np.all(np.diff(ramp) <= 0)


def test_no_shadows_from_the_zenith_and_points_above_are_lit() -> None:
    rng = np.random.default_rng(1)
    hf = Heightfield.centered(rng.standard_normal((40, 40)).astype(np.float32), 0.25)
    assert np.all(sun_shadow(hf, (0.0, 0.0, 1.0)).visibility() == 1.0)
    shadow = sun_shadow(hf, _sun(120.0, 1.0))
    assert shadow.visibility().min() == 0.0  # rough ground at 1 deg: shadows
    x, y = hf.xy_of(np.arange(40), np.arange(40))
    high = shadow.visibility_at(x, y, hf.sample(x, y) + 50.0)
    np.testing.assert_array_equal(high, 1.0)
    a = sun_shadow(hf, _sun(120.0, 1.0))
    np.testing.assert_array_equal(a.depth_m, shadow.depth_m)  # deterministic


def test_outer_terrain_of_a_level_of_detail_scene_casts_into_the_focus() -> None:
    """A 10 m wall 30-40 m east, on the coarse outer grid only (the outer's focus square is
    lowered under the focus terrain), shadows the whole focus at a 10 deg sun from the east
    (shadow 57 m long) and none of it at 30 deg (17 m)."""
    from marsscene.terrain.horizon import shadow_with_outer

    focus = Heightfield.centered(np.zeros((81, 81), np.float32), 0.25)  # 20 m square
    z = np.zeros((101, 101), np.float32)  # 100 m at 1 m posts
    x = (np.arange(101) - 50.0)[None, :] + 0 * (np.arange(101)[:, None])
    z[(x >= 30.0) & (x <= 40.0)] = 10.0
    z[40:61, 40:61] = -5.0  # the lowered focus square
    outer = Heightfield.centered(z, 1.0)
    for elevation, shadowed in ((10.0, True), (30.0, False)):
        e = math.radians(elevation)
        sun = (math.cos(e), 0.0, math.sin(e))
        alone = sun_shadow(focus, sun)
        both = shadow_with_outer(alone, sun_shadow(outer, sun))
        assert (alone.visibility() == 1.0).all()  # the focus alone is flat: no shadows
        vis = both.visibility()
        assert (vis == 0.0).all() if shadowed else (vis == 1.0).all(), (elevation, vis.mean())
        if shadowed:  # the occluder: the wall's west top edge (x = 30 m), 20-40 m away
            assert 19.0 <= both.distance_m.min() and both.distance_m.max() <= 41.0
    with pytest.raises(ValueError, match="different sun directions"):
        shadow_with_outer(sun_shadow(focus, (1.0, 0.0, 0.1)), sun_shadow(outer, (0.0, 1.0, 0.1)))
