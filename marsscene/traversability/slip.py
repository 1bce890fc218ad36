"""Predicted wheel slip climbing a slope on a soil: the steady slip at which the Wong--Reece
drawbar pull of a wheel carries its share of the rover's weight up the slope.

On a slope ``theta`` each of the six wheels carries ``W cos(theta)`` (``W`` its level share of
the weight) and must pull ``W sin(theta)``; the slip is the least ``s`` in [0, 1] with
``DP(W cos theta, s) >= W sin theta`` (1 where even full slip does not pull enough: the rover
cannot climb). The drawbar pull comes from the wheel's soil table
(:func:`marsscene.rover.soil_table.soil_table`, the model :mod:`marsscene.sim.wheel_soil`
drives the MuJoCo wheels with). Rigid ground: no slip up to the Coulomb limit
``tan(theta) = mu``, full slip beyond. Slip is tabulated once per soil over slope and read per
cell by linear interpolation.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from marsscene.rover.soil_table import soil_table
from marsscene.rover.terramechanics import Soil

__all__ = ["WHEELS", "rigid_slip", "slip_curve", "soil_slip"]

#: Wheels sharing the rover's weight (rocker-bogie: six).
WHEELS = 6
#: The slope grid (degrees) the slip is tabulated on, and the slips searched.
_SLOPES_DEG = np.linspace(0.0, 90.0, 361)
_SLIPS = np.linspace(0.0, 1.0, 401)


def slip_curve(soil: Soil, *, radius_m: float, width_m: float, weight_n: float) -> tuple[
        NDArray[np.float64], NDArray[np.float64]]:
    """Slopes (deg) and the uphill slip on ``soil`` at each (non-decreasing in slope)."""
    share = weight_n / WHEELS
    table = soil_table(soil, float(radius_m), float(width_m), float(share))
    theta = np.radians(_SLOPES_DEG)[:, None]
    state = table.lookup(share * np.cos(theta), _SLIPS[None, :])
    excess = state.thrust_n - state.resistance_n - share * np.sin(theta)
    ok = excess >= 0.0
    first = np.argmax(ok, axis=1)  # the first slip that pulls enough
    climbs = ok.any(axis=1)
    i = np.clip(first, 1, len(_SLIPS) - 1)
    rows = np.arange(len(first))
    lo, hi = excess[rows, i - 1], excess[rows, i]
    frac = np.where(hi > lo, -lo / np.where(hi > lo, hi - lo, 1.0), 1.0)
    s = _SLIPS[i - 1] + np.clip(frac, 0.0, 1.0) * (_SLIPS[i] - _SLIPS[i - 1])
    s = np.where(first == 0, 0.0, s)
    s = np.where(climbs, s, 1.0)
    return _SLOPES_DEG.copy(), np.maximum.accumulate(s)


def soil_slip(slope_deg: NDArray[np.floating], soil: Soil, *, radius_m: float,
              width_m: float, weight_n: float) -> NDArray[np.float64]:
    """Uphill slip on ``soil`` at each slope of ``slope_deg``."""
    x, s = slip_curve(soil, radius_m=radius_m, width_m=width_m, weight_n=weight_n)
    return np.interp(np.asarray(slope_deg, dtype=np.float64), x, s)


def rigid_slip(slope_deg: NDArray[np.floating], friction: float) -> NDArray[np.float64]:
    """Rigid ground: 0 up to the Coulomb limit ``atan(friction)``, 1 beyond."""
    limit = np.degrees(np.arctan(friction))
    return np.where(np.asarray(slope_deg) > limit, 1.0, 0.0)
