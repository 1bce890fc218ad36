"""How a navigation episode ends: at the goal, or by a failure; truncated at the time limit.

``terminated`` at a step: the goal is reached (``info["termination"] == "goal"``), or, when it
is not, the first failure of

==============  ==========================================================================
``tipped``      roll or pitch beyond ``task.max_tilt_deg``
``left_world``  within ``task.edge_m`` of the terrain's edge
``strayed``     farther than ``task.max_stray_m`` from the start-goal segment
``stuck``       less than ``task.stuck_m`` moved in ``task.stuck_s`` of commanded motion
==============  ==========================================================================

``truncated``: not terminated at the episode's last step (``info["steps_left"] == 0``).

:func:`compute_terminated` and :func:`compute_truncated` recompute both from
``achieved_goal`` / ``desired_goal`` pairs (vectorised, for hindsight relabelling as
:func:`~marsscene.env.reward.compute_reward`): the goal test is redone, the failures are the
step's (``info["termination"]``; on a step that reached its own goal the failures are not
judged, as the reward's ``stray`` term is not).
"""

from __future__ import annotations

import math
from collections import deque
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.env.reward import goal_reached, info_field
from marsscene.env.task import NavTask

__all__ = ["FAILURES", "FailureJudge", "compute_terminated", "compute_truncated", "up_z"]

#: The reasons an episode ends without the goal, in the order they are judged.
FAILURES = ("tipped", "left_world", "strayed", "stuck")


def up_z(q_wxyz: Any) -> float:
    """The z component of the body's up axis in the world (the cosine of its tilt)."""
    _, x, y, _ = q_wxyz
    return float(1.0 - 2.0 * (x * x + y * y))


class FailureJudge:
    """The failures of one episode, judged step by step (it keeps the stuck clock).

    Parameters
    ----------
    task : NavTask
        The thresholds.
    bounds_xy_m : (float, float, float, float)
        The terrain's ``x0, y0, x1, y1``.
    start_xy_m, goal_xy_m : ndarray (2,)
        The ends of the corridor.
    """

    def __init__(self, task: NavTask, bounds_xy_m: tuple[float, float, float, float],
                 start_xy_m: NDArray[np.float64], goal_xy_m: NDArray[np.float64]) -> None:
        self.task, self.bounds_xy_m = task, bounds_xy_m
        self.start_xy_m, self.goal_xy_m = start_xy_m, goal_xy_m
        self._track: deque[tuple[float, float, float]] = deque()

    def __call__(self, obs: Any, moving: bool) -> str:
        """The failure at this step's observation (``""``: none); ``moving``: motion was
        commanded (a pause restarts the stuck clock)."""
        task, xy = self.task, obs.gt_xyz_m[:2]
        if up_z(obs.gt_quat_wxyz) < math.cos(math.radians(task.max_tilt_deg)):
            return "tipped"
        x0, y0, x1, y1 = self.bounds_xy_m
        if min(xy[0] - x0, x1 - xy[0], xy[1] - y0, y1 - xy[1]) < task.edge_m:
            return "left_world"
        start, seg = self.start_xy_m, self.goal_xy_m - self.start_xy_m
        s = np.clip(np.dot(xy - start, seg) / max(np.dot(seg, seg), 1e-9), 0.0, 1.0)
        if math.hypot(*(xy - start - s * seg)) > task.max_stray_m:
            return "strayed"
        return "stuck" if self._stuck(obs.t_s, xy, moving) else ""

    def _stuck(self, t_s: float, xy: NDArray[np.float64], moving: bool) -> bool:
        task = self.task
        if not moving:
            self._track.clear()
            return False
        self._track.append((t_s, float(xy[0]), float(xy[1])))
        while t_s - self._track[0][0] > task.stuck_s + 1e-9:
            self._track.popleft()
        t0, x0, y0 = self._track[0]
        return t_s - t0 >= task.stuck_s - 1e-9 and math.hypot(xy[0] - x0, xy[1] - y0) < task.stuck_m


def compute_terminated(achieved_goal: Any, desired_goal: Any, info: Any, *,
                       tolerance_m: float) -> Any:
    """Whether ``achieved_goal`` / ``desired_goal`` pairs (any leading shape) end the episode.

    ``info``: one step's info dict, a dict of arrays, or a sequence of info dicts; it supplies
    ``termination`` (the step's failure, if any). A bool for one pair, else a bool array.
    """
    reached = goal_reached(achieved_goal, desired_goal, tolerance_m)
    failed = np.isin(info_field(info, "termination", dtype=str), FAILURES)
    out = reached | failed
    return bool(out) if np.ndim(out) == 0 else out


def compute_truncated(achieved_goal: Any, desired_goal: Any, info: Any, *,
                      tolerance_m: float) -> Any:
    """Whether the pairs are cut by the time limit: not terminated, and no steps left
    (``info["steps_left"]``). A bool for one pair, else a bool array."""
    ended = compute_terminated(achieved_goal, desired_goal, info, tolerance_m=tolerance_m)
    out = ~np.asarray(ended) & (info_field(info, "steps_left") <= 0)
    return bool(out) if np.ndim(out) == 0 else out
