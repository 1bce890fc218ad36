"""The navigation task's terms, each stated once: the reward terms with their weights and the
ways an episode ends, for one rover or thousands (numpy or PyTorch arrays of a batch axis).

:func:`marsscene.env.judgement.judge_step` reads these tables for the CPU environment and the
batched one alike. **Adding a reward term** is one function ``value(q, weight) -> (N,)`` of the
step's :class:`Quantities` and one :class:`RewardTerm` (name, function, default weight) in
:data:`DENSE_TERMS`; a :class:`~marsscene.env.reward.RewardConfig` field of its name, whose
default is read from the table (:data:`WEIGHTS`), makes its weight a setting. Terms are summed
in the table's order.

Termination codes, one table (:data:`TERMINATIONS`): 0 the episode goes on, 1 the goal, then
``2 + i`` for failure ``i`` of :data:`FAILURES`, judged in that order (the first wins). The CPU
environment's ``info["termination"]`` is the code's name (``""`` for 0), the batched
environment's the code. The time limit is no termination: a step at it that ends no other way
is ``truncated`` (the time-out flag).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

__all__ = ["DENSE_TERMS", "FAILURES", "GOAL", "GOAL_TERMS", "SPARSE_TERMS", "TERMINATIONS",
           "WEIGHTS", "Quantities", "RewardTerm", "reward_terms"]

#: The ways an episode ends, by code (index): none, the goal, then the failures in the order
#: they are judged.
TERMINATIONS = ("", "goal", "tipped", "left_world", "strayed", "stuck")
#: The code of a reached goal.
GOAL = TERMINATIONS.index("goal")
#: The failures, in the order they are judged (code ``2 + index``).
FAILURES = TERMINATIONS[GOAL + 1:]


@dataclass
class Quantities:
    """What the reward terms of a step read, each (N,) (``action`` and ``last_action`` (N, 2)).

    Goal terms read ``dist_m`` (to the goal), ``bearing_rad`` (its absolute bearing),
    ``reached``, ``steps_left`` and ``steps_total``; the others the actions, ``collided``,
    ``strayed`` and ``progress_m`` (goal distance gained this step). ``zero`` is zeros like
    ``dist_m`` (made once: on one rover each array call costs more than its arithmetic).
    """

    xp: Any
    zero: Any
    dist_m: Any
    bearing_rad: Any
    reached: Any
    steps_left: Any
    steps_total: float
    action: Any = None
    last_action: Any = None
    collided: Any = None
    strayed: Any = None
    progress_m: Any = None


@dataclass(frozen=True)
class RewardTerm:
    """One reward term: its name (the ``RewardConfig`` field of its weight), its weighted value,
    its default weight (RLRoverLab's), and whether it reads the goal (recomputed when a goal is
    relabelled); ``optional`` terms are left out while their weight is 0."""

    name: str
    value: Callable[[Quantities, float], Any]
    weight: float
    goal: bool
    optional: bool = False


def _distance(q: Quantities, w: float) -> Any:
    return w / (1.0 + 0.11 * q.dist_m * q.dist_m) / q.steps_total


def _bearing(q: Quantities, w: float) -> Any:
    return w / (1.0 + q.dist_m) / (1.0 + q.bearing_rad) / q.steps_total


def _goal(q: Quantities, w: float) -> Any:
    return q.xp.where(q.reached, w * 2.0 * q.steps_left / q.steps_total, q.zero)


def _heading_away(q: Quantities, w: float) -> Any:
    b = q.bearing_rad
    return q.xp.where(b > 2.0, w * b / q.steps_total, q.zero)


def _oscillation(q: Quantities, w: float) -> Any:
    xp = q.xp
    jump = 3.0 * xp.abs(q.action - q.last_action)
    osc = xp.sum(xp.where(jump > 0.05, jump**2, xp.zeros_like(jump)) ** 2, axis=-1)
    return w * osc / q.steps_total


def _when(flag: Any, value: float, q: Quantities) -> Any:
    return q.xp.where(flag, q.zero + value, q.zero)


def _reverse(q: Quantities, w: float) -> Any:
    return _when(q.action[..., 0] < 0.0, w / q.steps_total, q)


def _collision(q: Quantities, w: float) -> Any:
    return _when(q.collided, w / q.steps_total, q)


def _stray(q: Quantities, w: float) -> Any:
    return _when(q.strayed, w, q)


def _progress(q: Quantities, w: float) -> Any:
    return w * q.progress_m


def _sparse_goal(q: Quantities, w: float) -> Any:
    return q.xp.where(q.reached, q.zero, q.zero - w)


#: The dense reward (RLRoverLab's terms; values and sources in :mod:`marsscene.env.reward`).
DENSE_TERMS = (
    RewardTerm("distance", _distance, 5.0, goal=True),
    RewardTerm("bearing", _bearing, 5.0, goal=True),
    RewardTerm("goal", _goal, 5.0, goal=True),
    RewardTerm("heading_away", _heading_away, -1.5, goal=True),
    RewardTerm("oscillation", _oscillation, -0.05, goal=False),
    RewardTerm("reverse", _reverse, -0.5, goal=False),
    RewardTerm("collision", _collision, -3.0, goal=False),
    RewardTerm("stray", _stray, -2.0, goal=False),
    RewardTerm("progress", _progress, 0.0, goal=False, optional=True),
)
#: The dense terms' default weights, by name (``RewardConfig``'s defaults).
WEIGHTS = {t.name: t.weight for t in DENSE_TERMS}
#: The sparse reward: -1 a step until the goal, 0 at it (weight 1, not ``RewardConfig.goal``).
SPARSE_TERMS = (RewardTerm("goal", _sparse_goal, 1.0, goal=True),)
#: The names of the terms that read the goal (``info["reward_other"]`` sums the others).
GOAL_TERMS = frozenset(t.name for t in (*DENSE_TERMS, *SPARSE_TERMS) if t.goal)


def reward_terms(q: Quantities, cfg: Any, *, goal: bool | None = None) -> dict[str, Any]:
    """The weighted terms of ``cfg``'s reward (``cfg.kind``: dense or sparse) in table order;
    ``goal`` True or False keeps only the terms that do or do not read the goal."""
    sparse = cfg.kind == "sparse"
    out = {}
    for term in SPARSE_TERMS if sparse else DENSE_TERMS:
        weight = term.weight if sparse else float(getattr(cfg, term.name, term.weight))
        if (goal is None or term.goal == goal) and not (term.optional and not weight):
            out[term.name] = term.value(q, weight)
    return out
