"""Procedural landforms of the reference scenes: crater and canyon geometry within stated
ranges, purity and determinism through the pipeline."""

from __future__ import annotations

import numpy as np
import pytest

import marsscene as ms
from marsscene.craters.morphometry import fresh_depth_to_diameter
from marsscene.errors import ConfigError
from marsscene.landforms import add_landform, crater_height_m
from marsscene.terrain.heightfield import Heightfield


def _flat(size_m: float, cell_m: float) -> Heightfield:
    n = round(size_m / cell_m) + 1
    return Heightfield.centered(np.zeros((n, n), np.float32), cell_m)


def test_crater_rim_floor_and_wall_slopes() -> None:
    d = 1500.0
    hf = add_landform(_flat(3000.0, 5.0), "crater", size_m=d)
    z = hf.z_m.astype(np.float64)
    xv, yv = hf.grid_xy()
    r = np.hypot(xv[None, :], yv[:, None])
    rim_h = float(z.max())
    # rim crest: Melosh 0.036 D, slightly lowered by the 5 % diffusion
    assert 0.025 * d < rim_h <= 0.036 * d
    # the crest lies on the rim (0.95-1.1 R), the lowest point near the centre
    assert 0.95 * d / 2 <= float(r[np.unravel_index(np.argmax(z), z.shape)]) <= 1.1 * d / 2
    assert float(r[np.unravel_index(np.argmin(z), z.shape)]) < 0.15 * d / 2
    # rim-to-floor depth: the Garvin & Frawley fresh depth (within 15 %, diffusion shallows it)
    depth = rim_h - float(z.min())
    d_fresh = float(fresh_depth_to_diameter(d)) * d
    assert 0.85 * d_fresh <= depth <= d_fresh
    # inner walls: steepest slope 18-30 deg (fresh simple craters: ~20-35 deg)
    slope = hf.slope_deg()
    assert 18.0 <= float(slope[r < d / 2].max()) <= 30.0
    # far from the crater (beyond 2.5 R) the plain is untouched
    assert np.abs(z[r > 1.3 * d]).max() == 0.0


def test_canyon_relief_and_wall_slope() -> None:
    hf = add_landform(_flat(3000.0, 5.0), "canyon", size_m=300.0, depth_m=250.0)
    z = hf.z_m.astype(np.float64)
    assert float(z.max() - z.min()) == pytest.approx(250.0, abs=0.01)
    slope = hf.slope_deg()
    # half-cosine wall: steepest gradient pi depth / (2 w) = 0.98 -> 44.4 deg (grid: +-1.5 deg)
    assert float(slope.max()) == pytest.approx(np.degrees(np.arctan(np.pi * 250 / 800)), abs=1.5)
    # every column crosses the canyon: a flat floor and the plateau on both sides
    assert np.all((z <= -249.99).any(axis=0))
    assert np.all(z[0] == 0.0) and np.all(z[-1] == 0.0)
    # floor width 300 m: ~60 posts at -depth per column (meander shifts, never widens it)
    floor_posts = (z <= -249.99).sum(axis=0)
    assert floor_posts.min() >= 55 and floor_posts.max() <= 66


def test_landform_does_not_modify_input_and_plain_is_identity() -> None:
    hf = _flat(200.0, 2.0)
    before = hf.z_m.copy()
    add_landform(hf, "crater", size_m=100.0)
    np.testing.assert_array_equal(hf.z_m, before)
    assert add_landform(hf, "plain") is hf


def _cfg(landform: str) -> ms.SceneConfig:
    return ms.SceneConfig.from_dict({
        "terrain": {"source": "procedural", "size_m": [200.0, 200.0], "post_m": 2.0,
                    "landform": landform, "landform_size_m": 120.0},
        "craters": {"enabled": False}, "rocks": {"enabled": False}})


def test_landform_builds_are_deterministic_and_seeded() -> None:
    a = ms.build_scene(_cfg("crater"), seed=4).heightfield.z_m
    b = ms.build_scene(_cfg("crater"), seed=4).heightfield.z_m
    c = ms.build_scene(_cfg("crater"), seed=5).heightfield.z_m
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    # the landform is the same in both seeds: the difference is the fBm only (rms 1 m)
    assert float(np.abs(a - c).max()) < 10.0
    # the landform is added to the same-seed fBm exactly (other stages untouched)
    scene = ms.build_scene(_cfg("fbm"), seed=4)
    xv, yv = scene.heightfield.grid_xy()
    crater = crater_height_m(xv[None, :], yv[:, None], diameter_m=120.0)
    np.testing.assert_allclose(a - scene.heightfield.z_m, crater, atol=1e-4)
    assert crater.min() < -15.0


def test_unknown_landform_is_a_config_error() -> None:
    with pytest.raises(ConfigError, match=r"terrain\.landform"):
        ms.SceneConfig.from_dict({"terrain": {"landform": "volcano"}})
