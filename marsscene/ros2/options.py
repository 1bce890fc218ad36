"""Options of a live ROS 2 session (:func:`marsscene.ros2.serve`): pure data, no DDS import."""

from __future__ import annotations

import os
import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from marsscene._validate import check_range, dataclass_from_mapping
from marsscene.errors import ConfigError
from marsscene.rover.config import GOAL_TOLERANCE_M
from marsscene.runs.export.options import DISTROS, IMAGES

__all__ = ["PACES", "SENSOR_QOS", "Ros2Options", "localhost_from_env"]

#: How sim time runs: with the wall clock, as fast as it goes, or only when commanded.
PACES = ("realtime", "max", "lockstep")
#: The sensor topics' reliability: ROS 2's sensor-data QoS, or reliable.
SENSOR_QOS = ("best-effort", "reliable")


def localhost_from_env(env: Mapping[str, str] | None = None) -> bool:
    """ROS 2's own switches for keeping discovery on this machine.

    ``ROS_AUTOMATIC_DISCOVERY_RANGE`` (Iron and later) ``LOCALHOST`` or ``OFF``, else the older
    ``ROS_LOCALHOST_ONLY=1`` (Humble).
    """
    env = os.environ if env is None else env
    rng = env.get("ROS_AUTOMATIC_DISCOVERY_RANGE", "").strip().upper()
    if rng:
        return rng in ("LOCALHOST", "OFF")
    return env.get("ROS_LOCALHOST_ONLY", "").strip() == "1"


@dataclass(frozen=True, kw_only=True)
class Ros2Options:
    """How the live rover speaks ROS 2 over DDS.

    Parameters
    ----------
    domain_id : int, optional
        DDS domain (default ``ROS_DOMAIN_ID``, else 0).
    localhost : bool, optional
        Keep every packet on the loopback interface: no multicast, unicast discovery of
        127.0.0.1 only (default: on when ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` or
        ``ROS_LOCALHOST_ONLY=1``; a ``CYCLONEDDS_URI`` is honoured either way).
    node_name : str
        The node ``ros2 node list`` shows (``ros_discovery_info``).
    cmd_vel_topic : str
        Velocity commands the rover obeys.
    rover_cmd_vel : bool
        Also obey ``/rover/cmd_vel`` (the topic a MarsLab stack publishes; the bag records the
        command there) besides ``cmd_vel_topic``.
    cmd_vel_stamped : bool
        ``geometry_msgs/TwistStamped`` on ``cmd_vel_topic`` (Nav2's ``enable_stamped_cmd_vel``)
        instead of ``Twist``.
    cmd_timeout_s : float
        Sim seconds without a command after which the rover stops (0 = never).
    pace : str
        ``"realtime"`` (sim time follows the wall clock, times ``realtime_factor``), ``"max"``
        (as fast as the simulation and the writers go) or ``"lockstep"`` (sim time stands
        still until a command arrives; each ``cmd_vel`` message drives ``lockstep_steps``
        control steps, and once they are done and every sample of them is out, ``/clock``
        reads the time reached: a slow client misses nothing, and the same commands give the
        same run).
    lockstep_steps : int
        Control steps each command drives with ``pace="lockstep"``.
    realtime_factor : float
        Sim seconds per wall second with ``pace="realtime"``.
    sensor_qos : str
        ``"best-effort"`` (ROS 2's sensor-data QoS: depth 5) or ``"reliable"`` for the IMU,
        camera and LiDAR topics (for subscribers that insist on reliable ones); always
        reliable with ``pace="lockstep"``.
    images : str
        ``"both"`` (raw and image_transport's compressed topics; each is encoded only while
        someone subscribes), ``"raw"`` or ``"compressed"``.
    goal_tolerance_m : float
        A goal (``/marsscene/goal``) counts as reached within this distance (ground truth;
        default :data:`~marsscene.rover.config.GOAL_TOLERANCE_M`, the navigation task's).
    stop_at_goal : bool
        End the session when the goal is reached.
    distro : str
        ``"jazzy"`` or ``"humble"`` message definitions (they differ in ``ros_discovery_info``).
    services : bool
        Serve ``simulation_interfaces``' services and the ``SimulateSteps`` action
        (:mod:`.sim_control`; clients on ``rmw_cyclonedds_cpp``).
    sim_namespace : str
        In front of the services' names (``/`` : ``/get_simulation_state``; ``/gzserver`` for
        scripts written for Gazebo).
    map_tf : bool
        Publish ``map -> odom`` on ``/tf`` (from ground truth: a perfect localiser); turn it off
        when a SLAM or localisation stack publishes its own.
    """

    domain_id: int | None = None
    localhost: bool | None = None
    node_name: str = "marsscene_rover"
    cmd_vel_topic: str = "/cmd_vel"
    rover_cmd_vel: bool = True
    cmd_vel_stamped: bool = False
    cmd_timeout_s: float = 0.5
    pace: str = "realtime"
    lockstep_steps: int = 1
    realtime_factor: float = 1.0
    sensor_qos: str = "best-effort"
    images: str = "both"
    goal_tolerance_m: float = GOAL_TOLERANCE_M
    stop_at_goal: bool = False
    distro: str = "jazzy"
    map_tf: bool = True
    services: bool = True
    sim_namespace: str = "/"

    def __post_init__(self) -> None:
        if self.domain_id is not None:
            check_range("ros2.domain_id", self.domain_id, 0, 232)
        check_range("ros2.cmd_timeout_s", self.cmd_timeout_s, 0.0, 1e6)
        check_range("ros2.realtime_factor", self.realtime_factor, 0.0, 1e3, lo_open=True)
        check_range("ros2.lockstep_steps", self.lockstep_steps, 1, 1_000_000)
        check_range("ros2.goal_tolerance_m", self.goal_tolerance_m, 0.0, 1e6, lo_open=True)
        for name, value, allowed in (("pace", self.pace, PACES),
                                     ("sensor_qos", self.sensor_qos, SENSOR_QOS),
                                     ("images", self.images, IMAGES),
                                     ("distro", self.distro, DISTROS)):
            if value not in allowed:
                raise ConfigError(f"ros2.{name} = {value!r}; expected one of "
                                  f"{', '.join(allowed)}")
        if not self.cmd_vel_topic.startswith("/") or " " in self.cmd_vel_topic:
            raise ConfigError(f"ros2.cmd_vel_topic = {self.cmd_vel_topic!r} must be an "
                              "absolute topic name such as /cmd_vel")
        if not re.fullmatch(r"(/[A-Za-z_][A-Za-z0-9_]*)*/?", self.sim_namespace) \
                or not self.sim_namespace.startswith("/"):
            raise ConfigError(f"ros2.sim_namespace = {self.sim_namespace!r} must be an "
                              "absolute ROS namespace such as / or /gzserver")
        if not self.node_name.isidentifier():
            raise ConfigError(f"ros2.node_name = {self.node_name!r} must be a ROS name "
                              "(letters, digits, underscores)")

    @property
    def cmd_vel_topics(self) -> tuple[str, ...]:
        """The command topics obeyed, in the order they are read."""
        extra = ("/rover/cmd_vel",) if self.rover_cmd_vel else ()
        return tuple(dict.fromkeys((self.cmd_vel_topic, *extra)))

    @property
    def domain(self) -> int:
        """The DDS domain in force (``domain_id``, ``ROS_DOMAIN_ID`` or 0)."""
        if self.domain_id is not None:
            return self.domain_id
        raw = os.environ.get("ROS_DOMAIN_ID", "").strip()
        if not raw:
            return 0
        if not raw.isdigit() or int(raw) > 232:
            raise ConfigError(f"ROS_DOMAIN_ID = {raw!r} must be an integer 0..232")
        return int(raw)

    @property
    def localhost_only(self) -> bool:
        """Whether the session keeps to loopback (``localhost``, else ROS 2's switches)."""
        return self.localhost if self.localhost is not None else localhost_from_env()

    @classmethod
    def from_dict(cls, mapping: Mapping[str, Any]) -> Ros2Options:
        """From a TOML/JSON table; unknown keys are an error."""
        return dataclass_from_mapping(cls, mapping, "ros2")
