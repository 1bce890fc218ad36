"""The bag's ROS 2 messages made from a drive's samples as they come (a live publisher's side).

:class:`SampleMessages` has the drive listener's methods (``control``, ``imu``, ``lidar``,
``camera``, ``stereo``: :mod:`marsscene.sim.session`) and returns, for each sample, the
``(topic, message)`` pairs that the bag holds for it, built by the same
:class:`~.bag_messages.MessageBuilder` builders and content helpers (:mod:`.bag_data`,
:mod:`.bag_images`) that :mod:`.bag_topics` uses on a run folder's files. What differs is only
what a live stream cannot know: the ground-truth twist and the steering rates are backward
differences (the bag, written afterwards, takes central ones), and the odometry pose
covariance is integrated step by step (:class:`~marsscene.rover.odometry_covariance.
PoseCovarianceStep`, the same sums). Pixels, depth and LiDAR points are the very bytes the bag
carries for the same drive (PNG is lossless; the run folder's PNG and PLY encoders are used).

Topics that no one wants (``wanted(topic)`` false, e.g. no subscriber) are not built.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from marsscene.rover.config import NoiseConfig, RoverConfig
from marsscene.rover.geometry import DRIVE_JOINTS, STEER_JOINTS, body_twists_from_wheels
from marsscene.rover.odometry_covariance import PoseCovarianceStep, twist_covariance
from marsscene.runs.export import bag_data as bd
from marsscene.runs.export import bag_images as bi
from marsscene.runs.export.bag_messages import MessageBuilder
from marsscene.runs.export.bag_topics import ImageOptions
from marsscene.runs.export.frames import camera_frame, rover_urdf, static_transforms
from marsscene.runs.export.imu_noise import imu_noise_of
from marsscene.runs.export.topic_table import STEREO_SIDES, WHEEL_SOIL_TOPIC, Topic, topic_table
from marsscene.runs.logs import depth_mm, scan_record

__all__ = ["SampleMessages"]

Pairs = list[tuple[str, Any]]


def _xyzw(q_wxyz: Any) -> np.ndarray:
    q = np.asarray(q_wxyz, dtype=np.float64)
    return np.array([q[1], q[2], q[3], q[0]])


class SampleMessages:
    """The bag's messages of each drive sample, as the sample is made.

    Parameters
    ----------
    rover : RoverConfig
    noise : NoiseConfig
        The drive's noise (IMU and odometry covariances).
    imu_hz : float
    lidar : dict, optional
        The LiDAR's spec (``LidarSpec.to_dict()``, as ``run.json`` holds it).
    camera : dict, optional
        The navcam's intrinsics (``RoverSim.camera_intrinsics()``); ``stereo`` those of the
        stereo pair's views (``{"left": ..., "right": ...}``).
    camera_depth : bool
        The navcam renders depth.
    images : ImageOptions, optional
        Raw and/or compressed images, codec, depth encoding, the depth cloud.
    distro : str
        ``"jazzy"`` or ``"humble"`` message definitions.
    wanted : callable, optional
        ``wanted(topic)``: build that topic's messages (default: all).
    map_tf : bool
        ``/tf`` carries ``map -> odom`` (from ground truth) besides ``odom -> base_link``.
    soil : WheelSoil, optional
        The simulation's wheel--soil model (``RoverSim.wheel_soil``): each control step also
        gives ``/rover/wheel_soil`` (sinkage, slip and load per wheel, as the bag's).
    """

    def __init__(self, rover: RoverConfig, noise: NoiseConfig, *, imu_hz: float,
                 lidar: dict[str, Any] | None = None, camera: dict[str, Any] | None = None,
                 stereo: dict[str, dict[str, Any]] | None = None, camera_depth: bool = True,
                 images: ImageOptions | None = None, distro: str = "jazzy",
                 wanted: Callable[[str], bool] | None = None, map_tf: bool = True,
                 soil: Any = None) -> None:
        self.b = MessageBuilder(distro)
        self.rover, self.noise, self.lidar_cfg = rover, noise, lidar
        self.cam_intr, self.stereo_intr, self.camera_depth = camera, stereo or {}, camera_depth
        self.opts = images if images is not None else ImageOptions()
        self.wanted = wanted if wanted is not None else (lambda topic: True)
        self.map_tf = map_tf
        self.soil = soil  # the simulation's WheelSoil (its state now), or None: rigid ground
        nd = imu_noise_of(asdict(noise), imu_hz)
        self.g_var = nd["gyroscope_noise_density"] ** 2 * nd["rate_hz"]
        self.a_var = nd["accelerometer_noise_density"] ** 2 * nd["rate_hz"]
        self.names = [*DRIVE_JOINTS, *STEER_JOINTS]
        self._prev: tuple[Any, ...] | None = None  # t, gt xyz, gt rotation, steer, odom yaw
        self._angle = np.zeros(6)
        self._pose_cov = PoseCovarianceStep()

    def topics(self) -> list[Topic]:
        """Every topic this publisher can make (:mod:`.topic_table` rows, in the bag's order)."""
        return topic_table(images=self.opts.images, camera=self.cam_intr is not None,
                           depth=self.camera_depth, stereo=bool(self.stereo_intr),
                           lidar=self.lidar_cfg is not None, depth_cloud=self.opts.depth_cloud,
                           soil=self.soil is not None)

    def static(self, t_s: float) -> Pairs:
        """``/tf_static`` (sensor mounts) and ``/rover/robot_description`` (the URDF)."""
        b = self.b
        statics = static_transforms(self.rover, self.stereo_intr)
        tf = b.tf_message([b.tf(t_s, s.parent, s.child, s.xyz_m, s.quat_xyzw) for s in statics])
        urdf = b.T["std_msgs/msg/String"](data=rover_urdf(self.rover, statics))
        return [("/tf_static", tf), ("/rover/robot_description", urdf)]

    def control(self, t: float, v: float, w: float, rates: Any, steer: Any,
                gt: tuple[Any, Any], odom: tuple[Any, Any]) -> Pairs:
        """``/tf``, ``/rover/odom``, ``/rover/GT_Trajectory``, ``/rover/joint_states`` and the
        command in force (``/rover/cmd_vel``) of one control step."""
        b, want = self.b, self.wanted
        rates, steer = np.asarray(rates, dtype=np.float64), np.asarray(steer, dtype=np.float64)
        gt_xyz, od_xyz = np.asarray(gt[0], dtype=np.float64), np.asarray(odom[0], np.float64)
        r_gt, r_od = Rotation.from_quat(_xyzw(gt[1])), Rotation.from_quat(_xyzw(odom[1]))
        od_yaw = float(r_od.as_euler("xyz")[2])
        twist = body_twists_from_wheels(rates, steer, self.rover)[0]
        tw_cov2 = twist_covariance(rates, steer, self.noise, self.rover)[0]
        prev, self._prev = self._prev, (t, gt_xyz, r_gt, steer, od_yaw)
        dt = t - prev[0] if prev is not None else 0.0
        pose3 = (self._pose_cov.step(dt, twist[0], prev[4], tw_cov2) if prev is not None
                 else np.zeros((3, 3)))
        self._angle = self._angle + rates * dt
        out: Pairs = []
        if want("/tf") and self.map_tf:
            rot = r_gt * r_od.inv()
            out.append(("/tf", b.state_tf(t, (gt_xyz - rot.apply(od_xyz), rot.as_quat()),
                                          (od_xyz, r_od.as_quat()))))
        elif want("/tf"):  # a SLAM stack publishes map -> odom itself
            out.append(("/tf", b.tf_message([b.tf(t, "odom", "base_link", od_xyz,
                                                  r_od.as_quat())])))
        if want("/rover/cmd_vel"):
            out.append(("/rover/cmd_vel", b.twist(v, w)))
        if want("/rover/odom"):
            pose_cov, twist_cov = np.zeros((6, 6)), np.zeros((6, 6))
            for k in (2, 3, 4):
                pose_cov[k, k] = bd.UNOBSERVED_VAR
            for k in (1, 2, 3, 4):
                twist_cov[k, k] = bd.UNOBSERVED_VAR
            pose_cov[np.ix_([0, 1, 5], [0, 1, 5])] = pose3
            twist_cov[np.ix_([0, 5], [0, 5])] = tw_cov2
            out.append(("/rover/odom", b.odometry(t, "odom", od_xyz, r_od.as_quat(),
                                                  (twist[0], 0, 0), (0, 0, twist[1]),
                                                  pose_cov.ravel(), twist_cov.ravel())))
        if want("/rover/GT_Trajectory"):
            lin, ang = np.zeros(3), np.zeros(3)
            if prev is not None and dt > 0:  # backward differences, body frame
                lin = r_gt.inv().apply((gt_xyz - prev[1]) / dt)
                ang = (prev[2].inv() * r_gt).as_rotvec() / dt
            out.append(("/rover/GT_Trajectory", b.odometry(t, "map", gt_xyz, r_gt.as_quat(),
                                                           lin, ang)))
        if want("/rover/joint_states"):
            steer_rate = (steer - prev[3]) / dt if prev is not None and dt > 0 else 0 * steer
            out.append(("/rover/joint_states", b.joint_state(
                t, self.names, np.concatenate([self._angle, steer]),
                np.concatenate([rates, steer_rate]))))
        if self.soil is not None and want(WHEEL_SOIL_TOPIC):
            ws = self.soil  # as the bag's: sinkage, slip and load as position, velocity, effort
            out.append((WHEEL_SOIL_TOPIC, b.joint_state(t, list(DRIVE_JOINTS), ws.sinkage_m,
                                                        ws.slip, ws.load_n)))
        return out

    def imu(self, t: float, acc: Any, gyr: Any, acc_true: Any, gyr_true: Any,
            bias: Any = None) -> Pairs:
        """``/clock`` (the IMU's clock is the finest) and both IMU topics."""
        b, want = self.b, self.wanted
        out: Pairs = [("/clock", b.clock(t))] if want("/clock") else []
        if want("/rover/imu_noisy"):
            out.append(("/rover/imu_noisy", b.imu(t, acc, gyr, self.g_var, self.a_var)))
        if want("/rover/imu"):
            out.append(("/rover/imu", b.imu(t, acc_true, gyr_true, 0.0, 0.0)))
        return out

    def lidar(self, t: float, index: int, scan: dict[str, Any]) -> Pairs:
        """``/rover/lidar/points`` (the run folder's PLY records) and ``/rover/scan``."""
        b, cfg = self.b, self.lidar_cfg
        if cfg is None:
            return []
        want_cloud, want_scan = self.wanted("/rover/lidar/points"), self.wanted("/rover/scan")
        if not (want_cloud or want_scan):
            return []
        rec = scan_record(scan["xyz_m"], scan["intensity"], scan["ring"], scan.get("t_s"))
        out: Pairs = []
        if want_cloud:
            out.append(("/rover/lidar/points", b.cloud(t, "lidar_link", rec, (1, len(rec)))))
        if want_scan:
            period = 1.0 / float(cfg.get("rate_hz", 10.0))
            out.append(("/rover/scan", b.laser_scan(t, bd.laser_scan(rec, cfg), period,
                                                    int(cfg["horizontal_samples"]))))
        return out

    def camera(self, t: float, index: int, rgb: Any, depth: Any) -> Pairs:
        """The navcam's colour, depth, camera infos and (``depth_cloud``) the depth cloud."""
        if self.cam_intr is None:
            return []
        frame, out = camera_frame("navcam"), self._colour("/rover/rgb", t, "navcam", rgb, 0.0)
        if depth is None:
            return out
        b, want, opts, intr = self.b, self.wanted, self.opts, self.cam_intr
        mm = depth_mm(depth)
        if want("/rover/depth/image_raw") and opts.images in ("raw", "both"):
            arr = bd.depth_m(mm) if opts.depth_encoding == "32FC1" else mm.astype("<u2")
            out.append(("/rover/depth/image_raw", b.image(t, frame, arr, opts.depth_encoding)))
        topic = "/rover/depth/image_raw/compressedDepth"
        if want(topic) and opts.images in ("compressed", "both"):
            out.append((topic, b.compressed(t, frame, bi.compressed_depth_mm(
                mm, opts.depth_encoding, b.distro))))
        if want("/rover/depth/camera_info"):
            out.append(("/rover/depth/camera_info", self._info(t, frame, intr, 0.0)))
        if want("/rover/depth/points") and opts.depth_cloud:
            pts = bd.depth_points(mm, _k(intr), opts.cloud_stride_px)
            dtype = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4")])
            out.append(("/rover/depth/points", b.cloud(
                t, frame, np.ascontiguousarray(pts).view(dtype)[..., 0], pts.shape[:2])))
        return out

    def stereo(self, t: float, index: int, pair: Any) -> Pairs:
        """Both views of the rectified stereo pair, each with its camera info."""
        out: Pairs = []
        for side, img in zip(STEREO_SIDES, pair, strict=True):
            intr = self.stereo_intr.get(side)
            if intr is None:
                continue
            base = float(intr.get("baseline_m", intr.get("stereo_baseline_m", 0.0)))
            tx = -float(intr["fx"]) * base if side == "right" else 0.0
            out += self._colour(f"/rover/stereo/{side}", t, side, img, tx)
        return out

    def _colour(self, prefix: str, t: float, stream: str, img: Any, tx: float) -> Pairs:
        b, want, opts = self.b, self.wanted, self.opts
        frame = camera_frame(stream)
        intr = self.cam_intr if stream == "navcam" else self.stereo_intr[stream]
        info = f"{prefix}/camera_info"
        out: Pairs = []
        if want(f"{prefix}/image_raw") and opts.images in ("raw", "both"):
            out.append((f"{prefix}/image_raw", b.image(
                t, frame, img, "rgb8" if np.ndim(img) == 3 else "mono8")))
        if want(f"{prefix}/image_raw/compressed") and opts.images in ("compressed", "both"):
            out.append((f"{prefix}/image_raw/compressed", b.compressed(
                t, frame, bi.compressed_image_array(img, opts.codec,
                                                    jpeg_quality=opts.jpeg_quality))))
        if want(info) and intr is not None:
            out.append((info, self._info(t, frame, intr, tx)))
        return out

    def _info(self, t: float, frame: str, intr: dict[str, Any], tx: float) -> Any:
        return self.b.camera_info_k(t, frame, _k(intr), int(intr["width"]), int(intr["height"]),
                                    tx)


def _k(intr: dict[str, Any]) -> np.ndarray:
    return np.array([[intr["fx"], 0.0, intr["cx"]], [0.0, intr["fy"], intr["cy"]],
                     [0.0, 0.0, 1.0]])
