"""Mars24 sun position against the docs/science/sun.md worked examples."""

from __future__ import annotations

import datetime as dt

import numpy as np
import pytest

from marsscene.errors import ConfigError
from marsscene.lighting import (
    mars_sun_position,
    solar_longitude_deg,
    sun_position_at_local_time,
    sun_track,
)
from marsscene.lighting.mars24 import mars24_terms
from marsscene.lighting.timescale import jd_tt_from_utc, tt_minus_utc_s, utc_from_jd_tt

# (utc, lat, lon_east, expected) -- Example A (GISS test case) and Example B (docs/science/sun.md)
EXAMPLES = [
    ("2000-01-06T00:00:00Z", 0.0, 0.0, dict(
        jd_tt=2451549.500743, ls=277.187589, mst=23.994249, lmst=23.994249, ltst=23.648400,
        eot=-5.187746, dec=-25.228244, r=1.393583, zen=154.261757, az=191.039051)),
    ("2004-01-03T13:46:31Z", -14.640, -184.702, dict(
        jd_tt=2453008.074713, ls=327.324162, mst=13.165369, lmst=0.851902, ltst=0.000200,
        eot=-12.775531, dec=-13.420399, r=1.477672, zen=151.939600, az=179.993795)),
]


@pytest.mark.parametrize("utc, lat, lon, ref", EXAMPLES, ids=["A", "B"])
def test_worked_examples(utc: str, lat: float, lon: float, ref: dict[str, float]) -> None:
    p = mars_sun_position(utc, lat_deg=lat, lon_east_deg=lon)
    assert jd_tt_from_utc(utc) == pytest.approx(ref["jd_tt"], abs=2e-6)
    assert p.ls_deg == pytest.approx(ref["ls"], abs=1e-4)
    assert p.mst_h == pytest.approx(ref["mst"], abs=1e-4)
    assert p.lmst_h == pytest.approx(ref["lmst"], abs=1e-4)
    assert p.ltst_h == pytest.approx(ref["ltst"], abs=3e-4)
    assert p.eot_deg == pytest.approx(ref["eot"], abs=1e-4)
    assert p.declination_deg == pytest.approx(ref["dec"], abs=1e-4)
    assert p.distance_au == pytest.approx(ref["r"], abs=1e-6)
    assert p.zenith_deg == pytest.approx(ref["zen"], abs=1e-4)
    assert p.elevation_deg == pytest.approx(90.0 - ref["zen"], abs=1e-4)
    assert p.azimuth_deg == pytest.approx(ref["az"], abs=1e-3)


def test_gray_quoted_values_example_a() -> None:
    # Bill Gray's marstime comments quoting the GISS test case (docs/science/sun.md, [S]).
    p = mars_sun_position("2000-01-06T00:00:00Z", lat_deg=0.0, lon_east_deg=0.0)
    assert p.ls_deg == pytest.approx(277.1875876, abs=1e-5)
    assert p.ltst_h == pytest.approx(23.648333, abs=3e-4)


def test_datetime_input_equals_string() -> None:
    when = dt.datetime(2000, 1, 6, tzinfo=dt.UTC)
    a = mars_sun_position(when, lat_deg=0.0, lon_east_deg=0.0)
    b = mars_sun_position("2000-01-06T01:00:00+01:00", lat_deg=0.0, lon_east_deg=0.0)
    assert a.ls_deg == b.ls_deg and a.azimuth_deg == b.azimuth_deg


def test_leap_seconds() -> None:
    assert tt_minus_utc_s("2000-01-06T00:00Z") == pytest.approx(64.184)
    assert tt_minus_utc_s("2016-12-31T23:59:59Z") == pytest.approx(68.184)
    assert tt_minus_utc_s("2017-01-01T00:00:00Z") == pytest.approx(69.184)
    assert tt_minus_utc_s("2026-11-01T00:00:00Z") == pytest.approx(69.184)
    when = dt.datetime(2021, 2, 18, 20, 55, 12, 345678, tzinfo=dt.UTC)
    # a float64 Julian date resolves ~40 us
    assert abs(utc_from_jd_tt(jd_tt_from_utc(when)) - when) < dt.timedelta(microseconds=100)


def test_ls_wraps_at_mars_year_36_start() -> None:
    a = solar_longitude_deg("2021-02-07T00:00:00Z")
    b = solar_longitude_deg("2021-02-08T00:00:00Z")
    assert a == pytest.approx(359.7707, abs=1e-4)
    assert b == pytest.approx(0.2700, abs=1e-4)
    hours = np.arange(0, 49, 1.0)
    ls = mars24_terms(jd_tt_from_utc("2021-02-07T00:00Z") + hours / 24)["ls_deg"]
    assert np.all((ls >= 0) & (ls < 360))
    assert int(np.sum(np.diff(ls) < 0)) == 1  # exactly one wrap 360 -> 0


def test_local_time_inverse_round_trip() -> None:
    p = sun_position_at_local_time(mars_year=36, ls_deg=5.0, ltst_h=15.0,
                                   lat_deg=18.4447, lon_east_deg=77.4508)
    assert p.ltst_h == pytest.approx(15.0, abs=1e-6)
    assert abs(p.ls_deg - 5.0) < 0.35  # nearest sol: Ls moves ~0.5 deg per sol
    assert dt.datetime(2021, 2, 7, tzinfo=dt.UTC) < p.utc < dt.datetime(2021, 3, 1, tzinfo=dt.UTC)
    q = sun_position_at_local_time(mars_year=35, ls_deg=359.9, ltst_h=0.5,
                                   lat_deg=0.0, lon_east_deg=0.0)
    assert q.utc < dt.datetime(2021, 2, 8, tzinfo=dt.UTC)  # still Mars Year 35
    assert q.ls_deg > 359.0


def test_sun_track_matches_scalar_and_noon_is_highest() -> None:
    track = sun_track("2021-02-18T00:00Z", hours=24.7, step_min=10.0, lat_deg=18.4447,
                      lon_east_deg=77.4508)
    p = mars_sun_position("2021-02-18T05:00Z", lat_deg=18.4447, lon_east_deg=77.4508)
    i = 30
    assert track["elevation_deg"][i] == pytest.approx(p.elevation_deg, abs=1e-9)
    assert track["azimuth_deg"][i] == pytest.approx(p.azimuth_deg, abs=1e-9)
    k = int(np.argmax(track["elevation_deg"]))
    assert track["ltst_h"][k] == pytest.approx(12.0, abs=0.1)
    # Near the equinox at 18.4 N the noon elevation is ~90 - 18.4 + declination.
    assert track["elevation_deg"][k] == pytest.approx(90 - 18.4447 + 2.4, abs=0.3)


def test_direction_vector_matches_angles() -> None:
    p = mars_sun_position("2021-02-18T20:55Z", lat_deg=18.4447, lon_east_deg=77.4508)
    e, n, u = p.direction_enu
    assert np.degrees(np.arctan2(e, n)) % 360 == pytest.approx(p.azimuth_deg)
    assert np.degrees(np.arcsin(u)) == pytest.approx(p.elevation_deg)
    assert p.angular_diameter_deg == pytest.approx(0.5330 * 1.0 / p.distance_au, rel=2e-3)


@pytest.mark.parametrize("bad", [dt.datetime(2021, 2, 18, 20, 55), "2021-02-18T20:55",
                                 "yesterday", 12345])
def test_bad_time_is_rejected(bad: object) -> None:
    with pytest.raises(ConfigError, match="utc"):
        mars_sun_position(bad, lat_deg=0.0, lon_east_deg=0.0)  # type: ignore[arg-type]


def test_naive_datetime_message_is_clear() -> None:
    with pytest.raises(ConfigError, match="no time zone"):
        solar_longitude_deg(dt.datetime(2021, 2, 18, 20, 55))


@pytest.mark.parametrize("lat", [-90.5, 91.0, float("nan")])
def test_bad_latitude(lat: float) -> None:
    with pytest.raises(ConfigError, match="lat_deg"):
        mars_sun_position("2021-02-18T20:55Z", lat_deg=lat, lon_east_deg=77.45)
