"""Pure-pursuit path follower with bounded commands (Coulter 1992, CMU-RI-TR-92-01).

The MarsLab protocol: ``0 <= v <= 0.5 m/s``, ``|omega| <= 0.2 rad/s`` at 50 Hz. When the pursuit
curvature would need a faster turn, ``v`` is reduced so the curvature is kept and
``|omega| = omega_max``; a target behind the rover gives a turn in place.

The follower stops within :data:`STOP_RADIUS_M` (0.25 m) of the route's end, half the goal
tolerance (:data:`~marsscene.rover.config.GOAL_TOLERANCE_M`, 0.5 m): a stopped rover has reached
the goal by the one goal test (:func:`~marsscene.sim.goal.goal_reached`), with margin. The
radius is the follower's own, not a second goal tolerance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from marsscene._validate import check_range
from marsscene.rover.config import OMEGA_MAX_RAD_S, V_MAX_M_S
from marsscene.sim.goal import goal_reached
from marsscene.sim.route import Route

__all__ = ["STOP_RADIUS_M", "PurePursuit", "PursuitConfig"]

#: The pure-pursuit follower stops within this distance (m) of its route's end (its last
#: lookahead): its stopping radius, inside the goal tolerance (``GOAL_TOLERANCE_M``, 0.5 m).
STOP_RADIUS_M = 0.25


@dataclass(frozen=True, kw_only=True)
class PursuitConfig:
    """Pure-pursuit parameters (m, m/s, rad/s); it is called at the run's control rate
    (``RunConfig.control_hz``).

    ``goal_tolerance_m`` is the follower's stopping radius (:data:`STOP_RADIUS_M`), not the
    goal tolerance of arrival (``GOAL_TOLERANCE_M``); the name is the one ``run.json`` and the
    ``[pursuit]`` tables have always carried.
    """

    lookahead_m: float = 1.0
    v_max_m_s: float = V_MAX_M_S
    omega_max_rad_s: float = OMEGA_MAX_RAD_S
    goal_tolerance_m: float = STOP_RADIUS_M
    slow_down_m: float = 1.0

    def __post_init__(self) -> None:
        check_range("pursuit.lookahead_m", self.lookahead_m, 0.05, 50.0)
        check_range("pursuit.v_max_m_s", self.v_max_m_s, 0.0, V_MAX_M_S, lo_open=True)
        check_range("pursuit.omega_max_rad_s", self.omega_max_rad_s, 0.0, OMEGA_MAX_RAD_S,
                    lo_open=True)
        check_range("pursuit.goal_tolerance_m", self.goal_tolerance_m, 0.01, 10.0)
        check_range("pursuit.slow_down_m", self.slow_down_m, 0.0, 50.0)


class PurePursuit:
    """Follow a :class:`Route`; call :meth:`command` once per control period.

    A controller of a drive (:mod:`marsscene.sim.control`): called with an observation it
    steers on the ground-truth pose (the MarsLab protocol) and sets :attr:`done` at the goal.
    """

    def __init__(self, route: Route, config: PursuitConfig | None = None) -> None:
        self.route = route
        self.config = config if config is not None else PursuitConfig()
        self.s = route.s_m
        self.index = 0
        self.done = False

    def _advance(self, x: float, y: float) -> None:
        # nearest point in a forward window: progress is monotone, and the window reaches at
        # most half the route ahead, so a closed route's end, beside its start, is not taken
        # for the nearest point (and the goal) before the rover has driven half of it
        ahead = min(3 * self.config.lookahead_m + 1.0, 0.5 * float(self.s[-1]))
        hi = int(np.searchsorted(self.s, self.s[self.index] + ahead))
        win = self.route.xy_m[self.index : hi + 1]
        d = np.hypot(win[:, 0] - x, win[:, 1] - y)
        self.index += int(np.argmin(d))

    def __call__(self, obs: Any) -> tuple[float, float]:
        """The command for an :class:`~marsscene.sim.control.Observation` (its ground truth)."""
        return self.command(obs.gt_xyz_m[0], obs.gt_xyz_m[1], obs.gt_yaw_rad)

    def command(self, x_m: float, y_m: float, yaw_rad: float) -> tuple[float, float]:
        """``(v, omega)`` for the current pose; ``(0, 0)`` once the goal is reached."""
        cfg = self.config
        if self.done:
            return 0.0, 0.0
        self._advance(x_m, y_m)
        goal = self.route.xy_m[-1]
        to_go = self.s[-1] - self.s[self.index]
        if to_go < cfg.lookahead_m and goal_reached((x_m, y_m), goal, cfg.goal_tolerance_m):
            self.done = True
            return 0.0, 0.0
        j = min(int(np.searchsorted(self.s, self.s[self.index] + cfg.lookahead_m)), len(self.s) - 1)
        tx, ty = self.route.xy_m[j]
        dx, dy = tx - x_m, ty - y_m
        c, s = math.cos(yaw_rad), math.sin(yaw_rad)
        bx, by = c * dx + s * dy, -s * dx + c * dy
        dist = math.hypot(bx, by)
        if dist < 1e-6:
            return 0.0, 0.0
        alpha = math.atan2(by, bx)
        if abs(alpha) > math.pi / 2:  # target behind: turn in place
            return 0.0, math.copysign(cfg.omega_max_rad_s, alpha)
        kappa = 2.0 * math.sin(alpha) / dist
        v = cfg.v_max_m_s
        if cfg.slow_down_m > 0:
            v *= min(1.0, max(to_go, 0.0) / cfg.slow_down_m + 0.1)
        omega = v * kappa
        if abs(omega) > cfg.omega_max_rad_s:
            v = cfg.omega_max_rad_s / abs(kappa)
            omega = math.copysign(cfg.omega_max_rad_s, kappa)
        return min(max(v, 0.0), cfg.v_max_m_s), max(
            -cfg.omega_max_rad_s, min(cfg.omega_max_rad_s, omega)
        )
