"""The orbital DTM's noise is spatially correlated with the stated length: its measured
autocorrelation falls to 1/e at ``dem_noise_correlation_m`` and its std is ``dem_noise_sigma_m``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from marsscene.orbital import OrbitalModel, procedural_orbital_map
from marsscene.orbital.model import correlated_noise
from marsscene.terrain.heightfield import Heightfield


def _autocorrelation(a: np.ndarray, lag: int) -> float:
    """Mean of the lag correlations along rows and columns."""
    a = a - a.mean()
    var = float((a * a).mean())
    return 0.5 * float((a[:, lag:] * a[:, :-lag]).mean() + (a[lag:] * a[:-lag]).mean()) / var


@pytest.mark.parametrize("corr_m, cell_m", [(3.0, 1.0), (4.0, 0.5)])
def test_measured_correlation_length_matches_the_stated_one(corr_m: float, cell_m: float) -> None:
    noise = correlated_noise((512, 512), cell_m, 0.25, corr_m, rng=np.random.default_rng(4))
    lag = round(corr_m / cell_m)
    assert _autocorrelation(noise, lag) == pytest.approx(math.exp(-1.0), abs=0.03)
    half = lag // 2
    assert _autocorrelation(noise, half) == pytest.approx(
        math.exp(-((half * cell_m / corr_m) ** 2)), abs=0.03)
    assert noise.std() == pytest.approx(0.25, rel=0.05)


def test_zero_correlation_is_white() -> None:
    noise = correlated_noise((256, 256), 1.0, 0.25, 0.0, rng=np.random.default_rng(5))
    assert abs(_autocorrelation(noise, 1)) < 0.02
    assert noise.std() == pytest.approx(0.25, rel=0.03)


def test_a_flat_terrain_s_orbital_map_is_its_correlated_noise() -> None:
    flat = Heightfield(np.zeros((401, 401), np.float32), 0.5, (-100.0, -100.0))
    omap = procedural_orbital_map(flat, None, 3, OrbitalModel(), image=False)
    z = omap.dem_m.astype(np.float64)
    assert z.std() == pytest.approx(0.25, rel=0.1)
    assert _autocorrelation(z, 3) == pytest.approx(math.exp(-1.0), abs=0.06)
