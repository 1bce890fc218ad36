"""The host side of batched drives (``marsscene.sim.batch``): how many rover-seconds a second
the noise, odometry and run-folder writing of ``drive_batch`` keep up with, no GPU needed.

Usage::

    python perf/run.py batch_host [--drives 64,1024,4096] [--seconds 5] [--workers 16]

A batch's loop hands the host one tick at the IMU rate (100 Hz; control at 50 Hz): host copies
of every rover's state. Here the ticks are made up (a random walk of the rovers' joints at the
batch model's layout) and fed to what ``drive_batch`` feeds them to (``BatchSink``: every
drive's wheel encoders, IMU noise and odometry at once; the workers writing each drive's
``gt.tum``, ``odom.tum``, ``cmd.csv``, ``wheels.csv`` and the IMU logs, flushed once a
simulated second), with the LN-200S noise. The figure is the ceiling the host puts on a GPU
batch of state-only drives: simulated rover-seconds per wall second, the physics taking no time.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from perf.suite import Param, ints

PARAMS = (
    Param("drives", ints, "drives in a batch", quick=(4,), full=(64, 1024, 4096)),
    Param("seconds", float, "sim seconds of each drive", quick=1.0, full=5.0),
    Param("workers", int, "threads writing the run folders (0: the CPU cores, at most 16)",
          quick=0, full=0),
)

TICK_HZ, CONTROL_EVERY = 100, 2  # the IMU's rate; control every 2nd tick (50 Hz)
NQ, NV = 17, 16  # the batch rover's layout: free joint + 6 drive + 4 steer joints


def _ids() -> dict[str, Any]:
    return {"qpos_root": 0, "drive_dof": np.arange(6, 12), "steer_qpos": np.arange(13, 17),
            "_acc_adr": 0, "_gyr_adr": 3}


def _sinks(n: int, root: Path, workers: int) -> tuple[Any, Any]:
    import marsscene as ms
    from marsscene.env.batch.env import BATCH_ROVER
    from marsscene.sim.batch.noise import BatchNoise
    from marsscene.sim.batch.setup import DriveSim
    from marsscene.sim.batch.sink import BatchSink, DriveSink, SinkPool

    config = ms.RunConfig(noise=ms.NoiseConfig(profile="ln200s"))
    sim = DriveSim(config, BATCH_ROVER, 1.0 / 500.0, None)
    sinks = [DriveSink(i, sim=sim, out=root / f"{i:05d}", meta={}, lidar=None, camera=False,
                       route=None) for i in range(n)]
    pool = SinkPool(sinks, workers or min(16, os.cpu_count() or 1))
    qpos0 = np.zeros((n, NQ))
    qpos0[:, 3] = 1.0
    host = BatchSink(pool, BatchNoise(config.noise, config.imu_hz, range(n)), ids=_ids(),
                     offsets_xy_m=np.zeros((n, 2)), qpos0=qpos0, rover=BATCH_ROVER,
                     dt_control_s=CONTROL_EVERY / TICK_HZ)
    return host, sinks


def _ticks(n: int, seconds: float) -> Any:
    """Made-up host copies of the batch's state, tick by tick (float32, as the device's)."""
    from marsscene.sim.batch.sink import Tick

    rng = np.random.default_rng(0)
    qpos = np.zeros((n, NQ), np.float32)
    qpos[:, 3] = 1.0
    every = np.ones(n, bool)
    for k in range(round(seconds * TICK_HZ) + 1):
        qpos[:, :3] += rng.normal(0.0, 1e-3, (n, 3)).astype(np.float32)
        qvel = rng.normal(0.0, 1.0, (n, NV)).astype(np.float32)
        control = k % CONTROL_EVERY == 0
        yield Tick(k=k, t_s=k / TICK_HZ, flush=k % TICK_HZ == 0 and k > 0,
                   control=every if control else None, sense=every, imu=True,
                   cmd=rng.normal(size=(n, 2)).astype(np.float32) if control else None,
                   qpos=qpos.copy(), qvel=qvel,
                   sensordata=rng.normal(size=(n, 6)).astype(np.float32))


def main(drives: tuple[int, ...], seconds: float, workers: int) -> list[dict[str, Any]]:
    rows = []
    for n in drives:
        root = Path(tempfile.mkdtemp(prefix="bench_batch_host_"))
        try:
            ticks = list(_ticks(n, seconds))
            host, sinks = _sinks(n, root, workers)
            t0 = time.perf_counter()
            for tick in ticks:
                host.put(tick)
            host.close()
            wall = time.perf_counter() - t0
            for s in sinks:
                s.writer.close()
            row = {"drives": n, "sim_s": seconds, "wall_s": round(wall, 3),
                   "rover_sim_s_per_s": round(n * seconds / wall, 1),
                   "realtime_factor": round(seconds / wall, 3), "cores": os.cpu_count()}
            print(row, flush=True)
            rows.append(row)
        finally:
            shutil.rmtree(root, ignore_errors=True)
    return rows
