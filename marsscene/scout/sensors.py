"""The scout's downward sensors, cast on the scene's terrain (:func:`~marsscene.sensors.raycast.
ray_heightfield`, the LiDAR's caster): a laser altimeter (LIDAR-Lite v3 class: range along the
body's -z axis, Gaussian noise of ``altimeter_sigma_m``) and the navigation camera (a pinhole
of Ingenuity's 133 deg diagonal field of view looking down; each pixel is the Lambertian
shading ``255 max(n . s, 0)`` of the terrain it sees under a sun at ``sun_dir``, a uniform
albedo; rocks are not drawn: the heightfield only).

Camera frame (optical): x right, y down, z forward; on the body: z_cam = -z_body,
x_cam = -y_body, y_cam = -x_body (image up = the vehicle's nose).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from marsscene.sensors.raycast import ray_heightfield
from marsscene.terrain.heightfield import Heightfield

__all__ = ["BODY_TO_CAMERA", "altimeter_m", "nadir_image", "pixel_rays"]

#: Columns: the camera's x, y, z axes in the body frame.
BODY_TO_CAMERA = np.array([[0.0, -1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


def altimeter_m(hf: Heightfield, p: NDArray[np.float64], rot: NDArray[np.float64],
                range_m: float) -> float:
    """True range (m) from ``p`` along the body's -z to the terrain (``inf`` beyond range)."""
    dist, _ = ray_heightfield(hf, p, -rot[:, 2][None, :], (0.0, range_m))
    return float(dist[0])


def pixel_rays(width_px: int, height_px: int, fov_diag_deg: float) -> NDArray[np.float64]:
    """Unit rays (H * W, 3) of the pinhole's pixel centres in the camera frame."""
    f = math.hypot(width_px, height_px) / 2.0 / math.tan(math.radians(fov_diag_deg) / 2.0)
    u, v = np.meshgrid(np.arange(width_px) + 0.5 - width_px / 2,
                       np.arange(height_px) + 0.5 - height_px / 2)
    rays = np.stack([u.ravel() / f, v.ravel() / f, np.ones(u.size)], axis=1)
    return np.asarray(rays / np.linalg.norm(rays, axis=1, keepdims=True), dtype=np.float64)


def nadir_image(hf: Heightfield, p: NDArray[np.float64], rot: NDArray[np.float64],
                rays_cam: NDArray[np.float64], shape: tuple[int, int],
                sun_dir: NDArray[np.float64], range_m: float = 200.0) -> NDArray[np.uint8]:
    """An 8-bit grey image (H, W) of the terrain below (0 where a ray sees no ground)."""
    dirs = rays_cam @ (rot @ BODY_TO_CAMERA).T
    _, normal = ray_heightfield(hf, p, dirs, (0.0, range_m))
    shade = np.clip(normal @ sun_dir, 0.0, 1.0)
    return np.asarray(np.clip(shade * 255.0, 0, 255).round(), dtype=np.uint8).reshape(shape)
