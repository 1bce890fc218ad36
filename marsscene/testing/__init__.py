"""Helpers for testing and measuring code that uses marsscene (not needed to build or drive).

* :mod:`.pds3`: writes HiRISE-style PDS3 DTMs and orthoimages (attached or detached label;
  GDAL cannot write PDS3) from an array, to test DEM pipelines without downloading a product;
* :mod:`.vision`: a small OpenCV visual front end (corners, KLT, PnP RGB-D odometry) scored
  against a run's ground truth (needs ``opencv-python-headless``).

The test suite and the performance scripts (``perf/``) share them.
"""
