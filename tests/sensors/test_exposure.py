"""Camera exposure: sRGB reference values, auto-exposure target and saturation, noise."""

from __future__ import annotations

import numpy as np
import pytest

from marsscene.sensors.exposure import Exposure, srgb_encode


def test_srgb_reference_values() -> None:
    # IEC 61966-2-1: 0.5 -> 0.7354, 0.0031308 -> 0.04045, 0.18 -> 0.4614
    np.testing.assert_allclose(srgb_encode(np.array([0.0, 0.0031308, 0.18, 0.5, 1.0])),
                               [0.0, 0.04045, 0.46135, 0.73536, 1.0], atol=2e-5)


def test_auto_exposure_hits_target_and_limits_saturation() -> None:
    rng = np.random.default_rng(0)
    dark = rng.uniform(0.0, 0.05, size=(120, 160, 3))  # a dim scene
    out = Exposure().apply(dark)
    assert out.mean() / 255 == pytest.approx(0.45, abs=0.01)
    bright = dark.copy()
    bright[:30] = 0.9  # a quarter of the frame is a very bright sky
    exp = Exposure(max_saturated=0.01)
    img = exp.apply(bright)
    assert (img.max(axis=-1) >= 255).mean() <= 0.02


def test_auto_exposure_smooths_and_fixed_is_linear() -> None:
    a = np.full((20, 20, 3), 0.05)
    exp = Exposure(smoothing=0.5)
    exp.apply(a)
    g0 = exp.gain
    exp.apply(a * 4)  # scene 4x brighter: gain moves half-way in log (to g0 / 2)
    assert exp.gain == pytest.approx(g0 / 2, rel=0.02)
    fixed = Exposure("fixed", fixed_gain=2.0)
    np.testing.assert_array_equal(fixed.apply(a), np.rint(srgb_encode(a * 2) * 255))


def test_sensor_noise_is_seeded_with_shot_and_read_statistics() -> None:
    lin = np.full((200, 200, 3), 0.25)
    exp = Exposure("fixed", full_well_e=10000.0, read_noise_e=10.0)
    a = exp.apply(lin, np.random.default_rng(4))
    b = exp.apply(lin, np.random.default_rng(4))
    np.testing.assert_array_equal(a, b)
    # linear std = sqrt(2500 + 100) / 10000 = 0.0051; in sRGB near 0.25 the slope is ~1.24
    lin_back = ((a / 255 + 0.055) / 1.055) ** 2.4
    assert lin_back.std() == pytest.approx(np.sqrt(2600) / 10000, rel=0.15)
