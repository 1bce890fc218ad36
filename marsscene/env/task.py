"""Where an episode starts and where its goal is: on traversable ground, a route apart.

Start and goal are drawn on the route planner's own grid of free cells
(:func:`marsscene.sim.route.traversable_grid`: no slope above the limit within the rover's
half width, no tall rock within the clearance), at a straight-line distance in
``distance_m`` and in one connected component of free cells, so that
:func:`~marsscene.sim.route.author_route` joins them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from marsscene._validate import check_range
from marsscene.errors import ConfigError, RuntimeSimError
from marsscene.rover.config import GOAL_TOLERANCE_M, OMEGA_MAX_RAD_S, V_MAX_M_S
from marsscene.rover.spawn import SETTLE_S
from marsscene.sim.route import MAX_SLOPE_DEG, traversable_grid

__all__ = ["NavTask", "TaskMap"]


@dataclass(frozen=True, kw_only=True)
class NavTask:
    """The navigation task: goal distance, tolerance, time limit, the ground allowed.

    Parameters
    ----------
    distance_m : (float, float)
        Straight-line start-goal distance range.
    goal_tolerance_m : float
        The goal is reached within this distance (of ``base_link``, horizontally).
    max_episode_s : float
        Episodes are truncated after this much simulated time (RLRoverLab: 150 s).
    max_slope_deg, max_obstacle_height_m, clearance_m
        What counts as traversable for start and goal (the route planner's rule, with the
        rover's half width, 1 m, as the clearance from a rock's edge to its centre line).
    margin_m : float
        Start and goal keep this distance from the terrain's edge.
    start_max_tilt_deg : float
        A drawn start where the settled rover leans over this (roll or pitch) is drawn again; a
        given start is refused.
    start_settle_s : float
        Simulated time the rover settles on the ground at the start before the episode begins.
    max_tilt_deg : float
        Roll or pitch beyond this ends the episode (tipped over).
    stuck_s, stuck_m : float
        Moving less than ``stuck_m`` in ``stuck_s`` while commanding motion (driving or
        turning) ends it (stuck).
    max_stray_m : float
        Leaving the corridor of this half width around the start-goal line ends it.
    edge_m : float
        Coming within this distance of the terrain's edge ends it (left the world); less than
        ``margin_m``.

    Attributes
    ----------
    ACTION_SCALE : (float, float)
        A normalised action ``(1, 1)`` commands this ``(v, omega)`` (m/s, rad/s): the rover's
        route-following bounds, :data:`~marsscene.rover.config.V_MAX_M_S` and
        :data:`~marsscene.rover.config.OMEGA_MAX_RAD_S`.
    MOVING_CMD : float
        A commanded speed (m/s) or yaw rate (rad/s) above this counts as motion (the stuck
        clock runs).
    """

    ACTION_SCALE: ClassVar[tuple[float, float]] = (V_MAX_M_S, OMEGA_MAX_RAD_S)
    MOVING_CMD: ClassVar[float] = 0.05

    distance_m: tuple[float, float] = (5.0, 20.0)
    goal_tolerance_m: float = GOAL_TOLERANCE_M
    max_episode_s: float = 150.0
    max_slope_deg: float = MAX_SLOPE_DEG
    max_obstacle_height_m: float = 0.3
    clearance_m: float = 1.0
    margin_m: float = 4.0
    start_max_tilt_deg: float = 20.0
    start_settle_s: float = SETTLE_S
    max_tilt_deg: float = 35.0
    stuck_s: float = 20.0
    stuck_m: float = 0.2
    max_stray_m: float = 11.0
    edge_m: float = 2.0

    def __post_init__(self) -> None:
        lo, hi = (float(v) for v in self.distance_m)
        check_range("task.distance_m[0]", lo, 0.5, 1e4)
        check_range("task.distance_m[1]", hi, lo, 1e4)
        object.__setattr__(self, "distance_m", (lo, hi))
        check_range("task.goal_tolerance_m", self.goal_tolerance_m, 0.05, 10.0)
        check_range("task.max_episode_s", self.max_episode_s, 1.0, 1e5)
        check_range("task.max_slope_deg", self.max_slope_deg, 1.0, 60.0)
        check_range("task.margin_m", self.margin_m, 2.0, 1e3)
        check_range("task.start_max_tilt_deg", self.start_max_tilt_deg, 1.0, 90.0)
        check_range("task.start_settle_s", self.start_settle_s, 0.0, 60.0)
        check_range("task.max_tilt_deg", self.max_tilt_deg, 5.0, 90.0)
        check_range("task.stuck_s", self.stuck_s, 0.5, 1e4)
        check_range("task.stuck_m", self.stuck_m, 0.0, 100.0)
        check_range("task.max_stray_m", self.max_stray_m, 1.0, 1e4)
        check_range("task.edge_m", self.edge_m, 0.0, self.margin_m, hi_open=True)

    def episode_steps(self, control_hz: float) -> int:
        """Control steps in ``max_episode_s`` at ``control_hz`` (at least one): the step at
        which an episode is truncated, and the ``max_episode_steps`` of the registered ids."""
        return max(1, round(self.max_episode_s * control_hz))

    def stuck_steps(self, control_hz: float) -> int:
        """Control steps in ``stuck_s`` at ``control_hz``: the stuck clock's window."""
        return round(self.stuck_s * control_hz)

    def command(self, action: Any) -> tuple[Any, Any]:
        """``(v_m_s, omega_rad_s)`` of normalised actions (..., 2) (numpy or PyTorch)."""
        return action[..., 0] * self.ACTION_SCALE[0], action[..., 1] * self.ACTION_SCALE[1]

    def moving(self, v_m_s: Any, omega_rad_s: Any) -> Any:
        """Whether each command counts as motion (:attr:`MOVING_CMD`), an array of its shape."""
        return (abs(v_m_s) > self.MOVING_CMD) | (abs(omega_rad_s) > self.MOVING_CMD)


class TaskMap:
    """A world's free cells and their connected components, for drawing starts and goals."""

    def __init__(self, heightfield: Any, obstacles: Any, task: NavTask) -> None:
        free, cell, origin = traversable_grid(
            heightfield, cell_m=0.5, max_slope_deg=task.max_slope_deg, obstacles=obstacles,
            max_obstacle_height_m=task.max_obstacle_height_m, clearance_m=task.clearance_m)
        rows, cols = free.shape
        x = origin[0] + np.arange(cols) * cell
        y = origin[1] + np.arange(rows) * cell
        x0, y0, x1, y1 = heightfield.bounds_xy_m
        inside = ((x[None, :] >= x0 + task.margin_m) & (x[None, :] <= x1 - task.margin_m)
                  & (y[:, None] >= y0 + task.margin_m) & (y[:, None] <= y1 - task.margin_m))
        self.free = free & inside
        self.labels, _ = ndimage.label(free, structure=np.ones((3, 3), bool))
        self.cell_m, self.origin = cell, origin
        rr, cc = np.nonzero(self.free)
        self.cells_xy = np.column_stack([origin[0] + cc * cell, origin[1] + rr * cell])
        self.cell_label = self.labels[rr, cc]
        self.task = task
        if not len(self.cells_xy):
            raise RuntimeSimError("the world has no traversable ground for a start")

    def label_at(self, xy: NDArray[np.float64]) -> int:
        """The component of the cell at ``xy`` (0: not free)."""
        j = round((xy[0] - self.origin[0]) / self.cell_m)
        i = round((xy[1] - self.origin[1]) / self.cell_m)
        if not (0 <= i < self.free.shape[0] and 0 <= j < self.free.shape[1]) \
                or not self.free[i, j]:
            return 0
        return int(self.labels[i, j])

    def draw(self, rng: np.random.Generator, tries: int = 64
             ) -> tuple[NDArray[np.float64], float, NDArray[np.float64]]:
        """A start, a start heading and a goal: both free, joined by free ground, at a
        distance in ``task.distance_m``."""
        lo, hi = self.task.distance_m
        pool = np.arange(len(self.cells_xy))
        for k in range(2 * tries):
            if k == tries:  # the free ground is broken up: starts on its largest piece only
                pool = np.flatnonzero(self.cell_label == np.bincount(self.cell_label).argmax())
            start = self.cells_xy[pool[int(rng.integers(len(pool)))]]
            d = np.hypot(*(self.cells_xy - start).T)
            ok = (d >= lo) & (d <= hi) & (self.cell_label == self.label_at(start))
            if ok.any():
                goal = self.cells_xy[rng.choice(np.flatnonzero(ok))]
                return start.copy(), float(rng.uniform(-math.pi, math.pi)), goal.copy()
        raise RuntimeSimError(f"found no start and goal {lo:g}-{hi:g} m apart on connected "
                              f"free ground in {2 * tries} tries; lower task.distance_m")

    def check(self, start: NDArray[np.float64], goal: NDArray[np.float64]) -> None:
        """Refuse a start or a goal given in ``reset(options=...)`` off the free ground."""
        for name, xy in (("start", start), ("goal", goal)):
            if self.label_at(xy) == 0:
                raise ConfigError(f"{name} ({xy[0]:.2f}, {xy[1]:.2f}) m is not on traversable "
                                  "ground (slope, rocks or the terrain's edge)")
        if self.label_at(start) != self.label_at(goal):
            raise ConfigError("no route joins the start and the goal (blocked ground between)")
