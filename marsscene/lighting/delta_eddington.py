"""COMIMART-style delta-Eddington two-stream fluxes (Joseph, Wiscombe & Weinman 1976;
Vicente-Retortillo et al. 2015, J. Space Weather Space Clim. 5, A33, Eqs. 10-23 as transcribed in
:doc:`/science/atmosphere`). Broadband use with user (omega, g, surface albedo)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from marsscene._validate import check_range

__all__ = ["delta_eddington_fluxes"]


def delta_eddington_fluxes(
    mu0: ArrayLike,
    *,
    tau: ArrayLike,
    single_scattering_albedo: float,
    asymmetry: float,
    surface_albedo: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Total and direct downward flux at the surface, normalised by the TOA horizontal flux.

    Parameters
    ----------
    mu0 : array_like
        Cosine of the sun zenith angle, in (0, 1].
    tau : array_like
        Optical depth (unscaled), >= 0.
    single_scattering_albedo, asymmetry, surface_albedo : float
        omega in [0, 1), g in [0, 1), A in [0, 1].

    Returns
    -------
    total, direct : ndarray
        ``T/E`` and ``exp(-tau/mu0)``; diffuse = total - direct.

    Examples
    --------
    >>> t, d = delta_eddington_fluxes(0.7, tau=1.0, single_scattering_albedo=0.97,
    ...                               asymmetry=0.70, surface_albedo=0.25)
    >>> round(float(t), 4)  # COMIMART Table 3 (mu0 = 0.7, tau = 1): 0.8276
    0.8276
    """
    check_range("single_scattering_albedo", single_scattering_albedo, 0.0, 1.0)
    check_range("asymmetry", asymmetry, 0.0, 1.0, hi_open=True)
    check_range("surface_albedo", surface_albedo, 0.0, 1.0)
    w = min(single_scattering_albedo, 1.0 - 1e-9)  # omega' = 1 is a removable singularity
    g, a = asymmetry, surface_albedo
    mu, t = np.broadcast_arrays(np.asarray(mu0, float), np.asarray(tau, float))
    mu = np.clip(mu, 1e-6, 1.0)
    gs = g / (1.0 + g)
    ws = w * (1.0 - g * g) / (1.0 - w * g * g)
    ts = t * (1.0 - w * g * g)
    k = np.sqrt(3.0 * (1.0 - ws) * (1.0 - gs * ws))
    p = (2.0 / 3.0) * np.sqrt(3.0 * (1.0 - ws) / (1.0 - gs * ws))
    den_mu = 1.0 - mu**2 * k**2
    mu = np.where(np.abs(den_mu) < 1e-9, mu * (1.0 + 1e-6), mu)  # mu0 k = 1 singularity
    den_mu = 1.0 - mu**2 * k**2
    alpha = 0.75 * mu * ws * (1.0 + gs * (1.0 - ws)) / den_mu
    beta = 0.5 * mu * ws * (1.0 / mu + 3.0 * mu * gs * (1.0 - ws)) / den_mu
    c3 = a + (1.0 - a) * alpha - (1.0 + a) * beta
    c4 = 1.0 - a + p * (1.0 + a)
    c5 = 1.0 - a - p * (1.0 + a)
    ekp = np.exp(np.minimum(k * ts, 700.0))
    ekm = np.exp(-k * ts)
    edir_s = np.exp(-ts / mu)
    den = (1.0 + p) * c4 * ekp - (1.0 - p) * c5 * ekm
    c1 = -((1.0 - p) * c3 * edir_s - (alpha + beta) * c4 * ekp) / den
    c2 = ((1.0 + p) * c3 * edir_s - (alpha + beta) * c5 * ekm) / den
    total = c1 * ekm * (1.0 + p) + c2 * ekp * (1.0 - p) - (alpha + beta - 1.0) * edir_s
    direct = np.exp(-t / mu)
    return np.clip(total, direct, None), direct
