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

The codes of these endings are one table, :data:`marsscene.env.terms.TERMINATIONS`; a step is
judged by :func:`marsscene.env.judgement.judge_step`.

:func:`compute_terminated` and :func:`compute_truncated` recompute both from
``achieved_goal`` / ``desired_goal`` pairs (vectorised, for hindsight relabelling as
:func:`~marsscene.env.reward.compute_reward`): the goal test is redone, the failures are the
step's (``info["termination"]``; on a step that reached its own goal the failures are not
judged, as the reward's ``stray`` term is not).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from marsscene.env.reward import info_field
from marsscene.env.terms import FAILURES
from marsscene.sim.goal import goal_reached

__all__ = ["compute_terminated", "compute_truncated"]


def compute_terminated(achieved_goal: Any, desired_goal: Any, info: Any, *,
                       tolerance_m: float) -> Any:
    """Whether ``achieved_goal`` / ``desired_goal`` pairs (any leading shape) end the episode.

    ``info``: one step's info dict, a dict of arrays, or a sequence of info dicts; it supplies
    ``termination`` (the step's failure, if any). A bool for one pair, else a bool array.
    """
    reached = np.asarray(goal_reached(achieved_goal, desired_goal, tolerance_m))
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
