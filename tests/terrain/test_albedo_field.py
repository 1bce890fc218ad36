"""Large-scale albedo field: seeded, documented amplitudes, orthoimage modulation."""

from __future__ import annotations

import numpy as np
import pytest

from marsscene.terrain.albedo_field import AlbedoField, albedo_field, ortho_gain
from marsscene.terrain.appearance import AppearanceModel


def test_field_is_seeded_and_world_anchored() -> None:
    x, y = np.meshgrid(np.linspace(-300, 300, 301), np.linspace(-50, 250, 151))
    a = albedo_field(rng=np.random.default_rng(5)).log_gain(x, y)
    b = albedo_field(rng=np.random.default_rng(5)).log_gain(x, y)
    c = albedo_field(rng=np.random.default_rng(6)).log_gain(x, y)
    assert a.tobytes() == b.tobytes() and a.tobytes() != c.tobytes()
    # a function of world position: sampling a sub-grid gives the same values
    f = albedo_field(rng=np.random.default_rng(5))
    np.testing.assert_array_equal(f.log_gain(x[::3, ::7], y[::3, ::7]), a[::3, ::7])


def test_band_amplitudes_follow_the_documented_sigmas() -> None:
    m = AppearanceModel.default()
    f = albedo_field(rng=np.random.default_rng(1))
    x, y = np.meshgrid(np.arange(0, 1024, 0.5), np.arange(0, 1024, 0.5))
    g = f.log_gain(x, y).astype(np.float64)
    total = np.hypot(m.albedo_mid_sigma, m.albedo_large_sigma)
    assert g.std() == pytest.approx(total, rel=0.15)
    # 16 m block means keep the decametre band and average the 1-8 m band away
    blocks = g.reshape(64, 32, 64, 32).mean(axis=(1, 3))
    assert blocks.std() == pytest.approx(m.albedo_large_sigma, rel=0.25)
    # the metre band: what is left inside 16 m blocks
    resid = (g.reshape(64, 32, 64, 32) - blocks[:, None, :, None]).std()
    assert 0.6 * m.albedo_mid_sigma < resid < 1.1 * m.albedo_mid_sigma
    # Guinness (1981) VL1 soils: red reflectance 0.30-0.39, i.e. ~ +-13 % about the mean
    assert np.exp(1.5 * m.albedo_large_sigma) == pytest.approx(0.39 / 0.345, rel=0.03)


def _blob_image(n: int, seed: int) -> np.ndarray:
    from scipy.ndimage import gaussian_filter

    blob = gaussian_filter(np.random.default_rng(seed).standard_normal((n, n)), 8, mode="wrap")
    return np.clip(128 * np.exp(0.3 * blob / blob.std()), 0, 255).astype(np.uint8)


def test_ortho_replaces_the_decametre_band_and_keeps_its_orientation() -> None:
    img = _blob_image(128, 9)  # 0.5 m pixels over 64 m, row 0 = north
    og = ortho_gain(np.repeat(img[..., None], 3, -1), x0_m=10.0, y0_m=-20.0, width_m=64.0)
    m = AppearanceModel.default()
    assert og.log_gain.std() == pytest.approx(m.albedo_large_sigma, rel=0.05)
    f = albedo_field(rng=np.random.default_rng(2))
    zero_mid = AlbedoField(np.zeros_like(f.mid), f.large, og)
    # pixel centres of the image's southern row lie at y0 + 0.25 m; column j at x0 + 0.5 j + 0.25
    cols = np.arange(8, 120)
    xs, ys = 10.0 + 0.5 * cols + 0.25, np.full(cols.size, -20.0 + 0.25 + 0.5 * 40)
    got = zero_mid.log_gain(xs, ys)
    lum = np.log(img[::-1][40, cols].astype(float))
    assert np.corrcoef(got, lum)[0, 1] > 0.9
    # outside the image the gain is 1
    assert float(zero_mid.log_gain(np.array([-500.0]), np.array([0.0]))[0]) == 0.0
