"""Public helpers for testing code that uses marsscene, like :mod:`numpy.testing` (not needed
to build a scene or drive the rover).

* :mod:`.pds3`: writes HiRISE-style PDS3 DTMs and orthoimages (attached or detached label;
  GDAL cannot write PDS3) from an array, to test DEM pipelines without downloading a product.
  It needs only the core dependencies.

This package is part of the public API: its names keep their meaning between releases. A
helper added here that needs an optional dependency imports it inside the function and raises
:func:`marsscene.errors.missing_dependency` (one line naming the extra) when it is missing.
The marsscene test suite's own support code (the DDS peer, the Newton checks, the shadow truth,
the OpenCV front end) lives with the tests, in ``tests/support/``.
"""
