"""RGB-D odometry baselines with Open3D: frame to frame, plain or with the wheel odometry.

Both run Open3D's ``compute_rgbd_odometry`` (Steinbrücker et al. 2011 photometric term plus
Park et al. 2017 depth term, ``RGBDOdometryJacobianFromHybridTerm``) from each frame to the
next on the TUM RGB-D export and chain the steps.

* ``open3d-rgbd`` (plain): every pair starts from the identity; a pair Open3D reports as failed
  keeps the previous step (constant velocity).
* ``open3d-rgbd`` with ``options.wheel_prior = true``: the rover's odometry, what RTAB-Map
  receives as ``odom_topic`` in the paper's RGB-D + wheel-odometry setup, gives each pair's
  **initial guess**, the camera's motion between the two frames, and its **fallback**: where
  Open3D fails, or its step departs from the odometry's by more than ``max_step_dev_m``
  (translation) or ``max_step_dev_deg`` (rotation), the odometry's step is used. Tracked frames
  are those whose visual step was kept. The odometry is the LiDAR baseline's prior
  (:mod:`.odometry_prior`): the travel from the wheels (``odom.tum``, planar, from the wheel
  rates and steering) and the rotation from the gyro (``imu.csv``), so a fallback across a
  crater rim keeps the rover's tilt change; ``options.gyro = false`` takes the rotation from
  the planar wheel odometry too.

``decimate = 2`` runs on images halved in each direction (colour and depth averaged over 2 x 2
pixels, a block with a missing depth has none; intrinsics halved): a quarter of the pixels,
about a quarter of the time.

The pairs are computed in chunks (:mod:`.rgbd_pairs`): each pair's result depends on its two
frames and its initial guess alone, so with a ``checkpoint`` folder every finished chunk of
``checkpoint_every`` pairs is saved, a call with the same folder and key computes only the
missing ones (a benchmark stopped during a 13,000-frame cell loses at most a chunk of work
per process), and ``processes > 1`` shares the chunks out over that many processes with the
same result. The folder is removed once every pair is done.

Open3D's result is not bit-reproducible run to run: the same pair gives transforms that
differ by ~1e-14 between calls, with one OpenMP thread too (``OMP_NUM_THREADS=1``; no setting
of the Python API removes it), and over thousands of pairs the rare pair near a convergence
or success threshold then ends differently (1.049 vs 1.054 m ATE on one cell's data). Every
other baseline of the benchmark is deterministic.
"""

from __future__ import annotations

import json
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from marsscene.benchmark.slam.rgbd_pairs import PairJob, pair_results, require_open3d
from marsscene.errors import RuntimeSimError
from marsscene.runs.export.datasets import tum_associations
from marsscene.runs.runlog import RunLog

__all__ = ["RgbdOdometry", "rgbd_odometry", "step_deviation", "wheel_camera_steps"]


@dataclass(frozen=True)
class RgbdOdometry:
    """Camera-to-world poses (N, 4, 4) at ``stamps_s`` (N,); ``visual[k]``: frame k's pose
    came from a kept visual step (frame 0: True)."""

    stamps_s: NDArray[np.float64]
    poses: NDArray[np.float64]
    visual: NDArray[np.bool_]

    @property
    def fallbacks(self) -> int:
        """Pairs whose step was not Open3D's (failed, or departing from the wheel prior)."""
        return int((~self.visual[1:]).sum())


def wheel_camera_steps(run_dir: Path, stamps_s: NDArray[np.float64], *,
                       gyro: bool = True) -> NDArray[np.float64]:
    """The navcam's motion between consecutive frames from the rover's odometry: (N - 1, 4, 4),
    the pose of frame k in the optical frame of frame k - 1 (the wheels' travel and the gyro's
    rotation, or with ``gyro=False`` the planar ``odom.tum`` alone, at the frames' stamps,
    composed with the navcam's mount)."""
    from marsscene.benchmark.slam.odometry_prior import stored_steps
    from marsscene.runs.export.frames import camera_frame, frame_in_base, static_transforms

    run = RunLog(run_dir)
    odom = run.odom
    idx = np.clip(np.searchsorted(odom.timestamps_s, stamps_s - 1e-6), 0, len(odom) - 1)
    if np.abs(odom.timestamps_s[idx] - stamps_s).max(initial=0.0) > 0.011:
        raise RuntimeSimError(f"{run_dir}: odom.tum has no pose at some camera frames")
    name = run.camera_streams()[0].name
    mount = frame_in_base(static_transforms(run.rover, {}), camera_frame(name))
    return stored_steps(run, stamps_s, mount, gyro=gyro)


def step_deviation(a: NDArray[np.float64], b: NDArray[np.float64]) -> tuple[float, float]:
    """Translation (m) and rotation (deg) between two rigid steps."""
    d = np.linalg.inv(a) @ b
    cos = np.clip((np.trace(d[:3, :3]) - 1.0) / 2.0, -1.0, 1.0)
    return float(np.linalg.norm(a[:3, 3] - b[:3, 3])), float(np.degrees(np.arccos(cos)))


def rgbd_odometry(folder: Path, run_dir: Path, *, depth_trunc_m: float = 12.0,
                  wheel_prior: bool = False, max_step_dev_m: float = 0.02,
                  max_step_dev_deg: float = 1.0, gyro: bool = True, decimate: int = 1,
                  checkpoint: Path | None = None, checkpoint_key: str = "",
                  checkpoint_every: int = 500, processes: int = 1) -> RgbdOdometry:
    """Frame-to-frame Open3D RGB-D odometry over a TUM RGB-D folder (module doc).

    Parameters
    ----------
    folder : Path
        The TUM RGB-D export (its depth scale from ``orbslam3_rgbd.yaml``).
    run_dir : Path
        The run folder (intrinsics; ``odom.tum`` and ``imu.csv`` for the wheel prior).
    depth_trunc_m : float
        Depth beyond this is ignored (m).
    wheel_prior : bool
        Start each pair from the odometry's step and fall back to it (module doc).
    max_step_dev_m, max_step_dev_deg : float
        With ``wheel_prior``: largest departure of a visual step from the wheel step that is
        kept (m, deg).
    gyro : bool
        With ``wheel_prior``: the odometry's rotation from the gyro (False: the planar wheel
        odometry's).
    decimate : {1, 2, 4}
        Image size divisor (module doc).
    checkpoint : Path, optional
        Folder that keeps the finished chunks of pairs; a call whose ``checkpoint_key``
        matches theirs computes only the others (module doc).
    checkpoint_key : str
        What the pairs were computed from (the caller's digest of inputs and options).
    checkpoint_every : int
        Pairs in a chunk: the unit of work saved, and shared out over ``processes``.
    processes : int
        Processes that compute the chunks (1: this one). The result does not depend on it.
    """
    if decimate not in (1, 2, 4):
        raise RuntimeSimError(f"open3d-rgbd decimate = {decimate!r}; expected 1, 2 or 4")
    if processes < 1 or checkpoint_every < 1:
        raise RuntimeSimError(f"open3d-rgbd processes = {processes!r}, checkpoint_every = "
                              f"{checkpoint_every!r}; expected at least 1")
    require_open3d()
    rows = tum_associations(folder)
    if not rows:
        raise RuntimeSimError(f"{folder}: associations.txt lists no frames")
    i = json.loads((run_dir / "camera" / "intrinsics.json").read_text(encoding="utf-8"))
    d = float(decimate)
    job = PairJob(str(folder), {1: 0, 2: 1, 4: 2}[decimate], float(depth_trunc_m),
                  (int(i["width"]) // decimate, int(i["height"]) // decimate,
                   i["fx"] / d, i["fy"] / d, i["cx"] / d, i["cy"] / d), checkpoint_key)
    stamps = np.array([float(r[0]) for r in rows])
    prior = wheel_camera_steps(run_dir, stamps, gyro=gyro) if wheel_prior else None
    # Open3D's transform maps the source (previous) frame's points into the target
    init: NDArray[np.float64] = np.tile(np.eye(4), (max(len(rows) - 1, 0), 1, 1)) \
        if prior is None else np.linalg.inv(prior).astype(np.float64)
    success, trans = pair_results(job, init, checkpoint=checkpoint,
                                  chunk_pairs=checkpoint_every, processes=processes)
    pose, step = np.eye(4), np.eye(4)
    poses, visual = [pose], [True]
    for k in range(len(success)):
        kept = bool(success[k])
        if kept:
            seen = np.linalg.inv(trans[k])
            if prior is not None:
                dev_m, dev_deg = step_deviation(prior[k], seen)
                kept = dev_m <= max_step_dev_m and dev_deg <= max_step_dev_deg
            if kept:
                step = seen
        if not kept and prior is not None:
            step = prior[k]  # plain: a failed pair keeps the last motion (constant velocity)
        pose = pose @ step
        poses.append(pose)
        visual.append(kept)
    if checkpoint is not None:
        shutil.rmtree(checkpoint, ignore_errors=True)
    return RgbdOdometry(stamps, np.array(poses), np.array(visual))
