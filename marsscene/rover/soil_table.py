"""A wheel's terramechanics, tabulated over load and slip for the physics loop.

Solving for the sinkage that carries a wheel's load takes milliseconds
(:func:`marsscene.rover.terramechanics.sinkage_for_load`): too slow for a rover stepped
hundreds of times a second. :class:`SoilTable` solves the Wong--Reece model once on a grid of
loads (uniform in the square root of the load, where sinkage changes fastest) and slips
(-1 to 1), and interpolates bilinearly between the grid points: sinkage, thrust, motion
resistance and torque for any number of wheels in a few microseconds each. The grid's error
against the direct solution is tested (``tests/rover/test_soil_table.py``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from marsscene.rover.terramechanics import Soil, sinkage_for_load, wheel_forces

__all__ = ["SoilTable", "WheelSoilState", "soil_table"]

#: Grid points over load (0 to the table's maximum) and slip (-1 to 1).
LOAD_POINTS, SLIP_POINTS = 48, 41


@dataclass(frozen=True)
class WheelSoilState:
    """A table's answer for each wheel (arrays of the query's shape).

    Attributes
    ----------
    sinkage_m, thrust_n, resistance_n, torque_nm : ndarray
        As :class:`marsscene.rover.terramechanics.WheelForces` (drawbar pull is
        ``thrust_n - resistance_n``).
    """

    sinkage_m: NDArray[np.float64]
    thrust_n: NDArray[np.float64]
    resistance_n: NDArray[np.float64]
    torque_nm: NDArray[np.float64]


@dataclass(frozen=True)
class SoilTable:
    """Sinkage and forces of one wheel size on one soil, over load and slip.

    Build it with :func:`soil_table` (cached). Loads above ``max_load_n`` keep its sinkage and
    scale the forces with the load.
    """

    soil: Soil
    radius_m: float
    width_m: float
    max_load_n: float
    grid: NDArray[np.float64] = field(repr=False)
    """(load, slip, 4): sinkage, thrust, resistance and torque at the grid points."""

    def __post_init__(self) -> None:
        g = self.grid  # each grid cell's four corners side by side: one gather per lookup
        cells = np.concatenate([g[:-1, :-1], g[:-1, 1:], g[1:, :-1], g[1:, 1:]], axis=2)
        cells = cells.reshape(-1, 16)
        cells.setflags(write=False)
        object.__setattr__(self, "_cells", cells)

    def lookup(self, load_n: ArrayLike, slip: ArrayLike) -> WheelSoilState:
        """The state of wheels carrying ``load_n`` at ``slip`` (broadcast together)."""
        load, s = np.broadcast_arrays(np.asarray(load_n, dtype=np.float64),
                                      np.asarray(slip, dtype=np.float64))
        rel = load / self.max_load_n
        x = np.sqrt(np.clip(rel, 0.0, 1.0)) * (LOAD_POINTS - 1)
        y = (np.clip(s, -1.0, 1.0) + 1.0) * (0.5 * (SLIP_POINTS - 1))
        i = np.minimum(x.astype(np.intp), LOAD_POINTS - 2)
        j = np.minimum(y.astype(np.intp), SLIP_POINTS - 2)
        fx, fy = (x - i)[..., None], (y - j)[..., None]
        c = self._cells[i * (SLIP_POINTS - 1) + j]  # type: ignore[attr-defined]
        v = ((c[..., 0:4] * (1 - fy) + c[..., 4:8] * fy) * (1 - fx)
             + (c[..., 8:12] * (1 - fy) + c[..., 12:16] * fy) * fx)
        over = np.maximum(rel, 1.0)
        return WheelSoilState(sinkage_m=v[..., 0], thrust_n=v[..., 1] * over,
                              resistance_n=v[..., 2] * over, torque_nm=v[..., 3] * over)


@cache
def soil_table(soil: Soil, radius_m: float, width_m: float, max_load_n: float) -> SoilTable:
    """Solve the model on the grid (about 0.2 s; cached per soil, wheel and load range)."""
    load = max_load_n * (np.linspace(0.0, 1.0, LOAD_POINTS) ** 2)[:, None]
    slip = np.linspace(-1.0, 1.0, SLIP_POINTS)[None, :]
    z = sinkage_for_load(soil, radius_m, width_m, load, slip)
    f = wheel_forces(soil, radius_m, width_m, z, slip)
    grid = np.stack([z, f.thrust_n, f.resistance_n, f.torque_nm], axis=-1)
    grid.setflags(write=False)
    return SoilTable(soil, float(radius_m), float(width_m), float(max_load_n), grid)
