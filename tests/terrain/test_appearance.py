"""Regolith / rock appearance: literature albedos, seamless multi-scale tiles, seeding."""

from __future__ import annotations

import numpy as np
import pytest

from marsscene.terrain.appearance import (
    AppearanceModel,
    bump_shading,
    normal_map_rgb,
    regolith_tile,
    rock_albedo_rgb,
)


@pytest.fixture(scope="module")
def tile():
    return regolith_tile(size_px=512, tile_m=4.0, rng=np.random.default_rng(11))


def test_soil_albedo_matches_viking_lander_soils(tile) -> None:
    mean = tile.albedo_rgb.reshape(-1, 3).mean(axis=0)
    # Guinness (1981): ~0.30-0.39 red, ~0.17 green, ~0.11 blue; Mars albedo ~0.1-0.3
    assert 0.30 <= mean[0] <= 0.39
    assert mean[1] == pytest.approx(0.17, abs=0.02) and mean[2] == pytest.approx(0.11, abs=0.02)
    assert tile.albedo_rgb.min() >= 0.02 and tile.albedo_rgb.max() <= 0.95


def test_tile_is_seamless_and_multiscale(tile) -> None:
    g = tile.albedo_rgb[..., 0].astype(np.float64)
    inner = np.abs(np.diff(g, axis=1)).mean()
    wrap = np.abs(g[:, 0] - g[:, -1]).mean()  # across the tile edge
    assert wrap < 1.5 * inner
    # variation at 0.25 m (block means) and at ~1 cm (neighbouring texels) scales; metre
    # scales and beyond come from the albedo field (tests/terrain/test_albedo_field.py)
    blocks = g.reshape(16, 32, 16, 32).mean(axis=(1, 3))
    assert blocks.std() / g.mean() > 0.04
    metre = g.reshape(4, 128, 4, 128).mean(axis=(1, 3))
    assert metre.std() / g.mean() < 0.02  # the tile's mottling stops at 1 m
    assert inner / g.mean() > 0.01
    assert tile.texel_m == pytest.approx(4.0 / 512)


def test_tile_is_seeded(tile) -> None:
    again = regolith_tile(size_px=512, tile_m=4.0, rng=np.random.default_rng(11))
    other = regolith_tile(size_px=512, tile_m=4.0, rng=np.random.default_rng(12))
    assert again.albedo_rgb.tobytes() == tile.albedo_rgb.tobytes()
    assert other.albedo_rgb.tobytes() != tile.albedo_rgb.tobytes()


def test_rocks_darker_and_greyer_than_soil() -> None:
    m = AppearanceModel.default()
    rgb = rock_albedo_rgb(2000, rng=np.random.default_rng(0))
    soil = np.asarray(m.soil_rgb)
    assert rgb[:, 0].mean() < soil[0]  # darker in red (Johnson et al. 1999, 2006)
    assert (rgb[:, 0] / rgb[:, 2]).mean() < soil[0] / soil[2]  # less red: greyer


def test_bump_shading_and_normal_map(tile) -> None:
    flat = bump_shading(tile, (0.0, 0.0, 1.0), 1.0)  # overhead sun: n . s = n_z <= 1
    assert flat.max() <= 1.0 + 1e-6 and flat.mean() > 0.9
    low = bump_shading(tile, (0.97, 0.0, 0.2425), 0.8)
    assert low.std() > 3 * flat.std()  # grazing light brings out the relief
    # a slope facing the sun (+x) is brighter: correlate with -dh/dx
    dhdx = np.roll(tile.height_m, -1, axis=1) - np.roll(tile.height_m, 1, axis=1)
    assert np.corrcoef(low.ravel(), -dhdx.ravel())[0, 1] > 0.5
    nm = normal_map_rgb(tile)
    assert nm.dtype == np.uint8 and nm.shape == (512, 512, 3)
    assert abs(nm[..., 2].mean() - 255) < 10  # mostly facing +z
