"""Procedural fBm terrain statistics and sub-DEM detail."""

from __future__ import annotations

import numpy as np
import pytest

from marsscene.terrain import Heightfield, add_detail, measure_hurst, resample, synthesize


@pytest.mark.parametrize("hurst", [0.5, 0.8])
def test_procedural_rms_and_hurst_match_configuration(hurst: float) -> None:
    measured = []
    for seed in range(4):
        hf = synthesize((128.0, 128.0), 0.25, hurst=hurst, rms_height_m=2.0,
                        rng=np.random.default_rng(seed))
        assert float(hf.z_m.std()) == pytest.approx(2.0, rel=1e-4)
        measured.append(measure_hurst(hf, lag_posts=(1, 2, 4, 8, 16)))
    # The variogram slope over 0.25-4 m lags recovers H within 0.08 (finite-grid bias).
    assert np.mean(measured) == pytest.approx(hurst, abs=0.08)
    assert np.std(measured) < 0.05


def test_rms_slope_option() -> None:
    hf = synthesize((64.0, 64.0), 0.25, hurst=0.8, rms_height_m=1.0, rms_slope_deg=10.0,
                    rng=np.random.default_rng(3))
    gx, gy = hf.grid_gradient()
    rms = np.degrees(np.arctan(np.sqrt(np.mean(gx**2 + gy**2))))
    assert rms == pytest.approx(10.0, rel=0.02)


def test_procedural_is_seeded() -> None:
    a = synthesize((20.0, 20.0), 0.5, hurst=0.7, rms_height_m=1.0, rng=np.random.default_rng(1))
    b = synthesize((20.0, 20.0), 0.5, hurst=0.7, rms_height_m=1.0, rng=np.random.default_rng(1))
    c = synthesize((20.0, 20.0), 0.5, hurst=0.7, rms_height_m=1.0, rng=np.random.default_rng(2))
    assert np.array_equal(a.z_m, b.z_m) and not np.array_equal(a.z_m, c.z_m)


def _coarse_dem() -> Heightfield:
    return synthesize((96.0, 96.0), 1.0, hurst=0.8, rms_height_m=1.5,
                      rng=np.random.default_rng(11))


def test_detail_keeps_the_coarse_terrain_and_adds_fine_roughness() -> None:
    coarse = _coarse_dem()
    before = coarse.z_m.copy()
    fine = add_detail(coarse, post_m=0.25, hurst=0.8, rng=np.random.default_rng(5))
    assert np.array_equal(coarse.z_m, before)  # input untouched
    assert fine.cell_size_m == 0.25 and fine.shape == (385, 385)
    assert fine.origin_xy_m == coarse.origin_xy_m
    # Sampled back at the coarse posts the detailed terrain equals the DEM to within the
    # detail's own RMS: the detail is band-limited above the DEM's Nyquist frequency.
    plain = resample(coarse, post_m=0.25)
    detail = fine.z_m - plain.z_m
    assert abs(float(detail.mean())) < 0.01
    back = fine.z_m[::4, ::4]
    assert np.sqrt(np.mean((back - before) ** 2)) <= 1.5 * float(detail.std())
    # Roughness continues the DEM spectrum: 1-post variogram at 0.25 m ~ (0.25/1)^H x DEM's.
    v_coarse = np.mean(np.diff(before, axis=1) ** 2)
    v_fine = np.mean(np.diff(fine.z_m, axis=1) ** 2)
    ratio = np.sqrt(v_fine / v_coarse)
    assert 0.25**0.8 * 0.6 < ratio < 0.25**0.8 * 1.6


def test_detail_rms_override_and_determinism() -> None:
    coarse = _coarse_dem()
    a = add_detail(coarse, post_m=0.5, hurst=0.8, detail_rms_m=0.05,
                   rng=np.random.default_rng(9))
    b = add_detail(coarse, post_m=0.5, hurst=0.8, detail_rms_m=0.05,
                   rng=np.random.default_rng(9))
    assert np.array_equal(a.z_m, b.z_m)
    d = a.z_m - resample(coarse, post_m=0.5).z_m
    assert float(d.std()) == pytest.approx(0.05, rel=0.05)


def test_resample_reproduces_a_smooth_surface() -> None:
    hf0 = Heightfield.centered(np.zeros((41, 41), np.float32), 1.0)
    xs, ys = hf0.grid_xy()
    z = np.sin(xs[None, :] / 7.0) * np.cos(ys[:, None] / 5.0)
    hf = hf0.with_z(z)
    fine = resample(hf, post_m=0.25)
    fx, fy = fine.grid_xy()
    exact = np.sin(fx[None, :] / 7.0) * np.cos(fy[:, None] / 5.0)
    assert np.abs(fine.z_m - exact).max() < 2e-3
