"""The judgement of a navigation step, once, for the CPU environment (one rover, batch shape
``()``) and the batched one (N rovers, ``(N,)``): reward, terminated, truncated and the
termination code.

:class:`~marsscene.env.episode.NavEpisode` (``RoverNavEnv``) and
:class:`~marsscene.env.batch.BatchNavEnv` call :func:`judge_step` with the step's
:class:`~marsscene.env.state.RoverState` and their episodes' arrays; the order of judgement is
the goal test (:func:`marsscene.sim.goal.goal_reached` on the achieved and desired goals as
``info`` holds them, float32), the failures (:func:`~marsscene.env.taskmath.failure_code`, the
stuck clock), the goal distance, the reward terms of :mod:`.terms` in their table's order, their
sum, and the time limit.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from marsscene._xp import namespace
from marsscene.env import taskmath
from marsscene.env.state import RoverState
from marsscene.env.terms import FAILURES, GOAL, Quantities, reward_terms
from marsscene.sim.goal import goal_distance_m, goal_reached

__all__ = ["Judgement", "goal_quantities", "judge_step"]

_STRAYED = GOAL + 1 + FAILURES.index("strayed")


@dataclass(frozen=True)
class Judgement:
    """A step's judgement, each of the batch shape (N,): ``reward`` (the sum of ``terms``, each
    weighted, in table order), ``terminated``, ``truncated``, ``code``
    (:data:`~marsscene.env.terms.TERMINATIONS`) and ``distance_m`` (the goal distance, the next
    step's ``last_distance_m``)."""

    reward: Any
    terms: dict[str, Any]
    terminated: Any
    truncated: Any
    code: Any
    distance_m: Any


def goal_quantities(xy_m: Any, yaw_rad: Any, goal_xy_m: Any, steps_left: Any, *,
                    tolerance_m: float, steps_total: float) -> Quantities:
    """What the goal terms read, for rovers at ``xy_m`` (N, 2) heading ``yaw_rad`` (N,) and
    goals ``goal_xy_m`` (N, 2): the position as ``info["achieved_goal"]`` holds it (float32),
    the goal test on it and on the goal as ``info["desired_goal"]`` holds it, the distance and
    bearing to the goal itself."""
    xp = namespace(xy_m, goal_xy_m)
    ag, dg = _float32_rounded(xp, xy_m), _float32_rounded(xp, goal_xy_m)
    dist = goal_distance_m(ag, goal_xy_m)
    return Quantities(xp=xp, zero=xp.zeros_like(dist), dist_m=dist,
                      bearing_rad=xp.abs(taskmath.bearing_rad(ag, goal_xy_m, yaw_rad)),
                      reached=goal_reached(ag, dg, tolerance_m), steps_left=steps_left,
                      steps_total=float(steps_total))


def _float32_rounded(xp: Any, x: Any) -> Any:
    """``x`` rounded to float32, as float64 (numpy's own ``astype`` for numpy arrays: the
    namespace's wrapper costs more than the rounding on one rover)."""
    if isinstance(x, np.ndarray):
        return x.astype(np.float32).astype(np.float64)
    return xp.astype(xp.astype(x, xp.float32), xp.float64)


def judge_step(state: RoverState, *, start_xy_m: Any, goal_xy_m: Any, bounds_xy_m: Any,
               steps_left: Any, action: Any, last_action: Any, last_distance_m: Any,
               collided: Any, moving: Any, stuck_clock: taskmath.StuckClock, task: Any,
               reward: Any, steps_total: float) -> Judgement:
    """Judge the step that led to ``state``.

    Parameters
    ----------
    state : RoverState
        The rovers after the step.
    start_xy_m, goal_xy_m, bounds_xy_m : (N, 2), (N, 2), (N, 4)
        Each episode's start and goal, and its terrain's ``x0, y0, x1, y1``.
    steps_left : (N,)
        Steps of the episode left after this one (0: the time limit).
    action, last_action : (N, 2)
        This step's and the last step's normalised actions.
    last_distance_m : (N,)
        The goal distance before the step (the ``progress`` term).
    collided, moving : (N,) bool
        The rover touched a rock or ground raised by one; motion was commanded (the stuck
        clock, ``stuck_clock``, runs).
    task : NavTask
    reward : RewardConfig
    steps_total : float
        Steps of a full episode.
    """
    q = goal_quantities(state.xy_m, state.yaw_rad, goal_xy_m, steps_left,
                        tolerance_m=task.goal_tolerance_m, steps_total=steps_total)
    xp = q.xp
    stuck = stuck_clock(state.xy_m, moving)
    fail = taskmath.failure_code(state.quat_wxyz, state.xy_m, bounds_xy_m, start_xy_m,
                                 goal_xy_m, stuck, task)
    code = xp.where(q.reached, fail * 0 + GOAL, fail)
    q.action, q.last_action, q.collided = action, last_action, collided
    q.strayed, q.progress_m = code == _STRAYED, last_distance_m - q.dist_m
    terms = reward_terms(q, reward)
    total = q.zero
    for value in terms.values():
        total = total + value
    terminated = code > 0
    return Judgement(reward=total, terms=terms, terminated=terminated,
                     truncated=~terminated & (steps_left <= 0), code=code,
                     distance_m=q.dist_m)
