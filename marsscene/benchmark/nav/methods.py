"""The navigation methods: what each one hands :func:`marsscene.drive` for a start-goal pair.

- ``straight``: a straight route to the goal followed by pure pursuit (no planning: the floor);
- ``global-astar``: the least-cost path on the ground-truth planning grid (1 m cells,
  :class:`~marsscene.benchmark.nav.grid.PlanGrid`), smoothed and followed by pure pursuit (the
  "perfect map" case);
- ``orbital-astar``: the same on the traversability of what an orbiter sees
  (:func:`marsscene.orbital.orbital_map`: the terrain at HiRISE-like 1 m posts, rocks under
  1 m missing, no soil), driven on the real scene (the realistic case);
- ``arc-navigator``: :class:`marsscene.env.ArcNavigator` closing the loop every control step on
  a 10 m height scan around the rover (the terrain and rocks, as the navigation environments
  observe it) with the goal from the ground-truth pose;
- ``controller``: a user's ``MODULE:NAME``, a callable ``controller(obs) -> (v, omega)`` or a
  class, instantiated with those of ``goal_xy_m``, ``route`` (the straight route) and ``sim``
  its constructor takes; the drive ends at its ``done`` or at the goal;
- ``policy``: a trained policy's ``.npz`` (:class:`~marsscene.env.policy.MLPPolicy` on the
  height scan, :class:`~marsscene.env.cnn_policy.CNNPolicy` on the navcam's depth) fed what
  :class:`~marsscene.env.RoverNavEnv` feeds it, at its control rate: the observation vector
  of the true pose towards the goal with the last (normalised, clipped) action, and the
  height scan or the depth frame taken at that step; its action is held between steps.
"""

from __future__ import annotations

import importlib
import inspect
import math
import sys
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.ndimage import gaussian_filter1d

from marsscene.benchmark.nav.grid import PlanGrid
from marsscene.benchmark.nav.spec import NavMethodSpec
from marsscene.errors import ConfigError
from marsscene.rover.config import OMEGA_MAX_RAD_S, V_MAX_M_S
from marsscene.sim.goal import goal_reached
from marsscene.sim.route import Route, resample_xy

__all__ = ["GoalArcController", "MethodPlan", "PolicyController", "plan_method",
           "policy_run_config", "straight_route"]

ROUTE_SPACING_M = 0.1
#: The arc navigator's height scan side (m): the 10 m scan its results were measured with.
ARC_SCAN_M = 10.0
SMOOTH_M = 1.0


@dataclass
class MethodPlan:
    """What a method drives: a route (followed by pure pursuit unless a controller steers),
    a controller or None, and the planner's calls and seconds."""

    route: Route
    controller: Any = None
    plan_calls: int = 0
    plan_s: float = 0.0
    config: Any = None
    """The drive's :class:`~marsscene.rover.config.RunConfig` (None: the default)."""


def straight_route(start: NDArray[np.float64], goal: NDArray[np.float64]) -> Route:
    """The straight line from ``start`` to ``goal`` at the route spacing."""
    return Route(resample_xy(np.stack([start, goal]), ROUTE_SPACING_M))


def planned_route(cells_xy: NDArray[np.float64], start: NDArray[np.float64],
                  goal: NDArray[np.float64]) -> Route:
    """A grid path through cell centres as a route from the exact start to the exact goal,
    resampled and smoothed over ``SMOOTH_M`` (the ends kept)."""
    pts = np.vstack([start, cells_xy[1:-1], goal]) if len(cells_xy) > 2 else np.stack(
        [start, goal])
    xy = resample_xy(pts, ROUTE_SPACING_M)
    if len(xy) > 5:
        sm = gaussian_filter1d(xy, SMOOTH_M / ROUTE_SPACING_M, axis=0, mode="nearest")
        w = np.clip(np.minimum(np.arange(len(xy)), np.arange(len(xy))[::-1]) * ROUTE_SPACING_M
                    / SMOOTH_M, 0.0, 1.0)[:, None]
        xy = w * sm + (1.0 - w) * xy
    return Route(xy)


def _astar(grid: PlanGrid, start: NDArray[np.float64], goal: NDArray[np.float64],
           weight: float, what: str) -> MethodPlan:
    t0 = time.perf_counter()
    cells, _ = grid.shortest(start, goal, cost_weight=weight)
    dt = time.perf_counter() - t0
    if cells is None:  # the map sees no way: drive straight (the map's failure is scored)
        return MethodPlan(straight_route(start, goal), None, 1, dt)
    return MethodPlan(planned_route(cells, start, goal), None, 1, dt)


class GoalArcController:
    """:class:`~marsscene.env.ArcNavigator` as a drive controller towards a fixed goal."""

    def __init__(self, sim: Any, goal_xy_m: NDArray[np.float64]) -> None:
        from marsscene.env import ArcNavigator, HeightScan
        from marsscene.env.observe import HeightScanner
        from marsscene.sim.world import scene_obstacles

        scan = HeightScan(size_m=ARC_SCAN_M, resolution_m=0.1)
        self.nav = ArcNavigator(scan)
        self.scanner = HeightScanner(scan, sim.heightfield, scene_obstacles(sim))
        self.goal = np.asarray(goal_xy_m, dtype=np.float64)
        self.done = False
        self.calls, self.seconds = 0, 0.0

    def __call__(self, obs: Any) -> tuple[float, float]:
        t0 = time.perf_counter()
        xy, yaw = np.asarray(obs.gt_xyz_m[:2]), float(obs.gt_yaw_rad)
        self.done = bool(goal_reached(xy, self.goal))
        d = self.goal - xy
        c, s = math.cos(yaw), math.sin(yaw)
        vec = np.zeros(17, np.float32)
        vec[:3] = (c * d[0] + s * d[1], -s * d[0] + c * d[1], math.hypot(*d))
        act = self.nav({"observation": vec,
                        "height_scan": self.scanner(obs.gt_xyz_m, yaw)})
        self.calls += 1
        self.seconds += time.perf_counter() - t0
        return float(act[0]) * V_MAX_M_S, float(act[1]) * OMEGA_MAX_RAD_S


class PolicyController:
    """A trained policy towards a fixed goal, observing as :class:`~marsscene.env.RoverNavEnv`
    observes (called at :func:`policy_run_config`'s control rate)."""

    def __init__(self, sim: Any, goal_xy_m: NDArray[np.float64], policy: Any) -> None:
        from marsscene.env.observe import HeightScanner
        from marsscene.sim.world import scene_obstacles

        self.policy, self.rover = policy, sim.rover
        obs_config = policy.observations()
        self.scanner = (HeightScanner(obs_config.height_scan, sim.heightfield,
                                      scene_obstacles(sim))
                        if obs_config.height_scan is not None else None)
        self.depth_px = obs_config.camera if obs_config.depth else None
        self.goal = np.asarray(goal_xy_m, dtype=np.float64)
        self.last_action = np.zeros(2)
        self.done = False
        self.calls, self.seconds = 0, 0.0

    def observe(self, obs: Any) -> dict[str, Any]:
        """The policy's observation dict at ``obs``."""
        from marsscene.env.state import RoverState

        out = RoverState.of_observation(obs, self.rover).observations(self.goal,
                                                                        self.last_action)
        if self.scanner is not None:
            out["height_scan"] = self.scanner(obs.gt_xyz_m, float(obs.gt_yaw_rad))
        if self.depth_px is not None:
            frame = obs.camera
            if frame is None or frame.depth_m is None:  # before the first frame: all far
                out["depth"] = np.zeros(self.depth_px[::-1], np.float32)
            else:
                out["depth"] = np.nan_to_num(frame.depth_m, nan=0.0,
                                             posinf=0.0).astype(np.float32)
        return out

    def __call__(self, obs: Any) -> tuple[float, float]:
        t0 = time.perf_counter()
        self.done = bool(goal_reached(np.asarray(obs.gt_xyz_m[:2]), self.goal))
        act = np.clip(np.asarray(self.policy(self.observe(obs)), np.float64).reshape(2),
                      -1.0, 1.0)
        self.last_action = act
        self.calls += 1
        self.seconds += time.perf_counter() - t0
        return float(act[0]) * V_MAX_M_S, float(act[1]) * OMEGA_MAX_RAD_S


def policy_run_config(policy: Any) -> Any:
    """The drive's rates and camera for ``policy``: :class:`~marsscene.env.RoverNavEnv`'s
    control rate (its action period), IMU at twice that, the navcam at the policy's size
    at the control rate if it sees depth."""
    from marsscene.env.nav import CONTROL_HZ
    from marsscene.rover.config import RunConfig

    camera = policy.observations().camera_config(CONTROL_HZ)
    return RunConfig(control_hz=CONTROL_HZ, imu_hz=2 * CONTROL_HZ, camera=camera)


class _Stopping:
    """A user's controller, ended at the goal (or at its own ``done``)."""

    def __init__(self, inner: Any, goal: NDArray[np.float64]) -> None:
        self.inner, self.goal, self.done = inner, goal, False

    def __call__(self, obs: Any) -> tuple[float, float]:
        cmd = self.inner(obs)
        self.done = bool(getattr(self.inner, "done", False)) or bool(
            goal_reached(np.asarray(obs.gt_xyz_m[:2]), self.goal))
        return cmd


def load_controller(ref: str) -> Any:
    """The object ``MODULE:NAME`` (a one-line error when it cannot be imported)."""
    import os

    module_name, _, name = ref.partition(":")
    if os.getcwd() not in sys.path:
        sys.path.insert(0, os.getcwd())
    try:
        obj = getattr(importlib.import_module(module_name), name)
    except (ImportError, AttributeError) as err:
        raise ConfigError(f"controller {ref!r}: {type(err).__name__}: {err}") from None
    if not callable(obj):
        raise ConfigError(f"controller {ref!r} is not callable")
    return obj


def _user(ref: str, route: Route, goal: NDArray[np.float64]) -> Any:
    from marsscene.sim.control import OnStart

    obj = load_controller(ref)
    if not inspect.isclass(obj):
        return _Stopping(obj, goal)
    params = inspect.signature(obj).parameters

    def make(sim: Any) -> Any:
        given = {"goal_xy_m": goal.copy(), "route": route, "sim": sim}
        return _Stopping(obj(**{k: v for k, v in given.items() if k in params}), goal)

    return OnStart(make)


def plan_method(method: NavMethodSpec, start: NDArray[np.float64], goal: NDArray[np.float64],
                grids: dict[str, PlanGrid]) -> MethodPlan:
    """The route and controller of ``method`` for one pair (``grids``: ``"gt"`` and
    ``"orbital"`` planning grids)."""
    kind = method.kind
    if kind == "global-astar":
        return _astar(grids["gt"], start, goal, method.cost_weight, kind)
    if kind == "orbital-astar":
        return _astar(grids["orbital"], start, goal, method.cost_weight, kind)
    route = straight_route(start, goal)
    if kind == "straight":
        return MethodPlan(route)
    if kind == "arc-navigator":
        from marsscene.sim.control import OnStart

        return MethodPlan(route, OnStart(lambda sim: GoalArcController(sim, goal)))
    if kind == "policy":
        from marsscene.env.cnn_policy import load_policy
        from marsscene.sim.control import OnStart

        assert method.policy is not None
        policy = load_policy(method.policy)
        return MethodPlan(route, OnStart(lambda sim: PolicyController(sim, goal, policy)),
                          config=policy_run_config(policy))
    assert method.controller is not None
    return MethodPlan(route, _user(method.controller, route, goal))
