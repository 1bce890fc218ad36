"""The mast camera's RGB and depth (and segmentation) in every world of a batch, ray traced in
Warp: the world the CPU camera (:class:`~marsscene.sensors.camera.MastCamera`) sees.

**Why a ray tracer of its own**, not MuJoCo Warp's batch renderer with Warp kernels after it.
The renderer draws the physics model: its rocks are the heightfield's relief (blocky domes of
0.25 m posts), its terrain one grey material; it has no texture on a heightfield, no sky, no fog
and one set of lights for all worlds. Post-processing its depth could add the ground's albedo
(the hit point from the depth), the sky and the fog, but not the rocks' meshes (thousands of
mesh geoms in the physics model slow every step; a second render model needs a second BVH and
render pass) nor a sun per world (its shadows come from the model's lights): the shading pass
would cast its own shadow rays anyway, so only the primary ray would be the renderer's. That
primary ray is the cheap part: on one H200 a plain Warp kernel marching a heightfield traced
2.37 G rays/s where the renderer's depth pass gave 1.49 G pixels/s (issue 64; on this machine's
Warp CPU device, 16 rovers at 64 x 64, the renderer's depth-only pass took 130 ms a batch and
this camera's whole RGB-D frame 231 ms: ``perf/speed/bench_batch_sensors.py``). So one kernel
(:mod:`._trace`) does it all: the terrain posts marched cell by cell, every rock of the batch in
one static ``wp.Mesh`` BVH, the albedo looked up by world xy, a shadow ray to the sun, the sky
for misses, fog; then exposure and sRGB (:mod:`._expose`). Each camera has its own lighting.

What it draws (:mod:`.appearance`): the CPU camera's regolith detail tile (micro-relief shading
baked in) times each world's large-scale albedo field, on the world's full-resolution posts
(the CPU camera's near mesh; its far mesh, beyond 8 m or so, has every second post), marched
an 8 x 8-cell block at a time past blocks wholly below the ray; the batch's rocks (the MJCF
rocks its physics has) and, when given, the catalogue's smaller rocks and the scene's placed
assets, as jittered 80-face icospheres (rocks) with the CPU camera's rock colours. With
``sensor_noise`` each frame carries the CPU camera's shot and read noise. What differs from
the CPU camera (measured in :doc:`/batch_sensors`): shadows are hard (the CPU's terrain
shadows have the sun disc's penumbra); the rover itself is not drawn and casts no shadow.
Depth is planar, 0 where the pixel sees sky.
The same inputs give the same bytes (no atomics but the exposure's integer histograms).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.errors import ConfigError
from marsscene.sensors.batch.appearance import (
    GAIN_STEP_M,
    appearance,
    light_arrays,
    rock_mesh,
)
from marsscene.sensors.camera import MAX_EXPOSURE_GAIN
from marsscene.sensors.exposure import FULL_WELL_E, READ_NOISE_E, Exposure

__all__ = ["BatchCamera", "camera_rays", "scene_lights"]

#: The CPU camera's near clip (m).
NEAR_M = 0.05
#: A shadow ray starts this far off the surface along its normal (m).
SHADOW_LIFT_M = 0.01
#: The CPU camera's auto-exposure settings (clipped share, smoothing).
_AE = Exposure()


def camera_rays(config: Any) -> np.ndarray:
    """Camera-frame rays of every pixel (H * W, 3), row 0 at the top, MuJoCo's camera frame
    (x right, y up, looking along -z), z = -1: a ray's parameter is planar depth."""
    w, h = int(config.width_px), int(config.height_px)
    f = 0.5 * h / math.tan(math.radians(config.fovy_deg) / 2.0)
    c, r = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)
    return np.stack([(c - w / 2.0) / f, -(r - h / 2.0) / f, -np.ones_like(c)],
                    axis=-1).reshape(-1, 3).astype(np.float32)


def scene_lights(config: Any, scene_dir: Any = None) -> Any:
    """The CPU camera's :class:`~marsscene.lighting.Lighting`: the scene folder's lighting (or
    the lighting stage's defaults), with the camera config's tau, sun and irradiance scale."""
    from marsscene.sensors.camera_scene import scaled_irradiance, scene_lighting

    folder = Path(scene_dir) if scene_dir is not None else Path(__file__)  # no manifest
    return scaled_irradiance(scene_lighting(
        folder, tau=config.tau, sun_elevation_deg=config.sun_elevation_deg,
        sun_azimuth_deg=config.sun_azimuth_deg), config.irradiance_scale)


class BatchCamera:
    """RGB-D cameras of N rovers on the worlds of a ``WorldBatch``, on one Warp device.

    Parameters
    ----------
    batch : WorldBatch
        The worlds (terrain posts, rocks).
    num_cameras : int
        Cameras N.
    config : CameraConfig, optional
        Size, field of view, exposure (``"auto"`` or ``"fixed"``); default ``CameraConfig()``.
    lighting : Lighting or sequence of Lighting, optional
        Every camera's lighting, or one per camera (default :func:`scene_lights` of
        ``config``). The detail tile's micro-relief shading is baked for the first.
    offsets_xy_m : array (W, 2), optional
        The tile frame the poses are in, minus world coordinates (the batch model's
        ``TiledModel.offsets_xy_m``); default 0 (one world, or poses in world coordinates).
    seeds : sequence of int, optional
        Each world's scene seed (its albedo field; default ``0 .. W-1``); ``texture_seed`` the
        detail tile's and the rocks' colours (default ``seeds[0]``).
    catalogue : sequence of array (N, 6), optional
        Per world, the rock catalogue's rocks to draw beside the batch's (MJCF) rocks, as
        :func:`~marsscene.sensors.camera_rocks.read_rock_catalog` reads them (id, x, y, z,
        diameter, height + burial; world coordinates): the CPU camera's meshes and colours of
        them. Default: none (only the batch's rocks).
    rgb : bool
        False: depth and segmentation only (no shading, shadow rays, exposure or sRGB;
        :attr:`rgb` and :attr:`linear` stay zero), what a depth-only observer needs.
    device : str, optional
        Warp device (default the current one).
    """

    def __init__(self, batch: Any, num_cameras: int, *, config: Any = None,
                 lighting: Any = None, offsets_xy_m: Any = None, seeds: Any = None,
                 texture_seed: int | None = None, catalogue: Any = None,
                 noise_seeds: Any = None, assets: Any = None, fixed_exposure: Any = None,
                 rgb: bool = True, device: str | None = None) -> None:
        import warp as wp

        from marsscene.rover.config import CameraConfig
        from marsscene.sensors.batch._trace import BLOCK

        self.config = cfg = config if config is not None else CameraConfig()
        if cfg.exposure not in ("auto", "fixed"):
            raise ConfigError(f"exposure {cfg.exposure!r}; use 'auto' or 'fixed'")
        self.width, self.height, self.n = int(cfg.width_px), int(cfg.height_px), int(num_cameras)
        self.shaded = bool(rgb)
        self.device = wp.get_device(device)
        lightings = (list(lighting) if isinstance(lighting, (list, tuple)) else
                     [lighting if lighting is not None else scene_lights(cfg)] * self.n)
        if len(lightings) != self.n:
            raise ConfigError(f"{len(lightings)} lightings for {self.n} cameras")
        self.lighting = lightings[0]
        per = [light_arrays(lt) for lt in lightings]
        self.lights = per[0]
        nw = batch.count
        seeds = list(seeds) if seeds is not None else list(range(nw))
        off = (np.zeros((nw, 2)) if offsets_xy_m is None
               else np.asarray(offsets_xy_m, dtype=np.float64).reshape(nw, 2))
        look = appearance(batch, self.lighting, seeds=seeds,
                          texture_seed=seeds[0] if texture_seed is None else texture_seed,
                          tile_m=cfg.texture_tile_m, tile_px=cfg.texture_px)
        if catalogue is not None and len(catalogue) != nw:
            raise ConfigError(f"{len(catalogue)} rock catalogues for {nw} worlds")
        if assets is not None and len(assets) != nw:
            raise ConfigError(f"{len(assets)} asset meshes for {nw} worlds")
        verts, faces, vnormal, albedo = rock_mesh(batch, off, look.rng, catalogue, assets)
        sx, sy = batch.size_m
        self.far_m = float(math.hypot(sx, sy) + 10.0)
        def arr(a: Any, t: Any) -> Any:
            return wp.array(np.ascontiguousarray(a), dtype=t, device=self.device)

        self._points = arr(verts, wp.vec3)
        self._faces = arr(faces.ravel(), int)
        self.mesh = wp.Mesh(points=self._points, indices=self._faces)
        n, hw = self.n, self.width * self.height
        self._static = dict(
            rays=arr(camera_rays(cfg), wp.vec3),
            posts=arr(batch.posts_z_m.astype(np.float32), float),
            tops=arr(block_tops(batch.posts_z_m.astype(np.float32), int(BLOCK)), float),
            grid_origin=arr(np.asarray(batch.origins_xy_m) + off, wp.vec2),
            z_top=arr(_tops_z_m(batch, catalogue, assets), float),
            offset=arr(off, wp.vec2), vnormal=arr(vnormal, wp.vec3),
            face_albedo=arr(albedo, wp.vec3),
            tile=arr(np.concatenate([t.reshape(-1, 3) for t in look.tile_rgb]), wp.vec3),
            gain=arr(look.gain, float), gain_corner=arr(look.gain_origin_xy_m, wp.vec2),
            sun_dir=arr([lt.sun_dir for lt in per], wp.vec3),
            sun_rgb=arr([lt.sun_rgb for lt in per], wp.vec3),
            sky_rgb=arr([lt.sky_rgb for lt in per], wp.vec3),
            visibility_m=arr([lt.visibility_m for lt in per], float),
            max_gain=arr([MAX_EXPOSURE_GAIN * lt.fixed_scale for lt in per], float),
            fixed_gain=arr([float(cfg.exposure_gain) * lt.fixed_scale for lt in per], float))
        self._cell_m, self._texel_m = float(batch.cell_m), float(look.tile_texel_m)
        self._levels, self._tile_px = len(look.tile_rgb), int(look.tile_rgb[0].shape[0])
        zeros = lambda shape, t: wp.zeros(shape, dtype=t, device=self.device)  # noqa: E731
        self.linear = zeros((n, hw), wp.vec3)
        self._depth, self._seg = zeros((n, hw), float), zeros((n, hw), wp.uint8)
        self.rgb = zeros((n, 3, self.height, self.width), wp.uint8)
        self.depth = self._depth.reshape((n, self.height, self.width))
        self.segmentation = self._seg.reshape((n, self.height, self.width))
        self.gain = zeros(n, float)
        self._hist, self._peak = zeros((n, 256), int), zeros((n, 256), int)
        self._world: Any = None
        noise = (np.arange(n) if noise_seeds is None else np.asarray(noise_seeds)).astype(
            np.int64) % (2 ** 31)
        if len(noise) != n:
            raise ConfigError(f"{len(noise)} noise seeds for {n} cameras")
        self._noise_seeds, self._frame = arr(noise.astype(np.int32), int), 0
        mask = (np.full(n, cfg.exposure == "fixed") if fixed_exposure is None
                else np.asarray(fixed_exposure, dtype=bool))
        if mask.shape != (n,):
            raise ConfigError(f"{mask.size} exposures for {n} cameras")
        self._fixed = arr(mask.astype(np.int32), int) if 0 < mask.sum() < n else None
        self._all_fixed = bool(mask.all())

    def intrinsics(self) -> tuple[float, float, float, float]:
        """``fx, fy, cx, cy`` in pixels (pinhole; the CPU camera's)."""
        f = 0.5 * self.height / math.tan(math.radians(self.config.fovy_deg) / 2.0)
        return f, f, self.width / 2.0, self.height / 2.0

    def restart(self) -> None:
        """Forget the auto exposure's gains (a new drive's first frame sets them afresh)."""
        self.gain.zero_()

    def render(self, cam_xpos: Any, cam_xmat: Any, world: Any, *, camera: int = 0) -> Any:
        """Render every camera: poses ``cam_xpos[i, camera]`` (vec3) and ``cam_xmat[i, camera]``
        (mat33, MuJoCo's camera frame) in the tile frame, camera ``i`` on world ``world[i]``
        (int32 Warp array or array-like (N,)). Fills :attr:`rgb` (N, 3, H, W) uint8 sRGB,
        :attr:`depth` (N, H, W) float32 planar m (0: sky), :attr:`segmentation` (N, H, W)
        uint8 (0 sky, 1 terrain, 2 rock) and :attr:`linear` (a camera made with ``rgb=False``:
        depth and segmentation only); returns :attr:`rgb`. The
        buffers are the camera's own, overwritten by the next call (``wp.to_torch`` views
        them); nothing is copied to the host. With ``config.sensor_noise`` each frame carries
        the CPU camera's shot and read noise, camera ``i``'s from its ``noise_seeds[i]`` and
        the frame's count since the camera was made."""
        import warp as wp

        from marsscene.sensors.batch import _expose, _trace

        if tuple(cam_xpos.shape[:1]) != (self.n,):
            raise ConfigError(f"BatchCamera was made for {self.n} cameras; the poses hold "
                              f"{cam_xpos.shape[0]}")
        self._world = w = (world if isinstance(world, wp.array) else
                           wp.array(np.asarray(world, dtype=np.int32), dtype=int,
                                    device=self.device))
        s, n, hw, dev = self._static, self.n, self.width * self.height, self.device
        wp.launch(_trace.trace, dim=(n, hw), device=dev, inputs=[
            cam_xpos, cam_xmat, int(camera), s["rays"], w, s["posts"], s["tops"],
            s["grid_origin"], s["z_top"], self._cell_m, s["offset"], self.mesh.id, self._faces,
            s["vnormal"],
            s["face_albedo"], s["tile"], self._levels, self._tile_px, self._texel_m,
            1.0 / self.intrinsics()[0], s["gain"], s["gain_corner"],
            GAIN_STEP_M, s["sun_dir"], s["sun_rgb"], s["sky_rgb"], s["visibility_m"], NEAR_M,
            self.far_m, SHADOW_LIFT_M, int(self.shaded)],
            outputs=[self.linear, self._depth, self._seg])
        if not self.shaded:
            return self.rgb
        cfg = self.config
        if self._all_fixed:
            wp.copy(self.gain, self._static["fixed_gain"])
        else:
            sub_r, sub_c = -(-self.height // 4), -(-self.width // 4)
            self._hist.zero_()
            self._peak.zero_()
            wp.launch(_expose.histogram, dim=(n, sub_r * sub_c), device=dev,
                      inputs=[self.linear, self.width, sub_c], outputs=[self._hist, self._peak])
            wp.launch(_expose.auto_gain, dim=n, device=dev, inputs=[
                self._hist, self._peak, float(cfg.target_mean), _AE.max_saturated,
                s["max_gain"], _AE.smoothing],
                outputs=[self.gain])
            if self._fixed is not None:  # some cameras keep their fixed gain
                wp.launch(_expose.keep_fixed, dim=n, device=dev,
                          inputs=[self._fixed, s["fixed_gain"]], outputs=[self.gain])
        if cfg.sensor_noise:
            wp.launch(_expose.encode_noisy, dim=(n, hw), device=dev,
                      inputs=[self.linear, self.gain, self.width, self._noise_seeds,
                              self._frame, FULL_WELL_E, READ_NOISE_E], outputs=[self.rgb])
        else:
            wp.launch(_expose.encode, dim=(n, hw), device=dev,
                      inputs=[self.linear, self.gain, self.width], outputs=[self.rgb])
        self._frame += 1
        return self.rgb

    def render_data(self, data: Any, world: Any, camera_id: int) -> Any:
        """:meth:`render` from a MuJoCo Warp ``Data``'s camera poses (``cam_xpos``, after
        ``kinematics`` and ``camlight``) of the model's camera ``camera_id``."""
        return self.render(data.cam_xpos, data.cam_xmat, world, camera=camera_id)


def block_tops(posts_z_m: NDArray[np.float32], block: int) -> NDArray[np.float32]:
    """(W, ceil((rows - 1) / block), ceil((cols - 1) / block)): the highest post of each block
    of ``block`` x ``block`` cells of every world's posts (W, rows, cols), its edge posts
    included."""
    nw, rows, cols = posts_z_m.shape
    nr, nc = -(-(rows - 1) // block), -(-(cols - 1) // block)
    z = np.full((nw, nr * block + 1, nc * block + 1), -np.inf, dtype=np.float32)
    z[:, :rows, :cols] = posts_z_m
    z = np.maximum(z[:, :-1].reshape(nw, nr, block, -1).max(axis=2), z[:, block::block])
    return np.maximum(z[:, :, :-1].reshape(nw, nr, nc, block).max(axis=3),
                      z[:, :, block::block]).astype(np.float32)


def _tops_z_m(batch: Any, catalogue: Any, assets: Any) -> NDArray[np.float64]:
    """(W,) a height above every world's terrain, rocks and assets (m)."""
    nw = batch.count
    top = batch.posts_z_m.reshape(nw, -1).max(axis=1) + np.array(
        [_rock_top(batch, w) for w in range(nw)])
    for w, rocks in enumerate(catalogue or ()):
        rk = np.asarray(rocks, dtype=np.float64).reshape(-1, 6)
        top[w] = max(top[w], float(np.max(rk[:, 3] + rk[:, 5], initial=-np.inf)) + 0.01)
    for w, mesh in enumerate(assets or ()):
        if mesh is not None and len(mesh.vertices_m):
            top[w] = max(top[w], float(np.max(mesh.vertices_m[:, 2])) + 0.01)
    return np.asarray(top, dtype=np.float64)


def _rock_top(batch: Any, w: int) -> float:
    """How far world ``w``'s rocks rise above its highest post at most (m)."""
    k = np.asarray(batch.rock_world) == w
    return float(np.max(batch.rock_height_m[k], initial=0.0)) + 0.01
