"""The live ROS 2 tests need cyclonedds and rosbags (``pip install "marsscene[ros2]"``); every DDS
packet stays on 127.0.0.1 (localhost mode, unicast discovery, no multicast)."""

import pytest

pytest.importorskip("cyclonedds")
pytest.importorskip("rosbags")
