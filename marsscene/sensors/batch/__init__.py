"""Sensors for every world of a MuJoCo Warp batch (``pip install "marsscene[gpu]"``): the CPU
sensors' models, cast on the device for thousands of rovers at once.

- :class:`BatchLidar`: the spinning LiDAR's beam models
  (:class:`~marsscene.rover.lidar.LidarConfig`) by ``mujoco_warp.rays`` through a render
  context's BVH, with per-ray time, motion distortion and the CPU LiDAR's noise (seeded per
  world).
- :class:`BatchDepthCamera`: metric depth images of the mast camera at the CPU camera's
  intrinsics (:class:`~marsscene.rover.config.CameraConfig`), by MuJoCo Warp's renderer.
- :class:`BatchCamera`: the mast camera's RGB, depth and segmentation of the world the CPU
  camera sees (regolith texture, rock meshes, sun and shadows, sky, fog, exposure, sRGB), ray
  traced in Warp (:mod:`.rgbd` says why).

Docs: :doc:`/batch_sensors`.
"""

from __future__ import annotations

from marsscene._lazy import lazy_attributes

__all__ = ["BatchCamera", "BatchDepthCamera", "BatchLidar", "BatchScan"]

__getattr__ = lazy_attributes(__name__, {
    "BatchCamera": "marsscene.sensors.batch.rgbd",
    "BatchDepthCamera": "marsscene.sensors.batch.camera",
    "BatchLidar": "marsscene.sensors.batch.lidar",
    "BatchScan": "marsscene.sensors.batch.lidar",
})
