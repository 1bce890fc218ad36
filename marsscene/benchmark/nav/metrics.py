"""Scores of one navigation episode and of a method over its episodes (pure numpy).

Per episode: success (:func:`marsscene.sim.goal.goal_reached` on the drive's last pose), SPL
(success weighted by path length, Anderson et al. 2018: ``S l / max(p, l)``, with ``l`` the
shortest traversable path on the ground-truth grid and ``p`` the path driven), the path length
ratio ``p / l``, sim time, wheel slip (``1 - p / odometry distance``: the share of the wheels'
travel that did not move the rover), hazard entries and time (the rover's centre in a hazard
cell of the ground-truth map, a configuration-space map: some wheel or the belly then meets
what the map forbids), tip-over (roll or pitch beyond 45 degrees, the rovers' static stability
rating) and stuck (not arrived, and under 1 m moved in the last 60 s).

Reference: Anderson, P., Chang, A., Chaplot, D. S., Dosovitskiy, A., Gupta, S., Koltun, V.,
Kosecka, J., Malik, J., Mottaghi, R., Savva, M., Zamir, A. R. (2018), On evaluation of
embodied navigation agents, arXiv:1807.06757.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from marsscene.benchmark.nav.grid import PlanGrid
from marsscene.sim.goal import goal_reached

__all__ = ["TIP_OVER_DEG", "episode_scores", "spl", "summarise"]

#: Roll or pitch counted as a tip-over (degrees): Perseverance's static stability rating.
TIP_OVER_DEG = 45.0
STUCK_WINDOW_S = 60.0
STUCK_MOVE_M = 1.0


def spl(success: ArrayLike, shortest_m: ArrayLike, path_m: ArrayLike) -> float:
    """Success weighted by (normalised inverse) path length over episodes (Anderson et al.
    2018): ``mean(S_i l_i / max(p_i, l_i))``.

    >>> spl([1, 1, 0], [10.0, 10.0, 10.0], [10.0, 20.0, 5.0])
    0.5
    """
    s = np.asarray(success, dtype=np.float64)
    lo = np.asarray(shortest_m, dtype=np.float64)
    p = np.asarray(path_m, dtype=np.float64)
    return float(np.mean(s * lo / np.maximum(p, lo)))


def _tilt_deg(quat_xyzw: np.ndarray) -> np.ndarray:
    """Angle (deg) between the body's z axis and the world's up, per pose (TUM order)."""
    x, y = quat_xyzw[:, 0], quat_xyzw[:, 1]
    zz = 1.0 - 2.0 * (x * x + y * y)  # the body z axis' world z component
    return np.degrees(np.arccos(np.clip(zz, -1.0, 1.0)))


def episode_scores(t_s: ArrayLike, xyz_m: ArrayLike, quat_xyzw: ArrayLike, *,
                   odom_length_m: float, goal_xy_m: ArrayLike, shortest_m: float,
                   grid: PlanGrid) -> dict[str, Any]:
    """The scores of one drive from its ground truth (t, xyz, TUM quaternion x y z w)."""
    t = np.asarray(t_s, dtype=np.float64)
    xyz = np.asarray(xyz_m, dtype=np.float64)
    q = np.asarray(quat_xyzw, dtype=np.float64)
    path = float(np.linalg.norm(np.diff(xyz[:, :2], axis=0), axis=1).sum())
    ok = bool(goal_reached(xyz[-1, :2], np.asarray(goal_xy_m, dtype=np.float64)))
    inside = grid.hazard_at(xyz[:, :2])
    entries = int(np.count_nonzero(inside[1:] & ~inside[:-1]) + int(inside[0]))
    dt = np.diff(t, prepend=t[0])
    late = t >= t[-1] - STUCK_WINDOW_S
    moved = float(np.linalg.norm(xyz[late][-1, :2] - xyz[late][0, :2]))
    stuck = (not ok) and t[-1] - t[0] >= STUCK_WINDOW_S and moved < STUCK_MOVE_M
    slip = 1.0 - path / odom_length_m if odom_length_m > 1e-6 else math.nan
    return {
        "success": ok,
        "spl": spl([ok], [shortest_m], [path]),
        "path_m": round(path, 3),
        "path_ratio": round(path / shortest_m, 4) if shortest_m > 0 else math.nan,
        "final_distance_m": round(float(np.hypot(*(xyz[-1, :2] - np.asarray(goal_xy_m)))), 3),
        "time_s": round(float(t[-1] - t[0]), 3),
        "slip": round(float(slip), 4),
        "hazard_entries": entries,
        "hazard_time_s": round(float(dt[inside].sum()), 3),
        "max_tilt_deg": round(float(_tilt_deg(q).max()), 2),
        "tip_over": bool(_tilt_deg(q).max() > TIP_OVER_DEG),
        "stuck": bool(stuck),
    }


def summarise(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """A method's scores over its episodes: success rate, SPL, means of the rest (ok rows; a
    failed row counts as an unsuccessful episode in success and SPL)."""
    n = len(rows)
    ok = [r for r in rows if r.get("status") == "ok"]

    def mean(key: str, only_success: bool = False) -> float:
        vals = [float(r[key]) for r in ok if key in r and (r["success"] or not only_success)
                and r[key] is not None and math.isfinite(float(r[key]))]
        return round(float(np.mean(vals)), 4) if vals else math.nan

    return {
        "episodes": n, "failed": n - len(ok),
        "success": round(sum(bool(r["success"]) for r in ok) / n, 4) if n else math.nan,
        "spl": round(sum(float(r["spl"]) for r in ok) / n, 4) if n else math.nan,
        "path_ratio": mean("path_ratio", only_success=True),
        "time_s": mean("time_s", only_success=True),
        "slip": mean("slip"),
        "hazard_entries": mean("hazard_entries"),
        "tip_overs": sum(bool(r["tip_over"]) for r in ok),
        "stuck": sum(bool(r["stuck"]) for r in ok),
        "plan_s": mean("plan_s"),
    }
