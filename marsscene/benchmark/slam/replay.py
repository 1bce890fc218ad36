"""A finished run folder fed to drive listeners as the drive fed them: the control steps' wheel
odometry, the IMU samples and the LiDAR scans, in the drive's order.

A live listener (:class:`~.kiss_icp.LiveKissIcp`) sees each control step, IMU sample and scan
the moment the drive makes it (:mod:`marsscene.sim.session`: at one tick the control step, then
the IMU, then the LiDAR). A drive made elsewhere (a batch of drives on a GPU,
:func:`marsscene.sim.batch.drive_batch`) had no listener; :func:`replay_run` gives its listeners
the same calls from the files it wrote: ``odom.tum`` at the control steps, ``imu.csv``, and the
scans' PLYs (their points and per-point times are the live scan's bytes: ``t`` in whole
nanoseconds either way), so a replayed KISS-ICP gives the estimate it gives live.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["replay_run"]

#: The session's order at one tick: control, then the IMU, then the LiDAR.
_CONTROL, _IMU, _LIDAR = 0, 1, 2


def replay_run(run_dir: str | os.PathLike[str], listeners: Sequence[Any]) -> int:
    """Call each listener's ``control``, ``imu`` and ``lidar`` with the run's samples, in time
    order (the session's order within a tick); the scans replayed."""
    from marsscene.runs.runlog import RunLog, read_ply

    run = RunLog(run_dir)
    odom = run.odom
    quat_wxyz = np.asarray(odom.quat_xyzw, dtype=np.float64)[:, [3, 0, 1, 2]]
    imu = np.asarray(run.imu, dtype=np.float64)
    stamps, files = run.lidar or (np.zeros(0), ())
    events = sorted([(float(t), _CONTROL, k) for k, t in enumerate(odom.timestamps_s)]
                    + [(float(t), _IMU, k) for k, t in enumerate(imu[:, 0])]
                    + [(float(t), _LIDAR, k) for k, t in enumerate(stamps)])
    for t, kind, k in events:
        if kind == _CONTROL:
            for sink in listeners:
                sink.control(t, 0.0, 0.0, None, None, None, (odom.xyz_m[k], quat_wxyz[k]))
        elif kind == _IMU:
            acc, gyr = imu[k, 1:4], imu[k, 4:7]
            for sink in listeners:
                sink.imu(t, acc, gyr, None, None)
        else:
            rec = read_ply(files[k])
            scan = {"xyz_m": np.column_stack([rec["x"], rec["y"], rec["z"]]),
                    "intensity": rec["intensity"], "ring": rec["ring"],
                    "t_s": rec["t"].astype(np.float64) * 1e-9}
            for sink in listeners:
                sink.lidar(t, k, scan)
    return len(stamps)
