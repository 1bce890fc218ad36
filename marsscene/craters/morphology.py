"""Crater radial profiles (:doc:`/science/craters`) and their degradation by topographic diffusion.

``rho = r / R`` (``R = D / 2``); heights are relative to the pre-impact surface. Three fresh
profile models:

``"watters-2015"``
    Power-law cavity ``h = h_r - d (1 - rho^alpha)`` with ``alpha = 1.75`` (the average cavity
    exponent of Watters et al. 2015, doi:10.1002/2014JE004630); ``d`` is the rim-crest-to-floor
    depth. Outside the rim an ejecta blanket ``h_r rho^-beta`` (``beta = 3``, McGetchin et al.
    1973, doi:10.1016/0012-821X(73)90118-0) shifted and rescaled to reach 0 at ``ejecta_reach``.
``"fassett-thomson-2014"``
    Fassett & Thomson (2014, doi:10.1002/2014JE004698) Eq. 4 polynomials (d/D ~ 0.22, fixed).
``"ftmod"``
    FTmod (Fassett, pers. comm. 2022, as in synthterrain): the same polynomials with a flat
    rim on ``0.98 < rho <= 1.02`` and a flat floor at ``0.036822 - d/D``. The outer polynomial is
    evaluated at ``rho - 0.04`` so the profile is continuous at ``rho = 1.02``.

Degradation: linear diffusion ``dh/dt = kappa laplacian(h)`` of the axisymmetric profile for
``kappa t``; the exact radial heat kernel gives ``h(rho; s)`` with ``s = sqrt(2 kappa t) / R``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import eigh_tridiagonal

from marsscene.craters.morphometry import (
    CAVITY_EXPONENT,
    DEFAULT_DEPTH_TO_DIAMETER,
    EJECTA_EXPONENT,
    RIM_HEIGHT_TO_DIAMETER,
)
from marsscene.errors import ConfigError

__all__ = [
    "PROFILE_IDS",
    "PROFILE_MODELS",
    "S_ERASE",
    "ProfileFamily",
    "crater_profile",
    "profile_family",
    "profile_over_diameter",
]

FloatArray = NDArray[np.float64]

#: Profile model name -> id stored in ``CraterTable.profile``.
PROFILE_IDS: dict[str, int] = {"watters-2015": 0, "fassett-thomson-2014": 1, "ftmod": 2}
PROFILE_MODELS: tuple[str, ...] = tuple(PROFILE_IDS)

_FT_RIM = 0.036822095
_RHO_STEP = 0.01  # radial grid step of the tabulated profiles (in crater radii)
#: Degradation table: s = sqrt(2 kappa t) / R; below S_MIN the crater is treated as fresh.
S_MIN = 0.02
S_MAX = 1.5
#: Recognisability limit: a crater diffused beyond ``s = S_ERASE`` keeps ~25 % of its fresh
#: relief (watters-2015 defaults) and no longer counts as a crater; the sampler drops it, and
#: equilibrium-capped sizes reach it exactly at their equilibrium age.
S_ERASE = 0.6
_S_GRID = np.concatenate([[0.0], np.geomspace(S_MIN, S_MAX, 40)])


def _ft_inner(rho: FloatArray) -> FloatArray:
    p = -0.228809953 + 0.227533882 * rho + 0.083116795 * rho**2 - 0.039499407 * rho**3
    return np.where(rho <= 0.2, -0.181, p)


def _ft_outer(rho: FloatArray) -> FloatArray:
    return 0.188253307 - 0.187050452 * rho + 0.01844746 * rho**2 + 0.01505647 * rho**3


def profile_over_diameter(
    rho: ArrayLike,
    *,
    model: str = "watters-2015",
    depth_to_diameter: float = DEFAULT_DEPTH_TO_DIAMETER,
    rim_height_to_diameter: float = RIM_HEIGHT_TO_DIAMETER,
    cavity_exponent: float = CAVITY_EXPONENT,
    ejecta_exponent: float = EJECTA_EXPONENT,
    ejecta_reach: float = 2.5,
) -> FloatArray:
    """Fresh profile in units of the diameter, ``h / D`` at ``rho = r / R``.

    Parameters
    ----------
    rho : array_like
        Radial distance in crater radii (>= 0).
    model : str
        One of :data:`PROFILE_MODELS`.
    depth_to_diameter : float
        Rim-crest-to-floor depth over diameter (``watters-2015`` and ``ftmod``).
    rim_height_to_diameter : float
        Rim height above the pre-impact surface over diameter (``watters-2015``).
    cavity_exponent, ejecta_exponent : float
        ``alpha`` and ``beta`` of the ``watters-2015`` model.
    ejecta_reach : float
        Where the ``watters-2015`` ejecta reaches zero (in crater radii, > 1).

    Returns
    -------
    ndarray
        ``h / D``, same shape as ``rho``.
    """
    r = np.abs(np.asarray(rho, dtype=np.float64))
    if model == "watters-2015":
        hr, d = rim_height_to_diameter, depth_to_diameter
        inner = hr - d * (1.0 - r**cavity_exponent)
        tail = ejecta_reach**-ejecta_exponent
        with np.errstate(divide="ignore"):
            outer = hr * (np.maximum(r, 1.0) ** -ejecta_exponent - tail) / (1.0 - tail)
        return np.where(r <= 1.0, inner, np.where(r < ejecta_reach, outer, 0.0))
    if model == "fassett-thomson-2014":
        out = np.where(r <= 0.98, _ft_inner(r), _ft_outer(r))
        return np.where(r > 1.5, 0.0, out)
    if model == "ftmod":
        inner = np.maximum(_ft_inner(r), _FT_RIM - depth_to_diameter)
        outer = np.where(r <= 1.54, _ft_outer(r - 0.04), 0.0)
        return np.where(r <= 0.98, inner, np.where(r <= 1.02, _FT_RIM, outer))
    raise ConfigError(
        f"craters.profile = {model!r} is unknown; choose one of {list(PROFILE_MODELS)}"
    )


def _fresh_reach(model: str, ejecta_reach: float) -> float:
    return {"watters-2015": ejecta_reach, "fassett-thomson-2014": 1.5, "ftmod": 1.54}[model]


@dataclass(frozen=True, eq=False)
class ProfileFamily:
    """Fresh and diffused profiles of one model, tabulated on ``rho`` and ``s``.

    Attributes
    ----------
    rho : ndarray of shape (n_rho,)
        Radial grid (in crater radii).
    s : ndarray of shape (n_s,)
        Diffusion length over radius, ``sqrt(2 kappa t) / R``; ``s[0] = 0`` is the fresh profile.
    h_over_d : ndarray of shape (n_s, n_rho)
        ``h / D`` per degradation state.
    reach : ndarray of shape (n_s,)
        Footprint radius per state (in crater radii); the profile is 0 beyond it.
    depth_over_d, rim_over_d : ndarray of shape (n_s,)
        Floor depth below / rim crest above the pre-impact surface, over D.
    """

    rho: FloatArray
    s: FloatArray
    h_over_d: FloatArray
    reach: FloatArray
    depth_over_d: FloatArray
    rim_over_d: FloatArray

    def state_of_depth(self, depth_over_d: ArrayLike) -> FloatArray:
        """Fractional row index into :attr:`s` of the state with a given floor depth over D."""
        rows = np.arange(self.s.size, dtype=np.float64)
        # depth decreases monotonically with s: interpolate on the reversed arrays
        return np.asarray(
            np.interp(np.asarray(depth_over_d, dtype=np.float64),
                      self.depth_over_d[::-1], rows[::-1]),
            dtype=np.float64,
        )

    def s_of_state(self, state: ArrayLike) -> FloatArray:
        """Diffusion length over radius at fractional row indices."""
        rows = np.arange(self.s.size, dtype=np.float64)
        return np.asarray(np.interp(np.asarray(state, dtype=np.float64), rows, self.s),
                          dtype=np.float64)

    def recognisable_depth_over_d(self) -> float:
        """Floor depth over D at the recognisability limit ``s = S_ERASE``: shallower craters
        are no longer counted (the population sampler drops them)."""
        state = float(self.state_of_s(S_ERASE))
        return float(np.interp(state, np.arange(self.s.size), self.depth_over_d))

    def state_of_s(self, s: ArrayLike) -> FloatArray:
        """Fractional row index of given ``s`` values (clipped to the table)."""
        rows = np.arange(self.s.size, dtype=np.float64)
        s_arr = np.asarray(s, dtype=np.float64)
        return np.asarray(np.interp(s_arr, self.s, rows), dtype=np.float64)


def _radial_diffusion_table(rho: FloatArray, h0: FloatArray, s: FloatArray) -> FloatArray:
    """Diffuse the axisymmetric profile ``h0(rho)`` to Gaussian widths ``s`` (in crater radii).

    Finite volumes on annuli (zero flux at the outer edge, so volume is conserved exactly); the
    symmetric tridiagonal operator is diagonalised once and every state is
    ``exp(-lambda s^2 / 2)`` applied in its eigenbasis (``kappa t = s^2 R^2 / 2``).
    """
    step = rho[1] - rho[0]
    edges = np.concatenate([[0.0], rho[:-1] + step / 2, [rho[-1] + step / 2]])
    area = np.pi * (edges[1:] ** 2 - edges[:-1] ** 2)
    flux = 2.0 * np.pi * edges[1:-1] / step
    diag = np.zeros(rho.size)
    diag[:-1] += flux
    diag[1:] += flux
    sq = np.sqrt(area)
    lam, vec = eigh_tridiagonal(diag / area, -flux / (sq[:-1] * sq[1:]))
    coef = vec.T @ (sq * h0)
    decay = np.exp(-np.maximum(lam, 0.0)[None, :] * (s[:, None] ** 2) / 2.0)
    return np.asarray(((coef[None, :] * decay) @ vec.T) / sq[None, :], dtype=np.float64)


@lru_cache(maxsize=16)
def profile_family(
    model: str,
    depth_to_diameter: float = DEFAULT_DEPTH_TO_DIAMETER,
    rim_height_to_diameter: float = RIM_HEIGHT_TO_DIAMETER,
    cavity_exponent: float = CAVITY_EXPONENT,
    ejecta_exponent: float = EJECTA_EXPONENT,
    ejecta_reach: float = 2.5,
) -> ProfileFamily:
    """Tabulate a profile model and its diffused states (cached; ~0.2 s per new parameter set)."""
    kw = {
        "model": model,
        "depth_to_diameter": depth_to_diameter,
        "rim_height_to_diameter": rim_height_to_diameter,
        "cavity_exponent": cavity_exponent,
        "ejecta_exponent": ejecta_exponent,
        "ejecta_reach": ejecta_reach,
    }
    fresh_reach = _fresh_reach(model, ejecta_reach)
    rho = np.arange(0.0, fresh_reach + 3.0 * S_MAX + _RHO_STEP / 2, _RHO_STEP)
    h0 = profile_over_diameter(rho, **kw)  # type: ignore[arg-type]
    table = _radial_diffusion_table(rho, h0, _S_GRID)
    table[0] = h0
    reach = np.full(_S_GRID.size, fresh_reach)
    weight = 2.0 * np.pi * rho * _RHO_STEP  # annulus areas (in R^2)
    for i in range(1, _S_GRID.size):
        row = table[i]
        big = np.nonzero(np.abs(row) > 2e-2 * np.abs(row).max())[0]
        reach[i] = max(fresh_reach, min(rho[-1], rho[big[-1]] + 0.1))
        cut = row * np.clip((reach[i] - rho) / 0.1, 0.0, 1.0)  # taper the far tail to 0
        # give the trimmed (positive, ejecta) tail volume back to the raised part: conserve volume
        pos = np.maximum(cut, 0.0) @ weight
        if pos > 0:
            cut = np.where(cut > 0, cut * (1.0 + ((row - cut) @ weight) / pos), cut)
        table[i] = cut
    for arr in (rho, table, reach):
        arr.setflags(write=False)
    return ProfileFamily(
        rho=rho,
        s=_S_GRID.copy(),
        h_over_d=table,
        reach=reach,
        depth_over_d=np.maximum(-table.min(axis=1), 0.0),
        rim_over_d=np.maximum(table.max(axis=1), 0.0),
    )


def crater_profile(
    rho: ArrayLike,
    *,
    diameter_m: float,
    model: str = "watters-2015",
    depth_to_diameter: float = DEFAULT_DEPTH_TO_DIAMETER,
    rim_height_to_diameter: float = RIM_HEIGHT_TO_DIAMETER,
    cavity_exponent: float = CAVITY_EXPONENT,
    ejecta_exponent: float = EJECTA_EXPONENT,
    ejecta_reach: float = 2.5,
    diffusion_length_m: float = 0.0,
) -> FloatArray:
    """Crater height relative to the pre-impact surface (in m) at ``rho = r / R``.

    Parameters
    ----------
    rho : array_like
        Radial distance in crater radii.
    diameter_m : float
        Rim-to-rim diameter (in m).
    model, depth_to_diameter, rim_height_to_diameter, cavity_exponent, ejecta_exponent, \
ejecta_reach
        See :func:`profile_over_diameter`.
    diffusion_length_m : float
        ``sqrt(2 kappa t)`` of topographic diffusion (in m); 0 for a fresh crater.

    Returns
    -------
    ndarray
        Height (in m), same shape as ``rho``.

    Examples
    --------
    >>> round(float(crater_profile(0.0, diameter_m=10.0)), 3)  # floor: (0.036 - 0.1889) D
    -1.529
    """
    r = np.abs(np.asarray(rho, dtype=np.float64))
    kw = (model, depth_to_diameter, rim_height_to_diameter, cavity_exponent, ejecta_exponent,
          ejecta_reach)
    s = 2.0 * diffusion_length_m / diameter_m
    if s < S_MIN:
        return diameter_m * profile_over_diameter(
            r, model=model, depth_to_diameter=depth_to_diameter,
            rim_height_to_diameter=rim_height_to_diameter, cavity_exponent=cavity_exponent,
            ejecta_exponent=ejecta_exponent, ejecta_reach=ejecta_reach)
    fam = profile_family(*kw)
    state = float(fam.state_of_s(s))
    i0 = min(int(state), fam.s.size - 2)
    f = state - i0
    row = (1.0 - f) * fam.h_over_d[i0] + f * fam.h_over_d[i0 + 1]
    return np.asarray(diameter_m * np.interp(r, fam.rho, row, right=0.0), dtype=np.float64)
