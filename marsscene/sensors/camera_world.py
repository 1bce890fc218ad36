"""The camera's view of a scene: textured, smooth terrain meshes and visual-only small rocks.

Built into a *separate* MuJoCo model that only the camera renders (the simulation model is not
changed; contacts keep the scene's rule):

* the terrain hfield is hidden and replaced by a near and a far **ground mesh** with
  per-vertex (smooth) normals and baked, world-anchored textures: the seeded regolith detail
  tile (:func:`marsscene.terrain.appearance.regolith_tile`, micro-relief shading baked in)
  times the large-scale albedo field (:mod:`marsscene.sensors.camera_ground`);
* every catalogue rock (``rocks.csv``, down to ``rocks.d_min_m``) in the window that is not an
  MJCF collision geom becomes part of **a merged visual mesh** (contype/conaffinity 0;
  :mod:`marsscene.sensors.camera_rocks`): a jittered icosphere per rock (80 faces near the
  camera, 20 elsewhere), scaled to its diameter and height, coloured per rock from
  :func:`marsscene.terrain.appearance.rock_albedo_rgb` through a texture atlas;
* at a low sun the terrain's shadows over the whole heightfield, and from a level-of-detail
  scene's coarse outer terrain too (:mod:`marsscene.sensors.camera_shadow`): the terrain
  meshes cast no shadow-map shadows, rocks in the terrain's shadow neither (they sit in
  meshes of their own); below ``BAKED_BELOW_DEG`` the rocks' shadows on the ground are baked
  into the same sun layer (:mod:`marsscene.sensors.rock_shadow`) and the rocks cast none into
  the shadow map.

All meshes have a fixed vertex count; when they move their vertex, normal and texcoord arrays
are rewritten in place and re-uploaded to GL (``mjr_uploadMesh``, ``mjr_uploadTexture``).
Textures hold ``albedo / ALBEDO_SCALE`` so that the renderer's 8 bits cover albedos up to 0.5.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from marsscene.sensors.camera_ground import GroundWindow
from marsscene.sensors.camera_rocks import (
    ATLAS,
    ATLAS_CELL_PX,
    PEBBLE_MAX_M,
    RockLOD,
    read_rock_catalog,
    rock_arrays,
    rock_look,
)
from marsscene.sensors.rock_shadow import BAKED_BELOW_DEG
from marsscene.terrain.albedo_field import AlbedoField
from marsscene.terrain.appearance import bump_shading, regolith_tile
from marsscene.terrain.heightfield import Heightfield
from marsscene.terrain.horizon import SUN_RADIUS_RAD, SunShadow, shadow_with_outer, sun_shadow

__all__ = ["ALBEDO_SCALE", "PEBBLE_MAX_M", "CameraWorld", "read_rock_catalog"]

#: Texture value 1.0 means this albedo.
ALBEDO_SCALE = 0.5


class CameraWorld:
    """Adds the camera's visual geometry to a spec and keeps it centred on the rover."""

    def __init__(
        self,
        heightfield: Heightfield,
        scene_dir: Path,
        *,
        window_m: float,
        tile_m: float,
        tile_px: int,
        sun_direction_enu: tuple[float, float, float],
        direct_share: float,
        rng: np.random.Generator,
        field: AlbedoField,
        near_m: float = 16.0,
        far_stride: int = 2,
        terrain_shadows: bool = True,
        sun_radius_rad: float = SUN_RADIUS_RAD,
        outer: Heightfield | None = None,
    ) -> None:
        self.hf = heightfield
        tile = regolith_tile(size_px=tile_px, tile_m=tile_m, rng=rng)
        shade = bump_shading(tile, sun_direction_enu, direct_share)
        # the terrain's shadows toward the sun over the whole heightfield (none with the sun on
        # or below the horizon: then there is no direct light to shadow); with them the ground
        # is drawn in two coincident layers, sun ("") and sky ("_sky": drawn after it)
        self.sun = np.asarray(sun_direction_enu, dtype=np.float64)
        self.sun_shadow: SunShadow | None = None
        if terrain_shadows and sun_direction_enu[2] > 0.0:
            self.sun_shadow = sun_shadow(heightfield, sun_direction_enu,
                                         sun_radius_rad=sun_radius_rad)
            if outer is not None:  # a level-of-detail scene: the coarse outer terrain casts too
                self.sun_shadow = shadow_with_outer(self.sun_shadow, sun_shadow(
                    outer, sun_direction_enu, sun_radius_rad=sun_radius_rad))
        self.layers: tuple[str, ...] = ("", "_sky") if self.sun_shadow is not None else ("",)
        # below BAKED_BELOW_DEG the rocks' shadows are baked into the sun layer too (the shadow
        # map's texels stretch along a low sun into blocks); then rocks cast none into the map
        elevation = math.degrees(math.atan2(self.sun[2], math.hypot(self.sun[0], self.sun[1])))
        self.rocks_baked = self.sun_shadow is not None and elevation < BAKED_BELOW_DEG
        self.ground = GroundWindow(
            heightfield, window_m=window_m, near_m=near_m, far_stride=far_stride,
            tile_u8=_to_u8(tile.albedo_rgb * shade[..., None] / ALBEDO_SCALE), tile_m=tile_m,
            field=field, sun_shadow=self.sun_shadow,
            shadow_rocks=read_rock_catalog(scene_dir, include_mjcf=True)
            if self.rocks_baked else None)
        self.nr, self.nc = self.ground.nr, self.ground.nc
        self.rocks = read_rock_catalog(scene_dir)
        look = rock_look(rng)
        cell = np.repeat(np.repeat(look.colours.reshape(ATLAS, ATLAS, 3), ATLAS_CELL_PX, 0),
                         ATLAS_CELL_PX, 1)
        self.rock_rgb = _to_u8(cell * look.speckle[..., None] / ALBEDO_SCALE)
        # two levels of detail: 80 faces for rocks >= PEBBLE_MAX_M in the near square, 20 for
        # the others (pebbles, and rocks farther away: a few pixels wide)
        self.lods = list(look.lods)

    # ---- spec ------------------------------------------------------------------------------
    def add_to_spec(self, spec: Any, xy_m: tuple[float, float],
                    forward_xy: tuple[float, float]) -> None:
        """Add textures, materials and the meshes (initial window at ``xy_m``)."""
        g = self.ground
        g.place(xy_m, forward_xy, force=True)
        textures = {**self._ground_textures(near=False), **self._ground_textures(near=True)}
        for name, rgb in (*textures.items(), ("cam_rock", self.rock_rgb)):
            _texture(spec, name, rgb)
            mat = spec.add_material(name=name, rgba=[1, 1, 1, 1], specular=0.0, shininess=0.0,
                                    reflectance=0.0)
            mat.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = name
        fr, fc = g.far_shape
        for layer in self.layers:
            _mesh(spec, "cam_terrain" + layer, *self._ground_arrays(False, layer),
                  _grid_faces(fr, fc))
            _mesh(spec, "cam_terrain_near" + layer, *self._ground_arrays(True, layer),
                  _grid_faces(g.nn_r, g.nn_c))
        hi, lo = self._split()
        self.lods[0].capacity = 2 * hi.size + 64
        self.lods[1].capacity = int((hi.size + lo.size) * 1.5) + 64
        for lod, idx in zip(self.lods, self._split(), strict=True):
            _mesh(spec, lod.name, *self._rock_arrays(lod, idx))
        for layer in self.layers:  # the sky layer after the sun layer: it wins equal depths
            for name, mat in (("cam_terrain", "cam_ground_far"),
                              ("cam_terrain_near", "cam_ground_near")):
                geom = spec.worldbody.add_geom(
                    name=name + layer, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name + layer,
                    material=mat + layer, contype=0, conaffinity=0, group=0)
                # with terrain shadows the ground casts no shadow-map shadows (acne at a
                # grazing sun; a map of +-20 m misses far terrain)
                geom.castshadow = self.sun_shadow is None
        for lod in self.lods:
            geom = spec.worldbody.add_geom(name=lod.name, type=mujoco.mjtGeom.mjGEOM_MESH,
                                           meshname=lod.name, material="cam_rock", contype=0,
                                           conaffinity=0, group=0)
            geom.castshadow = not self.rocks_baked

    def _ground_textures(self, *, near: bool) -> dict[str, NDArray[np.uint8]]:
        """The near or far ground texture per layer: sun (albedo x visibility), sky (albedo)."""
        g = self.ground
        plain = g.near_texture() if near else g.far_texture()
        name = "cam_ground_near" if near else "cam_ground_far"
        out = {name: g.sunlit(plain, near=near)}
        if len(self.layers) > 1:
            out[name + "_sky"] = plain
        return out

    def _ground_arrays(self, near: bool, layer: str) -> tuple[Any, Any, Any]:
        """Vertices, normals, texcoords of a ground mesh; the sky layer's normals face away
        from the sun (it adds nothing in the sun's pass)."""
        v, n, uv = self.ground.near_arrays() if near else self.ground.far_arrays()
        if layer:
            n = np.broadcast_to(-self.sun, n.shape)
        return v, n, uv

    # ---- window ----------------------------------------------------------------------------
    def window_bounds_xy_m(self) -> tuple[float, float, float, float]:
        """(x0, y0, x1, y1) of the current window."""
        return self.ground.bounds_xy_m()

    def _split(self) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """Window rocks drawn with 80 faces (near square, >= PEBBLE_MAX_M) and with 20."""
        g = self.ground
        idx = self._rocks_in(*(g.origin if g.origin is not None else (0, 0)))
        nr0, nc0 = g.near_origin if g.near_origin is not None else (0, 0)
        x0, y0 = self.hf.xy_of(nr0, nc0)
        x1, y1 = self.hf.xy_of(nr0 + g.nn_r - 1, nc0 + g.nn_c - 1)
        rk = self.rocks[idx]
        near = ((rk[:, 1] >= x0) & (rk[:, 1] <= x1) & (rk[:, 2] >= y0) & (rk[:, 2] <= y1)
                & (rk[:, 4] >= PEBBLE_MAX_M))
        hi = idx[near]
        cap = self.lods[0].capacity
        if cap and hi.size > cap:  # the largest get the fine mesh; the rest the coarse one
            hi = np.sort(hi[np.argsort(-self.rocks[hi, 4], kind="stable")[:cap]])
        return hi, np.setdiff1d(idx, hi, assume_unique=True)

    def _rock_arrays(self, lod: RockLOD, idx: NDArray[np.int64]) -> tuple[Any, Any, Any, Any]:
        return rock_arrays(lod, self.rocks, idx, hidden_z_m=float(self.hf.z_m.min()) - 50.0,
                           shadow=self.sun_shadow)

    def _rocks_in(self, r0: int, c0: int) -> NDArray[np.int64]:
        x0, y0 = self.hf.xy_of(r0, c0)
        x1, y1 = self.hf.xy_of(r0 + self.nr - 1, c0 + self.nc - 1)
        rk = self.rocks
        inside = ((rk[:, 1] >= min(x0, x1)) & (rk[:, 1] <= max(x0, x1))
                  & (rk[:, 2] >= min(y0, y1)) & (rk[:, 2] <= max(y0, y1)))
        return np.flatnonzero(inside)

    def update(self, model: Any, xy_m: tuple[float, float], forward_xy: tuple[float, float],
               force: bool = False) -> tuple[bool, bool]:
        """Re-place the ground meshes (and rocks with the far window); rewrite moved arrays.

        Returns ``(far_changed, near_changed)`` as :meth:`GroundWindow.place`; the caller
        re-uploads the meshes and textures that changed.
        """
        g = self.ground
        far, near = g.place(xy_m, forward_xy, force=force)
        for changed, is_near in ((far, False), (near, True)):
            if changed:
                for name, rgb in self._ground_textures(near=is_near).items():
                    _write_texture(model, name, rgb)
        for layer in self.layers:
            if near:
                _write_mesh(model, "cam_terrain_near" + layer, *self._ground_arrays(True, layer))
            if far or near:
                _write_mesh(model, "cam_terrain" + layer, *self._ground_arrays(False, layer))
        if far or near:
            for lod, idx in zip(self.lods, self._split(), strict=True):
                _write_mesh(model, lod.name, *self._rock_arrays(lod, idx)[:3])
        return far, near


def _grid_faces(nr: int, nc: int) -> NDArray[np.int32]:
    i = (np.arange(nr - 1)[:, None] * nc + np.arange(nc - 1)[None, :]).ravel()
    return np.concatenate([np.c_[i, i + 1, i + nc + 1], np.c_[i, i + nc + 1, i + nc]]).astype(
        np.int32)


def _to_u8(x: NDArray[Any]) -> NDArray[np.uint8]:
    return np.clip(np.rint(np.asarray(x) * 255.0), 0, 255).astype(np.uint8)


def _texture(spec: Any, name: str, rgb: NDArray[np.uint8]) -> None:
    h, w, _ = rgb.shape
    tex = spec.add_texture(name=name, type=mujoco.mjtTexture.mjTEXTURE_2D, width=w, height=h,
                           nchannel=3)
    tex.data = np.ascontiguousarray(rgb).tobytes()


def _mesh(spec: Any, name: str, v: Any, n: Any, uv: Any, f: Any) -> None:
    mesh = spec.add_mesh(name=name)
    mesh.uservert = np.asarray(v, dtype=np.float32).ravel().tolist()
    mesh.usernormal = np.asarray(n, dtype=np.float32).ravel().tolist()
    mesh.usertexcoord = np.asarray(uv, dtype=np.float32).ravel().tolist()
    mesh.userface = np.asarray(f, dtype=np.int32).ravel().tolist()
    mesh.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL


def _write_texture(model: Any, name: str, rgb: NDArray[np.uint8]) -> None:
    tid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TEXTURE, name)
    adr = int(model.tex_adr[tid])
    model.tex_data[adr : adr + rgb.size] = rgb.reshape(-1)


def _write_mesh(model: Any, name: str, v: Any, n: Any, uv: Any) -> None:
    mid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_MESH, name)
    gid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, name)
    va, nva = int(model.mesh_vertadr[mid]), int(model.mesh_vertnum[mid])
    na, ta = int(model.mesh_normaladr[mid]), int(model.mesh_texcoordadr[mid])
    # vertices are stored in the geom frame: identity rotation at the model's geom_pos
    model.geom_quat[gid] = (1.0, 0.0, 0.0, 0.0)
    model.geom_pos[gid] = 0.0
    model.mesh_vert[va : va + nva] = v
    model.mesh_normal[na : na + nva] = n
    model.mesh_texcoord[ta : ta + nva] = uv
