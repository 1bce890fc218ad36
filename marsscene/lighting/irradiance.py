"""Solar irradiance at the Martian surface (W m^-2): top of atmosphere, Beer's-law direct beam,
and the diffuse sky from the Appelbaum-Flood / Pollack net-flux table (:doc:`/science/atmosphere`).

All functions are pure and vectorised over ``zenith_deg`` (and ``tau`` where noted).

Air mass used where:

* :func:`direct_irradiance_w_m2` and the direct part subtracted in
  :func:`diffuse_irradiance_w_m2` use ``air_mass_model`` (default ``"spherical"``: the
  homogeneous spherical-shell form, finite at the horizon, within 0.5 % of ``1/cos z`` for
  z <= 60 deg). ``"secant"`` is Appelbaum & Flood's ``m = 1/cos z`` (their Eq. 14/18, meant for
  z <= ~80 deg; it is what their net-flux table was normalised with).
* The spherical form is standard geometry, not from Appelbaum & Flood.
"""

from __future__ import annotations

import warnings
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from marsscene._validate import check_choice, check_range, plain
from marsscene.errors import ConfigError, ExtrapolationWarning
from marsscene.lighting._netflux import (
    TABLE_TAU_MAX,
    TABLE_TAU_MIN,
    net_flux_polynomial,
    net_flux_table,
)
from marsscene.lighting.delta_eddington import delta_eddington_fluxes

__all__ = [
    "MEAN_DISTANCE_AU",
    "SOLAR_CONSTANT_W_M2",
    "air_mass",
    "diffuse_irradiance_w_m2",
    "direct_irradiance_w_m2",
    "global_irradiance_w_m2",
    "toa_irradiance_from_ls_w_m2",
    "toa_irradiance_w_m2",
]

#: Total solar irradiance at 1 AU (Kopp & Lean 2011, doi:10.1029/2010GL045777), W m^-2.
SOLAR_CONSTANT_W_M2 = 1361.0
#: Semi-major axis of Mars' orbit (Mars24 D-2), AU.
MEAN_DISTANCE_AU = 1.523679
#: Appelbaum & Flood (1989/1990): mean TOA beam at Mars, eccentricity, Ls of perihelion.
AF_MEAN_TOA_W_M2 = 590.0
AF_ECCENTRICITY = 0.093377
AF_LS_PERIHELION_DEG = 248.0
MARS_RADIUS_KM = 3396.0
ATMOSPHERE_SCALE_HEIGHT_KM = 11.0

AirMassModel = Literal["spherical", "secant"]
DiffuseModel = Literal["table", "polynomial", "delta_eddington"]
AIR_MASS_MODELS = ("spherical", "secant")
DIFFUSE_MODELS = ("table", "polynomial", "delta_eddington")

AF_CITATION = (
    "Appelbaum & Flood 1990, Solar Energy 45, 353, doi:10.1016/0038-092X(90)90156-7; "
    "NASA TM-103623 (Pollack net-flux table, 1991 update)"
)
DELTA_EDDINGTON_CITATION = (
    "delta-Eddington two-stream (Joseph, Wiscombe & Weinman 1976, "
    "doi:10.1175/1520-0469(1976)033<2452:TDEAFR>2.0.CO;2) as in COMIMART "
    "(Vicente-Retortillo et al. 2015, doi:10.1051/swsc/2015035)"
)


def _z(zenith_deg: ArrayLike) -> NDArray[np.float64]:
    z = np.asarray(zenith_deg, dtype=np.float64)
    if not np.all(np.isfinite(z)):
        raise ConfigError(f"zenith_deg must be finite; got {plain(zenith_deg)!r}")
    return z


def _tau(tau: ArrayLike) -> NDArray[np.float64]:
    t = np.asarray(tau, dtype=np.float64)
    if not np.all(np.isfinite(t)) or np.any(t < 0):
        raise ConfigError(f"tau = {plain(tau)!r} is out of range; optical depth must be >= 0")
    return t


def toa_irradiance_w_m2(
    distance_au: ArrayLike, *, solar_constant_w_m2: float = SOLAR_CONSTANT_W_M2
) -> NDArray[np.float64]:
    """Top-of-atmosphere normal irradiance ``S / r^2`` (W m^-2); 586.2 at 1.523679 AU."""
    r = np.asarray(distance_au, dtype=np.float64)
    if not np.all(np.isfinite(r)) or np.any(r <= 0):
        raise ConfigError(f"distance_au = {plain(distance_au)!r} must be > 0")
    return solar_constant_w_m2 / r**2


def toa_irradiance_from_ls_w_m2(ls_deg: ArrayLike) -> NDArray[np.float64]:
    """Appelbaum & Flood's TOA beam from the season:
    ``590 [1 + e cos(Ls - 248)]^2 / (1 - e^2)^2`` W m^-2 (717.8 at perihelion)."""
    ls = np.radians(np.asarray(ls_deg, dtype=np.float64) - AF_LS_PERIHELION_DEG)
    e = AF_ECCENTRICITY
    return AF_MEAN_TOA_W_M2 * (1.0 + e * np.cos(ls)) ** 2 / (1.0 - e * e) ** 2


def air_mass(
    zenith_deg: ArrayLike,
    *,
    model: AirMassModel = "spherical",
    scale_height_km: float = ATMOSPHERE_SCALE_HEIGHT_KM,
    radius_km: float = MARS_RADIUS_KM,
) -> NDArray[np.float64]:
    """Relative air mass m(z) for Beer's law.

    ``"spherical"``: ``sqrt((r cos z)^2 + 2r + 1) - r cos z`` with ``r = R/H`` (homogeneous
    spherical shell; 24.87 at the horizon for H = 11 km). ``"secant"``: ``1/cos z`` (Appelbaum
    & Flood; infinite at the horizon). Zenith angles beyond 90 deg are clamped to 90.
    """
    check_choice("air_mass_model", model, AIR_MASS_MODELS)
    check_range("scale_height_km", scale_height_km, 0.0, 1000.0, lo_open=True)
    z = np.clip(_z(zenith_deg), 0.0, 90.0)
    cz = np.cos(np.radians(z))
    if model == "secant":
        with np.errstate(divide="ignore"):
            return np.where(cz > 1e-12, 1.0 / np.maximum(cz, 1e-300), np.inf)
    r = radius_km / scale_height_km
    return np.sqrt((r * cz) ** 2 + 2.0 * r + 1.0) - r * cz


def direct_irradiance_w_m2(
    zenith_deg: ArrayLike,
    *,
    tau: ArrayLike,
    distance_au: ArrayLike = MEAN_DISTANCE_AU,
    air_mass_model: AirMassModel = "spherical",
    solar_constant_w_m2: float = SOLAR_CONSTANT_W_M2,
) -> NDArray[np.float64]:
    """Direct-beam **normal** irradiance ``I0 exp(-tau m(z))`` (W m^-2), 0 at/below the horizon.

    Multiply by ``cos z`` for the direct irradiance on a horizontal surface.

    Examples
    --------
    >>> round(float(direct_irradiance_w_m2(0.0, tau=1.0)), 2)  # 586.2 W/m^2 * e^-1
    215.66
    """
    z = _z(zenith_deg)
    t = _tau(tau)
    i0 = toa_irradiance_w_m2(distance_au, solar_constant_w_m2=solar_constant_w_m2)
    m = air_mass(z, model=air_mass_model)
    with np.errstate(over="ignore", invalid="ignore"):
        beam = i0 * np.exp(-t * m)
    return np.where(z < 90.0, np.nan_to_num(beam, nan=0.0), 0.0)


def _down_flux_ratio(
    z: NDArray[np.float64], t: NDArray[np.float64], model: str, albedo: float,
    single_scattering_albedo: float, asymmetry: float,
) -> NDArray[np.float64]:
    """Global horizontal / (I0 cos z): the downward flux normalised to the TOA horizontal."""
    if model == "delta_eddington":
        mu0 = np.cos(np.radians(np.clip(z, 0.0, 89.0)))
        total, _ = delta_eddington_fluxes(
            mu0, tau=t, single_scattering_albedo=single_scattering_albedo, asymmetry=asymmetry,
            surface_albedo=albedo,
        )
        return total
    zc = np.clip(z, 0.0, 85.0)  # the table stops at 85 deg: hold f, the cos z factor -> 0
    if model == "polynomial":
        if np.any(t > 6.0) or np.any(zc >= 80.0):
            warnings.warn(
                "A&F net-flux polynomial used at z >= 80 deg or tau > 6: error up to ~7 % "
                "(or more beyond tau = 6)", ExtrapolationWarning, stacklevel=3,
            )
        f = net_flux_polynomial(zc, t, albedo)
        return np.clip(f, 0.0, None) / (1.0 - albedo)
    if np.any(t > TABLE_TAU_MAX):
        warnings.warn(
            f"tau > {TABLE_TAU_MAX} is beyond the Appelbaum-Flood table; using the polynomial "
            "fit (extrapolated)", ExtrapolationWarning, stacklevel=3,
        )
    f_tab = net_flux_table(zc, np.clip(t, TABLE_TAU_MIN, TABLE_TAU_MAX))
    # Below tau = 0.1: linear in tau towards the no-atmosphere limit f = 1 - al (= 0.9).
    f_low = 0.9 + (net_flux_table(zc, np.full_like(t, TABLE_TAU_MIN)) - 0.9) * t / TABLE_TAU_MIN
    f_high = np.clip(net_flux_polynomial(zc, t, 0.1), 0.0, None)
    f = np.where(t < TABLE_TAU_MIN, f_low, np.where(t > TABLE_TAU_MAX, f_high, f_tab))
    return f / 0.9  # the table is for surface albedo 0.1 (A&F use it for others)


def global_irradiance_w_m2(
    zenith_deg: ArrayLike,
    *,
    tau: ArrayLike,
    distance_au: ArrayLike = MEAN_DISTANCE_AU,
    model: DiffuseModel = "table",
    albedo: float = 0.1,
    single_scattering_albedo: float = 0.93,
    asymmetry: float = 0.68,
    solar_constant_w_m2: float = SOLAR_CONSTANT_W_M2,
) -> NDArray[np.float64]:
    """Global (direct + diffuse) irradiance on a horizontal surface, W m^-2.

    ``"table"``/``"polynomial"``: A&F Eq. 17, ``G_h = I0 cos z f(z, tau, al) / (1 - al)``;
    ``"delta_eddington"``: total downward flux of the two-stream model with the given
    single-scattering albedo ``omega``, asymmetry ``g`` and surface albedo. 0 at/below horizon.
    """
    check_choice("diffuse_model", model, DIFFUSE_MODELS)
    check_range("albedo", albedo, 0.0, 0.9)
    z = _z(zenith_deg)
    t = _tau(tau)
    i0 = toa_irradiance_w_m2(distance_au, solar_constant_w_m2=solar_constant_w_m2)
    ratio = _down_flux_ratio(z, t, model, albedo, single_scattering_albedo, asymmetry)
    cz = np.cos(np.radians(np.clip(z, 0.0, 90.0)))
    return np.where(z < 90.0, i0 * cz * ratio, 0.0)


def diffuse_irradiance_w_m2(
    zenith_deg: ArrayLike,
    *,
    tau: ArrayLike,
    distance_au: ArrayLike = MEAN_DISTANCE_AU,
    model: DiffuseModel = "table",
    albedo: float = 0.1,
    single_scattering_albedo: float = 0.93,
    asymmetry: float = 0.68,
    air_mass_model: AirMassModel = "spherical",
    solar_constant_w_m2: float = SOLAR_CONSTANT_W_M2,
) -> NDArray[np.float64]:
    """Diffuse (sky) irradiance on a horizontal surface, ``G_h - G_b cos z`` (A&F Eq. 16), >= 0.

    Parameters
    ----------
    zenith_deg : array_like
        Sun zenith angle(s), degrees. At or below the horizon the result is 0 (twilight is not
        modelled).
    tau : array_like
        Dust optical depth (>= 0). The A&F table covers 0.1-6; below 0.1 it is interpolated
        linearly to the no-atmosphere limit, above 6 the polynomial is extrapolated (warning).
    distance_au : array_like
        Sun-Mars distance.
    model : {"table", "polynomial", "delta_eddington"}
        A&F/Pollack table (bilinear in tau and z), its polynomial fit, or a COMIMART-style
        delta-Eddington two-stream with ``single_scattering_albedo`` (omega), ``asymmetry`` (g)
        and surface ``albedo``.
    air_mass_model : {"spherical", "secant"}
        Air mass of the direct beam that is subtracted (see the module docstring).

    Returns
    -------
    ndarray
        W m^-2, broadcast shape of ``zenith_deg`` and ``tau``.

    Examples
    --------
    >>> g = float(global_irradiance_w_m2(60.0, tau=1.0))
    >>> d = float(diffuse_irradiance_w_m2(60.0, tau=1.0, air_mass_model="secant"))
    >>> round(d / g, 3)  # A&F reference cell: 0.781
    0.781
    """
    g_h = global_irradiance_w_m2(
        zenith_deg, tau=tau, distance_au=distance_au, model=model, albedo=albedo,
        single_scattering_albedo=single_scattering_albedo, asymmetry=asymmetry,
        solar_constant_w_m2=solar_constant_w_m2,
    )
    z = _z(zenith_deg)
    if model == "delta_eddington":  # the direct part of the two-stream uses the secant (mu0)
        air_mass_model = "secant"
    beam = direct_irradiance_w_m2(
        z, tau=tau, distance_au=distance_au, air_mass_model=air_mass_model,
        solar_constant_w_m2=solar_constant_w_m2,
    )
    return np.clip(g_h - beam * np.cos(np.radians(np.clip(z, 0.0, 90.0))), 0.0, None)

