"""The goal test, once: a rover has reached a point goal when its ``base_link`` is, horizontally,
less than the goal tolerance from it.

Every judge of arrival calls :func:`goal_reached`: the navigation environments (the CPU
environment and the batched one, :mod:`marsscene.env.judgement`), the pure-pursuit follower
(with its own stopping radius, :data:`marsscene.sim.pursuit.STOP_RADIUS_M`, inside the
tolerance), a drive's summary (``goal_reached`` in ``run.json``: the drive ended within the
tolerance of its route's end) and the live ROS 2 session. The tolerance is
:data:`marsscene.rover.config.GOAL_TOLERANCE_M` (0.5 m, a sixth of the rover's 3 m length).

Both functions take numpy or PyTorch arrays of any batch shape ``(..., 2)`` (or one point as a
sequence of two numbers) and return arrays of the batch shape.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from marsscene._xp import namespace
from marsscene.rover.config import GOAL_TOLERANCE_M

__all__ = ["GOAL_TOLERANCE_M", "goal_distance_m", "goal_reached"]


def goal_distance_m(xy_m: Any, goal_xy_m: Any) -> Any:
    """The horizontal distance (m, float64) of positions ``xy_m`` (..., 2) from goals
    ``goal_xy_m`` (..., 2): ``sqrt(dx^2 + dy^2)``, as ``numpy.linalg.norm`` computes it."""
    if _plain(xy_m) and _plain(goal_xy_m):  # numpy's own calls: one rover's cost is the calls
        d = np.asarray(xy_m, dtype=np.float64) - np.asarray(goal_xy_m, dtype=np.float64)
        return np.sqrt(np.add.reduce(d * d, axis=-1))
    xp = namespace(xy_m, goal_xy_m)
    d = xp.astype(xy_m, xp.float64) - xp.astype(goal_xy_m, xp.float64)
    return xp.sqrt(xp.sum(d * d, axis=-1))


def _plain(x: Any) -> bool:
    """``x`` is a numpy array or a plain sequence (not PyTorch or another array library's)."""
    return isinstance(x, np.ndarray | np.generic | list | tuple)


def goal_reached(xy_m: Any, goal_xy_m: Any, tolerance_m: float = GOAL_TOLERANCE_M) -> Any:
    """Whether each position ``xy_m`` (..., 2) is within ``tolerance_m`` of its goal (strictly
    less than it); a bool array of the batch shape."""
    return goal_distance_m(xy_m, goal_xy_m) < tolerance_m
