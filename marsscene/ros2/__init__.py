"""Live ROS 2 over DDS with no ROS installation: ``marsscene serve SCENE``.

:func:`serve` runs the MuJoCo rover with its sensors and speaks ROS 2 on the wire through
Eclipse Cyclone DDS (``pip install "marsscene[ros2]"``): the bag's topics published live (the
same message builders and ``rosbags`` CDR bytes), ``cmd_vel`` subscribed with a time-out, reset /
teleport / goal topics, sim time on ``/clock``, real-time pacing, as fast as it goes or in
lockstep, ``simulation_interfaces``' services for clients on ``rmw_cyclonedds``
(:mod:`.sim_control`), and a localhost-only mode. :func:`serve_team` serves a team of
robots, each under its own namespace (``/r1/odom``, ``r1/base_link``). Topics, QoS and how to
connect ROS 2: :doc:`/ros2_live`.

``cyclonedds`` is imported only when a session starts (:mod:`.dds`).
"""

from marsscene._lazy import lazy_attributes
from marsscene.ros2.options import Ros2Options

__all__ = ["Ros2Options", "serve", "serve_team"]

__getattr__ = lazy_attributes(__name__, {
    "serve": "marsscene.ros2.live",
    "serve_team": "marsscene.ros2.live_team",
})
