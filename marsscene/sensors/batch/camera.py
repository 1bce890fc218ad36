"""Metric depth images of the mast camera in every world of a MuJoCo Warp batch, by MuJoCo
Warp's batch renderer (``create_render_context`` + ``refit_bvh`` + ``render``).

The camera is the model's ``rover/navcam`` (its pose on the mast, as the CPU camera's) at the
CPU camera's intrinsics: :class:`~marsscene.rover.config.CameraConfig`'s ``width_px`` x
``height_px`` and vertical field of view ``fovy_deg`` (square pixels, principal point at the
centre). Depth is planar (along the optical axis, in m), as the CPU camera's depth image; a
pixel that sees nothing holds 0 (the CPU camera's sky holds its far plane). What it renders is
the batch model's geometry (the tiled heightfield, with rocks as its relief): the CPU camera
renders its own world (smooth terrain meshes, catalogue rock meshes), so the two agree on the
same model, not yet on the same scene (:doc:`/batch_sensors`).
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np

from marsscene.errors import ConfigError

__all__ = ["BatchDepthCamera"]

#: The mast camera in a model with the rover attached (``marsscene.sim.rover_sim.PREFIX``).
NAVCAM = "rover/navcam"
#: Geom groups the depth camera sees by default: terrain and rocks (0, 1) and the rover (2), as
#: the CPU camera's render.
CAMERA_GROUPS = (0, 1, 2)


class BatchDepthCamera:
    """One depth camera per world of a MuJoCo Warp batch.

    Parameters
    ----------
    mj_model : mujoco.MjModel
        The host model the batch was put from (``BatchNavEnv.mj_model``); not changed.
    model : mujoco_warp.Model
        Its device copy (``BatchNavEnv.mjw_model``).
    nworld : int
        Worlds in the batch.
    config : CameraConfig, optional
        Image size and field of view (default ``CameraConfig()``: 640 x 480, 60 deg).
    camera : str
        The model's camera (default the mast camera).
    geom_groups : tuple of int
        Geom groups rendered (default: 0, 1 and 2).
    """

    def __init__(self, mj_model: Any, model: Any, nworld: int, config: Any = None, *,
                 camera: str = NAVCAM, geom_groups: tuple[int, ...] = CAMERA_GROUPS) -> None:
        import mujoco
        import mujoco_warp as mjw

        from marsscene.rover.config import CameraConfig

        self.config = cfg = config if config is not None else CameraConfig()
        self.width, self.height = int(cfg.width_px), int(cfg.height_px)
        self.nworld, self.model, self._mjw = int(nworld), model, mjw
        cid = mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_CAMERA, camera)
        if cid < 0:
            raise ConfigError(f"the model has no camera {camera!r}")
        self.camera_id = int(cid)
        host = copy.copy(mj_model)  # the rays are the config's, whatever the model's fovy
        host.cam_fovy[cid] = float(cfg.fovy_deg)
        host.cam_sensorsize[cid] = 0.0  # fovy, not a sensor size, sets the intrinsics
        self.rc = mjw.create_render_context(
            host, nworld=self.nworld, cam_res=(self.width, self.height), render_rgb=False,
            render_depth=True, render_seg=False, use_textures=False, use_shadows=False,
            enabled_geom_groups=list(geom_groups), cam_active=[self.camera_id])
        enabled = np.isin(mj_model.geom_group, geom_groups)
        self.refit = bool(np.any(mj_model.body_weldid[mj_model.geom_bodyid[enabled]] != 0))
        self._depth = self.rc.depth_data.reshape((self.nworld, self.height, self.width))

    def intrinsics(self) -> tuple[float, float, float, float]:
        """``fx, fy, cx, cy`` in pixels (pinhole; the CPU camera's)."""
        f = 0.5 * self.height / np.tan(np.radians(self.config.fovy_deg) / 2.0)
        return float(f), float(f), self.width / 2.0, self.height / 2.0

    def depth(self, data: Any, *, bounds_xy_m: Any = None) -> Any:
        """Planar depth in m of every world from ``data``'s current kinematics: a Warp array
        (N, height, width) float32, row 0 at the top, 0 where nothing is seen. The render
        context's own buffer: overwritten by the next call; ``wp.to_torch`` views it.

        ``bounds_xy_m`` (N, 4), optional: each world's rectangle ``x0, y0, x1, y1`` in the
        model frame; a pixel that sees a point outside it sees nothing (a tiled batch's
        neighbouring tiles, as :meth:`BatchLidar.scan <.lidar.BatchLidar.scan>`)."""
        import warp as wp

        from marsscene.sensors.batch import _kernels
        from marsscene.sensors.batch.lidar import check_bounds

        if data.nworld != self.nworld:
            raise ConfigError(f"BatchDepthCamera was made for {self.nworld} worlds; data has "
                              f"{data.nworld}")
        clip = check_bounds(bounds_xy_m, self.nworld)
        if self.refit:
            self._mjw.refit_bvh(self.model, data, self.rc)
        self._mjw.render(self.model, data, self.rc)
        if clip:
            rays = self.rc.ray[: self.width * self.height]
            wp.launch(_kernels.clip_depth, dim=self.rc.depth_data.shape,
                      inputs=[rays, data.cam_xpos, data.cam_xmat, self.camera_id, bounds_xy_m],
                      outputs=[self.rc.depth_data], device=self.rc.depth_data.device)
        return self._depth
