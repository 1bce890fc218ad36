"""Mars coordinate systems with pyproj: label sphere CRS, lon/lat <-> projected metres.

Longitudes are planetocentric, **east-positive, 0-360** at this module's boundary (HiRISE labels
use that convention); pyproj works in -180..180 internally. Latitudes are planetocentric, which on
the label sphere equals the geodetic latitude of its geographic CRS.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from marsscene._validate import plain
from marsscene.errors import CRSError

__all__ = [
    "IAU_2015_MARS",
    "crs_from_wkt",
    "grid_convergence_deg",
    "iau_2015_code",
    "is_projected_metres",
    "lonlat_to_xy",
    "proj_params",
    "xy_to_lonlat",
]

#: IAU_2015 Mars CRSs on the 3396190 m sphere that a label CRS may match exactly.
IAU_2015_MARS: dict[str, dict[str, Any]] = {
    "IAU_2015:49910": {"proj": "eqc", "lat_ts": 0.0, "lon_0": 0.0, "lat_0": 0.0},
    "IAU_2015:49915": {"proj": "eqc", "lat_ts": 0.0, "lon_0": 180.0, "lat_0": 0.0},
    "IAU_2015:49930": {"proj": "stere", "lat_0": 90.0, "lon_0": 0.0},
    "IAU_2015:49935": {"proj": "stere", "lat_0": -90.0, "lon_0": 0.0},
}
_IAU_RADIUS_M = 3396190.0


@lru_cache(maxsize=32)
def crs_from_wkt(text: str) -> Any:
    """A ``pyproj.CRS`` from WKT or a PROJ string (cached)."""
    from pyproj import CRS
    from pyproj.exceptions import CRSError as ProjCRSError

    try:
        return CRS.from_user_input(text)
    except ProjCRSError as err:
        raise CRSError(f"unusable CRS {text[:80]!r}: {err}") from None


def is_projected_metres(text: str) -> bool:
    """True if the CRS is projected with metre axes."""
    crs = crs_from_wkt(text)
    if not crs.is_projected:
        return False
    units = {ax.unit_name.lower() for ax in crs.axis_info}
    return units <= {"metre", "meter", "m"}


@lru_cache(maxsize=32)
def _transformers(text: str) -> tuple[Any, Any]:
    from pyproj import Transformer

    crs = crs_from_wkt(text)
    geo = crs.geodetic_crs
    if geo is None:
        raise CRSError(f"CRS has no geographic base: {text[:80]!r}")
    fwd = Transformer.from_crs(geo, crs, always_xy=True)
    inv = Transformer.from_crs(crs, geo, always_xy=True)
    return fwd, inv


def lonlat_to_xy(
    crs_wkt: str, lon_deg: ArrayLike, lat_deg: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Projected ``(x, y)`` (in m) of planetocentric east longitude / latitude (in deg).

    Longitudes may be given in 0-360 or -180..180.

    Raises
    ------
    CRSError
        The CRS is not projected in metres, or the point cannot be projected.
    """
    if not is_projected_metres(crs_wkt):
        raise CRSError("the DEM's CRS is geographic (degrees) or not in metres; "
                       "a projected CRS in metres is needed")
    fwd, _ = _transformers(crs_wkt)
    lon = (np.asarray(lon_deg, dtype=np.float64) + 180.0) % 360.0 - 180.0
    x, y = fwd.transform(lon, np.asarray(lat_deg, dtype=np.float64))
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    if not (np.isfinite(x).all() and np.isfinite(y).all()):
        raise CRSError(
            f"lon/lat ({plain(lon_deg)!r}, {plain(lat_deg)!r}) cannot be projected into the "
            "DEM's CRS"
        )
    return x, y


def xy_to_lonlat(
    crs_wkt: str, x_m: ArrayLike, y_m: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Planetocentric ``(east longitude 0-360, latitude)`` (in deg) of projected points."""
    if not is_projected_metres(crs_wkt):
        raise CRSError("the DEM's CRS is geographic (degrees) or not in metres")
    _, inv = _transformers(crs_wkt)
    lon, lat = inv.transform(np.asarray(x_m, dtype=np.float64), np.asarray(y_m, dtype=np.float64))
    return np.asarray(lon, dtype=np.float64) % 360.0, np.asarray(lat, dtype=np.float64)


def proj_params(crs_wkt: str) -> dict[str, Any]:
    """PROJ parameters of a projected CRS (``{}`` for other CRSs)."""
    import warnings

    crs = crs_from_wkt(crs_wkt)
    if not crs.is_projected:
        return {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # "lose projection information": expected
        params: dict[str, Any] = crs.to_dict()
    return params


def iau_2015_code(crs_wkt: str) -> str | None:
    """The IAU_2015 Mars code equal to this CRS (same projection, centre and 3396190 m sphere).

    HiRISE equirectangular labels use the local radius at ``CENTER_LATITUDE`` and a non-zero
    latitude of true scale, so most DTMs have no IAU code (``None``); the label sphere is then the
    CRS of record.
    """
    params = proj_params(crs_wkt)
    radius = params.get("R", params.get("a"))
    if radius is None or params.get("b", radius) != radius:
        return None
    if not np.isclose(float(radius), _IAU_RADIUS_M, rtol=0, atol=0.5):
        return None
    for code, want in IAU_2015_MARS.items():
        if params.get("proj") != want["proj"]:
            continue
        if all(abs(float(params.get(k, 0.0)) - float(v)) <= 1e-9 for k, v in want.items()
               if k != "proj") and float(params.get("k", params.get("k_0", 1.0))) == 1.0:
            return code
    return None


def grid_convergence_deg(crs_wkt: str, lon_deg: float, lat_deg: float) -> float:
    """Angle from true north to grid north at a point (in deg; 0 on an equirectangular grid's
    meridians, the longitude offset on a polar stereographic grid)."""
    from pyproj import Proj

    try:
        factors = Proj(crs_from_wkt(crs_wkt)).get_factors(
            ((lon_deg + 180.0) % 360.0) - 180.0, lat_deg)
    except Exception:  # projections without factors: report none
        return 0.0
    value = float(factors.meridian_convergence)
    return value if np.isfinite(value) else 0.0
