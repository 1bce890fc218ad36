"""KISS-ICP (Vizzo et al. 2023, doi:10.1109/LRA.2023.3236571) as a LiDAR-odometry baseline.

:func:`run_kiss_icp` runs the ``kiss_icp_pipeline`` command on a run's ROS 2 bag exactly as a
user would (``kiss_icp_pipeline --topic /rover/lidar/points RUN/bag``, default configuration
unless ``config`` is given) and reads the TUM trajectory it writes; :class:`LiveKissIcp` is the
same odometry (KISS-ICP's own ``KissICP`` class, the pipeline's configuration) fed each scan as a
drive makes it, so a benchmark needs no copy of the LiDAR stream on disk. With ``wheel_prior``
it is LiDAR odometry with an odometry prior, as MOLA runs on a wheeled robot (Blanco-Claraco
2024, MOLA, arXiv:2407.20465): before each scan, KISS-ICP's constant-velocity prediction (the
pose step that deskews the scan and seeds the ICP) is replaced by the odometry's step since the
previous scan (the wheels' travel, the gyro's rotation: :mod:`.odometry_prior`), moved to the
LiDAR frame, and an ICP step outside a gate around it
is replaced by it: a standing start's ground rings, which KISS-ICP alone locks onto and slides
along, no longer move the estimate. Two gates (:func:`passes_gate`):

* ``"step"`` (rigid ground): the ICP step departs from the wheel step by at most
  ``max_step_dev_m`` and ``max_step_dev_deg`` (the gate of the RGB-D row's wheel prior,
  :mod:`.rgbd_odometry`);
* ``"slip"`` (deformable soil): the wheels may slip, the rover may not outrun them. Along the
  wheel step the ICP step may be anything from standing still (100 % slip) to the wheel step,
  each end widened by ``max_step_dev_m``; across it (side slip, sinkage) at most
  ``max_step_dev_m`` plus :data:`SIDE_SLIP_RATIO` of the wheel step; its rotation departs from
  the wheels' by at most ``max_step_dev_deg``. Slip is longitudinal slip of a driven wheel,
  ``1 - v / (omega r)`` in [0, 1] (Wong 2008, Theory of Ground Vehicles, 4th ed., ch. 2);
  Curiosity's wheels reached 77 % of it in the Hidden Valley megaripples (Arvidson et al.
  2016, doi:10.1002/rob.21647). On slipping wheels the step gate compares each ICP step with a
  wheel step that is itself wrong, rejects the LiDAR where it is right, and builds KISS-ICP's map
  from the slipping wheels' poses; on rigid ground the slip gate takes a standing start's ring
  lock (the ICP holding still while the wheels roll) for slip, so ``"step"`` is the default
  (docs/results/benchmark.md has the figures of both).
:func:`lidar_ground_truth`
is the run's ground truth moved to the ``lidar_link`` frame, the frame KISS-ICP estimates;
:func:`score_lidar_odometry` aligns one to the other (Umeyama, SE(3)) and reports ATE and the
estimated path length. A run that fails (no output, too few poses) is a result, not a crash.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from marsscene.benchmark.slam.odometry_prior import WheelGyroPrior
from marsscene.errors import MissingDependencyError
from marsscene.rover.geometry import sensor_mounts
from marsscene.runs.evaluation import ate
from marsscene.runs.runlog import RunLog
from marsscene.runs.tum import Trajectory, read_tum

__all__ = ["GATES", "SIDE_SLIP_RATIO", "LidarOdometryScore", "LiveKissIcp", "lidar_ground_truth",
           "lidar_mount", "passes_gate", "run_kiss_icp", "score_lidar_odometry"]

TOPIC = "/rover/lidar/points"
#: The wheel prior's gates (module doc).
GATES = ("step", "slip")
#: Largest side step of the ``"slip"`` gate per metre of wheel step, beyond ``max_step_dev_m``:
#: a slip angle up to atan(0.3) = 17 deg (side slip of a steered rover wheel on loose soil as
#: Ishigami et al. 2007, doi:10.1002/rob.20187, model it).
SIDE_SLIP_RATIO = 0.3


@dataclass(frozen=True)
class LidarOdometryScore:
    """ATE (SE(3)-aligned) of a LiDAR-odometry estimate against the lidar_link ground truth."""

    ate_rmse_m: float
    path_m: float
    estimated_path_m: float
    poses: int
    status: str = "ok"

    @property
    def ate_percent(self) -> float:
        return 100.0 * self.ate_rmse_m / max(self.path_m, 1e-9)


def passes_gate(wheel_step: np.ndarray, icp_step: np.ndarray, gate: str = "step", *,
                max_step_dev_m: float = 0.05, max_step_dev_deg: float = 1.0) -> bool:
    """Whether an ICP step (4 x 4) is kept beside the wheel odometry's step (module doc)."""
    from marsscene.benchmark.slam.rgbd_odometry import step_deviation

    dev_m, dev_deg = step_deviation(wheel_step, icp_step)
    if dev_deg > max_step_dev_deg:
        return False
    if gate == "step":
        return dev_m <= max_step_dev_m
    wheel_m = float(np.linalg.norm(wheel_step[:3, 3]))
    ahead = wheel_step[:3, 3] / wheel_m if wheel_m > 0.0 else np.zeros(3)
    along_m = float(icp_step[:3, 3] @ ahead)
    side_m = float(np.linalg.norm(icp_step[:3, 3] - along_m * ahead))
    return (-max_step_dev_m <= along_m <= wheel_m + max_step_dev_m
            and side_m <= max_step_dev_m + SIDE_SLIP_RATIO * wheel_m)


def _executable() -> str:
    exe = shutil.which("kiss_icp_pipeline") or str(Path(sys.executable).parent
                                                    / "kiss_icp_pipeline")
    if not Path(exe).is_file():
        raise MissingDependencyError("kiss_icp_pipeline not found: pip install "
                                     "'marsscene[bench]' (kiss-icp)")
    return exe


def run_kiss_icp(bag: str | Path, *, topic: str = TOPIC, config: str | Path | None = None,
                 timeout_s: float | None = None) -> Trajectory | None:
    """KISS-ICP's trajectory (lidar frame, starting at the identity) for a ROS 2 bag folder;
    ``None`` if it wrote none (a failure)."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [_executable(), "--topic", topic, str(Path(bag).resolve())]
        if config is not None:
            cmd += ["--config", str(Path(config).resolve())]
        env = dict(os.environ, kiss_icp_out_dir=tmp)
        done = subprocess.run(cmd, cwd=tmp, env=env, capture_output=True, text=True,
                              timeout=timeout_s, check=False)
        found = sorted(Path(tmp).rglob("*_tum.txt"))
        if done.returncode != 0 or not found:
            return None
        return read_tum(found[0])


class LiveKissIcp:
    """KISS-ICP as a drive listener (:mod:`marsscene.sim.session`): each scan is registered as
    the drive makes it, with the points and per-point times the run's bag would carry (float32
    x y z, ``t`` in whole nanoseconds, :func:`~marsscene.runs.logs.scan_record`) and the
    configuration ``kiss_icp_pipeline`` uses (``config``, else KISS-ICP's defaults).

    :meth:`trajectory` is the estimate (lidar frame, first pose the identity), what
    :func:`run_kiss_icp` gives on the bag of the same drive. With ``wheel_prior`` it also
    listens to the control steps and the IMU and predicts each scan's pose step from the wheel
    odometry's travel and the gyro's rotation (:class:`.WheelGyroPrior`; ``gyro = False``: the
    planar wheel odometry's rotation; ``lidar_mount``: :func:`lidar_mount` of the rover) instead
    of KISS-ICP's constant velocity,
    and keeps an ICP step only within ``gate`` (``"step"`` on rigid ground, ``"slip"`` where
    the wheels slip: :func:`passes_gate`).
    """

    def __init__(self, config: str | Path | None = None, *, wheel_prior: bool = False,
                 lidar_mount: np.ndarray | None = None, max_step_dev_m: float = 0.05,
                 max_step_dev_deg: float = 1.0, gate: str = "step", gyro: bool = True) -> None:
        from marsscene._validate import check_choice

        check_choice("kiss-icp gate", gate, GATES)
        try:
            from kiss_icp.config import load_config
            from kiss_icp.kiss_icp import KissICP
        except ImportError as err:
            raise MissingDependencyError("KISS-ICP is not installed: pip install "
                                         "'marsscene[bench]' (kiss-icp)") from err
        self.odometry = KissICP(config=load_config(None if config is None else Path(config)))
        self.stamps_s: list[float] = []
        self.poses: list[np.ndarray] = []
        self.seconds = 0.0  #: wall time spent registering scans
        self.wheel_prior = wheel_prior
        #: the wheel prior's steps (``gyro``: its rotation from the gyro, else the wheels')
        self.prior = WheelGyroPrior(lidar_mount, gyro=gyro)
        self.max_step_dev = (float(max_step_dev_m), float(max_step_dev_deg))
        self.gate = gate
        self.icp_steps_kept = 0  #: scans whose ICP step passed the wheel prior's gate

    def control(self, t: float, v: float, w: float, rates: Any, steer: Any,
                gt: tuple[Any, Any], odom: tuple[Any, Any]) -> None:
        """Keep the wheel odometry's pose of each control step (for ``wheel_prior``)."""
        if self.wheel_prior:
            self.prior.control(t, *odom)

    def imu(self, t: float, acc: Any, gyr: Any, acc_true: Any, gyr_true: Any,
            bias: Any = None) -> None:
        """Integrate the measured gyro rates (for ``wheel_prior``)."""
        if self.wheel_prior:
            self.prior.imu(t, gyr)

    def lidar(self, t: float, index: int, scan: dict[str, Any]) -> None:
        from marsscene.runs.logs import scan_record

        t0 = time.perf_counter()
        rec = scan_record(scan["xyz_m"], scan["intensity"], scan["ring"], scan["t_s"])
        xyz = np.column_stack([rec["x"], rec["y"], rec["z"]]).astype(np.float64)
        if self.wheel_prior:
            self._register_with_prior(xyz, rec["t"].astype(np.float64), self.prior.step(t))
        else:
            self.odometry.register_frame(xyz, rec["t"].astype(np.float64))
        self.seconds += time.perf_counter() - t0
        self.stamps_s.append(float(t))
        self.poses.append(np.array(self.odometry.last_pose, dtype=np.float64))

    def _register_with_prior(self, xyz: np.ndarray, stamps: np.ndarray,
                             step: np.ndarray | None) -> None:
        """``KissICP.register_frame`` with the wheel step as its prediction, and the gate."""
        kiss = self.odometry
        if step is not None:
            kiss.last_delta = step
        frame = kiss.preprocessor.preprocess(xyz, stamps, kiss.last_delta)
        source, frame_downsample = kiss.voxelize(frame)
        sigma = kiss.adaptive_threshold.get_threshold()
        guess = kiss.last_pose @ kiss.last_delta
        pose = kiss.registration.align_points_to_map(
            points=source, voxel_map=kiss.local_map, initial_guess=guess,
            max_correspondance_distance=3 * sigma, kernel=sigma)
        if step is not None:
            if passes_gate(step, np.linalg.inv(kiss.last_pose) @ pose, self.gate,
                           max_step_dev_m=self.max_step_dev[0],
                           max_step_dev_deg=self.max_step_dev[1]):
                self.icp_steps_kept += 1
            else:
                pose = guess
        kiss.adaptive_threshold.update_model_deviation(np.linalg.inv(guess) @ pose)
        kiss.local_map.update(frame_downsample, pose)
        kiss.last_delta = np.linalg.inv(kiss.last_pose) @ pose
        kiss.last_pose = pose

    def trajectory(self) -> Trajectory | None:
        """The estimate so far (None before the first scan)."""
        if not self.poses:
            return None
        from scipy.spatial.transform import Rotation

        poses = np.stack(self.poses)
        return Trajectory(np.asarray(self.stamps_s), poses[:, :3, 3],
                          Rotation.from_matrix(poses[:, :3, :3]).as_quat())


def lidar_mount(rover: Any) -> np.ndarray:
    """``lidar_link`` in ``base_link`` (4 x 4) for a :class:`~marsscene.rover.RoverConfig`."""
    from scipy.spatial.transform import Rotation

    (mx, my, mz), pitch = sensor_mounts(rover)["lidar"]
    mount = np.eye(4)
    mount[:3, :3] = Rotation.from_euler("y", pitch).as_matrix()
    mount[:3, 3] = (mx, my, mz)
    return mount


def lidar_ground_truth(gt: Trajectory, rover: Any) -> Trajectory:
    """The ground-truth pose of ``lidar_link``: the base pose ``gt`` (a run's ``gt.tum``)
    composed with the LiDAR mount of ``rover`` (a :class:`~marsscene.rover.RoverConfig`)."""
    from scipy.spatial.transform import Rotation

    (mx, my, mz), pitch = sensor_mounts(rover)["lidar"]
    rot = Rotation.from_quat(gt.quat_xyzw)
    xyz = gt.xyz_m + rot.apply(np.array([mx, my, mz]))
    quat = (rot * Rotation.from_euler("y", pitch)).as_quat()
    return Trajectory(gt.timestamps_s, xyz, quat)


def score_lidar_odometry(estimate: Trajectory | None, run: RunLog) -> LidarOdometryScore:
    """ATE of ``estimate`` against the run's lidar_link ground truth (``status`` says why a
    run has no score)."""
    gt = lidar_ground_truth(run.gt, run.rover)
    path = gt.path_length_m()
    if estimate is None or len(estimate) < 3:
        return LidarOdometryScore(float("nan"), path, float("nan"),
                                  0 if estimate is None else len(estimate), "lost")
    result = ate(estimate, gt)
    return LidarOdometryScore(float(result.stats.rmse), path, estimate.path_length_m(),
                              len(estimate))
