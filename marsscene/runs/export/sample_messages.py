"""The bag's ROS 2 messages made from a drive's samples as they come (a live publisher's side).

:class:`SampleMessages` has the drive listener's methods (``control``, ``imu``, ``lidar``,
``camera``, ``stereo``: :mod:`marsscene.sim.session`) and returns, for each sample, the
``(topic, message)`` pairs that the bag holds for it. It computes no field itself: every message
is composed by the functions the bag calls (:mod:`.compose_state`, :mod:`.compose_sensors`), on
the samples a live stream knows. So the ground-truth twist and the steering rates are backward
differences (the bag, written afterwards, has the next sample and takes central ones), and the
odometry pose covariance and the drive joints' angles are carried from step to step
(:class:`~.compose_state.Carry`, the same sums). Pixels, depth and LiDAR points are the very
bytes the bag carries for the same drive (PNG is lossless; the run folder's PNG and PLY encoders
are used).

Topics that no one wants (``wanted(topic)`` false, e.g. no subscriber) are not built.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict
from typing import Any

import numpy as np

from marsscene.rover.config import NoiseConfig, RoverConfig
from marsscene.runs.export import bag_images as bi
from marsscene.runs.export import compose_sensors as sensors
from marsscene.runs.export import compose_state as cs
from marsscene.runs.export.bag_messages import MessageBuilder
from marsscene.runs.export.bag_topics import ImageOptions
from marsscene.runs.export.frames import camera_frame, static_transforms
from marsscene.runs.export.topic_table import (
    ROVER,
    STEREO_SIDES,
    WHEEL_SOIL,
    RosNames,
    Topic,
    topic_table,
)
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
    names : RosNames
        The robot's topic namespace and frame prefix (a team robot's; default ``/rover``).
    """

    def __init__(self, rover: RoverConfig, noise: NoiseConfig, *, imu_hz: float,
                 lidar: dict[str, Any] | None = None, camera: dict[str, Any] | None = None,
                 stereo: dict[str, dict[str, Any]] | None = None, camera_depth: bool = True,
                 images: ImageOptions | None = None, distro: str = "jazzy",
                 wanted: Callable[[str], bool] | None = None, map_tf: bool = True,
                 soil: Any = None, names: RosNames = ROVER) -> None:
        self.b = MessageBuilder(distro, names)
        self.names = names
        self.rover, self.noise, self.lidar_cfg = rover, noise, lidar
        self.cam_intr, self.stereo_intr, self.camera_depth = camera, stereo or {}, camera_depth
        self.opts = images if images is not None else ImageOptions()
        self.wanted = wanted if wanted is not None else (lambda topic: True)
        self.map_tf = map_tf
        self.soil = soil  # the simulation's WheelSoil (its state now), or None: rigid ground
        self.imu_var = cs.imu_variances(asdict(noise), imu_hz)
        self._prev: tuple[Any, ...] | None = None  # the previous control sample (a row)
        self._carry = cs.Carry()

    def topics(self) -> list[Topic]:
        """Every topic this publisher can make (:mod:`.topic_table` rows, in the bag's order)."""
        return topic_table(self.names, images=self.opts.images, camera=self.cam_intr is not None,
                           depth=self.camera_depth, stereo=bool(self.stereo_intr),
                           lidar=self.lidar_cfg is not None, depth_cloud=self.opts.depth_cloud,
                           soil=self.soil is not None)

    def static(self, t_s: float) -> Pairs:
        """``/tf_static`` (sensor mounts) and ``/rover/robot_description`` (the URDF)."""
        statics = static_transforms(self.rover, self.stereo_intr)
        return [("/tf_static", cs.tf_static(self.b, t_s, statics)),
                (self.names.topic("robot_description"),
                 cs.robot_description(self.b, self.rover, statics))]

    def control(self, t: float, v: float, w: float, rates: Any, steer: Any,
                gt: tuple[Any, Any], odom: tuple[Any, Any]) -> Pairs:
        """``/tf``, ``/rover/odom``, ``/rover/GT_Trajectory``, ``/rover/joint_states`` and the
        command in force (``/rover/cmd_vel``) of one control step."""
        b, want, n = self.b, self.wanted, self.names.topic
        row = (t, gt[0], _xyzw(gt[1]), odom[0], _xyzw(odom[1]), rates, steer)
        rows = [row] if self._prev is None else [self._prev, row]
        self._prev = row
        f = cs.ControlFields(cs.ControlRows.of_samples(rows), self.rover, self.noise,
                              self._carry)
        out: Pairs = []
        if want("/tf"):
            out.append(("/tf", cs.tf(b, f, 0, self.map_tf)))
        if want(n("cmd_vel")):
            out.append((n("cmd_vel"), b.twist(v, w)))
        for topic, build in ((n("odom"), cs.odometry), (n("GT_Trajectory"), cs.ground_truth),
                             (n("joint_states"), cs.joint_states)):
            if want(topic):
                out.append((topic, build(b, f, 0)))
        if self.soil is not None and want(n(WHEEL_SOIL)):
            ws = self.soil  # the simulation's wheel--soil state now
            out.append((n(WHEEL_SOIL), cs.wheel_soil(b, t, ws.sinkage_m, ws.slip, ws.load_n)))
        return out

    def imu(self, t: float, acc: Any, gyr: Any, acc_true: Any, gyr_true: Any,
            bias: Any = None) -> Pairs:
        """``/clock`` (the IMU's clock is the finest) and both IMU topics."""
        b, want, n = self.b, self.wanted, self.names.topic
        out: Pairs = [("/clock", b.clock(t))] if want("/clock") else []
        if want(n("imu_noisy")):
            out.append((n("imu_noisy"), b.imu(t, acc, gyr, *self.imu_var)))
        if want(n("imu")):
            out.append((n("imu"), b.imu(t, acc_true, gyr_true, 0.0, 0.0)))
        return out

    def lidar(self, t: float, index: int, scan: dict[str, Any]) -> Pairs:
        """``/rover/lidar/points`` (the run folder's PLY records) and ``/rover/scan``."""
        b, cfg = self.b, self.lidar_cfg
        if cfg is None:
            return []
        cloud, laser = self.names.topic("lidar/points"), self.names.topic("scan")
        want_cloud, want_scan = self.wanted(cloud), self.wanted(laser)
        if not (want_cloud or want_scan):
            return []
        rec = scan_record(scan["xyz_m"], scan["intensity"], scan["ring"], scan.get("t_s"))
        out: Pairs = []
        if want_cloud:
            out.append((cloud, sensors.lidar_cloud(b, t, rec)))
        if want_scan:
            out.append((laser, sensors.laser_scan(b, t, rec, cfg)))
        return out

    def camera(self, t: float, index: int, rgb: Any, depth: Any) -> Pairs:
        """The navcam's colour, depth, camera infos and (``depth_cloud``) the depth cloud."""
        if self.cam_intr is None:
            return []
        n = self.names.topic
        frame, out = camera_frame("navcam"), self._colour(n("rgb"), t, "navcam", rgb)
        if depth is None:
            return out
        b, want, opts, intr = self.b, self.wanted, self.opts, self.cam_intr
        mm = depth_mm(depth)
        if want(n("depth/image_raw")) and opts.images in ("raw", "both"):
            out.append((n("depth/image_raw"),
                        sensors.depth_image(b, t, frame, mm, opts.depth_encoding)))
        topic = n("depth/image_raw/compressedDepth")
        if want(topic) and opts.images in ("compressed", "both"):
            out.append((topic, b.compressed(t, frame, bi.compressed_depth_mm(
                mm, opts.depth_encoding, b.distro))))
        if want(n("depth/camera_info")):
            out.append((n("depth/camera_info"), sensors.camera_info(b, t, frame, intr, 0.0)))
        if want(n("depth/points")) and opts.depth_cloud:
            out.append((n("depth/points"), sensors.depth_cloud(
                b, t, frame, mm, intr, opts.cloud_stride_px)))
        return out

    def stereo(self, t: float, index: int, pair: Any) -> Pairs:
        """Both views of the rectified stereo pair, each with its camera info."""
        out: Pairs = []
        for side, img in zip(STEREO_SIDES, pair, strict=True):
            if self.stereo_intr.get(side) is not None:
                out += self._colour(self.names.topic(f"stereo/{side}"), t, side, img)
        return out

    def _colour(self, prefix: str, t: float, stream: str, img: Any) -> Pairs:
        b, want, opts = self.b, self.wanted, self.opts
        frame = camera_frame(stream)
        intr = self.cam_intr if stream == "navcam" else self.stereo_intr[stream]
        info = f"{prefix}/camera_info"
        out: Pairs = []
        if want(f"{prefix}/image_raw") and opts.images in ("raw", "both"):
            out.append((f"{prefix}/image_raw", sensors.colour_image(b, t, frame, img)))
        if want(f"{prefix}/image_raw/compressed") and opts.images in ("compressed", "both"):
            out.append((f"{prefix}/image_raw/compressed", b.compressed(
                t, frame, bi.compressed_image_array(img, opts.codec,
                                                    jpeg_quality=opts.jpeg_quality))))
        if want(info) and intr is not None:
            out.append((info, sensors.camera_info(b, t, frame, intr,
                                                  sensors.projection_tx(stream, intr))))
        return out
