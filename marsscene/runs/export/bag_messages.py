"""ROS 2 message builders on one ``rosbags`` typestore and the time-ordered queue of a bag's
messages (the only module that touches ``rosbags`` types; :mod:`.bag` writes the bag).

Each builder makes one message from the fields it is given; what goes into each topic is
composed by :mod:`.compose_state` and :mod:`.compose_sensors`, which the bag (:mod:`.bag_topics`)
and the live publisher (:mod:`.sample_messages`) both call, and :meth:`MessageBuilder.serialize`
gives the CDR bytes that both the bag and the DDS wire carry."""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

import numpy as np

from marsscene._threads import ordered_map
from marsscene.errors import missing_dependency
from marsscene.runs.export.topic_table import QOS_PROFILES, ROVER, RosNames, Topic

__all__ = ["MessageBuilder"]


class MessageBuilder:
    """ROS 2 message builders on one ``rosbags`` typestore (Jazzy or Humble), and the queue.

    ``register`` adds topics (:mod:`.topic_table` rows; in write order for equal stamps),
    ``add`` queues a message, ``write`` builds, serialises (CDR) and writes them in stamp order.
    Every frame id a message carries is the robot's (``names.frame``: ``base_link`` is
    ``scout1/base_link`` for robot ``scout1`` of a team); the composers name bare frames.
    """

    def __init__(self, distro: str = "jazzy", names: RosNames = ROVER) -> None:
        try:
            from rosbags.typesys import Stores, get_typestore
        except ImportError:  # pragma: no cover - exercised without the extra only
            raise missing_dependency("rosbags", "ros") from None
        self.store = get_typestore(Stores.ROS2_HUMBLE if distro == "humble" else Stores.ROS2_JAZZY)
        self.distro, self.names = distro, names
        self._frame = names.frame if names.frame_prefix else str  # the rover's frames: as named
        self.T: Any = self.store.types
        self.topics: dict[str, Topic] = {}
        self.events: list[tuple[int, int, int, Callable[..., Any], tuple[Any, ...]]] = []

    def register(self, topics: Iterable[Topic]) -> None:
        """Add ``topics`` after those registered so far."""
        for topic in topics:
            self.topics[topic.name] = topic

    def add(self, topic: str, t_s: float, build: Callable[..., Any], *args: Any) -> None:
        """Queue a message: ``build(*args)`` is called when it is written (images load late)."""
        order = list(self.topics).index(topic)
        self.events.append((round(float(t_s) * 1e9), order, len(self.events), build, args))

    def serialize(self, msg: Any) -> bytes | memoryview:
        """CDR bytes of ``msg`` (little-endian, with the 4-byte encapsulation header)."""
        return self.store.serialize_cdr(msg, msg.__msgtype__)

    def stamp(self, t_s: float) -> Any:
        ns = round(t_s * 1e9)
        return self.T["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)

    def header(self, t_s: float, frame: str) -> Any:
        ns = round(t_s * 1e9)
        return self.T["std_msgs/msg/Header"](
            stamp=self.T["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9),
            frame_id=self._frame(frame),
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
            header=self.header(t_s, parent), child_frame_id=self._frame(child), transform=tr
        )

    def odometry(self, t_s: float, parent: str, xyz: Any, q: Any, lin: Any, ang: Any,
                 pose_cov: Any = None, twist_cov: Any = None) -> Any:
        """``nav_msgs/Odometry``; covariances default to zero (ground truth)."""
        point = self.T["geometry_msgs/msg/Point"](x=float(xyz[0]), y=float(xyz[1]),
                                                 z=float(xyz[2]))
        pose = self.T["geometry_msgs/msg/Pose"](position=point, orientation=self.quat(q))
        twist = self.T["geometry_msgs/msg/Twist"](linear=self.vec(lin), angular=self.vec(ang))
        return self.T["nav_msgs/msg/Odometry"](
            header=self.header(t_s, parent), child_frame_id=self._frame("base_link"),
            pose=self.T["geometry_msgs/msg/PoseWithCovariance"](
                pose=pose, covariance=np.zeros(36) if pose_cov is None else pose_cov),
            twist=self.T["geometry_msgs/msg/TwistWithCovariance"](
                twist=twist, covariance=np.zeros(36) if twist_cov is None else twist_cov),
        )

    def clock(self, t_s: float) -> Any:
        """``rosgraph_msgs/Clock`` at ``t_s``."""
        return self.T["rosgraph_msgs/msg/Clock"](clock=self.stamp(t_s))

    def tf_message(self, transforms: list[Any]) -> Any:
        return self.T["tf2_msgs/msg/TFMessage"](transforms=transforms)

    def state_tf(self, t_s: float, map_odom: tuple[Any, Any], odom_base: tuple[Any, Any]) -> Any:
        """``/tf``: ``map -> odom`` and ``odom -> base_link``, each ``(xyz_m, quat_xyzw)``."""
        return self.tf_message([self.tf(t_s, "map", "odom", *map_odom),
                                self.tf(t_s, "odom", "base_link", *odom_base)])

    def twist(self, v_m_s: float, omega_rad_s: float) -> Any:
        """``geometry_msgs/Twist`` of a ``cmd_vel`` ``(v, omega)``."""
        return self.T["geometry_msgs/msg/Twist"](linear=self.vec((v_m_s, 0, 0)),
                                                 angular=self.vec((0, 0, omega_rad_s)))

    def joint_state(self, t_s: float, names: list[str], position: Any, velocity: Any,
                    effort: Any = None) -> Any:
        return self.T["sensor_msgs/msg/JointState"](
            header=self.header(t_s, "base_link"), name=names,
            position=np.asarray(position, np.float64), velocity=np.asarray(velocity, np.float64),
            effort=np.zeros(0) if effort is None else np.asarray(effort, np.float64))

    def imu(self, t_s: float, accel_m_s2: Any, gyro_rad_s: Any, gyro_var: float,
            accel_var: float) -> Any:
        """``sensor_msgs/Imu`` (no orientation, REP-145) with diagonal noise variances."""
        cov_o = np.zeros(9)
        cov_o[0] = -1.0  # REP-145: no orientation estimate
        return self.T["sensor_msgs/msg/Imu"](
            header=self.header(t_s, "imu_link"), orientation=self.quat((0, 0, 0, 1)),
            orientation_covariance=cov_o, angular_velocity=self.vec(gyro_rad_s),
            angular_velocity_covariance=np.diag([gyro_var] * 3).ravel(),
            linear_acceleration=self.vec(accel_m_s2),
            linear_acceleration_covariance=np.diag([accel_var] * 3).ravel(),
        )

    def image(self, t_s: float, frame: str, arr: np.ndarray, encoding: str) -> Any:
        h, w = arr.shape[:2]
        data = np.ascontiguousarray(arr).view(np.uint8).reshape(-1)
        return self.T["sensor_msgs/msg/Image"](
            header=self.header(t_s, frame), height=h, width=w, encoding=encoding,
            is_bigendian=0, step=len(data) // h, data=data,
        )

    def compressed(self, t_s: float, frame: str, fmt_data: tuple[str, bytes]) -> Any:
        """``sensor_msgs/CompressedImage`` from a ``(format, data)`` pair (:mod:`.bag_images`)."""
        return self.T["sensor_msgs/msg/CompressedImage"](
            header=self.header(t_s, frame), format=fmt_data[0],
            data=np.frombuffer(fmt_data[1], dtype=np.uint8),
        )

    def camera_info_k(self, t_s: float, frame: str, k: Any, width: int, height: int,
                      tx: float) -> Any:
        """``sensor_msgs/CameraInfo``: plumb_bob, no distortion, ``P = [K | (tx, 0, 0)]``."""
        p = np.hstack([k, [[tx], [0.0], [0.0]]])
        roi = self.T["sensor_msgs/msg/RegionOfInterest"](
            x_offset=0, y_offset=0, height=0, width=0, do_rectify=False
        )
        return self.T["sensor_msgs/msg/CameraInfo"](
            header=self.header(t_s, frame), height=height,
            width=width, distortion_model="plumb_bob", d=np.zeros(5),
            k=k.ravel(), r=np.eye(3).ravel(), p=p.ravel(), binning_x=0, binning_y=0, roi=roi,
        )

    def cloud(self, t_s: float, frame: str, rec: np.ndarray, shape: tuple[int, int]) -> Any:
        pf = self.T["sensor_msgs/msg/PointField"]
        kinds = {np.dtype("<f4"): pf.FLOAT32, np.dtype("<u4"): pf.UINT32,
                 np.dtype("<u2"): pf.UINT16, np.dtype("u1"): pf.UINT8}
        fields = []
        for name in rec.dtype.names or ():
            sub, off = rec.dtype.fields[name][:2]  # type: ignore[index]
            fields.append(pf(name=name, offset=off, datatype=kinds[sub], count=1))
        data = np.ascontiguousarray(rec).view(np.uint8).reshape(-1)
        return self.T["sensor_msgs/msg/PointCloud2"](
            header=self.header(t_s, frame), height=shape[0], width=shape[1], fields=fields,
            is_bigendian=False, point_step=rec.dtype.itemsize,
            row_step=rec.dtype.itemsize * shape[1], data=data, is_dense=False,
        )

    def laser_scan(self, t_s: float, scan: dict[str, Any], period_s: float,
                   horizontal_samples: int) -> Any:
        """``sensor_msgs/LaserScan`` from :func:`~.bag_data.laser_scan`'s fields."""
        return self.T["sensor_msgs/msg/LaserScan"](
            header=self.header(t_s, "lidar_link"), time_increment=period_s / horizontal_samples,
            scan_time=period_s,
            **{k: v for k, v in scan.items() if k not in ("ring", "elevation_deg")})

    #: Threads that build and serialise messages ahead of the writer (image codecs and file
    #: reads release the GIL; the writer's chunk compression runs beside them).
    workers = min(4, os.cpu_count() or 1)

    def _encode(self, event: tuple[Any, ...]) -> tuple[int, int, bytes | memoryview]:
        ns, order, _, build, args = event
        msg = build(*args)
        return ns, order, self.serialize(msg)

    def write(self, path: Path, storage: str, compression: str,
              progress: Callable[[int, int], None] | None) -> dict[str, int]:
        """Write the queued messages in stamp order (:mod:`.bag_writer` sets the storage)."""
        from rosbags.interfaces import (
            Qos,
            QosDurability,
            QosHistory,
            QosLiveliness,
            QosReliability,
            QosTime,
        )

        from marsscene.runs.export.bag_writer import finish_metadata, open_writer

        forever = QosTime(sec=2147483647, nsec=4294967295)

        def offered(topic: Topic) -> list[Qos]:  # rosbag2 records the profile of latched topics
            if not topic.latched:
                return []
            p = QOS_PROFILES[topic.qos]
            return [Qos(QosHistory.KEEP_LAST, p.depth,
                        QosReliability.RELIABLE if p.reliable else QosReliability.BEST_EFFORT,
                        QosDurability.TRANSIENT_LOCAL, forever, forever,
                        QosLiveliness.AUTOMATIC, forever, False)]

        counts = dict.fromkeys(self.topics, 0)
        names = list(self.topics)
        self.events.sort(key=lambda e: e[:3])
        with open_writer(path, storage, compression, self.distro) as w:
            conns = [w.add_connection(t.name, t.msgtype, typestore=self.store,
                                      offered_qos_profiles=offered(t))
                     for t in self.topics.values()]
            for i, (ns, order, data) in enumerate(ordered_map(
                    self._encode, self.events, workers=self.workers, window=8 * self.workers,
                    name="marsscene-bag")):
                w.write(conns[order], ns, data)
                counts[names[order]] += 1
                if progress is not None and (i % 200 == 0 or i == len(self.events) - 1):
                    progress(i + 1, len(self.events))
        finish_metadata(path, self.distro)
        return counts
