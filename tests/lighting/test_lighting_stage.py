"""LightingConfig validation and the pipeline's lighting stage (site, defaults, determinism)."""

from __future__ import annotations

import dataclasses

import pytest

import marsscene as ms
from marsscene.errors import ConfigError
from marsscene.lighting import LightingConfig, compute_lighting, mars_sun_position
from marsscene.lighting.config import DEFAULT_SITE_LAT_LON_EAST_DEG

TINY = {"terrain": {"source": "procedural", "size_m": [12.0, 10.0], "post_m": 1.0},
        "craters": {"enabled": False}, "rocks": {"enabled": False}}


def _cfg(**lighting: object) -> ms.SceneConfig:
    return ms.SceneConfig.from_dict({**TINY, "lighting": lighting})


@pytest.mark.parametrize("bad, match", [
    ({"tau": -0.1}, "lighting.tau"),
    ({"utc": "2021-02-18T20:55"}, "no time zone"),
    ({"sun_azimuth_deg": 70.0}, "go together"),
    ({"site_lat_deg": 95.0, "site_lon_east_deg": 0.0}, "site_lat_deg"),
    ({"mars_year": 36, "ltst_h": 12.0}, "go together"),
    ({"mars_year": 36, "ls_deg": 360.0, "ltst_h": 12.0}, "lighting.ls_deg"),
    ({"diffuse_model": "disort"}, "diffuse_model"),
    ({"usd_units": "candela"}, "usd_units"),
    ({"unknown": 1}, "unknown key"),
])
def test_bad_config(bad: dict[str, object], match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        _cfg(**bad)


def test_sun_modes() -> None:
    assert LightingConfig().sun_mode == "default"
    assert LightingConfig(sun_azimuth_deg=1.0, sun_elevation_deg=2.0).sun_mode == "explicit"
    assert LightingConfig(mars_year=36, ls_deg=5.0, ltst_h=9.0).sun_mode == "local"
    assert LightingConfig(utc="2021-02-18T20:55Z", sun_azimuth_deg=1.0,
                          sun_elevation_deg=2.0).sun_mode == "utc"


def test_default_is_deterministic_and_documented() -> None:
    a = ms.build_scene(_cfg(), seed=1).lighting
    b = ms.build_scene(_cfg(), seed=2).lighting
    assert a == b
    assert a is not None and (a.sun_azimuth_deg, a.sun_elevation_deg) == (70.0, 13.0)
    assert (a.site_lat_deg, a.site_lon_east_deg) == DEFAULT_SITE_LAT_LON_EAST_DEG
    assert a.utc is None


def test_procedural_terrain_uses_jezero_for_a_utc() -> None:
    scene = ms.build_scene(_cfg(utc="2021-02-18T20:55Z"), seed=0)
    lt = scene.lighting
    assert lt is not None
    ref = mars_sun_position("2021-02-18T20:55Z", lat_deg=18.4447, lon_east_deg=77.4508)
    assert lt.sun_elevation_deg == pytest.approx(ref.elevation_deg)
    assert lt.sun_azimuth_deg == pytest.approx(ref.azimuth_deg)
    assert any(m.stage == "lighting" and "Allison" in m.citation
               for m in scene.provenance.models)
    assert scene.provenance.extra["lighting_tau"] == 0.5


@pytest.mark.filterwarnings("ignore::marsscene.errors.NodataFilledWarning")  # nodata corner
def test_site_comes_from_the_dem_centre(synthetic_dem_path: object) -> None:
    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "dem", "dem_path": str(synthetic_dem_path)},
        "craters": {"enabled": False}, "rocks": {"enabled": False},
        "lighting": {"utc": "2021-02-18T20:55Z"},
    })
    scene = ms.build_scene(cfg, seed=0)
    lon, lat = scene.provenance.frame.origin_lonlat_deg
    lt = scene.lighting
    assert lt is not None and lt.site_lat_deg == pytest.approx(lat)
    assert lt.site_lon_east_deg == pytest.approx(lon % 360.0)
    assert 18.0 < lat < 19.0  # the fixture DEM sits near Jezero
    override = dataclasses.replace(cfg.lighting, site_lat_deg=-4.6, site_lon_east_deg=137.4)
    lt2 = ms.build_scene(cfg.replace(lighting=override), seed=0).lighting
    assert lt2 is not None and lt2.site_lat_deg == -4.6
    assert lt2.sun_elevation_deg != pytest.approx(lt.sun_elevation_deg)


def test_replay_with_other_tau_changes_only_light() -> None:
    a = ms.build_scene(_cfg(utc="2021-02-18T20:55Z", tau=0.3), seed=3)
    b = ms.build_scene(_cfg(utc="2021-02-18T20:55Z", tau=3.0), seed=3)
    assert (a.heightfield.z_m == b.heightfield.z_m).all()
    assert a.lighting is not None and b.lighting is not None
    assert a.lighting.sun_elevation_deg == b.lighting.sun_elevation_deg
    assert b.lighting.direct_normal_w_m2 < a.lighting.direct_normal_w_m2
    assert b.lighting.visibility_m < a.lighting.visibility_m


def test_disabled_and_night() -> None:
    assert ms.build_scene(_cfg(enabled=False), seed=0).lighting is None
    night = compute_lighting(LightingConfig(utc="2021-02-19T08:00Z"), lat_deg=18.4447,
                             lon_east_deg=77.4508)
    assert night.sun_elevation_deg < 0
    assert night.direct_normal_w_m2 == 0.0 and night.diffuse_horizontal_w_m2 == 0.0


def test_local_time_mode_and_explicit_distance() -> None:
    lt = compute_lighting(LightingConfig(mars_year=36, ls_deg=90.0, ltst_h=12.0),
                          lat_deg=18.4447, lon_east_deg=77.4508)
    assert lt.ltst_h == pytest.approx(12.0, abs=1e-6)
    assert lt.sun_elevation_deg == pytest.approx(90 - (25.44 - 18.4447), abs=0.2)  # noon, sun north
    aph = compute_lighting(LightingConfig(sun_azimuth_deg=0.0, sun_elevation_deg=45.0,
                                          ls_deg=68.0), lat_deg=0.0, lon_east_deg=0.0)
    assert aph.toa_w_m2 == pytest.approx(1361.0 / 1.665956**2, rel=1e-3)
