"""One offscreen MuJoCo render pass that yields both the RGB image and metric depth.

``mujoco.Renderer`` renders the scene once for RGB and again (flat, in segmentation mode) for
depth. The lit RGB pass already fills the depth buffer, so :meth:`OffscreenView.render_rgbd`
reads both buffers of that one pass (``mjr_readPixels(rgb, depth, ...)``) and converts the
reversed-Z depth buffer to metres with the model's ``znear``/``zfar`` exactly as
``mujoco.Renderer`` does (float32 projection coefficients, float64 arithmetic).
"""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

__all__ = ["OffscreenView", "depth_buffer_to_m"]


def depth_buffer_to_m(buffer: NDArray[np.float32], znear_m: float, zfar_m: float
                      ) -> NDArray[np.float32]:
    """Metric depth (m) of a reversed-Z (``mjDEPTH_ZEROFAR``) perspective depth buffer."""
    zfar, znear = np.float32(zfar_m), np.float32(znear_m)
    c = -(zfar + znear) / (zfar - znear)
    d = -(np.float32(2) * zfar * znear) / (zfar - znear)
    c = np.float32(-0.5) * c - np.float32(0.5)
    d = np.float32(-0.5) * d
    return (d / (buffer.astype(np.float64) + c)).astype(np.float32)


class OffscreenView:
    """An offscreen GL context, scene and framebuffer of ``width`` x ``height`` pixels;
    ``max_geom`` sizes the scene's geom buffer (default: the model's geoms and 100 more)."""

    def __init__(self, model: Any, *, width: int, height: int,
                 max_geom: int | None = None) -> None:
        from mujoco import gl_context

        self.model = model
        self.width, self.height = int(width), int(height)
        self._gl = None
        self._ctx = None
        if gl_context.GLContext is None:
            raise RuntimeError("no OpenGL context class (set MUJOCO_GL=egl or osmesa)")
        # the view owns the context's lifetime (free the MjrContext first, then the GL context)
        owned = type("_OwnedGLContext", (gl_context.GLContext,), {"__del__": lambda self: None})
        self._gl = owned(self.width, self.height)
        self._gl.make_current()
        # room for every geom of the model (a world of many rocks passes MuJoCo's usual
        # 1,000: the geoms past the buffer, the terrain among them, were not drawn)
        self.scene = mujoco.MjvScene(model, maxgeom=max_geom or max(1000, model.ngeom + 100))
        self.option = mujoco.MjvOption()
        self.camera = mujoco.MjvCamera()
        self.camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
        self._rect = mujoco.MjrRect(0, 0, self.width, self.height)
        self._ctx = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_100)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._ctx)
        self._ctx.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
        self._rgb = np.zeros((self.height, self.width, 3), dtype=np.uint8)
        self._depth = np.zeros((self.height, self.width), dtype=np.float32)

    def make_current(self) -> None:
        if self._gl is not None:
            self._gl.make_current()

    def upload_mesh(self, mesh_id: int) -> None:
        self.make_current()
        mujoco.mjr_uploadMesh(self.model, self._ctx, mesh_id)

    def upload_texture(self, tex_id: int) -> None:
        self.make_current()
        mujoco.mjr_uploadTexture(self.model, self._ctx, tex_id)

    def render(self, data: Any, camera_id: int, flags: dict[int, bool], *, depth: bool
               ) -> tuple[NDArray[np.uint8], NDArray[np.float32] | None]:
        """RGB (H, W, 3) uint8 and, with ``depth``, metric depth (H, W) float32 of one pass."""
        if self._ctx is None:
            raise RuntimeError("render called after close")
        self.make_current()
        self.camera.fixedcamid = int(camera_id)
        mujoco.mjv_updateScene(self.model, data, self.option, None, self.camera,
                               mujoco.mjtCatBit.mjCAT_ALL, self.scene)
        for flag, on in flags.items():
            self.scene.flags[flag] = on
        mujoco.mjr_render(self._rect, self.scene, self._ctx)
        mujoco.mjr_readPixels(self._rgb, self._depth if depth else None, self._rect, self._ctx)
        rgb = np.flipud(self._rgb).copy()  # GL rows start at the bottom
        if not depth:
            return rgb, None
        extent = self.model.stat.extent
        metres = depth_buffer_to_m(np.flipud(self._depth), self.model.vis.map.znear * extent,
                                   self.model.vis.map.zfar * extent)
        return rgb, metres

    def close(self) -> None:
        if self._ctx is not None:
            self.make_current()
            self._ctx.free()
            self._ctx = None
        if self._gl is not None:
            self._gl.free()
            self._gl = None

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:  # interpreter shutdown: GL may be gone already
            pass
