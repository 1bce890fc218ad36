"""The mast RGB-D camera: MuJoCo offscreen rendering (``MUJOCO_GL=egl`` or ``osmesa``).

A software GL (llvmpipe) spends ~0.5 us per terrain post per frame, so a 1389 x 1345 terrain
costs ~0.9 s a frame. When the terrain is larger than ``CameraConfig.terrain_window_m``, the
camera renders a second model whose hfield is a full-resolution window around the rover; the
window is re-centred (and re-uploaded to GL) when the rover has moved a quarter of it. Rocks
and every other geom are rendered as in the simulation.
"""

from __future__ import annotations

import os
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from marsscene.errors import RuntimeSimError

__all__ = ["MastCamera"]


class MastCamera:
    """Offscreen renderer of a :class:`~marsscene.runtime.sim.RoverSim`'s ``navcam``."""

    def __init__(self, sim: Any) -> None:
        cam = sim.run.camera
        self.width: int = cam.width_px if cam is not None else 320
        self.height: int = cam.height_px if cam is not None else 240
        self.depth = cam.depth if cam is not None else True
        self.shadows = cam.shadows if cam is not None else False
        window_m = cam.terrain_window_m if cam is not None else 60.0
        hf = sim.heightfield
        self.n = int(window_m / hf.cell_size_m) // 2 * 2 + 1
        rows, cols = hf.shape
        self.windowed = self.n < rows or self.n < cols
        self.model, self.data = sim.model, sim.data
        if self.windowed:
            self.nr, self.nc = min(self.n, rows), min(self.n, cols)
            spec = sim.build_spec()
            h = spec.hfield("terrain")
            h.file = ""
            h.nrow, h.ncol = self.nr, self.nc
            h.userdata = np.zeros(self.nr * self.nc).tolist()
            size = list(h.size)
            h.size = [
                (self.nc - 1) * hf.cell_size_m / 2,
                (self.nr - 1) * hf.cell_size_m / 2,
                size[2],
                size[3],
            ]
            self.model = spec.compile()
            self.data = mujoco.MjData(self.model)
            self.terrain_geom = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, "terrain")
            self.hfield_id = int(self.model.geom_dataid[self.terrain_geom])
            self.z_min = float(hf.z_m.min())
            self.z_range = float(size[2])
            self.origin: tuple[int, int] | None = None
        self.camera_id = sim.camera_id
        self.vis = mujoco.MjvOption()
        self.vis.geomgroup[3] = 1  # the terrain lives in group 3 (see RoverSim)
        try:
            self.renderer = mujoco.Renderer(self.model, height=self.height, width=self.width)
        except Exception as err:
            raise RuntimeSimError(
                f"cannot create an offscreen renderer (MUJOCO_GL={os.environ.get('MUJOCO_GL')!r}):"
                f" {err}; install EGL or OSMesa (apt-get install libosmesa6) and set MUJOCO_GL "
                "before importing mujoco"
            ) from None

    def _recentre(self, sim: Any) -> None:
        hf = sim.heightfield
        rows, cols = hf.shape
        x, y = sim.pose()[0][:2]
        r, c = hf.rowcol_of(x, y)
        r0 = int(np.clip(round(float(r)) - self.nr // 2, 0, rows - self.nr))
        c0 = int(np.clip(round(float(c)) - self.nc // 2, 0, cols - self.nc))
        if self.origin is not None:
            dr, dc = abs(r0 - self.origin[0]), abs(c0 - self.origin[1])
            if max(dr, dc) < self.n // 4:
                return
        self.origin = (r0, c0)
        win = hf.z_m[r0 : r0 + self.nr, c0 : c0 + self.nc].astype(np.float64)
        m = self.model
        adr = int(m.hfield_adr[self.hfield_id])
        m.hfield_data[adr : adr + win.size] = ((win - self.z_min) / self.z_range).ravel()
        cx, cy = hf.xy_of(r0 + (self.nr - 1) / 2, c0 + (self.nc - 1) / 2)
        m.geom_pos[self.terrain_geom] = (float(cx), float(cy), self.z_min)
        ctx = self.renderer._mjr_context
        if self.renderer._gl_context:
            self.renderer._gl_context.make_current()
        mujoco.mjr_uploadHField(m, ctx, self.hfield_id)

    def render(self, sim: Any) -> tuple[NDArray[np.uint8], NDArray[np.float32] | None]:
        """RGB (H, W, 3) uint8 and depth (H, W) float32 in m (None if depth is off)."""
        if self.windowed:
            self._recentre(sim)
            self.data.qpos[:] = sim.data.qpos
            mujoco.mj_kinematics(self.model, self.data)
            mujoco.mj_camlight(self.model, self.data)
        r = self.renderer
        r.disable_depth_rendering()
        r.update_scene(self.data, camera=self.camera_id, scene_option=self.vis)
        r.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = self.shadows
        r.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = False
        rgb = r.render().copy()
        depth = None
        if self.depth:
            r.enable_depth_rendering()
            r.update_scene(self.data, camera=self.camera_id, scene_option=self.vis)
            depth = r.render().astype(np.float32)
            r.disable_depth_rendering()
        return rgb, depth

    def close(self) -> None:
        self.renderer.close()
