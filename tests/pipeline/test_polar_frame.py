"""Polar stereographic DEMs: scene +y is grid north, not true north (grid convergence).

The sun direction and the crater catalogue's lon/lat must follow true north.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
from pyproj import CRS, Transformer

import marsscene as ms
from marsscene.dem.model import DEM

POLAR = "+proj=stere +lat_0=90 +lon_0=0 +k=1 +x_0=0 +y_0=0 +R=3396190 +units=m +no_defs"
GEO = "+proj=longlat +R=3396190 +no_defs"


def _polar_dem(n: int, lon: float = 90.0, lat: float = 85.0) -> tuple[DEM, Transformer]:
    fwd = Transformer.from_crs(CRS.from_proj4(GEO), CRS.from_proj4(POLAR), always_xy=True)
    cx, cy = fwd.transform(lon, lat)
    transform = (1.0, 0.0, cx - n / 2, 0.0, -1.0, cy + n / 2)
    dem = DEM(np.zeros((n, n), np.float32), transform, crs_wkt=CRS.from_proj4(POLAR).to_wkt(),
              center_lonlat_deg=(lon, lat))
    return dem, fwd


def test_sun_direction_follows_true_north() -> None:
    dem, fwd = _polar_dem(41)
    cfg = ms.SceneConfig.from_dict({"craters": {"enabled": False}, "rocks": {"enabled": False},
                                    "lighting": {"utc": "2021-06-01T12:00:00Z"}})
    scene = ms.build_scene(cfg, seed=1, dem=dem)
    assert scene.provenance.frame.grid_convergence_deg == pytest.approx(90.0, abs=1e-6)
    lt = scene.lighting
    assert lt is not None
    # True north and east at the site, expressed in the scene (grid) frame, from pyproj.
    cx, cy = fwd.transform(90.0, 85.0)
    nx, ny = fwd.transform(90.0, 85.0001)
    north = np.array([nx - cx, ny - cy]) / np.hypot(nx - cx, ny - cy)
    east = np.array([north[1], -north[0]])  # 90 deg clockwise from north (seen from above)
    az = np.radians(lt.sun_azimuth_deg)
    horizontal = np.cos(np.radians(lt.sun_elevation_deg))
    expected_xy = horizontal * (np.sin(az) * east + np.cos(az) * north)
    np.testing.assert_allclose(lt.sun_direction_enu[:2], expected_xy, atol=1e-6)


def test_crater_catalogue_lonlat_follows_true_north(tmp_path: Path) -> None:
    dem, _ = _polar_dem(401)
    inv = Transformer.from_crs(CRS.from_proj4(POLAR), CRS.from_proj4(GEO), always_xy=True)
    cfg = ms.SceneConfig.from_dict({"craters": {"d_min_m": 5.0, "d_max_m": 40.0},
                                    "rocks": {"enabled": False}, "lighting": {"enabled": False},
                                    "export": {"formats": ["mjcf"]}})
    scene = ms.build_scene(cfg, seed=1, dem=dem)
    ms.write_scene(scene, tmp_path / "s")
    rows = list(csv.DictReader(open(tmp_path / "s" / "craters.csv", encoding="utf-8")))
    assert len(rows) > 3
    ox, oy = scene.provenance.frame.origin_projected_xy_m
    for r in rows:
        lon, lat = inv.transform(float(r["x_m"]) + ox, float(r["y_m"]) + oy)
        # Local equirectangular approximation: ~1e-4 deg over ~200 m at 85 N.
        assert float(r["lat_deg"]) == pytest.approx(lat, abs=2e-4)
        assert float(r["lon_deg"]) == pytest.approx(lon % 360.0, abs=2e-3)


def test_core_types_never_freeze_the_callers_array() -> None:
    z = np.zeros((4, 5), np.float32)
    ms.terrain.Heightfield(z, 1.0)
    DEM(z, (1.0, 0.0, 0.0, 0.0, -1.0, 0.0))
    z[0, 0] = 1.0  # still writeable
    assert z.flags.writeable


def test_resampled_dem_keeps_origin_lonlat_consistent(synthetic_dem_path: Path) -> None:
    cfg = ms.SceneConfig.from_dict(
        {"terrain": {"source": "dem", "dem_path": str(synthetic_dem_path), "post_m": 5.0},
         "craters": {"enabled": False}, "rocks": {"enabled": False},
         "lighting": {"enabled": False}}
    )
    with pytest.warns(ms.errors.NodataFilledWarning):
        frame = ms.build_scene(cfg, seed=1).provenance.frame
    to_geo = Transformer.from_crs(CRS.from_wkt(frame.crs_wkt),
                                  CRS.from_wkt(frame.crs_wkt).geodetic_crs, always_xy=True)
    lon, lat = to_geo.transform(*frame.origin_projected_xy_m)
    assert frame.origin_lonlat_deg[0] == pytest.approx(lon % 360.0, abs=1e-7)
    assert frame.origin_lonlat_deg[1] == pytest.approx(lat, abs=1e-7)
