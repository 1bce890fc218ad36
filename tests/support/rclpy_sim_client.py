"""A stock ROS 2 Jazzy client of ``simulation_interfaces`` on ``rmw_fastrtps_cpp`` (the
``ros-jazzy-*`` wheels; PyPI has no ``simulation_interfaces`` wheel, so the package comes from
``tools/ros_interfaces.py``, on ``PYTHONPATH`` and ``LD_LIBRARY_PATH``): it calls
``/get_simulation_state`` with a time-out, as a Fast DDS user would, and says what came back.
Imports nothing from marsscene. JSON on stdout: ``{"available": bool, "answered": bool}``."""

from __future__ import annotations

import json
import sys

import rclpy
from simulation_interfaces.srv import GetSimulationState


def main() -> None:
    rclpy.init()
    node = rclpy.create_node("sim_state_client")
    cli = node.create_client(GetSimulationState, "/get_simulation_state")
    available = cli.wait_for_service(timeout_sec=10.0)  # matches the topics: True
    fut = cli.call_async(GetSimulationState.Request())
    rclpy.spin_until_future_complete(node, fut, timeout_sec=5.0)
    sys.stdout.write(json.dumps({"available": available, "answered": fut.done()}) + "\n")
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
