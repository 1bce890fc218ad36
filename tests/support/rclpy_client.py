"""A stock ROS 2 Jazzy node (rclpy on ``rmw_fastrtps_cpp``, the ``ros-jazzy-*`` wheels from PyPI,
no ROS installation) that drives ``marsscene serve --pace lockstep``: run it with the Python
that has them, as a script (it imports nothing from marsscene)::

    RMW_IMPLEMENTATION=rmw_fastrtps_cpp ROS_DOMAIN_ID=D \\
    FASTRTPS_DEFAULT_PROFILES_FILE=tests/support/fastdds_loopback.xml \\
        python rclpy_client.py STEPS DT V W [--sleep-per-scan S]

It waits for ``/clock``, then STEPS times: publishes one ``geometry_msgs/Twist`` on
``/cmd_vel``, spins until ``/clock`` reaches the step's end, taking ``/rover/odom`` and
``/rover/lidar/points`` (sleeping S s in each cloud's callback: a slow subscriber); then one
stop command. JSON on stdout: counts, the SHA-256 of the odometry and clouds in order (a
cloud's stamp, layout and points), the wall time of the steps, the node names the ROS graph
shows, and the type hash it shows for each endpoint of four topics (the client's own and the
rover's).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import time

import rclpy
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from rclpy.serialization import serialize_message
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import PointCloud2


def _content(msg: object) -> bytes:
    """What a message says, as bytes: a cloud's stamp, layout and point data; else the
    serialised message (a cloud's serialisation carries padding bytes of no fixed value)."""
    if isinstance(msg, PointCloud2):
        st = msg.header.stamp
        return (f"{st.sec} {st.nanosec} {msg.height} {msg.width} {msg.point_step} "
                f"{[(f.name, f.offset, f.datatype) for f in msg.fields]}".encode()
                + bytes(msg.data))
    return bytes(serialize_message(msg))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("steps", type=int)
    ap.add_argument("dt", type=float)
    ap.add_argument("v", type=float)
    ap.add_argument("w", type=float)
    ap.add_argument("--sleep-per-scan", type=float, default=0.0)
    a = ap.parse_args()
    rclpy.init()
    node = rclpy.create_node("lockstep_client")
    now = [-1.0]
    hashes = {"odom": hashlib.sha256(), "lidar": hashlib.sha256()}
    counts = {"odom": 0, "lidar": 0}

    def on_clock(msg: Clock) -> None:
        now[0] = max(now[0], msg.clock.sec + msg.clock.nanosec * 1e-9)

    def on(key: str, pause_s: float = 0.0):
        def take(msg: object) -> None:
            hashes[key].update(_content(msg))
            counts[key] += 1
            time.sleep(pause_s)
        return take

    reliable = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    node.create_subscription(Clock, "/clock", on_clock, qos_profile_sensor_data)
    node.create_subscription(Odometry, "/rover/odom", on("odom"), reliable)
    node.create_subscription(PointCloud2, "/rover/lidar/points",
                             on("lidar", a.sleep_per_scan), reliable)
    cmd = node.create_publisher(Twist, "/cmd_vel", 10)

    def spin_until(t_s: float, limit_s: float = 60.0) -> None:
        t0 = time.monotonic()
        while now[0] < t_s - 1e-6:
            if time.monotonic() - t0 > limit_s:
                sys.exit(f"no /clock of {t_s:.3f} s (last {now[0]:.3f} s)")
            rclpy.spin_once(node, timeout_sec=0.01)

    spin_until(0.0)
    while cmd.get_subscription_count() == 0:
        rclpy.spin_once(node, timeout_sec=0.01)
    start, t0 = now[0], time.monotonic()
    for i in range(a.steps):
        cmd.publish(Twist(linear=Twist().linear.__class__(x=a.v),
                          angular=Twist().angular.__class__(z=a.w)))
        spin_until(start + (i + 1) * a.dt)
    wall = time.monotonic() - t0
    graph = sorted(node.get_node_names())
    hashes_seen = {  # topic: {node: type hash} of every endpoint, the client's own and the rover's
        t: {f"{i.node_name} {kind}": str(i.topic_type_hash)
            for kind, get in (("pub", node.get_publishers_info_by_topic),
                              ("sub", node.get_subscriptions_info_by_topic)) for i in get(t)}
        for t in ("/rover/odom", "/rover/lidar/points", "/cmd_vel", "/clock")}
    cmd.publish(Twist())  # the session's last step
    t_end = time.monotonic() + 1.0
    while time.monotonic() < t_end:
        rclpy.spin_once(node, timeout_sec=0.01)
    sys.stdout.write(json.dumps({"steps": a.steps, "wall_s": wall, "counts": counts,
                                 "sha256": {k: h.hexdigest() for k, h in hashes.items()},
                                 "nodes": graph, "type_hashes": hashes_seen}) + "\n")
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
