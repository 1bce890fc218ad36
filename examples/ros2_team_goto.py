"""Two ROS 2 nodes drive a served team: one node per robot, each in the robot's namespace.

Serve a team (``examples/team_serve.toml``: a Perseverance-class rover ``r1`` and a MER-class
rover ``r2``), then run this with a Python that has ROS 2 Jazzy's ``rclpy`` (a ROS install, or
``pip install "ros-jazzy-rclpy[fastrtps]" ros-jazzy-geometry-msgs ros-jazzy-nav-msgs``)::

    marsscene serve SCENE_DIR --team examples/team_serve.toml --localhost
    python examples/ros2_team_goto.py r1:2,-4 r2:-7.5,4 --seconds 30

Each node is made with ``namespace=NAME``, so its relative topics are the robot's own:
it reads ``odom`` (``/NAME/odom``, the wheel odometry; its ``odom`` frame is ``map`` at the
start) and publishes ``cmd_vel`` (``/NAME/cmd_vel``) at 10 Hz: turn towards the goal, drive at
up to ``--speed`` (the rover's own limit clips it), stop within ``--tolerance-m``. It prints one
JSON line: each robot's start, last odometry position and distance to its goal.
"""

from __future__ import annotations

import argparse
import json
import math
import time

import rclpy
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node


class GoTo(Node):
    """Drive one robot (this node's namespace) to ``goal_xy_m`` on its own odometry."""

    def __init__(self, name: str, goal_xy_m: tuple[float, float], speed_m_s: float,
                 tolerance_m: float) -> None:
        super().__init__("goto", namespace=name)
        self.goal, self.speed, self.tol = goal_xy_m, speed_m_s, tolerance_m
        self.pose: tuple[float, float, float] | None = None
        self.start: tuple[float, float] | None = None
        self.cmd = self.create_publisher(Twist, "cmd_vel", 10)
        self.create_subscription(Odometry, "odom", self.on_odom, 10)
        self.create_timer(0.1, self.step)

    def on_odom(self, msg: Odometry) -> None:
        p, q = msg.pose.pose.position, msg.pose.pose.orientation
        yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
        self.pose = (p.x, p.y, yaw)
        if self.start is None:
            self.start = (p.x, p.y)

    @property
    def distance_m(self) -> float:
        if self.pose is None:
            return math.inf
        return math.hypot(self.goal[0] - self.pose[0], self.goal[1] - self.pose[1])

    def step(self) -> None:
        if self.pose is None:
            return
        x, y, yaw = self.pose
        heading = math.atan2(self.goal[1] - y, self.goal[0] - x)
        err = math.atan2(math.sin(heading - yaw), math.cos(heading - yaw))
        t = Twist()
        if self.distance_m > self.tol:
            t.angular.z = max(-0.5, min(0.5, 1.5 * err))
            t.linear.x = self.speed * max(0.0, math.cos(err)) if abs(err) < 0.8 else 0.0
        self.cmd.publish(t)


def _goal(text: str) -> tuple[str, tuple[float, float]]:
    name, _, xy = text.partition(":")
    x, y = (float(v) for v in xy.split(","))
    return name, (x, y)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("goals", nargs="+", type=_goal, metavar="NAME:X,Y",
                    help="a robot and its goal in the map frame (m)")
    ap.add_argument("--seconds", type=float, default=60.0, help="wall-clock limit")
    ap.add_argument("--speed", type=float, default=0.3, help="top speed asked (m/s)")
    ap.add_argument("--tolerance-m", type=float, default=0.3)
    a = ap.parse_args()
    rclpy.init()
    nodes = [GoTo(name, goal, a.speed, a.tolerance_m) for name, goal in a.goals]
    ex = SingleThreadedExecutor()
    for n in nodes:
        ex.add_node(n)
    t0 = time.monotonic()
    while time.monotonic() - t0 < a.seconds and not all(n.distance_m <= a.tolerance_m
                                                         for n in nodes):
        ex.spin_once(timeout_sec=0.05)
    for n in nodes:  # stop
        n.cmd.publish(Twist())
    print(json.dumps({n.get_namespace().strip("/"): {
        "start_xy_m": n.start, "last_xy_m": n.pose[:2] if n.pose else None,
        "distance_m": n.distance_m} for n in nodes}))
    rclpy.shutdown()


if __name__ == "__main__":
    main()
