"""The test suite's own support code; not part of the ``marsscene`` package and not installed
with it.

* :mod:`.dds_peer`: an independent ROS 2 peer over DDS (plain ``cyclonedds`` + ``rosbags``, no
  marsscene), run as a script: ``python tests/support/dds_peer.py MODE ...``
  (:data:`DDS_PEER` is its path);
* :mod:`.drive`: :func:`~.drive.step`, one control period of ``cmd_vel`` on a ``RoverSim``;
* :mod:`.session_cache`: folders built once per test session for all xdist workers;
* :mod:`.extras`: skips that name the extra to install.

Tests import them as ``tests.support.<module>`` (pytest puts the repository root on
``sys.path``). The checks the tests and ``perf/`` share are public, in :mod:`marsscene.testing`
(the OpenCV front end, the shadow truth, the Newton checks, PDS3 writers).
"""

from pathlib import Path

DDS_PEER = Path(__file__).resolve().with_name("dds_peer.py")
"""The DDS peer script (run it with ``sys.executable``)."""
