"""ROS 2 bags from a run folder, with no ROS installation (the only importer of ``rosbags``).

Messages are built from ROS 2 Jazzy message classes of a ``rosbags`` typestore, serialised to
CDR by ``rosbags`` and written by ``rosbags.rosbag2.Writer`` (MCAP storage by default, sqlite3
as an alternative). Topics, frames and units: ``docs/ros.md``.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Collection
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from marsscene.errors import ExportError, RuntimeSimError, missing_dependency
from marsscene.runtime import bag_data as bd
from marsscene.runtime.frames import camera_frame, rover_urdf, static_transforms
from marsscene.runtime.rover import DRIVE_JOINTS, STEER_JOINTS
from marsscene.runtime.runlog import CameraStream, RunLog, read_image, read_ply, replace_dir

__all__ = ["BagSummary", "write_bag"]

STORAGES = ("mcap", "sqlite3")
DEPTH_ENCODINGS = ("32FC1", "16UC1")
SENSORS = ("camera", "stereo", "lidar")


@dataclass
class BagSummary:
    """What :func:`write_bag` wrote: the bag folder, message counts per topic, bytes on disk."""

    path: Path
    counts: dict[str, int] = field(default_factory=dict)
    size_bytes: int = 0


class _Bag:
    """Message builders on one typestore; ``add`` queues (stamp, topic, builder)."""

    def __init__(self) -> None:
        try:
            from rosbags.typesys import Stores, get_typestore
        except ImportError:  # pragma: no cover - exercised without the extra only
            raise missing_dependency("rosbags", "ros") from None
        self.store = get_typestore(Stores.ROS2_JAZZY)
        self.T: Any = self.store.types
        self.topics: dict[str, tuple[str, bool]] = {}  # topic -> (msgtype, latched)
        self.events: list[tuple[int, int, int, Callable[..., Any], tuple[Any, ...]]] = []

    def topic(self, name: str, msgtype: str, *, latched: bool = False) -> None:
        self.topics[name] = (msgtype, latched)

    def add(self, topic: str, t_s: float, build: Callable[..., Any], *args: Any) -> None:
        """Queue a message: ``build(*args)`` is called when it is written (images load late)."""
        order = list(self.topics).index(topic)
        self.events.append((round(float(t_s) * 1e9), order, len(self.events), build, args))

    def header(self, t_s: float, frame: str) -> Any:
        ns = round(t_s * 1e9)
        return self.T["std_msgs/msg/Header"](
            stamp=self.T["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9),
            frame_id=frame,
        )

    def vec(self, v: Any) -> Any:
        return self.T["geometry_msgs/msg/Vector3"](x=float(v[0]), y=float(v[1]), z=float(v[2]))

    def quat(self, q: Any) -> Any:
        return self.T["geometry_msgs/msg/Quaternion"](
            x=float(q[0]), y=float(q[1]), z=float(q[2]), w=float(q[3])
        )

    def tf(self, t_s: float, parent: str, child: str, xyz: Any, q: Any) -> Any:
        tr = self.T["geometry_msgs/msg/Transform"](translation=self.vec(xyz), rotation=self.quat(q))
        return self.T["geometry_msgs/msg/TransformStamped"](
            header=self.header(t_s, parent), child_frame_id=child, transform=tr
        )

    def odometry(self, t_s: float, parent: str, xyz: Any, q: Any, lin: Any, ang: Any) -> Any:
        point = self.T["geometry_msgs/msg/Point"](x=float(xyz[0]), y=float(xyz[1]),
                                                 z=float(xyz[2]))
        pose = self.T["geometry_msgs/msg/Pose"](position=point, orientation=self.quat(q))
        twist = self.T["geometry_msgs/msg/Twist"](linear=self.vec(lin), angular=self.vec(ang))
        return self.T["nav_msgs/msg/Odometry"](
            header=self.header(t_s, parent), child_frame_id="base_link",
            pose=self.T["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=np.zeros(36)),
            twist=self.T["geometry_msgs/msg/TwistWithCovariance"](twist=twist,
                                                                  covariance=np.zeros(36)),
        )

    def imu(self, t_s: float, row: Any, gyro_var: float, accel_var: float) -> Any:
        cov_o = np.zeros(9)
        cov_o[0] = -1.0  # REP-145: no orientation estimate
        return self.T["sensor_msgs/msg/Imu"](
            header=self.header(t_s, "imu_link"), orientation=self.quat((0, 0, 0, 1)),
            orientation_covariance=cov_o, angular_velocity=self.vec(row[4:7]),
            angular_velocity_covariance=np.diag([gyro_var] * 3).ravel(),
            linear_acceleration=self.vec(row[1:4]),
            linear_acceleration_covariance=np.diag([accel_var] * 3).ravel(),
        )

    def image(self, t_s: float, frame: str, arr: np.ndarray, encoding: str) -> Any:
        h, w = arr.shape[:2]
        data = np.ascontiguousarray(arr).view(np.uint8).reshape(-1)
        return self.T["sensor_msgs/msg/Image"](
            header=self.header(t_s, frame), height=h, width=w, encoding=encoding,
            is_bigendian=0, step=len(data) // h, data=data,
        )

    def camera_info(self, t_s: float, frame: str, cam: CameraStream, tx: float) -> Any:
        k = cam.k
        p = np.hstack([k, [[tx], [0.0], [0.0]]])
        roi = self.T["sensor_msgs/msg/RegionOfInterest"](
            x_offset=0, y_offset=0, height=0, width=0, do_rectify=False
        )
        return self.T["sensor_msgs/msg/CameraInfo"](
            header=self.header(t_s, frame), height=int(cam.intrinsics["height"]),
            width=int(cam.intrinsics["width"]), distortion_model="plumb_bob", d=np.zeros(5),
            k=k.ravel(), r=np.eye(3).ravel(), p=p.ravel(), binning_x=0, binning_y=0, roi=roi,
        )

    def cloud(self, t_s: float, frame: str, rec: np.ndarray, shape: tuple[int, int]) -> Any:
        pf = self.T["sensor_msgs/msg/PointField"]
        fields, off = [], 0
        for name in rec.dtype.names or ():
            sub = rec.dtype.fields[name][0]  # type: ignore[index]
            kind = pf.UINT16 if sub == np.dtype("<u2") else pf.FLOAT32
            fields.append(pf(name=name, offset=off, datatype=kind, count=1))
            off += sub.itemsize
        data = np.ascontiguousarray(rec).view(np.uint8).reshape(-1)
        return self.T["sensor_msgs/msg/PointCloud2"](
            header=self.header(t_s, frame), height=shape[0], width=shape[1], fields=fields,
            is_bigendian=False, point_step=rec.dtype.itemsize,
            row_step=rec.dtype.itemsize * shape[1], data=data, is_dense=False,
        )

    def write(self, path: Path, storage: str, progress: Callable[[int, int], None] | None
              ) -> dict[str, int]:
        from rosbags.interfaces import (
            Qos,
            QosDurability,
            QosHistory,
            QosLiveliness,
            QosReliability,
            QosTime,
        )
        from rosbags.rosbag2 import StoragePlugin, Writer

        forever = QosTime(sec=2147483647, nsec=4294967295)
        latched = Qos(QosHistory.KEEP_LAST, 1, QosReliability.RELIABLE,
                      QosDurability.TRANSIENT_LOCAL, forever, forever, QosLiveliness.AUTOMATIC,
                      forever, False)
        plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
        counts = dict.fromkeys(self.topics, 0)
        names = list(self.topics)
        self.events.sort(key=lambda e: e[:3])
        with Writer(path, version=9, storage_plugin=plugin) as w:
            conns = [
                w.add_connection(name, mt, typestore=self.store,
                                 offered_qos_profiles=[latched] if lat else [])
                for name, (mt, lat) in self.topics.items()
            ]
            for i, (ns, order, _, build, args) in enumerate(self.events):
                msg = build(*args)
                w.write(conns[order], ns, self.store.serialize_cdr(msg, msg.__msgtype__))
                counts[names[order]] += 1
                if progress is not None and (i % 200 == 0 or i == len(self.events) - 1):
                    progress(i + 1, len(self.events))
        return counts


def write_bag(
    run_dir: str | os.PathLike[str],
    out_dir: str | os.PathLike[str] | None = None,
    *,
    storage: str = "mcap",
    overwrite: bool = False,
    sensors: Collection[str] | None = None,
    depth_encoding: str = "32FC1",
    cloud_stride_px: int = 4,
    progress: Callable[[int, int], None] | None = None,
) -> BagSummary:
    """Write a run folder as a rosbag2 folder (``metadata.yaml`` + MCAP or sqlite3 storage).

    Parameters
    ----------
    run_dir : path
        A run folder of :func:`marsscene.runtime.driver.drive`.
    out_dir : path, optional
        Bag folder (default ``RUN_DIR/bag``); written to a temporary folder and renamed.
    storage : {"mcap", "sqlite3"}
    overwrite : bool
        Replace an existing bag folder (else :class:`~marsscene.errors.ExportError`).
    sensors : collection of {"camera", "stereo", "lidar"}, optional
        Sensor topics to write; each one named must be in the run (else
        :class:`~marsscene.errors.RuntimeSimError`). Default: every sensor the run has.
    depth_encoding : {"32FC1", "16UC1"}
        ``/rover/depth/image_raw`` in metres (NaN = no return) or millimetres (0 = no return).
    cloud_stride_px : int
        Pixel stride of the organised ``/rover/depth/points`` cloud (1 = every pixel).
    progress : callable, optional
        ``progress(messages_done, messages_total)``.
    """
    if storage not in STORAGES:
        raise ExportError(f"storage = {storage!r}; expected one of {', '.join(STORAGES)}")
    if depth_encoding not in DEPTH_ENCODINGS:
        raise ExportError(f"depth_encoding = {depth_encoding!r}; expected 32FC1 or 16UC1")
    if cloud_stride_px < 1:
        raise ExportError(f"cloud_stride_px = {cloud_stride_px}; expected >= 1")
    unknown = set(sensors or ()) - set(SENSORS)
    if unknown:
        raise ExportError(f"unknown sensor(s) {sorted(unknown)}; expected {', '.join(SENSORS)}")
    run = RunLog(run_dir)
    final = Path(out_dir) if out_dir is not None else run.path / "bag"
    cams = run.camera_streams()
    lidar = run.lidar
    have = {"camera": bool(cams), "stereo": len(cams) > 1, "lidar": lidar is not None}
    wanted = set(sensors) if sensors is not None else {s for s, ok in have.items() if ok}
    for s in sorted(wanted):
        if not have[s]:
            raise RuntimeSimError(f"{run.path} has no {s} logs; drive with --{s} to get "
                                  f"{s} topics" if s != "stereo" else
                                  f"{run.path} has no stereo camera folders (camera/left, "
                                  "camera/right)")
    bag = _Bag()
    _add_state(bag, run, cams, "stereo" in wanted)
    if "camera" in wanted:
        _add_camera(bag, cams[0], depth_encoding, cloud_stride_px)
    if "stereo" in wanted:
        for cam in cams[1:]:
            _add_stereo(bag, cam)
    if "lidar" in wanted and lidar is not None:
        _add_lidar(bag, run, *lidar)
    with replace_dir(final, overwrite=overwrite) as tmp:
        counts = bag.write(tmp, storage, progress)
    size = sum(p.stat().st_size for p in final.rglob("*") if p.is_file())
    return BagSummary(final, counts, size)


def _add_state(bag: _Bag, run: RunLog, cams: list[CameraStream], stereo: bool) -> None:
    extra = {c.name: c.intrinsics for c in cams[1:]} if stereo else {}
    statics = static_transforms(run.rover, extra)
    t0 = float(run.gt.timestamps_s[0])
    for name, mt in (("/clock", "rosgraph_msgs/msg/Clock"), ("/tf", "tf2_msgs/msg/TFMessage")):
        bag.topic(name, mt)
    bag.topic("/tf_static", "tf2_msgs/msg/TFMessage", latched=True)
    bag.topic("/rover/robot_description", "std_msgs/msg/String", latched=True)
    for name, mt in (("/rover/cmd_vel", "geometry_msgs/msg/Twist"),
                     ("/rover/odom", "nav_msgs/msg/Odometry"),
                     ("/rover/GT_Trajectory", "nav_msgs/msg/Odometry"),
                     ("/rover/joint_states", "sensor_msgs/msg/JointState"),
                     ("/rover/imu_noisy", "sensor_msgs/msg/Imu")):
        bag.topic(name, mt)
    tfm = bag.T["tf2_msgs/msg/TFMessage"]

    def tf_static() -> Any:
        return tfm(transforms=[bag.tf(t0, s.parent, s.child, s.xyz_m, s.quat_xyzw)
                               for s in statics])

    bag.add("/tf_static", t0, tf_static)
    bag.add("/rover/robot_description", t0, bag.T["std_msgs/msg/String"],
            rover_urdf(run.rover, statics))
    clock = bag.T["rosgraph_msgs/msg/Clock"]
    for t in run.imu[:, 0]:
        bag.add("/clock", t, lambda t: clock(clock=bag.header(t, "").stamp), t)
    mo_xyz, mo_q = bd.map_to_odom(run.gt, run.odom)
    pos, vel, twist = bd.joint_states(run.wheels, run.rover)
    gt_lin, gt_ang = bd.body_twist_from_poses(run.gt)
    od, gt = run.odom, run.gt
    names = [*DRIVE_JOINTS, *STEER_JOINTS]
    js = bag.T["sensor_msgs/msg/JointState"]
    tw = bag.T["geometry_msgs/msg/Twist"]

    def tf(i: int, t: float) -> Any:
        return tfm(transforms=[bag.tf(t, "map", "odom", mo_xyz[i], mo_q[i]),
                               bag.tf(t, "odom", "base_link", od.xyz_m[i], od.quat_xyzw[i])])

    def odom(i: int, t: float) -> Any:
        return bag.odometry(t, "odom", od.xyz_m[i], od.quat_xyzw[i], (twist[i, 0], 0, 0),
                            (0, 0, twist[i, 1]))

    def truth(i: int, t: float) -> Any:
        return bag.odometry(t, "map", gt.xyz_m[i], gt.quat_xyzw[i], gt_lin[i], gt_ang[i])

    for i, t in enumerate(od.timestamps_s):
        bag.add("/tf", t, tf, i, t)
        bag.add("/rover/odom", t, odom, i, t)
        bag.add("/rover/GT_Trajectory", t, truth, i, t)

    def joints(i: int, t: float) -> Any:
        return js(header=bag.header(t, "base_link"), name=names, position=pos[i],
                  velocity=vel[i], effort=np.zeros(0))

    def cmd(row: np.ndarray) -> Any:
        return tw(linear=bag.vec((row[1], 0, 0)), angular=bag.vec((0, 0, row[2])))

    for i, t in enumerate(run.wheels[:, 0]):
        bag.add("/rover/joint_states", t, joints, i, t)
    for row in run.cmd:
        bag.add("/rover/cmd_vel", row[0], cmd, row)
    noise = run.meta.get("noise", {})
    g_var = float(noise.get("gyro_sigma_rad_s", 0.0)) ** 2
    a_var = float(noise.get("accel_sigma_m_s2", 0.0)) ** 2
    for row in run.imu:
        bag.add("/rover/imu_noisy", row[0], bag.imu, row[0], row, g_var, a_var)
    if run.imu_true is not None:
        bag.topic("/rover/imu", "sensor_msgs/msg/Imu")
        for row in run.imu_true:
            bag.add("/rover/imu", row[0], bag.imu, row[0], row, 0.0, 0.0)


def _add_camera(bag: _Bag, cam: CameraStream, encoding: str, stride: int) -> None:
    frame = camera_frame(cam.name)
    bag.topic("/rover/rgb/image_raw", "sensor_msgs/msg/Image")
    bag.topic("/rover/rgb/camera_info", "sensor_msgs/msg/CameraInfo")

    def rgb(i: int, t: float) -> Any:
        return bag.image(t, frame, read_image(cam.rgb_files[i]), "rgb8")

    for i, t in enumerate(cam.stamps_s):
        bag.add("/rover/rgb/image_raw", t, rgb, i, t)
        bag.add("/rover/rgb/camera_info", t, bag.camera_info, t, frame, cam, 0.0)
    if not cam.depth_files:
        return
    bag.topic("/rover/depth/image_raw", "sensor_msgs/msg/Image")
    bag.topic("/rover/depth/camera_info", "sensor_msgs/msg/CameraInfo")
    bag.topic("/rover/depth/points", "sensor_msgs/msg/PointCloud2")
    dtype = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4")])
    cache: dict[int, np.ndarray] = {}

    def depth(i: int) -> np.ndarray:  # the image and the cloud share one PNG decode
        return cache.pop(i) if i in cache else cache.setdefault(i, read_image(cam.depth_files[i]))

    def image(i: int, t: float) -> Any:
        mm = depth(i)
        arr = bd.depth_m(mm) if encoding == "32FC1" else mm.astype("<u2")
        return bag.image(t, frame, arr, encoding)

    def cloud(i: int, t: float) -> Any:
        pts = bd.depth_points(depth(i), cam.k, stride)
        return bag.cloud(t, frame, np.ascontiguousarray(pts).view(dtype)[..., 0], pts.shape[:2])

    for i, t in enumerate(cam.stamps_s):
        bag.add("/rover/depth/image_raw", t, image, i, t)
        bag.add("/rover/depth/camera_info", t, bag.camera_info, t, frame, cam, 0.0)
        bag.add("/rover/depth/points", t, cloud, i, t)


def _add_stereo(bag: _Bag, cam: CameraStream) -> None:
    frame = camera_frame(cam.name)
    base = cam.intrinsics.get("baseline_m", cam.intrinsics.get("stereo_baseline_m", 0.0))
    tx = -float(cam.k[0, 0]) * float(base) if cam.name == "right" else 0.0  # ROS P[0,3]
    img, info = f"/rover/stereo/{cam.name}/image_raw", f"/rover/stereo/{cam.name}/camera_info"
    bag.topic(img, "sensor_msgs/msg/Image")
    bag.topic(info, "sensor_msgs/msg/CameraInfo")

    def build(i: int, t: float) -> Any:
        arr = read_image(cam.rgb_files[i])
        return bag.image(t, frame, arr, "rgb8" if arr.ndim == 3 else "mono8")

    for i, t in enumerate(cam.stamps_s):
        bag.add(img, t, build, i, t)
        bag.add(info, t, bag.camera_info, t, frame, cam, tx)


def _add_lidar(bag: _Bag, run: RunLog, stamps: np.ndarray, files: tuple[Path, ...]) -> None:
    cfg = run.meta.get("lidar") or {}
    bag.topic("/rover/lidar/points", "sensor_msgs/msg/PointCloud2")
    bag.topic("/rover/scan", "sensor_msgs/msg/LaserScan")
    scan_t = bag.T["sensor_msgs/msg/LaserScan"]
    period = 1.0 / float(cfg.get("rate_hz", 10.0))
    cache: dict[int, np.ndarray] = {}

    def load(i: int) -> np.ndarray:  # the cloud and the scan share one file read
        return cache.pop(i) if i in cache else cache.setdefault(i, read_ply(files[i]))

    def laser(i: int, t: float) -> Any:
        s = bd.laser_scan(load(i), cfg)
        return scan_t(header=bag.header(t, "lidar_link"), time_increment=0.0, scan_time=period,
                      **{k: v for k, v in s.items() if k not in ("ring", "elevation_deg")})

    def cloud(i: int, t: float) -> Any:
        rec = load(i)
        return bag.cloud(t, "lidar_link", rec, (1, len(rec)))

    for i, t in enumerate(stamps):
        bag.add("/rover/lidar/points", t, cloud, i, t)
        bag.add("/rover/scan", t, laser, i, t)
