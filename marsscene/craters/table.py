"""The :class:`CraterTable`: a crater population as column arrays."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["CraterTable"]


@dataclass(frozen=True, eq=False)
class CraterTable:
    """Craters as columns (one row per crater).

    Rows are in formation order (oldest first) when produced by
    :func:`~marsscene.craters.sample_craters`.

    Attributes
    ----------
    center_xy_m : ndarray of shape (N, 2)
        Centre (x east, y north) in the scene frame (in m).
    diameter_m : ndarray of shape (N,)
        Rim-to-rim diameter (in m).
    depth_m : ndarray of shape (N,)
        Floor depth below the pre-impact surface, after degradation (in m).
    rim_height_m : ndarray of shape (N,)
        Rim crest height above the pre-impact surface, after degradation (in m).
    age_ga : ndarray of shape (N,)
        Formation age (in Ga before present).
    profile : ndarray of shape (N,), int
        Profile model id (see ``marsscene.craters.PROFILE_IDS``).
    axis_ratio : ndarray of shape (N,), optional
        Minor/major axis ratio of the rim outline (1 = circular; default all 1). ``diameter_m``
        is the equal-area diameter, so the semi-axes are ``R / sqrt(q)`` and ``R sqrt(q)``.
    azimuth_deg : ndarray of shape (N,), optional
        Direction of the major axis, counter-clockwise from +x (east) (in degrees; default 0).
    """

    center_xy_m: NDArray[np.float64]
    diameter_m: NDArray[np.float64]
    depth_m: NDArray[np.float64]
    rim_height_m: NDArray[np.float64]
    age_ga: NDArray[np.float64]
    profile: NDArray[np.int64]
    axis_ratio: NDArray[np.float64] | None = None
    azimuth_deg: NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        n = len(self.diameter_m)
        ratio = np.ones(n) if self.axis_ratio is None else self.axis_ratio
        azimuth = np.zeros(n) if self.azimuth_deg is None else self.azimuth_deg
        cols = {
            "center_xy_m": np.asarray(self.center_xy_m, dtype=np.float64).reshape(n, 2),
            "diameter_m": np.asarray(self.diameter_m, dtype=np.float64),
            "depth_m": np.asarray(self.depth_m, dtype=np.float64),
            "rim_height_m": np.asarray(self.rim_height_m, dtype=np.float64),
            "age_ga": np.asarray(self.age_ga, dtype=np.float64),
            "profile": np.asarray(self.profile, dtype=np.int64),
            "axis_ratio": np.asarray(ratio, dtype=np.float64),
            "azimuth_deg": np.asarray(azimuth, dtype=np.float64),
        }
        for name, arr in cols.items():
            if arr.shape[0] != n:
                raise ValueError(f"CraterTable.{name} has {arr.shape[0]} rows; expected {n}")
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    def __len__(self) -> int:
        return int(self.diameter_m.shape[0])

    @classmethod
    def empty(cls) -> CraterTable:
        z = np.zeros(0)
        return cls(np.zeros((0, 2)), z, z, z, z, np.zeros(0, dtype=np.int64))

    def take(self, index: NDArray[np.int64] | NDArray[np.bool_]) -> CraterTable:
        """A new table with the selected rows."""
        return CraterTable(
            self.center_xy_m[index],
            self.diameter_m[index],
            self.depth_m[index],
            self.rim_height_m[index],
            self.age_ga[index],
            self.profile[index],
            self.axis_ratio[index],  # type: ignore[index]
            self.azimuth_deg[index],  # type: ignore[index]
        )
