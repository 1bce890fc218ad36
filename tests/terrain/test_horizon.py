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
