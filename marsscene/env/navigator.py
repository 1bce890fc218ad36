"""``ArcNavigator``: a classical closed-loop navigator on the height scan (no learning).

Every control step it evaluates a fan of constant-curvature arcs, as rover autonomy has done
since the MER rovers' GESTALT (Goldberg, Maimone & Matthies 2002, "Stereo vision and rover
navigation software for planetary exploration", IEEE Aerospace Conference,
doi:10.1109/AERO.2002.1035370; Mars 2020's Enhanced AutoNav ranks candidate paths the same
way before checking their clearance): each arc is rolled out in the scan over the
rover's three wheel tracks, rejected where a track meets a step (a rock) or the tracks a tilt
beyond the limit, and the safe arc that brings the rover closest to the goal is driven until
the next step's scan replans. When every arc is blocked it turns in place towards the goal.

It reads only what the environment observes (the goal in the body frame and the height scan),
so its success rate is a baseline for learned policies on the same observations.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.env.observe import HeightScan

__all__ = ["ArcNavigator"]


class ArcNavigator:
    """A policy ``navigator(obs) -> action`` (normalised ``[v, omega]``) for
    :class:`~marsscene.env.nav.RoverNavEnv` observations with a height scan.

    Parameters
    ----------
    scan : HeightScan
        The environment's height scan (size and resolution).
    track_m : float
        Distance between the left and right wheel tracks.
    step_m : float
        Largest height change along a track between samples 0.2 m apart (a rock's face); the
        default is the wheel radius, about what a rocker-bogie wheel climbs.
    max_tilt_deg : float
        Largest cross-track tilt (left track against right).
    arcs : int
        Arcs in the fan (curvatures from full left to full right at full speed).
    turn_in_place_rad : float
        A goal bearing beyond this is turned to in place first (the tightest arc has a 2.5 m
        radius).
    """

    def __init__(self, scan: HeightScan | None = None, *, track_m: float = 2.0,
                 step_m: float = 0.25, max_tilt_deg: float = 15.0, arcs: int = 15,
                 turn_in_place_rad: float = 0.8) -> None:
        self.turn_in_place_rad = float(turn_in_place_rad)
        self.scan = scan if scan is not None else HeightScan()
        self.track_m, self.step_m = float(track_m), float(step_m)
        self.max_tilt = math.tan(math.radians(max_tilt_deg))
        omega = np.linspace(-0.2, 0.2, arcs)
        self.kappa = omega / 0.5  # curvature of each arc at full speed (1/m)
        half = self.scan.size_m / 2.0
        self.length_m = max(1.0, half - 0.3)
        s = np.arange(0.2, self.length_m + 1e-9, 0.2)
        self.s_m = s
        k = self.kappa[:, None]
        with np.errstate(divide="ignore", invalid="ignore"):
            x = np.where(np.abs(k) > 1e-9, np.sin(k * s) / k, s)
            y = np.where(np.abs(k) > 1e-9, (1.0 - np.cos(k * s)) / k, 0.0)
        heading = k * s
        off = np.array([-track_m / 2, 0.0, track_m / 2])  # right, centre, left tracks
        self.px = x[:, :, None] - np.sin(heading)[:, :, None] * off  # (arcs, samples, tracks)
        self.py = y[:, :, None] + np.cos(heading)[:, :, None] * off
        self.end_xy = np.stack([x[:, -1], y[:, -1]], axis=1)

    def _heights(self, grid: NDArray[np.float32]) -> NDArray[np.float64]:
        """The scan's heights at the arcs' track points (nearest cell; outside: NaN)."""
        n, res = self.scan.points, self.scan.resolution_m
        row = np.rint((n - 1) / 2.0 - self.px / res).astype(int)  # rows: x forward, far first
        col = np.rint((n - 1) / 2.0 - self.py / res).astype(int)  # columns: y left first
        ok = (row >= 0) & (row < n) & (col >= 0) & (col < n)
        h = np.full(self.px.shape, np.nan)
        h[ok] = grid[row[ok], col[ok]]
        return h

    def __call__(self, obs: dict[str, Any]) -> NDArray[np.float32]:
        vec = obs["observation"]
        goal = np.array([vec[0], vec[1]], dtype=np.float64)
        dist = float(vec[2])
        h = self._heights(np.asarray(obs["height_scan"], dtype=np.float64))
        h[:, self.s_m > dist + 1.0, :] = np.nan  # past the goal: not driven
        with np.errstate(all="ignore"):
            step = np.nan_to_num(np.nanmax(np.abs(np.diff(h, axis=1)), axis=(1, 2)))
            tilt = np.nan_to_num(np.nanmax(np.abs(h[:, :, 2] - h[:, :, 0]), axis=1))
        safe = (step <= self.step_m) & (tilt / self.track_m <= self.max_tilt)
        bearing = math.atan2(goal[1], goal[0])
        if not safe.any():  # boxed in: turn in place towards the least bad side
            worst = np.maximum(step / self.step_m, tilt / self.track_m / self.max_tilt)
            return np.array([0.0, 1.0 if worst[-1] < worst[0] else -1.0], dtype=np.float32)
        if dist < 2.0:  # close in: face the goal, then creep to it
            turn = float(np.clip(2.0 * bearing / 0.2, -1.0, 1.0))
            if abs(bearing) > 0.15:
                return np.array([0.0, turn], dtype=np.float32)
            return np.array([float(np.clip(dist / 2.0, 0.3, 1.0)), turn], dtype=np.float32)
        reach = min(1.0, dist / self.length_m)  # near the goal: judge arcs by a shorter end
        ends = self.end_xy * reach
        cost = np.hypot(ends[:, 0] - goal[0], ends[:, 1] - goal[1])
        cost = np.where(safe, cost, np.inf)
        best = int(np.argmin(cost))
        if abs(bearing) > self.turn_in_place_rad:  # well off the heading: turn in place
            return np.array([0.0, math.copysign(1.0, bearing)], dtype=np.float32)
        omega = self.kappa[best] * 0.5
        return np.array([1.0, omega / 0.2], dtype=np.float32)
