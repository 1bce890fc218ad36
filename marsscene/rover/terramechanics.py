"""A rigid wheel on deformable soil: normal and shear stress around the contact arc, and the
load, drawbar pull and torque they add up to (the Wong--Reece model as planetary-rover work
uses it).

The wheel (radius ``r``, width ``b``) sinks ``z`` into the soil: it touches it from the entry
angle ``theta_1 = acos(1 - z / r)`` (ahead of the axle, measured from the vertical) back to the
exit angle ``theta_2`` (0: the soil does not rebound). Driven at slip
``s = 1 - v / (r * omega)`` it presses and shears the soil:

- normal stress after Bekker's pressure--sinkage law ``p = (k_c / b + k_phi) z^n`` (``n``
  growing with slip where the soil says so: Ding et al. 2011), applied to the local sinkage
  ``r (cos theta - cos theta_1)`` ahead of the angle of maximum stress
  ``theta_m = (a_0 + a_1 s) theta_1`` and mirrored behind it (Wong & Reece 1967; the
  slip-dependent ``theta_m`` of Iagnemma & Dubowsky 2004);
- shear stress after Janosi & Hanamoto (1961): ``tau = (c + sigma tan phi)(1 - exp(-j / K))``
  with the shear displacement ``j(theta) = r ((theta_1 - theta) - (1 - s)(sin theta_1 -
  sin theta))``;
- the wheel's vertical load ``W = r b int (sigma cos + tau sin)``, drawbar pull
  ``DP = r b int (tau cos - sigma sin)`` and driving torque ``T = r^2 b int tau`` over
  ``[theta_2, theta_1]``.

The integrals are taken by Gauss--Legendre quadrature on each side of ``theta_m`` (the stress
has a kink there), vectorised over any number of wheels, sinkages and slips.
:func:`sinkage_for_load` finds the sinkage at which the soil carries a load (bisection, also
vectorised). Soil parameters and their sources: ``data/soils.toml`` (:func:`soils`).

References: Wong, J. Y., Reece, A. R. (1967), Prediction of rigid wheel performance based on
the analysis of soil-wheel stresses, J. Terramechanics 4(1), 81-98 and 4(2), 7-25; Janosi, Z.,
Hanamoto, B. (1961), The analytical determination of drawbar pull as a function of slip for
tracked vehicles in deformable soils, Proc. 1st ISTVS Conf., Turin; Iagnemma, K., Dubowsky, S.
(2004), Mobile Robots in Rough Terrain, Springer; Ishigami, G., Miwa, A., Nagatani, K.,
Yoshida, K. (2007), Terramechanics-based model for steering maneuver of planetary exploration
rovers on loose soil, J. Field Robotics 24(3), 233-250, doi:10.1002/rob.20187; Ding, L., Gao,
H., Deng, Z., Nagatani, K., Yoshida, K. (2011), Experimental study and analysis on driving
wheels' performance for planetary exploration rovers moving in deformable soil, J.
Terramechanics 48(1), 27-45.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from functools import cache
from importlib import resources
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from marsscene.errors import ConfigError

__all__ = ["Soil", "WheelForces", "sinkage_for_load", "soil", "soils", "wheel_forces"]

#: Gauss--Legendre points on each side of the angle of maximum stress.
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(24)


@dataclass(frozen=True)
class Soil:
    """One soil's terramechanics parameters (SI units).

    Attributes
    ----------
    name : str
    cohesion_pa : float
        ``c``.
    friction_deg : float
        Internal friction angle ``phi``.
    k_c : float
        Cohesive modulus of deformation (N/m^(n+1)).
    k_phi : float
        Frictional modulus of deformation (N/m^(n+2)).
    n : float
        Sinkage exponent (at zero slip).
    n_slip : float
        Its growth with slip, ``n + n_slip * |s|`` (slip sinkage: Ding et al. 2011).
    shear_modulus_m : float
        Shear deformation modulus ``K`` (m).
    a0, a1 : float
        The angle of maximum stress ``theta_m = (a0 + a1 s) theta_1``.
    exit_ratio : float
        The exit angle over the entry angle, ``theta_2 / theta_1`` (0: no rebound).
    reference : str
    """

    name: str
    cohesion_pa: float
    friction_deg: float
    k_c: float
    k_phi: float
    n: float
    shear_modulus_m: float
    n_slip: float = 0.0
    a0: float = 0.4
    a1: float = 0.15
    exit_ratio: float = 0.0
    reference: str = ""

    def __post_init__(self) -> None:
        for key in ("k_phi", "n", "shear_modulus_m"):
            if not getattr(self, key) > 0:
                raise ConfigError(f"soil {self.name!r}: {key} must be positive, "
                                  f"got {getattr(self, key)}")
        if not 0 <= self.friction_deg < 90 or self.cohesion_pa < 0 or self.k_c < 0:
            raise ConfigError(f"soil {self.name!r}: cohesion, k_c must be >= 0 and the "
                              "friction angle in [0, 90) degrees")
        if not 0 < self.a0 + self.a1 <= 1 or not 0 <= self.exit_ratio < self.a0:
            raise ConfigError(f"soil {self.name!r}: need 0 < a0 + a1 <= 1 and "
                              "0 <= exit_ratio < a0")


@dataclass(frozen=True)
class WheelForces:
    """What the soil does to a wheel (arrays of the inputs' broadcast shape).

    Attributes
    ----------
    load_n : ndarray
        Vertical load the soil carries, ``W``.
    drawbar_n : ndarray
        Drawbar pull ``DP``: thrust less motion resistance (negative: the wheel is held back).
    torque_nm : ndarray
        Torque the soil resists the wheel's turning with, ``T``.
    thrust_n : ndarray
        The shear stress's share of the drawbar pull, ``r b int tau cos``.
    resistance_n : ndarray
        The normal stress's motion (compaction) resistance, ``r b int sigma sin``:
        ``DP = thrust - resistance``.
    """

    load_n: NDArray[np.float64]
    drawbar_n: NDArray[np.float64]
    torque_nm: NDArray[np.float64]
    thrust_n: NDArray[np.float64]
    resistance_n: NDArray[np.float64]


@cache
def soils() -> dict[str, Soil]:
    """The soils of ``data/soils.toml``, by name (each with its source)."""
    text = resources.files("marsscene.rover").joinpath("data/soils.toml").read_text("utf-8")
    return {name: Soil(name=name, **row) for name, row in tomllib.loads(text).items()}


def soil(name: str) -> Soil:
    """A soil of :func:`soils` by name (one-line error for an unknown one)."""
    table = soils()
    if name not in table:
        raise ConfigError(f"soil {name!r} is unknown; use one of {', '.join(table)}")
    return table[name]


def _stresses(soil: Soil, r: Any, b: Any, angles: tuple[Any, Any, Any], theta: Any,
              slip: Any) -> tuple[Any, Any]:
    """Normal and shear stress (Pa) at angles ``theta`` (..., m) of wheels whose exit, maximum
    stress and entry angles are ``angles`` (each (..., 1))."""
    s = slip
    t2, tm, theta1 = angles
    front = theta >= tm
    mirrored = theta1 - (theta - t2) / np.maximum(tm - t2, 1e-12) * (theta1 - tm)
    local = np.where(front, np.cos(theta), np.cos(mirrored)) - np.cos(theta1)
    k = soil.k_c / b + soil.k_phi
    sigma = k * (r * np.maximum(local, 0.0)) ** (soil.n + soil.n_slip * np.abs(s))
    j = r * ((theta1 - theta) - (1.0 - s) * (np.sin(theta1) - np.sin(theta)))
    tau = (soil.cohesion_pa + sigma * math.tan(math.radians(soil.friction_deg))) * np.sign(j) * (
        1.0 - np.exp(-np.abs(j) / soil.shear_modulus_m))
    return sigma, tau


def wheel_forces(soil: Soil, radius_m: ArrayLike, width_m: ArrayLike, sinkage_m: ArrayLike,
                 slip: ArrayLike) -> WheelForces:
    """Load, drawbar pull and torque of rigid wheels sunk ``sinkage_m`` at ``slip``; the inputs
    broadcast together.

    ``0 <= slip < 1`` drives the wheel; ``-1 <= slip < 0`` brakes it (the wheel turns slower
    than it travels, ``slip = r omega / v - 1``): the shear displacement ``j`` is then
    negative and so is the shear stress, which holds the wheel back.
    """
    r, b, z, s = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64)
                                       for v in (radius_m, width_m, sinkage_m, slip)))
    theta1 = np.arccos(np.clip(1.0 - z / r, -1.0, 1.0))[..., None]
    tm = (soil.a0 + soil.a1 * s[..., None]) * theta1
    t2 = soil.exit_ratio * theta1
    total = {"w": 0.0, "h": 0.0, "r": 0.0, "t": 0.0}
    for lo, hi in ((t2, tm), (tm, theta1)):
        half = 0.5 * (hi - lo)
        theta = lo + half * (_NODES + 1.0)
        sigma, tau = _stresses(soil, r[..., None], b[..., None], (t2, tm, theta1), theta,
                               s[..., None])
        w = half * _WEIGHTS
        total["w"] = total["w"] + np.sum(w * (sigma * np.cos(theta) + tau * np.sin(theta)), -1)
        total["h"] = total["h"] + np.sum(w * tau * np.cos(theta), -1)
        total["r"] = total["r"] + np.sum(w * sigma * np.sin(theta), -1)
        total["t"] = total["t"] + np.sum(w * tau, -1)
    thrust, resistance = r * b * total["h"], r * b * total["r"]
    return WheelForces(load_n=r * b * total["w"], drawbar_n=thrust - resistance,
                       torque_nm=r * r * b * total["t"], thrust_n=thrust,
                       resistance_n=resistance)


def sinkage_for_load(soil: Soil, radius_m: ArrayLike, width_m: ArrayLike, load_n: ArrayLike,
                     slip: ArrayLike, *, tol_m: float = 1e-6) -> NDArray[np.float64]:
    """The sinkage (m) at which the soil carries ``load_n`` under wheels at ``slip``
    (bisection on ``[0, r]``; ``r`` where even full sinkage does not carry the load)."""
    r, b, load, s = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64)
                                          for v in (radius_m, width_m, load_n, slip)))
    lo, hi = np.zeros_like(r), r.copy()
    for _ in range(max(1, math.ceil(math.log2(float(np.max(r)) / tol_m)))):
        mid = 0.5 * (lo + hi)
        carries = wheel_forces(soil, r, b, mid, s).load_n >= load
        hi, lo = np.where(carries, mid, hi), np.where(carries, lo, mid)
    return 0.5 * (lo + hi)
