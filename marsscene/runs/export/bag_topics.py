"""The bag's messages: which topics (rows of :mod:`.topic_table`), at which stamps, built from
which run-folder logs.

Each ``add_*`` queues ``(stamp, topic, builder, args)`` on a
:class:`marsscene.runs.export.bag_messages.MessageBuilder`; images and scans are read only when
the message is written. What goes into each message is composed by :mod:`.compose_state` and
:mod:`.compose_sensors`, which the live publisher (:mod:`.sample_messages`) calls too; this
module only says which logged samples go in. No ``rosbags`` import here (that stays in
:mod:`marsscene.runs.export.bag_messages`).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from marsscene.errors import RuntimeSimError
from marsscene.runs.export import bag_data as bd
from marsscene.runs.export import bag_images as bi
from marsscene.runs.export import compose_sensors as sensors
from marsscene.runs.export import compose_state as cs
from marsscene.runs.export import topic_table as tt
from marsscene.runs.export.frames import camera_frame, static_transforms
from marsscene.runs.export.imu_noise import rate_hz
from marsscene.runs.runlog import CameraStream, RunLog, read_image, read_ply

if TYPE_CHECKING:
    from marsscene.runs.export.bag_messages import MessageBuilder

__all__ = ["ImageOptions", "add_camera", "add_lidar", "add_state", "add_stereo"]


@dataclass(frozen=True)
class ImageOptions:
    """How camera images go into the bag.

    ``images``: ``"raw"`` (``sensor_msgs/Image``), ``"compressed"`` (image_transport's
    ``compressed`` / ``compressedDepth`` sub-topics) or ``"both"``; ``codec``: ``"png"`` or
    ``"jpeg"`` for colour and mono; ``depth_cloud``: write ``depth/points`` (stride
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
    """Clock, TF, the URDF, command, odometry, ground truth, joints, wheel--soil and IMU."""
    extra = {c.name: c.intrinsics for c in cams[1:]} if stereo else {}
    statics = static_transforms(run.rover, extra)
    t0 = float(run.gt.timestamps_s[0])
    n = bag.names.topic
    bag.register(tt.state_topics(bag.names, imu_true=run.imu_true is not None,
                                 soil=run.soil is not None))
    bag.add("/tf_static", t0, cs.tf_static, bag, t0, statics)
    bag.add(n("robot_description"), t0, cs.robot_description, bag, run.rover, statics)
    for t in run.imu[:, 0]:
        bag.add("/clock", t, bag.clock, t)
    f = cs.ControlFields(cs.ControlRows.of_run(run), run.rover, bd.noise_of_run(run.meta))
    for i, t in enumerate(f.t_s):
        bag.add("/tf", t, cs.tf, bag, f, i)
        bag.add(n("odom"), t, cs.odometry, bag, f, i)
        bag.add(n("GT_Trajectory"), t, cs.ground_truth, bag, f, i)
    for i, t in enumerate(f.t_s):
        bag.add(n("joint_states"), t, cs.joint_states, bag, f, i)
    if run.soil is not None:  # columns: t, slip (6), sinkage (6), load (6)
        for row in run.soil:
            bag.add(n(tt.WHEEL_SOIL), row[0], cs.wheel_soil, bag, row[0], row[7:13],
                    row[1:7], row[13:19])
    for row in run.cmd:
        bag.add(n("cmd_vel"), row[0], bag.twist, row[1], row[2])
    g_var, a_var = cs.imu_variances(run.meta.get("noise", {}), rate_hz(run.imu[:, 0]))
    for row in run.imu:
        bag.add(n("imu_noisy"), row[0], bag.imu, row[0], row[1:4], row[4:7], g_var, a_var)
    if run.imu_true is not None:
        for row in run.imu_true:
            bag.add(n("imu"), row[0], bag.imu, row[0], row[1:4], row[4:7], 0.0, 0.0)


def add_camera(bag: MessageBuilder, cam: CameraStream, opts: ImageOptions) -> None:
    """RGB, depth, camera infos and (``opts.depth_cloud``) the organised depth cloud."""
    frame, intr = camera_frame(cam.name), cam.intrinsics
    raw, packed = opts.images in ("raw", "both"), opts.images in ("compressed", "both")
    n = bag.names.topic
    bag.register(tt.camera_topics(bag.names, images=opts.images, depth=bool(cam.depth_files),
                                  depth_cloud=opts.depth_cloud))
    _add_colour(bag, cam, opts, n("rgb"))
    if not cam.depth_files:
        return
    encoding, depth_topic = opts.depth_encoding, n("depth/image_raw")
    # the image and the cloud share one PNG decode
    depth = _Shared(lambda i: read_image(cam.depth_files[i]), int(raw) + int(opts.depth_cloud))

    def image(i: int, t: float) -> Any:
        return sensors.depth_image(bag, t, frame, depth(i), encoding)

    def image_packed(i: int, t: float) -> Any:
        return bag.compressed(t, frame, bi.compressed_depth(cam.depth_files[i], encoding,
                                                            bag.distro))

    def cloud(i: int, t: float) -> Any:
        return sensors.depth_cloud(bag, t, frame, depth(i), intr, opts.cloud_stride_px)

    for i, t in enumerate(cam.stamps_s):
        if raw:
            bag.add(depth_topic, t, image, i, t)
        if packed:
            bag.add(depth_topic + "/compressedDepth", t, image_packed, i, t)
        bag.add(n("depth/camera_info"), t, sensors.camera_info, bag, t, frame, intr, 0.0)
        if opts.depth_cloud:
            bag.add(n("depth/points"), t, cloud, i, t)


def add_stereo(bag: MessageBuilder, cam: CameraStream, opts: ImageOptions) -> None:
    """One view of the stereo pair: its image(s) and camera info."""
    bag.register(tt.stereo_topics(cam.name, bag.names, images=opts.images))
    _add_colour(bag, cam, opts, bag.names.topic(f"stereo/{cam.name}"))


def _add_colour(bag: MessageBuilder, cam: CameraStream, opts: ImageOptions, prefix: str) -> None:
    """``PREFIX/image_raw`` and/or ``.../compressed`` and ``PREFIX/camera_info`` of each frame."""
    frame, intr = camera_frame(cam.name), cam.intrinsics
    tx = sensors.projection_tx(cam.name, intr)
    raw, packed = opts.images in ("raw", "both"), opts.images in ("compressed", "both")

    def build(i: int, t: float) -> Any:
        return sensors.colour_image(bag, t, frame, read_image(cam.rgb_files[i]))

    def build_packed(i: int, t: float) -> Any:  # the PNG's bytes, or its (cached) JPEG
        return bag.compressed(t, frame, bi.compressed_image(
            cam.rgb_files[i], opts.codec, jpeg_quality=opts.jpeg_quality,
            cached=opts.cached_jpeg(cam, i)))

    for i, t in enumerate(cam.stamps_s):
        if raw:
            bag.add(f"{prefix}/image_raw", t, build, i, t)
        if packed:
            bag.add(f"{prefix}/image_raw/compressed", t, build_packed, i, t)
        bag.add(f"{prefix}/camera_info", t, sensors.camera_info, bag, t, frame, intr, tx)


def add_lidar(
    bag: MessageBuilder, run: RunLog, stamps: np.ndarray, files: tuple[Path, ...]
) -> None:
    """The LiDAR's clouds and scans, one PLY read for both."""
    cfg = run.meta.get("lidar") or {}
    if "channels" not in cfg:
        raise RuntimeSimError(f"{run.path / 'run.json'} has no LiDAR configuration")
    bag.register(tt.lidar_topics(bag.names))
    load = _Shared(lambda i: read_ply(files[i]), 2)  # the cloud and the scan share one read

    def laser(i: int, t: float) -> Any:
        return sensors.laser_scan(bag, t, load(i), cfg)

    def cloud(i: int, t: float) -> Any:
        return sensors.lidar_cloud(bag, t, load(i))

    for i, t in enumerate(stamps):
        bag.add(bag.names.topic("lidar/points"), t, cloud, i, t)
        bag.add(bag.names.topic("scan"), t, laser, i, t)


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
