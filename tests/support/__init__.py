"""Support code shared by the test suite and the performance scripts (``perf/``); not part of
the ``marsscene`` package and not installed with it.

* :mod:`.dds_peer`: an independent ROS 2 peer over DDS (plain ``cyclonedds`` + ``rosbags``, no
  marsscene), run as a script: ``python tests/support/dds_peer.py MODE ...``
  (:data:`DDS_PEER` is its path);
* :mod:`.newton_checks`: worlds and checks for the USD rover in Newton (extra ``newton``);
* :mod:`.shadow_truth`: a penumbra-aware terrain-shadow truth for rendered frames;
* :mod:`.vision`: an OpenCV visual front end and RGB-D odometry scored against ground truth;
* :mod:`.drive`: :func:`~.drive.step`, one control period of ``cmd_vel`` on a ``RoverSim``.

Tests import them as ``tests.support.<module>`` (pytest puts the repository root on
``sys.path``); a perf script inserts the repository root first, as it does ``perf/`` for
``_measure``. Public test helpers for users live in :mod:`marsscene.testing`.
"""

from pathlib import Path

DDS_PEER = Path(__file__).resolve().with_name("dds_peer.py")
"""The DDS peer script (run it with ``sys.executable``)."""
