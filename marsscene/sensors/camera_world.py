"""The camera's view of a scene: textured, smooth terrain meshes and visual-only small rocks.

Built into a *separate* MuJoCo model that only the camera renders (the simulation model is not
changed; contacts keep the scene's rule):

* the terrain hfield is hidden and replaced by a near and a far **ground mesh** with
  per-vertex (smooth) normals and baked, world-anchored textures: the seeded regolith detail
  tile (:func:`marsscene.terrain.appearance.regolith_tile`, micro-relief shading baked in)
  times the large-scale albedo field (:mod:`marsscene.sensors.camera_ground`);
* every catalogue rock (``rocks.csv``, down to ``rocks.d_min_m``) in the window that is not an
  MJCF collision geom becomes part of **one of two merged visual meshes** (contype/conaffinity
  0): a jittered icosphere per rock (80 faces near the camera, 20 elsewhere), scaled to its
  diameter and height, coloured per rock from
  :func:`marsscene.terrain.appearance.rock_albedo_rgb` through a texture atlas.

All meshes have a fixed vertex count; when they move their vertex, normal and texcoord arrays
are rewritten in place and re-uploaded to GL (``mjr_uploadMesh``, ``mjr_uploadTexture``).
Textures hold ``albedo / ALBEDO_SCALE`` so that the renderer's 8 bits cover albedos up to 0.5.
"""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from marsscene.sensors.camera_ground import GroundWindow
from marsscene.terrain.albedo_field import AlbedoField
from marsscene.terrain.appearance import bump_shading, regolith_tile, rock_albedo_rgb
from marsscene.terrain.heightfield import Heightfield

__all__ = ["ALBEDO_SCALE", "CameraWorld", "read_rock_catalog"]

#: Texture value 1.0 means this albedo.
ALBEDO_SCALE = 0.5
_ATLAS = 8  # rock texture atlas: 8 x 8 colour cells
_CELL_PX = 32
_VARIANTS = 8
#: Rocks smaller than this are drawn with 20 faces instead of 80.
PEBBLE_MAX_M = 0.15


def _read_parquet_catalog(path: Path) -> NDArray[np.float64]:
    from marsscene._optional import require_pyarrow

    require_pyarrow()
    import pyarrow.parquet as pq

    t = pq.read_table(str(path))
    col = {name: t.column(name).to_numpy().astype(np.float64) for name in t.column_names}
    keep = col["in_mjcf"] == 0
    return np.column_stack([col[k][keep] for k in ("id", "x_m", "y_m", "z_m", "diameter_m")]
                           + [(col["height_m"] + col["burial_m"])[keep]]).reshape(-1, 6)


def read_rock_catalog(scene_dir: Path) -> NDArray[np.float64]:
    """``rocks.csv`` (else ``rocks.parquet``) rows not already MJCF geoms: (N, 6) id, x, y,
    z, d, h+burial (m)."""
    path = scene_dir / "rocks.csv"
    if not path.is_file():
        if (scene_dir / "rocks.parquet").is_file():
            return _read_parquet_catalog(scene_dir / "rocks.parquet")
        return np.zeros((0, 6))
    with open(path, encoding="utf-8") as fh:
        header = next(csv.reader(fh))
    col = {name: i for i, name in enumerate(header)}
    raw = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    if raw.size == 0:
        return np.zeros((0, 6))
    keep = raw[:, col["in_mjcf"]] == 0 if "in_mjcf" in col else np.ones(len(raw), bool)
    r = raw[keep]
    return np.column_stack([
        r[:, col["id"]], r[:, col["x_m"]], r[:, col["y_m"]], r[:, col["z_m"]],
        r[:, col["diameter_m"]], r[:, col["height_m"]] + r[:, col["burial_m"]],
    ])


def _icosphere(subdivide: bool) -> tuple[NDArray[np.float64], NDArray[np.int32]]:
    t = (1.0 + 5.0**0.5) / 2.0
    v = np.array([[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
                  [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]],
                 dtype=np.float64)
    f = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9],
                  [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2],
                  [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10],
                  [8, 6, 7], [9, 8, 1]])
    if not subdivide:
        return v / np.linalg.norm(v, axis=1, keepdims=True), f.astype(np.int32)
    edges = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    uniq, inv = np.unique(edges, axis=0, return_inverse=True)
    mid = len(v) + inv.reshape(3, -1).T  # midpoints of edges (01, 12, 20) per face
    v = np.vstack([v, (v[uniq[:, 0]] + v[uniq[:, 1]]) / 2])
    a, b, c = f.T
    ab, bc, ca = mid.T
    f2 = np.concatenate([np.c_[a, ab, ca], np.c_[b, bc, ab], np.c_[c, ca, bc], np.c_[ab, bc, ca]])
    return v / np.linalg.norm(v, axis=1, keepdims=True), f2.astype(np.int32)


class _RockLOD:
    """One merged rock mesh: a jittered icosphere template (8 variants) and a capacity."""

    def __init__(self, name: str, subdivide: bool, rng: np.random.Generator) -> None:
        self.name = name
        base, self.faces = _icosphere(subdivide)
        self.v = base[None] * np.exp(0.22 * rng.standard_normal((_VARIANTS, len(base), 1)))
        self.n = np.stack([_normals_of(v, self.faces) for v in self.v])
        lon = np.arctan2(base[:, 1], base[:, 0])
        self.uv = np.c_[0.5 + 0.45 * np.cos(lon) * (1 - np.abs(base[:, 2])) ** 0.5,
                        0.5 + 0.45 * base[:, 2]]
        self.capacity = 0


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
    ) -> None:
        self.hf = heightfield
        tile = regolith_tile(size_px=tile_px, tile_m=tile_m, rng=rng)
        shade = bump_shading(tile, sun_direction_enu, direct_share)
        self.ground = GroundWindow(
            heightfield, window_m=window_m, near_m=near_m, far_stride=far_stride,
            tile_u8=_to_u8(tile.albedo_rgb * shade[..., None] / ALBEDO_SCALE), tile_m=tile_m,
            field=field)
        self.nr, self.nc = self.ground.nr, self.ground.nc
        self.rocks = read_rock_catalog(scene_dir)
        colours = rock_albedo_rgb(_ATLAS * _ATLAS, rng=rng)
        speckle = np.exp(0.25 * rng.standard_normal((_ATLAS * _CELL_PX,) * 2))
        cell = np.repeat(np.repeat(colours.reshape(_ATLAS, _ATLAS, 3), _CELL_PX, 0), _CELL_PX, 1)
        self.rock_rgb = _to_u8(cell * speckle[..., None] / ALBEDO_SCALE)
        # two levels of detail: 80 faces for rocks >= PEBBLE_MAX_M in the near square, 20 for
        # the others (pebbles, and rocks farther away: a few pixels wide)
        self.lods = [_RockLOD("cam_rocks", True, rng), _RockLOD("cam_pebbles", False, rng)]

    # ---- spec ------------------------------------------------------------------------------
    def add_to_spec(self, spec: Any, xy_m: tuple[float, float],
                    forward_xy: tuple[float, float]) -> None:
        """Add textures, materials and the meshes (initial window at ``xy_m``)."""
        g = self.ground
        g.place(xy_m, forward_xy, force=True)
        _texture(spec, "cam_ground_far", g.far_texture())
        _texture(spec, "cam_ground_near", g.near_texture())
        _texture(spec, "cam_rock", self.rock_rgb)
        for name in ("cam_ground_far", "cam_ground_near", "cam_rock"):
            mat = spec.add_material(name=name, rgba=[1, 1, 1, 1], specular=0.0, shininess=0.0,
                                    reflectance=0.0)
            mat.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = name
        fr, fc = g.far_shape
        _mesh(spec, "cam_terrain", *g.far_arrays(), _grid_faces(fr, fc))
        _mesh(spec, "cam_terrain_near", *g.near_arrays(), _grid_faces(g.nn_r, g.nn_c))
        hi, lo = self._split()
        self.lods[0].capacity = 2 * hi.size + 64
        self.lods[1].capacity = int((hi.size + lo.size) * 1.5) + 64
        for lod, idx in zip(self.lods, self._split(), strict=True):
            _mesh(spec, lod.name, *self._rock_arrays(lod, idx))
        for name, mat in (("cam_terrain", "cam_ground_far"),
                          ("cam_terrain_near", "cam_ground_near")):
            spec.worldbody.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name,
                                    material=mat, contype=0, conaffinity=0, group=0)
        for lod in self.lods:
            spec.worldbody.add_geom(name=lod.name, type=mujoco.mjtGeom.mjGEOM_MESH,
                                    meshname=lod.name, material="cam_rock", contype=0,
                                    conaffinity=0, group=0)

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

    def _rocks_in(self, r0: int, c0: int) -> NDArray[np.int64]:
        x0, y0 = self.hf.xy_of(r0, c0)
        x1, y1 = self.hf.xy_of(r0 + self.nr - 1, c0 + self.nc - 1)
        rk = self.rocks
        inside = ((rk[:, 1] >= min(x0, x1)) & (rk[:, 1] <= max(x0, x1))
                  & (rk[:, 2] >= min(y0, y1)) & (rk[:, 2] <= max(y0, y1)))
        return np.flatnonzero(inside)

    def _rock_arrays(self, lod: _RockLOD, idx: NDArray[np.int64]) -> tuple[Any, Any, Any, Any]:
        cap, nv = lod.capacity, lod.v.shape[1]
        rk = self.rocks
        if len(idx) > cap:  # keep the largest (stable order)
            idx = np.sort(idx[np.argsort(-rk[idx, 4], kind="stable")[:cap]])
        ids = np.zeros(cap, dtype=np.int64)
        centre = np.zeros((cap, 3))
        scale = np.full((cap, 3), 1e-3)
        k = len(idx)
        ids[:k] = rk[idx, 0].astype(np.int64)
        ids[k:] = np.arange(cap - k)
        centre[:k] = rk[idx, 1:4]
        centre[k:] = [0.0, 0.0, float(self.hf.z_m.min()) - 50.0]
        centre[k:, 0] = np.arange(cap - k) * 0.01  # distinct, hidden under the terrain
        d, hb = rk[idx, 4], rk[idx, 5]
        scale[:k] = np.c_[d / 2, d / 2, hb / 2]
        centre[:k, 2] += hb / 2
        var = ids % _VARIANTS
        yaw = (ids * 0.6180339887) % 1.0 * 2 * np.pi
        cy, sy = np.cos(yaw), np.sin(yaw)
        local = lod.v[var] * scale[:, None, :]
        v = np.empty_like(local)
        v[..., 0] = cy[:, None] * local[..., 0] - sy[:, None] * local[..., 1]
        v[..., 1] = sy[:, None] * local[..., 0] + cy[:, None] * local[..., 1]
        v[..., 2] = local[..., 2]
        v += centre[:, None, :]
        ln = lod.n[var] / scale[:, None, :]
        n = np.empty_like(ln)
        n[..., 0] = cy[:, None] * ln[..., 0] - sy[:, None] * ln[..., 1]
        n[..., 1] = sy[:, None] * ln[..., 0] + cy[:, None] * ln[..., 1]
        n[..., 2] = ln[..., 2]
        n /= np.linalg.norm(n, axis=-1, keepdims=True)
        cell = (ids * 2654435761) % (_ATLAS * _ATLAS)
        cu, cv = (cell % _ATLAS)[:, None], (cell // _ATLAS)[:, None]
        uv = np.stack([(cu + lod.uv[None, :, 0]) / _ATLAS,
                       (cv + lod.uv[None, :, 1]) / _ATLAS], axis=-1)
        f = (lod.faces[None] + (np.arange(cap) * nv)[:, None, None]).reshape(-1, 3)
        return v.reshape(-1, 3), n.reshape(-1, 3), uv.reshape(-1, 2), f

    def update(self, model: Any, xy_m: tuple[float, float], forward_xy: tuple[float, float],
               force: bool = False) -> tuple[bool, bool]:
        """Re-place the ground meshes (and rocks with the far window); rewrite moved arrays.

        Returns ``(far_changed, near_changed)`` as :meth:`GroundWindow.place`; the caller
        re-uploads the meshes and textures that changed.
        """
        g = self.ground
        far, near = g.place(xy_m, forward_xy, force=force)
        if far:
            _write_texture(model, "cam_ground_far", g.far_texture())
        if near:
            _write_texture(model, "cam_ground_near", g.near_texture())
            _write_mesh(model, "cam_terrain_near", *g.near_arrays())
        if far or near:
            _write_mesh(model, "cam_terrain", *g.far_arrays())
            for lod, idx in zip(self.lods, self._split(), strict=True):
                _write_mesh(model, lod.name, *self._rock_arrays(lod, idx)[:3])
        return far, near


def _normals_of(v: NDArray[np.float64], f: NDArray[np.int32]) -> NDArray[np.float64]:
    fn = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    n = np.zeros_like(v)
    for k in range(3):
        np.add.at(n, f[:, k], fn)
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)


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
