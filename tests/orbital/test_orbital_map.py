"""The orbital map of a scene: the PSF's stated transfer, the noise's stated sigma, rocks below
the orbiter's cut-off absent, GeoTIFFs on the scene's posts with its CRS, reproducible bytes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import marsscene as ms
from marsscene.dem.io import read_dem
from marsscene.dem.texture import same_crs
from marsscene.orbital import (
    OrbitalModel,
    apply_psf,
    orbital_map,
    procedural_orbital_map,
    psf_gain,
    read_orbital_map,
    write_orbital_map,
)
from marsscene.rocks.table import RockTable
from marsscene.seeding import STAGE_IDS
from marsscene.terrain.heightfield import Heightfield
from marsscene.testing.pds3 import write_pds3_dtm


def _amplitude(z: np.ndarray, x: np.ndarray, wavelength_m: float) -> float:
    """Least-squares amplitude of the sinusoid of ``wavelength_m`` along x in ``z``."""
    k = 2 * np.pi / wavelength_m
    a = np.column_stack([np.sin(k * x), np.cos(k * x), np.ones_like(x)])
    coef = np.linalg.lstsq(a, z, rcond=None)[0]
    return float(np.hypot(coef[0], coef[1]))


@pytest.mark.parametrize("wavelength_m", [3.0, 6.0, 12.0])
def test_psf_keeps_half_a_sinusoid_at_the_stated_wavelength(wavelength_m: float) -> None:
    m = OrbitalModel()
    cell = 0.25
    x = cell * np.arange(480)
    z = np.tile(np.sin(2 * np.pi * x / wavelength_m + 0.3), (40, 1))
    out = apply_psf(z, cell, m.dem_psf_fwhm_m)[20]
    inner = slice(60, -60)  # away from the reflected edges
    gain = _amplitude(out[inner], x[inner], wavelength_m)
    want = 0.5 ** ((m.dem_half_wavelength_m / wavelength_m) ** 2)  # exp(-c / lambda^2)
    assert gain == pytest.approx(want, abs=2e-3)
    assert float(psf_gain(m.dem_psf_fwhm_m, wavelength_m)) == pytest.approx(want, rel=1e-12)
    if wavelength_m == m.dem_half_wavelength_m:
        assert gain == pytest.approx(0.5, abs=2e-3)


def _flat(size: int = 161, cell: float = 0.25) -> Heightfield:
    return Heightfield(np.zeros((size, size), np.float32), cell, (-20.0, -20.0))


def test_white_dem_noise_has_the_stated_sigma_and_zero_mean() -> None:
    m = OrbitalModel(dem_noise_correlation_m=0.0)  # the correlated default: test_correlated_noise
    hf = Heightfield(np.zeros((801, 801), np.float32), 0.25, (-100.0, -100.0))
    z = procedural_orbital_map(hf, None, 11, m, image=False).dem_m.astype(np.float64)
    n = z.size  # 201 x 201 posts of a flat terrain: the noise alone
    assert z.shape == (201, 201)
    assert float(z.std()) == pytest.approx(m.dem_noise_sigma_m, abs=4 * m.dem_noise_sigma_m
                                           / np.sqrt(2 * n))
    assert abs(float(z.mean())) < 4 * m.dem_noise_sigma_m / np.sqrt(n)
    lag = np.corrcoef(z[:, :-1].ravel(), z[:, 1:].ravel())[0, 1]
    assert abs(lag) < 4 / np.sqrt(n)  # white: no correlation between neighbouring posts


def test_image_noise_is_the_stated_fraction() -> None:
    hf = _flat(401)
    noisy = procedural_orbital_map(hf, None, 5).image
    clean = procedural_orbital_map(hf, None, 5, OrbitalModel(image_noise_fraction=0.0)).image
    assert noisy is not None and clean is not None and noisy.shape == (200, 200)
    rel = noisy.astype(np.float64) / clean - 1.0
    assert float(rel.std()) == pytest.approx(0.01, abs=4 * 0.01 / np.sqrt(2 * rel.size))


def _rocks(xy: list[tuple[float, float]], d_m: list[float]) -> RockTable:
    n = len(d_m)
    d = np.asarray(d_m)
    xyz = np.column_stack([np.asarray(xy), -0.1 * np.ones(n)])
    quat = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))
    return RockTable(xyz, d, 0.5 * d, 0.1 * np.ones(n), quat, np.zeros(n, np.int64))


def test_rocks_below_the_cut_off_are_absent_and_boulders_present() -> None:
    quiet = OrbitalModel(dem_noise_sigma_m=0.0)
    hf = _flat()
    small = _rocks([(-8.0, -8.0), (-8.0, 8.0)], [0.6, 0.95])  # below rock_resolved_d_m = 1 m
    big = _rocks([(8.0, 8.0)], [2.5])
    none = procedural_orbital_map(hf, None, 1, quiet, image=False)
    with_small = procedural_orbital_map(hf, small, 1, quiet, image=False)
    np.testing.assert_array_equal(with_small.dem_m, none.dem_m)
    with_big = procedural_orbital_map(hf, big, 1, quiet, image=False)
    assert float(with_big.elevation_at(8.0, 8.0)[()]) > 0.5 * 1.25  # half its 1.25 m height
    assert float(np.abs(with_big.elevation_at(-8.0, -8.0))[()]) < 1e-6  # far from it: ground


def test_a_procedural_scene_map_is_its_rock_free_terrain_through_the_model() -> None:
    cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [40, 40]}})
    scene = ms.build_scene(cfg, seed=4)
    assert scene.rocks is not None and len(scene.rocks) > 0
    omap = orbital_map(scene)
    resolved = scene.rocks.take(scene.rocks.diameter_m >= 1.0)
    again = procedural_orbital_map(scene.heightfield, resolved, 4)
    assert omap.source == "procedural" and omap.cell_m == 1.0 and omap.shape == (41, 41)
    np.testing.assert_array_equal(omap.dem_m, again.dem_m)
    assert omap.image is not None and omap.image.shape == (80, 80)
    assert STAGE_IDS["orbital"] == 16


def test_same_seed_same_bytes_other_seed_other_noise(tmp_path: Path) -> None:
    hf = _flat()
    a = write_orbital_map(procedural_orbital_map(hf, None, 3), tmp_path / "a")
    b = write_orbital_map(procedural_orbital_map(hf, None, 3), tmp_path / "b")
    c = write_orbital_map(procedural_orbital_map(hf, None, 4), tmp_path / "c")
    names = sorted(p.name for p in a.iterdir())
    assert names == ["dem.tif", "orbital.json", "ortho.tif"]
    assert all((a / n).read_bytes() == (b / n).read_bytes() for n in names)
    assert (a / "dem.tif").read_bytes() != (c / "dem.tif").read_bytes()
    back = read_orbital_map(tmp_path / "a")
    np.testing.assert_array_equal(back.dem_m, procedural_orbital_map(hf, None, 3).dem_m)
    assert back.origin_xy_m == (-20.0, -20.0) and back.crs_wkt == ""


def test_a_dem_scene_map_is_its_dtm_on_its_posts_with_its_crs(tmp_path: Path) -> None:
    rows, cols = 60, 80
    y, x = np.mgrid[0:rows, 0:cols]
    z = (-2500.0 + 3.0 * np.sin(x / 7.0) + 2.0 * np.cos(y / 5.0)).astype(np.float32)
    dtm = write_pds3_dtm(tmp_path / "DTEEC_ORBITAL.IMG", z)
    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "dem", "dem_path": str(dtm), "detail": False},
        "craters": {"enabled": False}, "rocks": {"enabled": False},
        "lighting": {"enabled": False}})
    scene = ms.build_scene(cfg, seed=2)
    frame = scene.provenance.frame
    omap = orbital_map(scene)
    assert omap.source == "dem" and omap.cell_m == 1.0 and omap.shape == (rows, cols)
    np.testing.assert_allclose(omap.dem_m, (z[::-1] - frame.datum_m), atol=1e-4)
    assert omap.origin_xy_m == pytest.approx(scene.heightfield.origin_xy_m)
    out = write_orbital_map(omap, tmp_path / "scene")
    back = read_dem(out / "dem.tif")
    assert same_crs(back.crs_wkt, frame.crs_wkt) and back.crs_wkt
    assert frame.origin_projected_xy_m is not None
    sw = back.xy_of(rows - 1, 0)  # the south-west post, projected
    assert (float(sw[0]), float(sw[1])) == pytest.approx(
        (omap.origin_xy_m[0] + frame.origin_projected_xy_m[0],
         omap.origin_xy_m[1] + frame.origin_projected_xy_m[1]), abs=1e-6)
    np.testing.assert_array_equal(back.elevation_m[::-1], omap.dem_m)


def test_a_dem_scene_map_carries_its_orthoimage_at_its_own_pixels(tmp_path: Path) -> None:
    from marsscene.dem.io_write import write_geotiff

    z = np.full((40, 50), -2500.0, np.float32)
    z[10:20, 10:30] += 5.0
    dtm = write_pds3_dtm(tmp_path / "DTEEC_ORTHO.IMG", z)
    crs = read_dem(dtm).crs_wkt
    x0, y0, x1, y1 = read_dem(dtm).bounds_xy_m

    def dn(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return (0.2 + 1e-3 * (x - x0) + 2e-3 * (y - y0)).astype(np.float32)

    px = 0.5
    cx = x0 + px * (np.arange(round((x1 - x0) / px)) + 0.5)
    cy = y0 + px * (np.arange(round((y1 - y0) / px)) + 0.5)  # row 0 south, as scene grids
    ortho = write_geotiff(tmp_path / "ortho.tif", {"i_f": dn(*np.meshgrid(cx, cy))},
                          origin_xy_m=(float(cx[0]), float(cy[0])), cell_m=px, crs_wkt=crs,
                          origin_projected_xy_m=(0.0, 0.0))
    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "dem", "dem_path": str(dtm), "ortho_path": str(ortho),
                    "detail": False},
        "craters": {"enabled": False}, "rocks": {"enabled": False},
        "lighting": {"enabled": False}})
    scene = ms.build_scene(cfg, seed=2)
    omap = orbital_map(scene)
    assert omap.image is not None and omap.image_pixel_m == px
    assert omap.image_origin_xy_m is not None and omap.origin_projected_xy_m is not None
    ox, oy = omap.origin_projected_xy_m
    rows, cols = omap.image.shape
    want = dn(*np.meshgrid(omap.image_origin_xy_m[0] + ox + px * np.arange(cols),
                           omap.image_origin_xy_m[1] + oy + px * np.arange(rows)))
    np.testing.assert_allclose(omap.image, want, atol=1e-6)  # every pixel where it was
    fx0, fy0, fx1, fy1 = scene.heightfield.bounds_xy_m
    assert omap.image_origin_xy_m[0] <= fx0 and omap.image_origin_xy_m[1] <= fy0
    assert (omap.image_origin_xy_m[0] + px * (cols - 1) >= fx1
            and omap.image_origin_xy_m[1] + px * (rows - 1) >= fy1)
