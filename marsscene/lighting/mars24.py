"""Mars sun position: the Mars24 algorithm (Allison & McEwen 2000) with current constants.

Allison, M. & McEwen, M. (2000), "A post-Pathfinder evaluation of areocentric solar coordinates
with improved timing recipes for Mars seasonal/diurnal climate studies", Planet. Space Sci. 48,
215-235, doi:10.1016/S0032-0633(99)00092-6; current constants from the NASA GISS Mars24
algorithm page (:doc:`/science/sun`). Longitudes are planetocentric **east** (0-360); the
azimuth is measured clockwise from north (east = 90 deg).
"""

from __future__ import annotations

import datetime as dt
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from marsscene._validate import check_range
from marsscene.errors import ConfigError
from marsscene.lighting.timescale import jd_tt_from_utc, parse_utc, utc_from_jd_tt

__all__ = [
    "SunPosition",
    "mars24_terms",
    "mars_sun_position",
    "solar_longitude_deg",
    "sun_direction_enu",
    "sun_position_at_local_time",
    "sun_track",
]

MARS24_CITATION = (
    "Mars24 sun position: Allison & McEwen 2000, Planet. Space Sci. 48, 215, "
    "doi:10.1016/S0032-0633(99)00092-6 (current GISS Mars24 constants)"
)
_SOL_DAYS = 1.0274912517  # Mars solar day in Earth days (Mars24 C-2)
_MARS_YEAR_DAYS = 686.9726
_PBS = np.array([  # Mars24 B-3: amplitude (deg), period (Julian years), phase (deg)
    (0.0071, 2.2353, 49.409), (0.0057, 2.7543, 168.173), (0.0039, 1.1177, 191.837),
    (0.0037, 15.7866, 21.736), (0.0021, 2.1354, 15.704), (0.0020, 2.4694, 95.528),
    (0.0018, 32.8493, 49.095),
])
#: Ls = 0 of Mars Year 36 falls on 2021-02-07 (Piqueux et al. 2015 calendar).
_MY36_START = dt.datetime(2021, 2, 7, 12, tzinfo=dt.UTC)
_SUN_RADIUS_KM = 695_700.0  # IAU 2015 nominal solar radius
_AU_KM = 149_597_870.7


@dataclass(frozen=True, slots=True)
class SunPosition:
    """The sun seen from a point on Mars at one instant (angles in degrees, times in hours)."""

    utc: dt.datetime
    lat_deg: float
    lon_east_deg: float
    azimuth_deg: float
    """Clockwise from north (east = 90)."""
    elevation_deg: float
    zenith_deg: float
    ls_deg: float
    """Areocentric solar longitude (season; 0 = northern spring equinox)."""
    ltst_h: float
    """Local true solar time (12 h = sun on the meridian)."""
    lmst_h: float
    """Local mean solar time."""
    mst_h: float
    """Mars (Airy) mean solar time at longitude 0."""
    distance_au: float
    """Sun-Mars distance."""
    declination_deg: float
    subsolar_lon_east_deg: float
    eot_deg: float

    @property
    def direction_enu(self) -> tuple[float, float, float]:
        """Unit vector from the ground towards the sun (x east, y north, z up)."""
        v = sun_direction_enu(self.azimuth_deg, self.elevation_deg)
        return (float(v[0]), float(v[1]), float(v[2]))

    @property
    def angular_diameter_deg(self) -> float:
        """Apparent diameter of the solar disc (0.35 deg at Mars' mean distance)."""
        return sun_angular_diameter_deg(self.distance_au)


def sun_angular_diameter_deg(distance_au: float) -> float:
    """Apparent solar diameter in degrees at ``distance_au`` (0.533 deg at 1 AU)."""
    return math.degrees(2.0 * math.asin(_SUN_RADIUS_KM / (distance_au * _AU_KM)))


def sun_direction_enu(azimuth_deg: ArrayLike, elevation_deg: ArrayLike) -> NDArray[np.float64]:
    """Unit vector(s) towards the sun, shape ``(..., 3)`` (x east, y north, z up)."""
    az = np.radians(np.asarray(azimuth_deg, dtype=np.float64))
    el = np.radians(np.asarray(elevation_deg, dtype=np.float64))
    return np.stack([np.sin(az) * np.cos(el), np.cos(az) * np.cos(el), np.sin(el)], axis=-1)


def mars24_terms(jd_tt: ArrayLike) -> dict[str, NDArray[np.float64]]:
    """Mars24 steps B-1..D-2 for Julian date(s) in TT (vectorised).

    Returns a dict of arrays: ``ls_deg``, ``mst_h``, ``eot_deg``, ``declination_deg``,
    ``distance_au``, ``mean_anomaly_deg`` and ``msd`` (Mars sol date).
    """
    jd = np.asarray(jd_tt, dtype=np.float64)
    d_t = jd - 2451545.0
    m_deg = 19.3871 + 0.52402073 * d_t  # B-1
    alpha_fms = 270.3871 + 0.524038496 * d_t  # B-2
    amp, tau, phi = _PBS[:, 0], _PBS[:, 1], _PBS[:, 2]
    pbs = np.sum(amp * np.cos(np.radians(0.985626 * d_t[..., None] / tau + phi)), axis=-1)
    m = np.radians(m_deg)
    nu_m = (
        (10.691 + 3.0e-7 * d_t) * np.sin(m) + 0.623 * np.sin(2 * m) + 0.050 * np.sin(3 * m)
        + 0.005 * np.sin(4 * m) + 0.0005 * np.sin(5 * m) + pbs
    )  # B-4
    ls = np.mod(alpha_fms + nu_m, 360.0)  # B-5
    ls_r = np.radians(ls)
    eot = 2.861 * np.sin(2 * ls_r) - 0.071 * np.sin(4 * ls_r) + 0.002 * np.sin(6 * ls_r) - nu_m
    msd = (jd - 2451549.5) / _SOL_DAYS + 44796.0 - 0.0009626  # C-2
    mst = np.mod(24.0 * msd, 24.0)
    dec = np.degrees(np.arcsin(0.42565 * np.sin(ls_r))) + 0.25 * np.sin(ls_r)  # D-1
    r_au = 1.523679 * (
        1.00436 - 0.09309 * np.cos(m) - 0.004336 * np.cos(2 * m) - 0.00031 * np.cos(3 * m)
        - 0.00003 * np.cos(4 * m)
    )  # D-2
    return {"ls_deg": ls, "mst_h": mst, "eot_deg": eot, "declination_deg": dec,
            "distance_au": r_au, "mean_anomaly_deg": np.mod(m_deg, 360.0), "msd": msd}


def _check_site(lat_deg: float, lon_east_deg: float) -> None:
    check_range("lat_deg", lat_deg, -90.0, 90.0)
    check_range("lon_east_deg", lon_east_deg, -360.0, 360.0)


def _topocentric(terms: dict[str, Any], lat_deg: float, lon_east_deg: float) -> dict[str, Any]:
    """Mars24 C-3..D-5 at a site (vectorised over ``terms``)."""
    lon_w = np.mod(-lon_east_deg, 360.0)
    lmst = np.mod(terms["mst_h"] - lon_w / 15.0, 24.0)  # C-3
    ltst = np.mod(lmst + terms["eot_deg"] / 15.0, 24.0)  # C-4
    subsolar_w = np.mod(terms["mst_h"] * 15.0 + terms["eot_deg"] + 180.0, 360.0)  # C-5
    h = np.radians(lon_w - subsolar_w)  # hour angle, D-5
    phi = math.radians(lat_deg)
    dec = np.radians(terms["declination_deg"])
    cos_z = np.sin(dec) * math.sin(phi) + np.cos(dec) * math.cos(phi) * np.cos(h)
    zen = np.degrees(np.arccos(np.clip(cos_z, -1.0, 1.0)))
    # Mars24 azimuth formula written with sin/cos of the declination (no tan singularity).
    az = np.degrees(np.arctan2(
        np.sin(h) * np.cos(dec),
        math.cos(phi) * np.sin(dec) - math.sin(phi) * np.cos(dec) * np.cos(h),
    ))
    return {"lmst_h": lmst, "ltst_h": ltst, "zenith_deg": zen, "azimuth_deg": np.mod(az, 360.0),
            "subsolar_lon_east_deg": np.mod(-subsolar_w, 360.0)}


def mars_sun_position(
    utc: dt.datetime | str, *, lat_deg: float, lon_east_deg: float
) -> SunPosition:
    """Sun position at a Mars site and UTC instant (Mars24).

    Parameters
    ----------
    utc : datetime or str
        Timezone-aware datetime or ISO 8601 string with zone (``"2021-02-18T20:55Z"``).
    lat_deg : float
        Planetocentric latitude, in [-90, 90].
    lon_east_deg : float
        East longitude in degrees (0-360; negative values are west).

    Returns
    -------
    SunPosition

    Raises
    ------
    ConfigError
        Naive datetime, bad string, latitude out of range.

    Examples
    --------
    >>> p = mars_sun_position("2000-01-06T00:00:00Z", lat_deg=0.0, lon_east_deg=0.0)
    >>> round(p.ls_deg, 4), round(p.mst_h, 4)
    (277.1876, 23.9942)
    """
    when = parse_utc(utc)
    _check_site(lat_deg, lon_east_deg)
    terms = mars24_terms(jd_tt_from_utc(when))
    topo = _topocentric(terms, lat_deg, lon_east_deg)
    zen = float(topo["zenith_deg"])
    return SunPosition(
        utc=when, lat_deg=float(lat_deg), lon_east_deg=float(np.mod(lon_east_deg, 360.0)),
        azimuth_deg=float(topo["azimuth_deg"]), elevation_deg=90.0 - zen, zenith_deg=zen,
        ls_deg=float(terms["ls_deg"]), ltst_h=float(topo["ltst_h"]), lmst_h=float(topo["lmst_h"]),
        mst_h=float(terms["mst_h"]), distance_au=float(terms["distance_au"]),
        declination_deg=float(terms["declination_deg"]),
        subsolar_lon_east_deg=float(topo["subsolar_lon_east_deg"]), eot_deg=float(terms["eot_deg"]),
    )


def solar_longitude_deg(utc: dt.datetime | str) -> float:
    """Areocentric solar longitude Ls (deg, [0, 360)) at ``utc`` (Mars24 B-5)."""
    return float(mars24_terms(jd_tt_from_utc(parse_utc(utc)))["ls_deg"])


def sun_track(
    utc_start: dt.datetime | str, *, hours: float, step_min: float, lat_deg: float,
    lon_east_deg: float,
) -> dict[str, NDArray[np.float64]]:
    """Vectorised sun positions from ``utc_start`` over ``hours`` every ``step_min`` minutes.

    Returns arrays ``hours_since_start``, ``azimuth_deg``, ``elevation_deg``, ``zenith_deg``,
    ``ltst_h``, ``lmst_h``, ``ls_deg``, ``distance_au``.
    """
    check_range("hours", hours, 0.0, 24.0 * 800, lo_open=True)
    check_range("step_min", step_min, 0.0, lo_open=True)
    _check_site(lat_deg, lon_east_deg)
    t_h = np.arange(0.0, hours + 1e-9, step_min / 60.0)
    jd = jd_tt_from_utc(utc_start) + t_h / 24.0  # TT-UTC constant over the span (no leap)
    terms = mars24_terms(jd)
    topo = _topocentric(terms, lat_deg, lon_east_deg)
    return {"hours_since_start": t_h, "azimuth_deg": topo["azimuth_deg"],
            "elevation_deg": 90.0 - topo["zenith_deg"], "zenith_deg": topo["zenith_deg"],
            "ltst_h": topo["ltst_h"], "lmst_h": topo["lmst_h"], "ls_deg": terms["ls_deg"],
            "distance_au": terms["distance_au"]}


def _wrap180(x: float) -> float:
    return (x + 180.0) % 360.0 - 180.0


def sun_position_at_local_time(
    *, mars_year: int, ls_deg: float, ltst_h: float, lat_deg: float, lon_east_deg: float
) -> SunPosition:
    """Sun position at a site on the sol of Mars Year ``mars_year`` nearest ``ls_deg``, at local
    true solar time ``ltst_h``.

    Mars years follow Clancy et al. (2000) / Piqueux et al. (2015): MY 1 starts 1955-04-11,
    MY 36 on 2021-02-07 (Ls = 0). Ls advances ~0.5 deg per sol, so the returned ``ls_deg`` is
    within ~0.3 deg of the request; ``ltst_h`` matches to < 1e-6 h.

    Parameters
    ----------
    mars_year : int
        Mars Year (MY 36 began on 2021-02-07).
    ls_deg : float
        Areocentric solar longitude of the sol, in [0, 360) (90: northern summer solstice).
    ltst_h : float
        Local true solar time at the site, in hours [0, 24) (12: the sun crosses the meridian).
    lat_deg : float
        Planetocentric latitude, in [-90, 90].
    lon_east_deg : float
        East longitude in degrees (0-360; negative values are west).

    Returns
    -------
    SunPosition
        Elevation, azimuth (clockwise from north) and zenith in degrees, the UTC instant,
        ``ls_deg``, ``ltst_h``, the Sun–Mars distance and more (:func:`mars_sun_position`).

    Raises
    ------
    ConfigError
        A non-integer Mars year, or a value out of range.

    Examples
    --------
    Local noon at Jezero crater on the northern summer solstice of MY 36:

    >>> from marsscene.lighting import sun_position_at_local_time
    >>> p = sun_position_at_local_time(mars_year=36, ls_deg=90.0, ltst_h=12.0,
    ...                                lat_deg=18.4, lon_east_deg=77.5)
    >>> p.utc.date().isoformat(), round(p.elevation_deg, 1), round(p.ls_deg, 1)
    ('2021-08-24', 83.0, 89.9)
    """
    if isinstance(mars_year, bool) or not isinstance(mars_year, int | np.integer):
        raise ConfigError(f"mars_year = {mars_year!r} must be an integer")
    check_range("mars_year", int(mars_year), -200, 400)
    check_range("ls_deg", ls_deg, 0.0, 360.0, hi_open=True)
    check_range("ltst_h", ltst_h, 0.0, 24.0, hi_open=True)
    _check_site(lat_deg, lon_east_deg)
    jd = jd_tt_from_utc(_MY36_START) + (mars_year - 36 + ls_deg / 360.0) * _MARS_YEAR_DAYS
    for _ in range(20):  # Newton on Ls(t) with a numerical derivative
        f0 = _wrap180(float(mars24_terms(jd)["ls_deg"]) - ls_deg)
        rate = _wrap180(float(mars24_terms(jd + 1.0)["ls_deg"]) - float(mars24_terms(jd)["ls_deg"]))
        step = f0 / rate
        jd -= step
        if abs(step) < 1e-9:
            break
    for _ in range(6):  # move to the requested local true solar time within +-half a sol
        topo = _topocentric(mars24_terms(jd), lat_deg, lon_east_deg)
        dh = (ltst_h - float(topo["ltst_h"]) + 12.0) % 24.0 - 12.0
        jd += dh / 24.0 * _SOL_DAYS
        if abs(dh) < 1e-9:
            break
    return mars_sun_position(utc_from_jd_tt(jd), lat_deg=lat_deg, lon_east_deg=lon_east_deg)
