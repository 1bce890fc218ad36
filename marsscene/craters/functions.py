"""Mars crater production, chronology and equilibrium functions (:doc:`/science/craters`).

All coefficients live in ``data/mars_crater_functions.toml`` with their references. Public
functions take diameters in **metres** and return densities **per km^2**; ages are in Ga.

Production functions are used through their *shape* ``Phi(D) = N(>=D) / N(>=1 km)``, which is
time-invariant; the cumulative density of a surface of age ``t`` is ``Phi(D) * N1(t)``
(craterstats: "a0 is replaced by log10 N1(t)").
"""

from __future__ import annotations

import math
import tomllib
import warnings
from dataclasses import dataclass
from functools import cache
from importlib import resources
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from marsscene._validate import plain
from marsscene.errors import ConfigError, ExtrapolationWarning

__all__ = [
    "SYSTEMS",
    "ChronologySystem",
    "age_from_n1_ga",
    "chronology_system",
    "cumulative_density_per_km2",
    "equilibrium_density_per_km2",
    "n1_per_km2",
    "production_shape",
]

FloatArray = NDArray[np.float64]


@cache
def _data() -> dict[str, Any]:
    text = (resources.files("marsscene.craters") / "data" / "mars_crater_functions.toml").read_text(
        encoding="utf-8"
    )
    return tomllib.loads(text)


#: Names of the chronology systems (production function + chronology function).
SYSTEMS: tuple[str, ...] = tuple(sorted(_data()["system"]))


@dataclass(frozen=True)
class ChronologySystem:
    """A named production + chronology function pair (values from the TOML data file)."""

    name: str
    production: str
    chronology: str
    production_citation: str
    chronology_citation: str
    valid_diameter_m: tuple[float, float]
    valid_age_ga: tuple[float, float]
    cf_abc: tuple[float, float, float]


@cache
def chronology_system(system: str) -> ChronologySystem:
    """Look up a named chronology system (e.g. ``"neukum-ivanov-2001"``).

    Raises
    ------
    ConfigError
        If ``system`` is unknown.
    """
    data = _data()
    if system not in data["system"]:
        raise ConfigError(f"craters.system = {system!r} is unknown; choose one of {list(SYSTEMS)}")
    entry = data["system"][system]
    pf = data["production"][entry["production"]]
    cf = data["chronology"][entry["chronology"]]
    if pf["kind"] == "polynomial":
        lo_km, hi_km = pf["valid_diameter_km"]
    else:
        n = len(pf["incremental_per_km2"])
        lo_km = 2.0 ** ((0 - pf["index_1km"]) / 2.0)
        hi_km = 2.0 ** ((n - 1 - pf["index_1km"]) / 2.0)
    return ChronologySystem(
        name=system,
        production=entry["production"],
        chronology=entry["chronology"],
        production_citation=f"{pf['name']}: {pf['reference']}",
        chronology_citation=f"{cf['name']}: {cf['reference']}",
        valid_diameter_m=(lo_km * 1e3, hi_km * 1e3),
        valid_age_ga=(float(cf["valid_age_ga"][0]), float(cf["valid_age_ga"][1])),
        cf_abc=(float(cf["a"]), float(cf["b"]), float(cf["c"])),
    )


def _check_ages(age: FloatArray, cs: ChronologySystem) -> None:
    lo, hi = cs.valid_age_ga
    if age.size and (not np.isfinite(age).all() or age.min() < lo or age.max() > hi):
        bad = age[~((age >= lo) & (age <= hi))]
        raise ConfigError(
            f"age_ga = {plain(bad.ravel()[0])!r} is outside the {cs.chronology} chronology range "
            f"[{lo}, {hi}] Ga"
        )


def _warn_diameters(d_m: FloatArray, cs: ChronologySystem) -> None:
    lo, hi = cs.valid_diameter_m
    if d_m.size and (d_m.min() < lo * (1 - 1e-9) or d_m.max() > hi * (1 + 1e-9)):
        warnings.warn(
            f"{cs.production} production function evaluated at D = {d_m.min():.4g}-"
            f"{d_m.max():.4g} m, outside its validity range {lo:.4g}-{hi:.4g} m; extrapolated",
            ExtrapolationWarning,
            stacklevel=3,
        )


def n1_per_km2(age_ga: ArrayLike, *, system: str = "neukum-ivanov-2001") -> FloatArray:
    """Cumulative density of craters >= 1 km, ``N1(t) = a (e^(b t) - 1) + c t``.

    Parameters
    ----------
    age_ga : array_like
        Surface age (in Ga), within the chronology's range (0-4.5 Ga).
    system : str
        A name from :data:`SYSTEMS`.

    Returns
    -------
    ndarray
        N(>=1 km) (per km^2), same shape as ``age_ga``.

    Examples
    --------
    >>> float(n1_per_km2(1.0, system="ivanov-2001"))
    0.000413...
    """
    cs = chronology_system(system)
    t = np.asarray(age_ga, dtype=np.float64)
    _check_ages(t, cs)
    a, b, c = cs.cf_abc
    return a * np.expm1(b * t) + c * t


def age_from_n1_ga(n1: ArrayLike, *, system: str = "neukum-ivanov-2001") -> FloatArray:
    """Inverse of :func:`n1_per_km2` (Newton iterations; N1 is convex and increasing).

    Parameters
    ----------
    n1 : array_like
        N(>=1 km) (per km^2), >= 0.

    Returns
    -------
    ndarray
        Age (in Ga); may exceed the chronology range if ``n1`` does.
    """
    a, b, c = chronology_system(system).cf_abc
    y = np.asarray(n1, dtype=np.float64)
    # start right of the root (N1 convex): Newton then decreases monotonically to it
    t = np.maximum(y / c, 0.0)
    t = np.minimum(t, np.log1p(np.maximum(y, 0.0) / a) / b)
    for _ in range(60):
        f = a * np.expm1(b * t) + c * t - y
        step = f / (a * b * np.exp(b * t) + c)
        t = t - step
        if np.all(np.abs(step) <= 1e-13 * np.maximum(t, 1.0)):
            break
    return t


@cache
def _table_log_cumulative(production: str) -> tuple[FloatArray, FloatArray]:
    """log10 edge diameters (km) and log10 cumulative densities of a root-2 table, normalised
    to N(>=1 km) = 1."""
    pf = _data()["production"][production]
    h = np.asarray(pf["incremental_per_km2"], dtype=np.float64)
    cum = np.cumsum(h[::-1])[::-1]
    idx = np.arange(h.size)
    log_d = (idx - pf["index_1km"]) / 2.0 * math.log10(2.0)
    log_c = np.log10(cum) - math.log10(cum[pf["index_1km"]])
    return log_d, log_c


def _log_shape(production: str, d_km: FloatArray) -> FloatArray:
    """log10 Phi(D) for D in km."""
    pf = _data()["production"][production]
    x = np.log10(d_km)
    if pf["kind"] == "polynomial":
        coef = np.asarray(pf["coefficients"], dtype=np.float64)
        acc = np.zeros_like(x)
        for a in coef[:0:-1]:  # Horner over a_11 .. a_1, then times x
            acc = (acc + a) * x
        return acc
    log_d, log_c = _table_log_cumulative(production)
    out = np.interp(x, log_d, log_c)
    lo = x < log_d[0]  # linear extrapolation in log-log beyond the table ends
    hi = x > log_d[-1]
    s0 = (log_c[1] - log_c[0]) / (log_d[1] - log_d[0])
    s1 = (log_c[-1] - log_c[-2]) / (log_d[-1] - log_d[-2])
    out = np.where(lo, log_c[0] + s0 * (x - log_d[0]), out)
    return np.where(hi, log_c[-1] + s1 * (x - log_d[-1]), out)


def production_shape(diameter_m: ArrayLike, *, system: str = "neukum-ivanov-2001") -> FloatArray:
    """Normalised production function ``Phi(D) = N(>=D) / N(>=1 km)`` (dimensionless).

    Warns with :class:`~marsscene.errors.ExtrapolationWarning` outside the function's
    validity range.
    """
    cs = chronology_system(system)
    d = np.asarray(diameter_m, dtype=np.float64)
    if d.size and not (d > 0).all():
        raise ConfigError(f"diameter_m must be > 0; got min {plain(d.min())!r}")
    _warn_diameters(d, cs)
    return np.asarray(10.0 ** _log_shape(cs.production, d / 1e3), dtype=np.float64)


def cumulative_density_per_km2(
    diameter_m: ArrayLike, *, age_ga: ArrayLike, system: str = "neukum-ivanov-2001"
) -> FloatArray:
    """Cumulative crater density ``N(>=D)`` of a surface of a given age (isochron).

    Parameters
    ----------
    diameter_m : array_like
        Crater diameter (in m).
    age_ga : array_like
        Surface age (in Ga); broadcast against ``diameter_m``.
    system : str
        ``"neukum-ivanov-2001"`` (default: Ivanov 2001 PF + Hartmann & Neukum 2001 CF),
        ``"ivanov-2001"``, ``"hartmann-2005"`` or ``"hartmann-daubar-2016"``.

    Returns
    -------
    ndarray
        N(>=D) (per km^2).

    Warns
    -----
    ExtrapolationWarning
        When a diameter is outside the production function's validity range.

    Examples
    --------
    >>> float(cumulative_density_per_km2(100.0, age_ga=1.0, system="ivanov-2001"))
    1.5245...
    """
    shape = production_shape(diameter_m, system=system)
    return np.asarray(shape * n1_per_km2(age_ga, system=system), dtype=np.float64)


def equilibrium_density_per_km2(diameter_m: ArrayLike) -> FloatArray:
    """Hartmann (1984) saturation equilibrium, ``log10 N(>=D) = -1.14 - 1.83 log10 D[km]``.

    Parameters
    ----------
    diameter_m : array_like
        Crater diameter (in m).

    Returns
    -------
    ndarray
        Equilibrium cumulative density N(>=D) (per km^2).

    Examples
    --------
    >>> round(float(equilibrium_density_per_km2(100.0)), 4)
    4.8978
    """
    eq = _data()["equilibrium"]["hartmann-1984"]
    d = np.asarray(diameter_m, dtype=np.float64)
    return np.asarray(10.0 ** (eq["a0"] + eq["slope"] * np.log10(d / 1e3)), dtype=np.float64)


def equilibrium_citation() -> str:
    """Citation of the Hartmann (1984) equilibrium function."""
    eq = _data()["equilibrium"]["hartmann-1984"]
    return f"{eq['name']}: {eq['reference']}"

