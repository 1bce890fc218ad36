"""The bag's messages: which topics (rows of :mod:`.topic_table`), at which stamps, built from
which run-folder logs.

Each ``add_*`` queues ``(stamp, topic, builder, args)`` on a
:class:`marsscene.runs.export.bag_messages.MessageBuilder`; images and scans are read only when
the message is written. No ``rosbags`` import here (that stays in
:mod:`marsscene.runs.export.bag_messages`).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy.spatial.transform import Rotation

from marsscene.errors import RuntimeSimError
from marsscene.rover.geometry import DRIVE_JOINTS, STEER_JOINTS
from marsscene.runs.export import bag_data as bd
from marsscene.runs.export import bag_images as bi
from marsscene.runs.export import topic_table as tt
from marsscene.runs.export.frames import camera_frame, rover_urdf, static_transforms
from marsscene.runs.export.imu_noise import imu_noise_declared
from marsscene.runs.runlog import CameraStream, RunLog, read_image, read_ply

if TYPE_CHECKING:
    from marsscene.runs.export.bag_messages import MessageBuilder

__all__ = ["ImageOptions", "add_camera", "add_lidar", "add_state", "add_stereo"]


@dataclass(frozen=True)
class ImageOptions:
    """How camera images go into the bag.

    ``images``: ``"raw"`` (``sensor_msgs/Image``), ``"compressed"`` (image_transport's
    ``compressed`` / ``compressedDepth`` sub-topics) or ``"both"``; ``codec``: ``"png"`` or
    ``"jpeg"`` for colour and mono; ``depth_cloud``: write ``/rover/depth/points`` (stride
    ``cloud_stride_px``).
    """

    images: str = "compressed"
    codec: str = "jpeg"
    jpeg_quality: int = bi.JPEG_QUALITY
    depth_encoding: str = "16UC1"
    depth_cloud: bool = False
    cloud_stride_px: int = 4
    jpeg_cache: bi.JpegCache | None = None

    def cached_jpeg(self, cam: CameraStream, i: int) -> Path | None:
        """Frame ``i``'s JPEG encoded while driving, if the options carry a cache."""
        if self.jpeg_cache is None or self.jpeg_cache.quality != self.jpeg_quality:
            return None
        return self.jpeg_cache.file(cam.name, cam.rgb_files[i].name)


def add_state(bag: MessageBuilder, run: RunLog, cams: list[CameraStream], stereo: bool) -> None:
    extra = {c.name: c.intrinsics for c in cams[1:]} if stereo else {}
    statics = static_transforms(run.rover, extra)
    t0 = float(run.gt.timestamps_s[0])
    bag.register(tt.state_topics(imu_true=run.imu_true is not None, soil=run.soil is not None))

    def tf_static() -> Any:
        return bag.tf_message([bag.tf(t0, s.parent, s.child, s.xyz_m, s.quat_xyzw)
                               for s in statics])

    bag.add("/tf_static", t0, tf_static)
    bag.add("/rover/robot_description", t0, bag.T["std_msgs/msg/String"],
            rover_urdf(run.rover, statics))
    for t in run.imu[:, 0]:
        bag.add("/clock", t, bag.clock, t)
    mo_xyz, mo_q = bd.map_to_odom(run.gt, run.odom)
    pos, vel, twist = bd.joint_states(run.wheels, run.rover)
    gt_lin, gt_ang = bd.body_twist_from_poses(run.gt)
    od, gt = run.odom, run.gt
    od_yaw = Rotation.from_quat(od.quat_xyzw).as_euler("xyz")[:, 2]
    pose_cov, twist_cov = bd.odometry_covariances(run.meta, run.wheels, twist, od.timestamps_s,
                                                  np.unwrap(od_yaw), run.rover)
    names = [*DRIVE_JOINTS, *STEER_JOINTS]

    def tf(i: int, t: float) -> Any:
        return bag.state_tf(t, (mo_xyz[i], mo_q[i]), (od.xyz_m[i], od.quat_xyzw[i]))

    def odom(i: int, t: float) -> Any:
        return bag.odometry(t, "odom", od.xyz_m[i], od.quat_xyzw[i], (twist[i, 0], 0, 0),
                            (0, 0, twist[i, 1]), pose_cov[i], twist_cov[i])

    def truth(i: int, t: float) -> Any:
        return bag.odometry(t, "map", gt.xyz_m[i], gt.quat_xyzw[i], gt_lin[i], gt_ang[i])

    for i, t in enumerate(od.timestamps_s):
        bag.add("/tf", t, tf, i, t)
        bag.add("/rover/odom", t, odom, i, t)
        bag.add("/rover/GT_Trajectory", t, truth, i, t)

    def joints(i: int, t: float) -> Any:
        return bag.joint_state(t, names, pos[i], vel[i])

    def cmd(row: np.ndarray) -> Any:
        return bag.twist(row[1], row[2])

    for i, t in enumerate(run.wheels[:, 0]):
        bag.add("/rover/joint_states", t, joints, i, t)
    if run.soil is not None:  # sinkage, slip and load as position, velocity and effort
        for row in run.soil:
            bag.add(tt.WHEEL_SOIL_TOPIC, row[0], bag.joint_state, row[0], list(DRIVE_JOINTS),
                    row[7:13], row[1:7], row[13:19])
    for row in run.cmd:
        bag.add("/rover/cmd_vel", row[0], cmd, row)
    # per-sample white-noise variance of the simulated profile: density^2 * rate (+ sigma^2)
    nd = imu_noise_declared(run)
    g_var = nd["gyroscope_noise_density"] ** 2 * nd["rate_hz"]
    a_var = nd["accelerometer_noise_density"] ** 2 * nd["rate_hz"]
    for row in run.imu:
        bag.add("/rover/imu_noisy", row[0], bag.imu, row[0], row[1:4], row[4:7], g_var, a_var)
    if run.imu_true is not None:
        for row in run.imu_true:
            bag.add("/rover/imu", row[0], bag.imu, row[0], row[1:4], row[4:7], 0.0, 0.0)


def add_camera(bag: MessageBuilder, cam: CameraStream, opts: ImageOptions) -> None:
    """RGB, depth, camera infos and (``opts.depth_cloud``) the organised depth cloud."""
    frame = camera_frame(cam.name)
    raw, packed = opts.images in ("raw", "both"), opts.images in ("compressed", "both")
    rgb_topic = "/rover/rgb/image_raw"
    bag.register(tt.camera_topics(images=opts.images, depth=bool(cam.depth_files),
                                   depth_cloud=opts.depth_cloud))

    def rgb(i: int, t: float) -> Any:
        return bag.image(t, frame, read_image(cam.rgb_files[i]), "rgb8")

    def rgb_packed(i: int, t: float) -> Any:
        return bag.compressed(t, frame, bi.compressed_image(cam.rgb_files[i], opts.codec,
                                                            jpeg_quality=opts.jpeg_quality,
                                                            cached=opts.cached_jpeg(cam, i)))

    for i, t in enumerate(cam.stamps_s):
        if raw:
            bag.add(rgb_topic, t, rgb, i, t)
        if packed:
            bag.add(rgb_topic + "/compressed", t, rgb_packed, i, t)
        bag.add("/rover/rgb/camera_info", t, bag.camera_info, t, frame, cam, 0.0)
    if not cam.depth_files:
        return
    encoding, depth_topic = opts.depth_encoding, "/rover/depth/image_raw"
    dtype = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4")])
    # the image and the cloud share one PNG decode
    depth = _Shared(lambda i: read_image(cam.depth_files[i]), int(raw) + int(opts.depth_cloud))

    def image(i: int, t: float) -> Any:
        mm = depth(i)
        arr = bd.depth_m(mm) if encoding == "32FC1" else mm.astype("<u2")
        return bag.image(t, frame, arr, encoding)

    def image_packed(i: int, t: float) -> Any:
        return bag.compressed(t, frame, bi.compressed_depth(cam.depth_files[i], encoding,
                                                            bag.distro))

    def cloud(i: int, t: float) -> Any:
        pts = bd.depth_points(depth(i), cam.k, opts.cloud_stride_px)
        return bag.cloud(t, frame, np.ascontiguousarray(pts).view(dtype)[..., 0], pts.shape[:2])

    for i, t in enumerate(cam.stamps_s):
        if raw:
            bag.add(depth_topic, t, image, i, t)
        if packed:
            bag.add(depth_topic + "/compressedDepth", t, image_packed, i, t)
        bag.add("/rover/depth/camera_info", t, bag.camera_info, t, frame, cam, 0.0)
        if opts.depth_cloud:
            bag.add("/rover/depth/points", t, cloud, i, t)


def add_stereo(bag: MessageBuilder, cam: CameraStream, opts: ImageOptions) -> None:
    frame = camera_frame(cam.name)
    base = cam.intrinsics.get("baseline_m", cam.intrinsics.get("stereo_baseline_m", 0.0))
    tx = -float(cam.k[0, 0]) * float(base) if cam.name == "right" else 0.0  # ROS P[0,3]
    img, info = f"/rover/stereo/{cam.name}/image_raw", f"/rover/stereo/{cam.name}/camera_info"
    raw, packed = opts.images in ("raw", "both"), opts.images in ("compressed", "both")
    bag.register(tt.stereo_topics(cam.name, images=opts.images))

    def build(i: int, t: float) -> Any:
        arr = read_image(cam.rgb_files[i])
        return bag.image(t, frame, arr, "rgb8" if arr.ndim == 3 else "mono8")

    def build_packed(i: int, t: float) -> Any:
        return bag.compressed(t, frame, bi.compressed_image(cam.rgb_files[i], opts.codec,
                                                            jpeg_quality=opts.jpeg_quality,
                                                            cached=opts.cached_jpeg(cam, i)))

    for i, t in enumerate(cam.stamps_s):
        if raw:
            bag.add(img, t, build, i, t)
        if packed:
            bag.add(img + "/compressed", t, build_packed, i, t)
        bag.add(info, t, bag.camera_info, t, frame, cam, tx)


def add_lidar(
    bag: MessageBuilder, run: RunLog, stamps: np.ndarray, files: tuple[Path, ...]
) -> None:
    cfg = run.meta.get("lidar") or {}
    if "channels" not in cfg:
        raise RuntimeSimError(f"{run.path / 'run.json'} has no LiDAR configuration")
    bag.register(tt.lidar_topics())
    period = 1.0 / float(cfg.get("rate_hz", 10.0))
    load = _Shared(lambda i: read_ply(files[i]), 2)  # the cloud and the scan share one read

    def laser(i: int, t: float) -> Any:
        return bag.laser_scan(t, bd.laser_scan(load(i), cfg), period,
                              int(cfg["horizontal_samples"]))

    def cloud(i: int, t: float) -> Any:
        rec = load(i)
        return bag.cloud(t, "lidar_link", rec, (1, len(rec)))

    for i, t in enumerate(stamps):
        bag.add("/rover/lidar/points", t, cloud, i, t)
        bag.add("/rover/scan", t, laser, i, t)


class _Shared:
    """``load(i)`` once for the ``uses`` messages built from item ``i``, then forgotten.

    Messages are built on several threads (:meth:`MessageBuilder.write`), so the first caller
    of an index loads it under that index's lock and the others wait for it; the item is
    dropped when its last user took it, so nothing accumulates over a long run.
    """

    def __init__(self, load: Any, uses: int) -> None:
        self.load, self.uses = load, uses
        self.lock = threading.Lock()
        self.slots: dict[int, list[Any]] = {}  # i -> [lock, value, times taken]

    def __call__(self, i: int) -> Any:
        if self.uses < 2:
            return self.load(i)
        with self.lock:
            slot = self.slots.setdefault(i, [threading.Lock(), None, 0])
        with slot[0]:
            if slot[2] == 0:
                slot[1] = self.load(i)
            slot[2] += 1
            value = slot[1]
            if slot[2] >= self.uses:
                with self.lock:
                    del self.slots[i]
        return value
