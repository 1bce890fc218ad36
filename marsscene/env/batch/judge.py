"""The batched environment's judgement of a step: reward, termination, truncation -- the CPU
environment's (:class:`~marsscene.env.episode.NavEpisode`), term by term and in its order, on
(N,) arrays.

Termination codes (``info["termination"]``): 0 the episode goes on, 1 the goal, then
``2 + i`` for failure ``i`` of :data:`~marsscene.env.taskmath.FAILURES` (tipped, left_world,
strayed, stuck).
"""

from __future__ import annotations

from typing import Any

from array_api_compat import array_namespace, device

from marsscene.env import taskmath
from marsscene.transforms import yaw_of_quat

__all__ = ["GOAL", "collided", "judge"]

#: The termination code of a reached goal.
GOAL = 1


def collided(env: Any) -> Any:
    """(N,) bool: the chassis touches anything, or a wheel touches ground raised by a rock."""
    xp, con, ids = env.xp, env._con, env.ids
    n = env.num_envs
    wid = xp.clip(xp.astype(con["worldid"], xp.int64), 0, n - 1)
    count = con["worldid"].shape[0]
    valid = xp.arange(count, device=device(wid)) < xp.astype(env._v["nacon"][0],
                                                                        xp.int64)
    g0, g1 = con["geom"][:, 0], con["geom"][:, 1]
    chassis = (g0 == ids["chassis_geom"]) | (g1 == ids["chassis_geom"])
    wheel = xp.zeros(g0.shape, dtype=xp.bool, device=device(g0))
    for g in env._wheels:
        wheel = wheel | (g0 == g) | (g1 == g)
    world = env.world[wid]
    pos = xp.astype(con["pos"], xp.float64)
    x = pos[:, 0] - env._offsets[world, 0]
    y = pos[:, 1] - env._offsets[world, 1]
    rock = taskmath.scan_heights(env._rock_cells, env._grid_origins, env._cell_m, x, y,
                                 world) > 0.5
    hit = valid & (chassis | (wheel & rock))
    return env.bk.count_per(wid, hit, n) > 0


def judge(env: Any, action: Any, moving: Any) -> tuple[Any, Any, Any, Any]:
    """Reward, terminated, truncated and the termination code of the step just taken with
    ``action`` (N, 2) normalised; ``moving`` (N,): motion was commanded."""
    xp, task, cfg = env.xp, env.task, env.reward_config
    st = env._state()
    xy, goal = st["xyz"][:, :2], env.goal_xy_m
    # the achieved and desired goals are float32, as the CPU environment's info holds them
    ag = xp.astype(xp.astype(xy, xp.float32), xp.float64)
    dg = xp.astype(xp.astype(goal, xp.float32), xp.float64)
    reached = _norm(ag - dg) < task.goal_tolerance_m
    stuck = env._stuck(xy, moving)
    fail = taskmath.failure_code(st["quat"], xy, env._bounds[env.world], env.start_xy_m, goal,
                                 stuck, task)
    code = xp.where(reached, xp.ones_like(fail) * GOAL,
                    xp.where(fail > 0, fail + GOAL, fail * 0))
    terminated = code > 0
    left = env.steps_total - env.steps_done
    bearing = xp.abs(taskmath.bearing_rad(ag, goal, yaw_of_quat(st["quat"])))
    dist = _norm(ag - goal)  # the terms take the goal unrounded, as the CPU's info does
    terms = taskmath.goal_terms(dist, bearing, dist < task.goal_tolerance_m, left,
                                steps_total=env.steps_total, cfg=cfg)
    strayed = code == GOAL + 1 + taskmath.FAILURES.index("strayed")
    terms.update(taskmath.step_terms(action, env.last_action, collided(env), strayed,
                                     steps_total=env.steps_total, cfg=cfg,
                                     progress_m=env.last_distance_m - dist))
    env.last_distance_m = dist
    reward = xp.zeros_like(bearing)
    for value in terms.values():  # the CPU environment's sum, in its order
        reward = reward + value
    truncated = ~terminated & (left <= 0)
    return reward, terminated, truncated, code


def _norm(d: Any) -> Any:
    """Euclidean norm over the last axis as numpy's ``linalg.norm`` computes it."""
    xp = array_namespace(d)
    return xp.sqrt(xp.sum(d * d, axis=-1))
