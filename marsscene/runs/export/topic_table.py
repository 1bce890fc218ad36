"""The rover's ROS 2 topics, stated once: name, message type and QoS of each, in the bag's order.

A robot's topics live under its namespace and its frames carry its prefix (:class:`RosNames`):
the single rover of a drive is ``/rover/...`` with bare frames (``base_link``), robot ``scout1``
of a team ``/scout1/...`` with ``scout1/base_link``, as multi-robot ROS 2 systems name them
(Nav2's multi-robot bringup, ``robot_state_publisher``'s ``frame_prefix``). ``/clock``,
``/tf`` and ``/tf_static`` are global and ``map`` is shared.

The bag (:mod:`.bag_topics` registers these rows on its :class:`~.bag_messages.MessageBuilder`),
the live messages (:class:`~.sample_messages.SampleMessages`) and the live bridge
(:mod:`marsscene.ros2.bridge`) all read this table; so do the QoS settings: the bag's offered
profile of a latched topic (:mod:`.bag_messages`) and the DDS endpoints (:mod:`marsscene.ros2.dds`)
are both built from :data:`QOS_PROFILES`. Pure data: no ``rosbags`` or ``cyclonedds`` import.

Examples
--------
>>> [t.name for t in topic_table(images="compressed") if t.latched]
['/tf_static', '/rover/robot_description']
>>> [t.name for t in state_topics(RosNames.for_robot("scout1"))][3:6]
['/scout1/robot_description', '/scout1/cmd_vel', '/scout1/odom']
>>> QOS_PROFILES["latched"]
QosProfile(reliable=True, depth=1, transient_local=True)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["QOS_PROFILES", "ROVER", "STEREO_SIDES", "QosProfile", "RosNames", "Topic",
           "camera_topics",
           "lidar_topics", "state_topics", "stereo_topics", "topic_table"]


@dataclass(frozen=True)
class QosProfile:
    """A ROS 2 QoS profile as far as the rover's topics differ: reliability, history depth
    (keep last) and durability (transient local: "latched", served to late joiners)."""

    reliable: bool
    depth: int
    transient_local: bool = False


#: ROS 2's QoS conventions: rclcpp's SensorDataQoS (best effort, depth 5), ClockQoS (best effort,
#: depth 1), tf2's (reliable, 100), static-tf / latched topics (reliable, transient local, 1) and
#: the default profile (reliable, depth 10); ``sensor-reliable`` is the sensor profile for
#: subscribers that insist on reliable topics.
QOS_PROFILES: dict[str, QosProfile] = {
    "sensor": QosProfile(False, 5), "sensor-reliable": QosProfile(True, 5),
    "clock": QosProfile(False, 1), "tf": QosProfile(True, 100),
    "latched": QosProfile(True, 1, transient_local=True), "default": QosProfile(True, 10),
}

#: Frames every robot shares (not prefixed).
SHARED_FRAMES = ("map", "world")


@dataclass(frozen=True)
class RosNames:
    """One robot's names on ROS 2: its topics' namespace and its TF frames' prefix.

    ``control`` is the namespace of the bridge's own command topics (reset, teleport, goal).
    """

    namespace: str = "rover"
    frame_prefix: str = ""
    control: str = "/marsscene"

    @classmethod
    def for_robot(cls, name: str) -> RosNames:
        """A team robot's: ``/NAME/...`` topics, ``NAME/...`` frames, ``/marsscene/NAME``."""
        return cls(name, f"{name}/", f"/marsscene/{name}")

    @classmethod
    def of_meta(cls, meta: dict[str, Any]) -> RosNames:
        """The names a run folder's ``run.json`` states (``"ros"``), else the rover's."""
        ros = meta.get("ros") or {}
        return cls(**{k: str(v) for k, v in ros.items() if k in ("namespace", "frame_prefix",
                                                                   "control")})

    def to_dict(self) -> dict[str, str]:
        return {"namespace": self.namespace, "frame_prefix": self.frame_prefix,
                "control": self.control}

    def topic(self, relative: str) -> str:
        """``odom`` -> ``/rover/odom``."""
        return f"/{self.namespace}/{relative}"

    def frame(self, frame: str) -> str:
        """``base_link`` -> ``scout1/base_link``; shared frames (``map``) as they are."""
        return frame if frame in SHARED_FRAMES or not frame else self.frame_prefix + frame


#: The single rover's names (every drive, bag and session without a team).
ROVER = RosNames()

#: The stereo pair's views, in the bag's order.
STEREO_SIDES = ("left", "right")

_IMAGE = "sensor_msgs/msg/Image"
_COMPRESSED = "sensor_msgs/msg/CompressedImage"
_CAMERA_INFO = "sensor_msgs/msg/CameraInfo"
_CLOUD = "sensor_msgs/msg/PointCloud2"


@dataclass(frozen=True)
class Topic:
    """One topic: ``name``, ``msgtype`` (``pkg/msg/Type``) and ``qos``, a key of
    :data:`QOS_PROFILES` (``"sensor"`` for sensor data, which a live session may offer
    reliably instead)."""

    name: str
    msgtype: str
    qos: str = "sensor"

    @property
    def latched(self) -> bool:
        """Transient local: the bag offers the latched profile, late joiners get the message."""
        return QOS_PROFILES[self.qos].transient_local


#: Per wheel on deformable soil, as a ``JointState`` of the drive joints: position = sinkage
#: (m), velocity = slip (-1 to 1), effort = the soil's load on the wheel (N).
WHEEL_SOIL = "wheel_soil"


def state_topics(names: RosNames = ROVER, *, imu_true: bool = True,
                 soil: bool = False) -> list[Topic]:
    """Clock, TF, the URDF, the command, odometry, ground truth, joints, (``soil``) the
    wheels' slip and sinkage and the IMU (``imu_true``: also the noise-free ``/rover/imu``)."""
    n = names.topic
    out = [Topic("/clock", "rosgraph_msgs/msg/Clock", "clock"),
           Topic("/tf", "tf2_msgs/msg/TFMessage", "tf"),
           Topic("/tf_static", "tf2_msgs/msg/TFMessage", "latched"),
           Topic(n("robot_description"), "std_msgs/msg/String", "latched"),
           Topic(n("cmd_vel"), "geometry_msgs/msg/Twist", "default"),
           Topic(n("odom"), "nav_msgs/msg/Odometry", "default"),
           Topic(n("GT_Trajectory"), "nav_msgs/msg/Odometry", "default"),
           Topic(n("joint_states"), "sensor_msgs/msg/JointState", "default"),
           *([Topic(n(WHEEL_SOIL), "sensor_msgs/msg/JointState", "default")] if soil
             else []),
           Topic(n("imu_noisy"), "sensor_msgs/msg/Imu")]
    return [*out, Topic(n("imu"), "sensor_msgs/msg/Imu")] if imu_true else out


def _colour(prefix: str, images: str) -> list[Topic]:
    """``PREFIX/image_raw`` (raw), ``.../compressed`` (compressed) and ``PREFIX/camera_info``."""
    out = [Topic(f"{prefix}/image_raw", _IMAGE)] if images in ("raw", "both") else []
    if images in ("compressed", "both"):
        out.append(Topic(f"{prefix}/image_raw/compressed", _COMPRESSED))
    return [*out, Topic(f"{prefix}/camera_info", _CAMERA_INFO)]


def camera_topics(names: RosNames = ROVER, *, images: str, depth: bool = True,
                  depth_cloud: bool = False) -> list[Topic]:
    """The navcam: colour, then (``depth``) depth images, camera info and (``depth_cloud``)
    the organised cloud; ``images`` is ``"raw"``, ``"compressed"`` or ``"both"``."""
    n = names.topic
    out = _colour(n("rgb"), images)
    if not depth:
        return out
    out += [Topic(n("depth/image_raw"), _IMAGE)] if images in ("raw", "both") else []
    if images in ("compressed", "both"):
        out.append(Topic(n("depth/image_raw/compressedDepth"), _COMPRESSED))
    out.append(Topic(n("depth/camera_info"), _CAMERA_INFO))
    return [*out, Topic(n("depth/points"), _CLOUD)] if depth_cloud else out


def stereo_topics(side: str, names: RosNames = ROVER, *, images: str) -> list[Topic]:
    """One view of the stereo pair (``side``: one of :data:`STEREO_SIDES`)."""
    return _colour(names.topic(f"stereo/{side}"), images)


def lidar_topics(names: RosNames = ROVER) -> list[Topic]:
    """The LiDAR's point cloud and its ``LaserScan``."""
    return [Topic(names.topic("lidar/points"), _CLOUD),
            Topic(names.topic("scan"), "sensor_msgs/msg/LaserScan")]


def topic_table(names: RosNames = ROVER, *, images: str, imu_true: bool = True,
                camera: bool = False, depth: bool = False, stereo: bool = False,
                lidar: bool = False, depth_cloud: bool = False,
                soil: bool = False) -> list[Topic]:
    """Every topic of a bag (or a live session) with these sensors, in the bag's order."""
    out = state_topics(names, imu_true=imu_true, soil=soil)
    out += (camera_topics(names, images=images, depth=depth, depth_cloud=depth_cloud)
            if camera else [])
    for side in STEREO_SIDES if stereo else ():
        out += stereo_topics(side, names, images=images)
    return out + lidar_topics(names) if lidar else out
