"""The Appelbaum-Flood / Pollack normalised net-flux function f(z, tau[, al]) (data in data/)."""

from __future__ import annotations

from functools import lru_cache
from importlib import resources

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import RegularGridInterpolator

__all__ = ["TABLE_TAU_MAX", "TABLE_TAU_MIN", "net_flux_polynomial", "net_flux_table"]

TABLE_TAU_MIN = 0.1
TABLE_TAU_MAX = 6.0


def _rows(name: str) -> list[list[str]]:
    text = resources.files("marsscene.lighting").joinpath(f"data/{name}").read_text("utf-8")
    return [ln.split(",") for ln in text.splitlines() if ln.strip() and not ln.startswith("#")]


@lru_cache(maxsize=1)
def table_albedo_0p1() -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """``(tau (n,), zenith_deg (m,), f (n, m))`` of A&F Table III (1991 update), albedo 0.1."""
    rows = _rows("af_netflux_albedo0p1.csv")
    z = np.array([float(v) for v in rows[0][1:]])
    tau = np.array([float(r[0]) for r in rows[1:]])
    f = np.array([[float(v) for v in r[1:]] for r in rows[1:]])
    return tau, z, f


@lru_cache(maxsize=1)
def polynomial_coefficients() -> NDArray[np.float64]:
    """``p[k, j, i]`` (albedo power k, zenith power j, tau power i), shape (2, 6, 6)."""
    rows = _rows("af_netflux_polynomial.csv")[1:]
    p = np.zeros((2, 6, 6))
    for r in rows:
        p[int(r[0]), int(r[1]), :] = [float(v) for v in r[2:]]
    return p


@lru_cache(maxsize=1)
def _interpolator() -> RegularGridInterpolator:
    tau, z, f = table_albedo_0p1()
    return RegularGridInterpolator((tau, z), f, method="linear", bounds_error=True)


def net_flux_table(
    zenith_deg: NDArray[np.float64], tau: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Bilinear interpolation of the albedo-0.1 table; inputs inside z in [0, 85], tau in
    [0.1, 6] (broadcast together)."""
    z, t = np.broadcast_arrays(np.asarray(zenith_deg, float), np.asarray(tau, float))
    pts = np.stack([t.ravel(), z.ravel()], axis=-1)
    out: NDArray[np.float64] = _interpolator()(pts).reshape(z.shape)
    return out


def net_flux_polynomial(
    zenith_deg: NDArray[np.float64], tau: NDArray[np.float64], albedo: float
) -> NDArray[np.float64]:
    """A&F polynomial ``(1 - al) sum p_ijk tau^i (z/100)^j al^k`` (broadcast)."""
    p = polynomial_coefficients()
    z, t = np.broadcast_arrays(np.asarray(zenith_deg, float), np.asarray(tau, float))
    zp = (z[..., None] / 100.0) ** np.arange(6)  # (..., j)
    tp = t[..., None] ** np.arange(6)  # (..., i)
    coeff = p[0] + p[1] * albedo  # (j, i)
    out: NDArray[np.float64] = (1.0 - albedo) * np.einsum("...j,ji,...i->...", zp, coeff, tp)
    return out
