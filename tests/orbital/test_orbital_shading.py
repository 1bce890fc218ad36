"""The orthoimage's topographic shading: Lambert's law under the orbiter's sun, uniform on flat
ground, brighter on a slope facing the sun by the stated cosine, reproducible bytes."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from marsscene.errors import ConfigError
from marsscene.orbital import (
    OrbitalModel,
    procedural_orbital_map,
    read_orbital_map,
    write_orbital_map,
)
from marsscene.orbital.shading import lambert_mu0, sun_vector
from marsscene.terrain.heightfield import Heightfield

CELL_M = 0.25


def _ridge(slope: float, n: int = 241) -> Heightfield:
    """A north-south ridge at x = 0: the west face looks west, the east face east."""
    x = CELL_M * np.arange(n) - 30.0
    z = np.tile(-slope * np.abs(x), (n, 1)).astype(np.float32)
    return Heightfield(z, CELL_M, (-30.0, -30.0))


def _shading(hf: Heightfield, azimuth_deg: float = 252.0) -> np.ndarray:
    """The shaded image (no noise) over the albedo-only one: the shading the PSF kept."""
    lit_model = OrbitalModel(image_noise_fraction=0.0, image_sun_azimuth_deg=azimuth_deg)
    lit = procedural_orbital_map(hf, None, 2, lit_model).image
    flat = procedural_orbital_map(
        hf, None, 2, OrbitalModel(image_noise_fraction=0.0, image_shading="none")).image
    assert lit is not None and flat is not None
    return lit.astype(np.float64) / flat


def test_the_sun_vector_points_where_its_azimuth_says() -> None:
    np.testing.assert_allclose(sun_vector(90.0, 90.0), [1.0, 0.0, 0.0], atol=1e-12)  # east
    np.testing.assert_allclose(sun_vector(90.0, 0.0), [0.0, 1.0, 0.0], atol=1e-12)  # north
    np.testing.assert_allclose(sun_vector(0.0, 123.0), [0.0, 0.0, 1.0], atol=1e-12)


def test_flat_ground_is_uniformly_shaded_by_the_cosine_of_the_incidence() -> None:
    m = OrbitalModel()
    mu0 = lambert_mu0(np.full((30, 40), 7.0), 0.5, m.image_sun_incidence_deg,
                      m.image_sun_azimuth_deg)
    np.testing.assert_allclose(mu0, math.cos(math.radians(48.0)), rtol=1e-12)
    ratio = _shading(_ridge(0.0))
    np.testing.assert_allclose(ratio, math.cos(math.radians(48.0)), rtol=1e-6)


@pytest.mark.parametrize("azimuth_deg", [270.0, 252.0])
def test_a_slope_facing_the_sun_is_brighter_by_lamberts_law(azimuth_deg: float) -> None:
    slope = 0.3
    theta, i = math.atan(slope), math.radians(48.0)
    az = math.radians(azimuth_deg)
    # a face tilted by theta towards the west (-x): n = (-sin t, 0, cos t)
    want_west = math.cos(theta) * math.cos(i) + math.sin(theta) * math.sin(i) * -math.sin(az)
    want_east = math.cos(theta) * math.cos(i) - math.sin(theta) * math.sin(i) * -math.sin(az)
    ratio = _shading(_ridge(slope), azimuth_deg)
    cols = ratio.shape[1]
    west, east = ratio[10:-10, 10:cols // 2 - 10], ratio[10:-10, cols // 2 + 10:-10]
    assert float(np.median(west)) == pytest.approx(want_west, rel=2e-3)
    assert float(np.median(east)) == pytest.approx(want_east, rel=2e-3)
    assert float(np.median(west)) > 1.8 * float(np.median(east))  # towards the sun: brighter


def test_a_face_turned_from_the_sun_past_grazing_is_black() -> None:
    z = np.tile(-2.0 * np.arange(20.0), (20, 1))  # 63 deg down to the east
    mu0 = lambert_mu0(z, 1.0, 48.0, 270.0)  # the sun 48 deg from the zenith in the west
    np.testing.assert_array_equal(mu0, 0.0)
    lit = lambert_mu0(z, 1.0, 48.0, 90.0)  # in the east: the face looks 15 deg off the sun
    np.testing.assert_allclose(lit, math.cos(math.atan(2.0) - math.radians(48.0)), rtol=1e-12)
    np.testing.assert_array_equal(mu0, 0.0)


def _hills(n: int = 161) -> Heightfield:
    y, x = np.mgrid[0:n, 0:n] * CELL_M
    z = (0.8 * np.sin(x / 3.0) * np.cos(y / 4.0)).astype(np.float32)
    return Heightfield(z, CELL_M, (-20.0, -20.0))


def test_shaded_maps_have_reproducible_bytes_and_record_their_sun(tmp_path: Path) -> None:
    hf = _hills()
    a = write_orbital_map(procedural_orbital_map(hf, None, 3), tmp_path / "a")
    b = write_orbital_map(procedural_orbital_map(hf, None, 3), tmp_path / "b")
    plain = OrbitalModel(image_shading="none")
    c = write_orbital_map(procedural_orbital_map(hf, None, 3, plain), tmp_path / "c")
    assert (a / "ortho.tif").read_bytes() == (b / "ortho.tif").read_bytes()
    assert (a / "ortho.tif").read_bytes() != (c / "ortho.tif").read_bytes()
    assert (a / "dem.tif").read_bytes() == (c / "dem.tif").read_bytes()  # the DTM is unshaded
    model = json.loads((a / "orbital.json").read_text())["model"]
    assert (model["image_shading"], model["image_sun_incidence_deg"],
            model["image_sun_azimuth_deg"]) == ("lambert", 48.0, 252.0)
    assert read_orbital_map(tmp_path / "c").model.image_shading == "none"


def test_a_map_written_before_shading_reads_back_as_unshaded(tmp_path: Path) -> None:
    out = write_orbital_map(procedural_orbital_map(_hills(), None, 3), tmp_path)
    doc = json.loads((out / "orbital.json").read_text())
    for key in ("image_shading", "image_sun_incidence_deg", "image_sun_azimuth_deg"):
        del doc["model"][key]
    (out / "orbital.json").write_text(json.dumps(doc))
    assert read_orbital_map(tmp_path).model.image_shading == "none"


@pytest.mark.parametrize(("kw", "message"), [
    ({"image_shading": "hapke"}, "image_shading = 'hapke'; use one of lambert, none"),
    ({"image_sun_incidence_deg": 90.0}, "image_sun_incidence_deg must be in [0, 90); got 90.0"),
    ({"image_sun_azimuth_deg": -1.0}, "image_sun_azimuth_deg must be in [0, 360); got -1.0"),
])
def test_a_bad_sun_or_law_is_a_one_line_error(kw: dict[str, object], message: str) -> None:
    with pytest.raises(ConfigError, match=re.escape(message)) as err:
        OrbitalModel(**kw)  # type: ignore[arg-type]
    assert "\n" not in str(err.value)
