"""The batched environment's episode starts: every drawn start with the rover settled on it
once, in one MuJoCo Warp batch, when the environment is made.

A rover whose episode ends is put back at one of these states (position, velocities and sensor
readings), so a reset costs no settling while the other rovers drive on. The CPU environment
settles each start when its episode begins (:class:`~marsscene.env.episode.NavEpisode`); both
settle ``task.start_settle_s`` with the wheels braked and refuse a start where the rover leans
over ``task.start_max_tilt_deg`` (here: replaced by another start of its world).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from marsscene.env import taskmath
from marsscene.errors import ConfigError
from marsscene.rover.spawn import spawn_pose

__all__ = ["settle_pool"]


def settle_pool(env: Any, terrains: list[Any], data: Any, nconmax: int, njmax: int
                ) -> dict[str, Any]:
    """Every drawn start of ``env``'s batch (its rock ``terrains``), the rover settled there
    with its wheels braked: states, sensor readings, starts, goals and worlds."""
    b, ids, mjw = env.batch, env.ids, env._mjw
    offsets = env.bk.to_numpy(env._offsets)
    qpos = np.tile(env.mj_model.qpos0, (b.count * b.pool, 1))
    for w in range(b.count):
        for p in range(b.pool):
            pose = spawn_pose(terrains[w], tuple(b.starts_xy_m[w, p]), float(b.yaws_rad[w, p]),
                              env.rover)
            pose[:2] += offsets[w]
            qpos[w * b.pool + p, ids["qpos_root"]: ids["qpos_root"] + 7] = pose
    with env.bk.wp.ScopedDevice(env.device):
        d = mjw.put_data(env.mj_model, data, nworld=len(qpos), nconmax=nconmax, njmax=njmax)
        env.bk.view(d.qpos)[...] = env.bk.asarray(qpos)
        for _ in range(round(env.task.start_settle_s * env.mj_model.opt.timestep ** -1)):
            mjw.step(env.mjw_model, d)
    q = env.bk.to_numpy(env.bk.view(d.qpos))
    level = taskmath.up_z(q[:, ids["qpos_root"] + 3: ids["qpos_root"] + 7]) > math.cos(
        math.radians(env.task.start_max_tilt_deg))
    keep = np.arange(len(q))
    for w in range(b.count):  # a leaning start -> another start of its world
        rows = np.arange(w * b.pool, (w + 1) * b.pool)
        good = rows[level[rows]]
        if not len(good):
            raise ConfigError(f"world {w}: the rover does not stand level at any of its "
                              f"{b.pool} drawn starts")
        keep[rows[~level[rows]]] = good[0]
    env.pool_level_fraction = float(level.mean())
    sel = env.bk.asarray(keep)
    return {"qpos": env.bk.view(d.qpos)[sel], "qvel": env.bk.view(d.qvel)[sel],
            "sensordata": env.bk.view(d.sensordata)[sel],
            "start": env.bk.asarray(b.starts_xy_m.reshape(-1, 2)[keep]),
            "goal": env.bk.asarray(b.goals_xy_m.reshape(-1, 2)[keep]),
            "world": env.bk.asarray(keep // b.pool)}

