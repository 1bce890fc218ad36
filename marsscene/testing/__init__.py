"""Public helpers for testing code that uses marsscene, like :mod:`numpy.testing` (not needed
to build a scene or drive the rover).

* :mod:`.pds3`: writes HiRISE-style PDS3 DTMs and orthoimages (attached or detached label;
  GDAL cannot write PDS3) from an array, to test DEM pipelines without downloading a product.
  It needs only the core dependencies.
* :mod:`.vision`: a small OpenCV visual front end (Shi-Tomasi corners, KLT, PnP-RANSAC on
  depth) and RGB-D visual odometry scored against a drive's ground truth. Needs OpenCV (the
  extra ``bench``).
* :mod:`.shadow_truth`: a renderer-independent truth for terrain shadows (the horizon toward
  the sun by a ray march, the visible share of the sun's disc). Core dependencies only.
* :mod:`.newton_checks`: worlds and checks for the USD rover in Newton (a slope, rocks in the
  path, a sphere dropped on a rock, one ``cmd_vel`` plan in MuJoCo and in Newton). Needs the
  extra ``newton`` (and ``sim``).

The test suite and the performance scripts (``perf/``) both use them; ``perf/`` imports nothing
from ``tests/``. This package is part of the public API: its names keep their meaning between
releases. A helper here that needs an optional dependency imports it inside the function and
raises :func:`marsscene.errors.missing_dependency` (one line naming the extra) when it is
missing. The test suite's own fixtures (the DDS peer, the drive helpers) live with the tests,
in ``tests/support/``.
"""
