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

from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.env.reward import goal_reached, info_field
from marsscene.env.task import NavTask
from marsscene.env.taskmath import FAILURES, StuckClock, failure_code, up_z

__all__ = ["FAILURES", "FailureJudge", "compute_terminated", "compute_truncated", "up_z"]



class FailureJudge:
    """The failures of one episode, judged step by step (it keeps the stuck clock;
    :func:`marsscene.env.taskmath.failure_code` of one rover).

    Parameters
    ----------
    task : NavTask
        The thresholds.
    bounds_xy_m : (float, float, float, float)
        The terrain's ``x0, y0, x1, y1``.
    start_xy_m, goal_xy_m : ndarray (2,)
        The ends of the corridor.
    control_hz : float
        Steps per second (the stuck clock counts ``task.stuck_s`` of them).
    """

    def __init__(self, task: NavTask, bounds_xy_m: tuple[float, float, float, float],
                 start_xy_m: NDArray[np.float64], goal_xy_m: NDArray[np.float64], *,
                 control_hz: float) -> None:
        self.task, self.bounds_xy_m = task, np.asarray(bounds_xy_m, dtype=np.float64)
        self.start_xy_m = np.asarray(start_xy_m, dtype=np.float64)
        self.goal_xy_m = np.asarray(goal_xy_m, dtype=np.float64)
        self._stuck = StuckClock(self.start_xy_m, (), round(task.stuck_s * control_hz),
                                 task.stuck_m)

    def __call__(self, obs: Any, moving: bool) -> str:
        """The failure at this step's observation (``""``: none); ``moving``: motion was
        commanded (a pause restarts the stuck clock)."""
        xy = np.asarray(obs.gt_xyz_m[:2], dtype=np.float64)
        stuck = self._stuck(xy, np.asarray(moving))
        code = int(failure_code(np.asarray(obs.gt_quat_wxyz, dtype=np.float64), xy,
                                self.bounds_xy_m, self.start_xy_m, self.goal_xy_m, stuck,
                                self.task))
        return FAILURES[code - 1] if code else ""


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
