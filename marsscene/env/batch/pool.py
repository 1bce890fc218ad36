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


def settle_pool(batch: Any, terrains: list[Any], *, model: Any, warp_model: Any, data: Any,
                offsets_xy_m: Any, qpos_root: int, rover: Any, task: Any, backend: Any,
                nconmax: int, njmax: int) -> tuple[dict[str, Any], float]:
    """Every drawn start of ``batch`` (a :class:`~.worlds.WorldBatch`, its rock ``terrains``),
    the rover settled there with its wheels braked.

    Parameters
    ----------
    batch, terrains
        The worlds and their rock terrains.
    model, warp_model, data
        The tiled ``mujoco.MjModel``, its MuJoCo Warp model, and an ``MjData`` of it.
    offsets_xy_m : (W, 2) array
        Each world's tile offset.
    qpos_root : int
        The rover's free joint in ``qpos``.
    rover : RoverConfig
    task : NavTask
        ``start_settle_s``, ``start_max_tilt_deg``.
    backend : Backend
        The batch's arrays and Warp device.
    nconmax, njmax : int
        MuJoCo Warp's buffers.

    Returns
    -------
    pool : dict
        States, sensor readings, starts, goals and worlds (backend arrays, one row a start).
    level_fraction : float
        The fraction of drawn starts where the rover stood level (the others replaced).
    """
    import mujoco_warp as mjw

    b, bk, r = batch, backend, qpos_root
    offsets = bk.to_numpy(offsets_xy_m)
    qpos = np.tile(model.qpos0, (b.count * b.pool, 1))
    for w in range(b.count):
        for p in range(b.pool):
            pose = spawn_pose(terrains[w], tuple(b.starts_xy_m[w, p]), float(b.yaws_rad[w, p]),
                              rover)
            pose[:2] += offsets[w]
            qpos[w * b.pool + p, r: r + 7] = pose
    with bk.wp.ScopedDevice(bk.device):
        d = mjw.put_data(model, data, nworld=len(qpos), nconmax=nconmax, njmax=njmax)
        bk.view(d.qpos)[...] = bk.asarray(qpos)
        for _ in range(round(task.start_settle_s * model.opt.timestep ** -1)):
            mjw.step(warp_model, d)
    q = bk.to_numpy(bk.view(d.qpos))
    level = taskmath.up_z(q[:, r + 3: r + 7]) > math.cos(math.radians(task.start_max_tilt_deg))
    keep = np.arange(len(q))
    for w in range(b.count):  # a leaning start -> another start of its world
        rows = np.arange(w * b.pool, (w + 1) * b.pool)
        good = rows[level[rows]]
        if not len(good):
            raise ConfigError(f"world {w}: the rover does not stand level at any of its "
                              f"{b.pool} drawn starts")
        keep[rows[~level[rows]]] = good[0]
    sel = bk.asarray(keep)
    pool = {"qpos": bk.view(d.qpos)[sel], "qvel": bk.view(d.qvel)[sel],
            "sensordata": bk.view(d.sensordata)[sel],
            "start": bk.asarray(b.starts_xy_m.reshape(-1, 2)[keep]),
            "goal": bk.asarray(b.goals_xy_m.reshape(-1, 2)[keep]),
            "world": bk.asarray(keep // b.pool)}
    return pool, float(level.mean())
