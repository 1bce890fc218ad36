"""The mast camera (mono RGB-D, optional Navcam-like stereo): MuJoCo offscreen rendering.

``MUJOCO_GL=egl`` (or ``osmesa``). The camera renders its own model of the scene
(:class:`marsscene.sensors.camera_world.CameraWorld`): smooth terrain meshes around the rover
with baked, non-repeating ground textures (:mod:`marsscene.sensors.camera_ground`) and every
catalogue rock in the window as visual-only meshes. Lighting comes from the scene's lighting
stage (manifest), in linear units:

* sun: directional light, colour ``k E_dn sun_rgb``; shadow map centred on the camera;
* sky: ambient ``k E_diffuse sky_rgb`` and a skybox of radiance ``E_diffuse / pi`` (zenith
  0.8x, horizon 1.2x); dust fog with the meteorological visibility (``3.912 H / tau``);

where ``k`` scales the brightest sunlit surface to just below 1. The image is then exposed
(:class:`marsscene.sensors.exposure.Exposure`: auto-exposure, or fixed), optionally with
seeded shot + read noise, and sRGB-encoded. Depth is metric (m), read from the depth buffer
of the same render pass (:class:`marsscene.sensors.offscreen.OffscreenView`).
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from marsscene.errors import RuntimeSimError
from marsscene.sensors.camera_scene import (
    scaled_irradiance,
    scene_albedo_field,
    scene_lighting,
)
from marsscene.sensors.camera_shadow import shade_mesh_geoms
from marsscene.sensors.camera_world import ALBEDO_SCALE, CameraWorld
from marsscene.sensors.exposure import Exposure
from marsscene.sensors.offscreen import OffscreenView

__all__ = ["MastCamera", "scene_lighting", "shadow_light_position"]

#: Fixed-exposure mode: linear 1.0 is a surface of albedo ALBEDO_SCALE under this irradiance.
FIXED_REFERENCE_W_M2 = 600.0
#: Longest exposure of the auto mode, as a gain in the fixed mode's units (e.g. 1 ms at gain 1
#: up to 100 ms, a 10 Hz frame's whole period): twilight far below the horizon stays dark.
MAX_EXPOSURE_GAIN = 100.0
#: The sun's shadow map (rocks' and the rover's shadows; the terrain's come from
#: camera_shadow): an orthographic box of +-_SHADOW_CLIP_M around the ground ahead of the
#: camera with _SHADOW_MAP_PX texels a side, 1.3 cm texels. At 1024 (3.9 cm) the rover's mast
#: cast a saw-tooth strip at the bottom of the image (a texel is ~7 px at 3 m) and a 2 deg sun
#: stretched texels 1 / sin(elevation) along the ground into blocky rock-shadow ends; 4096
#: costs ~25 % more per frame on llvmpipe, 3072 ~10-15 % (:doc:`/camera`)
_SHADOW_CLIP_M = 20.0
_SHADOW_MAP_PX = 3072
_SKY_ZFAR_FRACTION = 0.45


class MastCamera:
    """Offscreen renderer of a :class:`~marsscene.sim.rover_sim.RoverSim`'s mast camera(s)."""

    def __init__(self, sim: Any, *, rng: np.random.Generator | None = None,
                 config: Any = None) -> None:
        from marsscene.rover.config import CameraConfig

        cam = config if config is not None else (
            sim.run.camera if sim.run.camera is not None else CameraConfig())
        self.config = cam
        self.width, self.height = cam.width_px, cam.height_px
        self.depth = cam.depth
        self.noise_rng = rng if cam.sensor_noise else None
        lt = scaled_irradiance(
            scene_lighting(sim.scene_dir, tau=cam.tau, sun_elevation_deg=cam.sun_elevation_deg,
                           sun_azimuth_deg=cam.sun_azimuth_deg), cam.irradiance_scale)
        self.lighting = lt
        share = lt.direct_horizontal_w_m2 / max(lt.global_horizontal_w_m2, 1e-9)
        from marsscene.seeding import stage_rng
        from marsscene.sensors.camera_scene import scene_seed

        seed = scene_seed(sim.scene_dir)
        self.world = CameraWorld(
            sim.heightfield, Path(sim.scene_dir), window_m=cam.terrain_window_m,
            tile_m=cam.texture_tile_m, tile_px=cam.texture_px,
            sun_direction_enu=lt.sun_direction_enu, direct_share=share,
            rng=stage_rng(seed, "texture"),
            field=scene_albedo_field(sim.scene_dir, sim.heightfield),
            near_m=cam.near_window_m, far_stride=cam.far_post_stride,
            terrain_shadows=bool(cam.shadows),
            sun_radius_rad=math.radians(lt.sun_angular_diameter_deg / 2.0),
            outer=getattr(sim, "outer_heightfield", None),
        )
        rows, cols = sim.heightfield.shape
        self.windowed = self.world.nr < rows or self.world.nc < cols
        spec = sim.build_spec()
        self._edit(spec, sim, lt)
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        self.world.update(self.model, tuple(sim.pose()[0][:2]), _forward_xy(sim), force=True)
        name = lambda n: mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_CAMERA, n)  # noqa: E731
        self.camera_id = name(sim.prefix + "navcam")
        self.stereo_ids = (name("cam_left"), name("cam_right")) if cam.stereo else None
        self.sun_id = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_LIGHT, "sun")
        m = self.model
        self.rock_geoms = np.flatnonzero(
            (m.geom_bodyid == 0) & (m.geom_type == mujoco.mjtGeom.mjGEOM_MESH)
            & (m.geom_contype != 0))
        if self.world.sun_shadow is not None:  # MJCF rocks standing in terrain shadows
            shade_mesh_geoms(m, self.rock_geoms, self.world.sun_shadow)
        if self.world.rocks_baked:  # their shadows are in the ground's sun layer
            m.geom_castshadow[self.rock_geoms] = 0
        self._show_window_rocks()
        self._flags = {mujoco.mjtRndFlag.mjRND_SHADOW: bool(cam.shadows),
                       mujoco.mjtRndFlag.mjRND_REFLECTION: False,
                       mujoco.mjtRndFlag.mjRND_FOG: True,
                       mujoco.mjtRndFlag.mjRND_SKYBOX: True}
        # the render's linear values in the fixed mode's units (the render itself is scaled to
        # use the 8 bits of the GL buffer in either mode: no banding in dark fixed exposures)
        scale = 1.0 / (FIXED_REFERENCE_W_M2 * self.render_scale)
        self._exposure_args = {"target_mean": cam.target_mean, "fixed_gain": cam.exposure_gain,
                               "input_scale": scale, "max_gain": MAX_EXPOSURE_GAIN}
        self.exposure, self.exposure_stereo = (
            Exposure(cam.exposure, **self._exposure_args) for _ in range(2))
        try:
            self.view = OffscreenView(self.model, width=self.width, height=self.height)
        except Exception as err:
            raise RuntimeSimError(
                f"cannot create an offscreen renderer (MUJOCO_GL={os.environ.get('MUJOCO_GL')!r}):"
                f" {err}; install EGL or OSMesa (apt-get install libosmesa6) and set MUJOCO_GL "
                "before importing mujoco"
            ) from None
        self._upload()

    # ---- model edits ---------------------------------------------------------------------------
    def _edit(self, spec: Any, sim: Any, lt: Any) -> None:
        cam = self.config
        # the terrain hfields (and a level-of-detail scene's coarse outer one) are not drawn:
        # the window meshes are. Left in the camera's model, hidden, MuJoCo's GL context would
        # still upload them as triangles (~170 B per post: 4.3 GB and 28 s for grand-canyon's
        # 25 M posts), so they are taken out of this model (the simulation keeps them)
        for name in ("terrain", "terrain_outer"):
            geom = spec.geom(name)
            if geom is not None:
                hfield = spec.hfield(geom.hfieldname) if geom.hfieldname else None
                spec.delete(geom)
                if hfield is not None:
                    spec.delete(hfield)
        for geom in spec.geoms:  # MJCF collision rocks: literature rock colour
            if geom.material == "rock":
                geom.material = "cam_rock_geom"
        spec.add_material(name="cam_rock_geom", rgba=[0.2 / ALBEDO_SCALE * 0.9,
                                                       0.145 / ALBEDO_SCALE * 0.9,
                                                       0.11 / ALBEDO_SCALE * 0.9, 1.0],
                          specular=0.0, shininess=0.0, reflectance=0.0)
        self.world.add_to_spec(spec, tuple(sim.pose()[0][:2]), _forward_xy(sim))
        e_dn, e_dif = lt.direct_normal_w_m2, lt.diffuse_horizontal_w_m2
        # render units: the brightest case (albedo ALBEDO_SCALE facing the sun, plus the sky;
        # or the skybox's horizon, 1.2 E_diffuse / pi) just below 1 in either exposure mode;
        # Exposure.input_scale converts for fixed gains
        k = 0.95 / max(e_dn + e_dif, 1.2 * e_dif / ALBEDO_SCALE, 1e-6)
        self.render_scale = k
        sun_rgb, sky_rgb = np.asarray(lt.sun_color_rgb), np.asarray(lt.sky_color_rgb)
        for light in spec.lights:
            light.active = light.name == "sun"
        sun = spec.light("sun")
        if sun is None:
            sun = spec.worldbody.add_light(name="sun")
        sun.type = mujoco.mjtLightType.mjLIGHT_DIRECTIONAL
        sun.dir = [-c for c in lt.sun_direction_enu]
        sun.diffuse = (k * e_dn * sun_rgb).tolist()
        sun.specular = [0.0, 0.0, 0.0]
        sun.ambient = [0.0, 0.0, 0.0]
        sun.castshadow = bool(cam.shadows)
        vis = spec.visual
        vis.headlight.ambient = (k * e_dif * sky_rgb).tolist()
        vis.headlight.diffuse = [0.0, 0.0, 0.0]
        vis.headlight.specular = [0.0, 0.0, 0.0]
        sky = k * e_dif * sky_rgb / ALBEDO_SCALE  # radiance E_diffuse / pi, in render units
        skybox = next((t for t in spec.textures
                       if t.type == mujoco.mjtTexture.mjTEXTURE_SKYBOX), None)
        if skybox is None:
            skybox = spec.add_texture(name="cam_sky", type=mujoco.mjtTexture.mjTEXTURE_SKYBOX,
                                      width=64, height=64)
        skybox.builtin = mujoco.mjtBuiltin.mjBUILTIN_GRADIENT
        skybox.file = ""
        skybox.rgb1 = np.clip(0.8 * sky, 0, 1).tolist()
        skybox.rgb2 = np.clip(1.2 * sky, 0, 1).tolist()
        extent = max(cam.terrain_window_m, 10.0)
        spec.stat.extent = extent
        vis.map.znear = 0.05 / extent
        vis.map.zfar = 4.0
        vis.map.shadowclip = _SHADOW_CLIP_M / extent
        vis.quality.shadowsize = _SHADOW_MAP_PX
        vis.quality.offsamples = 0
        vis.global_.offwidth = max(int(cam.width_px), 640)
        vis.global_.offheight = max(int(cam.height_px), 480)
        vis_m = lt.visibility_m if math.isfinite(lt.visibility_m) else 1e9
        vis.map.fogstart = 0.0
        vis.map.fogend = float(min(vis_m, 1e9) / extent)
        vis.rgba.fog = [*np.clip(1.2 * sky, 0, 1).tolist(), 1.0]
        if cam.stereo:
            body = spec.body(sim.prefix + "base_link")
            pos = np.asarray(sim.model.cam_pos[sim.camera_id], dtype=np.float64)
            quat = np.asarray(sim.model.cam_quat[sim.camera_id], dtype=np.float64)
            fovy = float(sim.model.cam_fovy[sim.camera_id])
            for name, dy in (("cam_left", cam.stereo_baseline_m / 2),
                             ("cam_right", -cam.stereo_baseline_m / 2)):
                body.add_camera(name=name, pos=(pos + np.array([0.0, dy, 0.0])).tolist(),
                                quat=quat.tolist(), fovy=fovy)

    def _upload(self, far: bool = True, near: bool = True) -> None:
        mesh = lambda n: mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_MESH, n)  # noqa: E731
        tex = lambda n: mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_TEXTURE, n)  # noqa: E731
        layers = self.world.layers
        for name in (*("cam_terrain" + x for x in layers), *(lod.name for lod in self.world.lods)):
            self.view.upload_mesh(mesh(name))
        for layer in layers:
            if far:
                self.view.upload_texture(tex("cam_ground_far" + layer))
            if near:
                self.view.upload_mesh(mesh("cam_terrain_near" + layer))
                self.view.upload_texture(tex("cam_ground_near" + layer))

    def restart(self, sim: Any, *, rng: np.random.Generator | None = None) -> None:
        """Start a new drive with this renderer (its scene is built once): fresh exposure
        state, a new noise stream, the terrain window placed at the rover's pose as a new
        renderer would place it."""
        cam = self.config
        self.noise_rng = rng if cam.sensor_noise else None
        self.exposure, self.exposure_stereo = (
            Exposure(cam.exposure, **self._exposure_args) for _ in range(2))
        self.world.update(self.model, tuple(sim.pose()[0][:2]), _forward_xy(sim), force=True)
        self._upload()
        self._show_window_rocks()

    # ---- rendering -----------------------------------------------------------------------------
    def _sync(self, sim: Any) -> None:
        xy = tuple(sim.pose()[0][:2])
        far, near = self.world.update(self.model, xy, _forward_xy(sim))
        if far or near:
            self._upload(far, near)
        if far:
            self._show_window_rocks()
        self.data.qpos[: sim.data.qpos.size] = sim.data.qpos
        mujoco.mj_kinematics(self.model, self.data)
        mujoco.mj_camlight(self.model, self.data)  # this frame's camera pose (cam_xpos)
        self.model.light_pos[self.sun_id] = shadow_light_position(
            self.data.cam_xpos[self.camera_id], self.data.cam_xmat[self.camera_id],
            self.lighting.sun_direction_enu)
        mujoco.mj_camlight(self.model, self.data)

    def _show_window_rocks(self) -> None:
        """MJCF rocks outside the terrain window would float in the sky: hide them."""
        x0, y0, x1, y1 = self.world.window_bounds_xy_m()
        p = self.model.geom_pos[self.rock_geoms]
        inside = (p[:, 0] >= x0) & (p[:, 0] <= x1) & (p[:, 1] >= y0) & (p[:, 1] <= y1)
        self.model.geom_group[self.rock_geoms] = np.where(inside, 0, 5)

    def _render(self, camera_id: int, depth: bool
                ) -> tuple[NDArray[np.float32], NDArray[np.float32] | None]:
        """Linear RGB in [0, 1] and (with ``depth``) metric depth from one render pass."""
        rgb, depth_m = self.view.render(self.data, camera_id, self._flags, depth=depth)
        linear = rgb.astype(np.float32) * np.float32(1.0 / 255.0)
        if depth_m is None:
            return linear, None
        # the lit pass draws the skybox camera-centred at >= ~0.5 zfar (measured 0.504); the
        # farthest terrain-window point is < 1.5 extent = 0.375 zfar: beyond 0.45 zfar is sky
        far = self.model.vis.map.zfar * self.model.stat.extent
        return linear, np.where(depth_m < _SKY_ZFAR_FRACTION * far, depth_m, 0.0).astype(
            np.float32)

    def _linear(self, camera_id: int) -> NDArray[np.float32]:
        return self._render(camera_id, False)[0]

    def render(self, sim: Any) -> tuple[NDArray[np.uint8], NDArray[np.float32] | None]:
        """RGB (H, W, 3) uint8 (exposed, sRGB) and depth (H, W) float32 in m (or None).

        One render pass fills both: the depth buffer of the lit RGB pass is read back too
        (0 where the ray meets the sky).
        """
        self._sync(sim)
        linear, depth = self._render(self.camera_id, self.depth)
        return self.exposure.apply(linear, self.noise_rng), depth

    def render_stereo(self, sim: Any) -> tuple[NDArray[np.uint8], NDArray[np.uint8]]:
        """Rectified stereo pair (left, right) at the current state (call after :meth:`render`)."""
        if self.stereo_ids is None:
            raise RuntimeSimError("the camera was configured without stereo")
        left = self.exposure_stereo.apply(self._linear(self.stereo_ids[0]), self.noise_rng)
        # both views share the left view's gain, as a synchronised stereo head does
        g = self.exposure_stereo.render_gain
        right_exp = Exposure("fixed", fixed_gain=g if g is not None else 1.0)
        right = right_exp.apply(self._linear(self.stereo_ids[1]), self.noise_rng)
        return left, right

    def close(self) -> None:
        self.view.close()


def shadow_light_position(cam_pos: Any, cam_xmat: Any, sun_direction: Any) -> NDArray[np.float64]:
    """World position of the sun's shadow-map camera for a mast camera at ``cam_pos``.

    The map is a box of +-_SHADOW_CLIP_M centred on the ground half that distance ahead of the
    camera, seen from 2 _SHADOW_CLIP_M up the sun's direction. The position is moved across
    the sun (by less than a texel) so that it falls on the map's texel lattice: MuJoCo's light
    view (``mjr_lookAt`` with ``mjr_orthoVec`` up) then puts every texel on a world-fixed
    lattice, so shadow edges neither shimmer nor jump between frames as the rover moves.
    """
    fwd = -np.asarray(cam_xmat, dtype=np.float64).reshape(3, 3)[:, 2]
    ahead = np.asarray(cam_pos, dtype=np.float64) + 0.5 * _SHADOW_CLIP_M * np.r_[fwd[:2], 0.0]
    s = np.asarray(sun_direction, dtype=np.float64)
    s = s / np.linalg.norm(s)
    eye = ahead + 2.0 * _SHADOW_CLIP_M * s
    # the light view's axes, as mjr_lookAt builds them for forward f = -s
    f = -s
    up = np.cross(f, [-1.0, 0.0, 0.0])
    if up @ up <= 0.01:
        up = np.cross(f, [0.0, 1.0, 0.0])
    side = np.cross(f, up)
    side /= np.linalg.norm(side)
    upv = np.cross(side, f)
    upv /= np.linalg.norm(upv)
    texel = 2.0 * _SHADOW_CLIP_M / (_SHADOW_MAP_PX - 2)  # mjr_render's viewport: size - 2
    for axis in (side, upv):
        c = axis @ eye
        eye = eye + (np.round(c / texel) * texel - c) * axis
    return eye


def _forward_xy(sim: Any) -> tuple[float, float]:
    """Horizontal viewing direction of the mast camera (its -z axis)."""
    fwd = -np.asarray(sim.data.cam_xmat[sim.camera_id]).reshape(3, 3)[:, 2]
    return float(fwd[0]), float(fwd[1])
