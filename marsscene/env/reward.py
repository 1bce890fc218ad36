"""Rewards of the navigation environment: dense terms after RLRoverLab, or sparse.

Dense terms (each divided by the episode's step count ``T`` as RLRoverLab does, so an episode's
return is O(1) whatever the control rate; ``d`` the goal distance, ``b`` the goal bearing in
the body frame, ``a`` the normalised action):

==============  ======  ===================================================================
term            weight  value per step
==============  ======  ===================================================================
distance        +5.0    ``1 / (1 + 0.11 d^2) / T``
bearing         +5.0    ``1 / (1 + d) / (1 + |b|) / T``
goal            +5.0    ``2 (T - t) / T`` once, at the step the goal is reached (time left)
oscillation     -0.05   ``sum_i (3 |a_i - a'_i|)^4 / T`` over ``3 |a_i - a'_i| > 0.05`` (jerks)
reverse         -0.5    ``1 / T`` when the speed command is negative
heading_away    -1.5    ``|b| / T`` when ``|b| > 2 rad``
collision       -3.0    ``1 / T`` per step the chassis, or a wheel against a rock, is in contact
stray           -2.0    ``1`` at the step the rover strays from the start-goal corridor
progress        0       metres of goal distance gained this step (off by default)
==============  ======  ===================================================================

``progress`` is potential-based shaping (Ng, Harada & Russell 1999, "Policy invariance under
reward transformations", ICML: a difference of a potential, the goal distance, leaves the
optimal policy unchanged). RLRoverLab's terms pull towards goals a few metres away; for goals
20-50 m away their pull is weak (``distance`` is 0.1 % of its peak at 30 m), and PPO trained on
them alone did not leave the start (:doc:`/results/gym`).

Source of the terms and weights: RLRoverLab, Aalborg University's Isaac Lab suite for rover
navigation (https://github.com/abmoRobotics/RLRoverLab, ``rover_envs/envs/navigation/mdp/
rewards.py`` and ``rover_env_cfg.py``, read 2026-11). Differences: the goal
needs no final heading (a point goal), oscillation counts changes of either sign, collisions do
not end the episode (the rover may climb a rock; getting stuck ends it) and so cost ``1 / T``
a step in contact (RLRoverLab's one-off -3 spread over a whole episode), and the goal tolerance
is the task's (0.5 m for a 3 m rover, RLRoverLab: 0.18 m for a 1 m rover).

Sparse: ``-1`` per step until the goal, ``0`` at it (Gymnasium-Robotics' convention).

The terms' functions and their order are one table, :data:`marsscene.env.terms.DENSE_TERMS`
(a term's weight is the :class:`RewardConfig` field of its name).

:func:`compute_reward` recomputes the goal terms from ``achieved_goal`` / ``desired_goal``
(vectorised, for hindsight relabelling) and adds the goal-free terms kept in ``info``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.env.judgement import goal_quantities
from marsscene.env.terms import WEIGHTS, reward_terms
from marsscene.errors import ConfigError

__all__ = ["RewardConfig", "compute_reward", "goal_terms", "info_field"]


@dataclass(frozen=True, kw_only=True)
class RewardConfig:
    """Reward kind and term weights (defaults: RLRoverLab's, from the terms' table,
    :data:`marsscene.env.terms.DENSE_TERMS`)."""

    kind: str = "dense"
    distance: float = WEIGHTS["distance"]
    bearing: float = WEIGHTS["bearing"]
    goal: float = WEIGHTS["goal"]
    oscillation: float = WEIGHTS["oscillation"]
    reverse: float = WEIGHTS["reverse"]
    heading_away: float = WEIGHTS["heading_away"]
    collision: float = WEIGHTS["collision"]
    stray: float = WEIGHTS["stray"]
    progress: float = WEIGHTS["progress"]

    def __post_init__(self) -> None:
        if self.kind not in ("dense", "sparse"):
            raise ConfigError(f"reward kind = {self.kind!r}; use dense or sparse")


def goal_terms(ag: Any, dg: Any, *, yaw_rad: Any, steps_left: Any, steps_total: float,
               tolerance_m: float, cfg: RewardConfig) -> dict[str, NDArray[np.float64]]:
    """The goal-dependent terms (weighted) of achieved / desired goal pairs, vectorised over
    leading dimensions (the goal terms of :data:`~marsscene.env.terms.DENSE_TERMS`, or the
    sparse reward's)."""
    q = goal_quantities(np.asarray(ag, dtype=np.float64), np.asarray(yaw_rad, dtype=np.float64),
                        np.asarray(dg, dtype=np.float64), np.asarray(steps_left),
                        tolerance_m=tolerance_m, steps_total=steps_total)
    return reward_terms(q, cfg, goal=True)


def info_field(info: Any, key: str, dtype: Any = np.float64) -> NDArray[Any]:
    """``info[key]`` as an array, of one step's info dict, a dict of arrays (a vector
    environment's) or a sequence of info dicts."""
    if isinstance(info, Mapping):
        return np.asarray(info[key], dtype=dtype)
    if isinstance(info, Sequence) or isinstance(info, np.ndarray):
        return np.asarray([i[key] for i in info], dtype=dtype)
    raise ConfigError("info must be a dict (one step or arrays) or a sequence of dicts")


def compute_reward(achieved_goal: Any, desired_goal: Any, info: Any, *,
                   cfg: RewardConfig, tolerance_m: float, steps_total: float) -> Any:
    """The reward of ``achieved_goal`` / ``desired_goal`` pairs (any leading shape).

    ``info``: one step's info dict, a dict of arrays, or a sequence of info dicts; it supplies
    ``yaw_rad``, ``steps_left`` and ``reward_other`` (the goal-free terms of the step).
    """
    yaw = info_field(info, "yaw_rad")
    left = info_field(info, "steps_left")
    other = info_field(info, "reward_other")
    terms = goal_terms(achieved_goal, desired_goal, yaw_rad=yaw, steps_left=left,
                       steps_total=steps_total, tolerance_m=tolerance_m, cfg=cfg)
    total = sum(terms.values()) + other
    return float(total) if np.ndim(total) == 0 else total
