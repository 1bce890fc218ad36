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

from marsscene._atomic import replacing_dir
from marsscene.errors import ExportError, RuntimeSimError, missing_dependency
from marsscene.runtime import bag_topics as bt
from marsscene.runtime.runlog import CameraStream, RunLog

__all__ = ["BagSummary", "MessageBuilder", "write_bag"]

STORAGES = ("mcap", "sqlite3")
DEPTH_ENCODINGS = ("32FC1", "16UC1")
SENSORS = ("camera", "stereo", "lidar")


@dataclass
class BagSummary:
    """What :func:`write_bag` wrote: the bag folder, message counts per topic, bytes on disk."""

    path: Path
    counts: dict[str, int] = field(default_factory=dict)
    size_bytes: int = 0


class MessageBuilder:
    """ROS 2 Jazzy message builders on one ``rosbags`` typestore, and the queue of messages.

    ``topic`` registers a topic (in write order for equal stamps), ``add`` queues a message,
    ``write`` builds, serialises (CDR) and writes them in stamp order.
    """

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
    bag = MessageBuilder()
    bt.add_state(bag, run, cams, "stereo" in wanted)
    if "camera" in wanted:
        bt.add_camera(bag, cams[0], depth_encoding, cloud_stride_px)
    if "stereo" in wanted:
        for cam in cams[1:]:
            bt.add_stereo(bag, cam)
    if "lidar" in wanted and lidar is not None:
        bt.add_lidar(bag, run, *lidar)
    with replacing_dir(final, overwrite=overwrite, create=False) as tmp:
        counts = bag.write(tmp, storage, progress)
    size = sum(p.stat().st_size for p in final.rglob("*") if p.is_file())
    return BagSummary(final, counts, size)
