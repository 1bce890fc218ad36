"""What the batch camera draws, built on the host once: the regolith albedo (the CPU camera's
detail tile and large-scale albedo field), the rocks as one merged icosphere mesh with per-face
albedo, and the lighting in the renderer's linear units.

The appearance is the CPU camera's (:mod:`marsscene.sensors.camera_world`): the seeded detail
tile (:func:`~marsscene.terrain.appearance.regolith_tile`) with its micro-relief shading baked in
(:func:`~marsscene.terrain.appearance.bump_shading`), times ``exp`` of the world-anchored
albedo field (:func:`~marsscene.terrain.albedo_field.albedo_field`, here sampled every
``GAIN_STEP_M`` and read bilinearly, as :func:`~marsscene.sensors.camera_ground.bake_ground`
does). Rocks are jittered 80-face icospheres (the CPU camera's near level of detail,
:class:`~marsscene.sensors.camera_rocks.RockLOD`) at each batch rock's footprint radius and
exposed height, buried by ``BURIED_FRACTION`` of their height (the rock population's default
buried fraction is drawn from 0 to 0.5, :mod:`marsscene.rocks.population`), of the CPU
camera's MJCF rock albedo with its rock texture's speckle per face (the batch's rocks are the
scene's MJCF rocks).

Lighting (:func:`light_arrays`) is the CPU camera's (:mod:`marsscene.sensors.camera`): with ``k
= 0.95 / max(E_dn + E_dif, 1.2 E_dif / ALBEDO_SCALE)``, a surface of albedo ``a`` has the linear
value ``a / ALBEDO_SCALE (k E_dif sky_rgb + k E_dn cos(i) v sun_rgb)`` (``v`` the sun's
visibility), the sky ``k E_dif sky_rgb / ALBEDO_SCALE`` times ``1 - 0.2 sin(elevation)`` (the
CPU camera's gradient skybox: 0.8 at the zenith, 1.2 at the nadir; measured: its sky within 1
sRGB code), fog toward ``1.2`` times the sky over the visibility ``3.912 H / tau``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.sensors.camera import FIXED_REFERENCE_W_M2
from marsscene.sensors.camera_rocks import (
    PEBBLE_MAX_M,
    SPECKLE_SIGMA,
    RockLOD,
    RockLook,
    rock_arrays,
    rock_look,
)
from marsscene.sensors.camera_world import ALBEDO_SCALE

__all__ = ["BURIED_FRACTION", "GAIN_STEP_M", "Appearance", "Lights", "appearance",
           "light_arrays", "rock_mesh"]

#: Spacing of the sampled large-scale albedo field (m): bake_ground's.
GAIN_STEP_M = 0.125
#: Albedo of the CPU camera's MJCF rocks (its ``cam_rock_geom`` material): the batch's rocks
#: are the scene's MJCF rocks.
ROCK_GEOM_ALBEDO_RGB = (0.18, 0.1305, 0.099)
#: A rock's radius per its bounding radius in a WorldBatch (the half diagonal of its world
#: box, :func:`marsscene.sim.world.world_obstacles`): catalogue diameter / 2 over it, median of
#: the 88 MJCF rocks of a 30 m ``rocks`` world (0.47).
RADIUS_PER_BOUND = 0.47
#: Share of a batch rock's full height below the ground (the population's mean buried fraction).
BURIED_FRACTION = 0.25


@dataclass(frozen=True, eq=False)
class Lights:
    """One lighting in render units (:func:`light_arrays`): ``sun_dir`` unit toward the sun,
    ``sun_rgb`` and ``sky_rgb`` the sun's and the sky's terms, ``visibility_m`` the fog's,
    ``render_scale`` ``k``, ``fixed_scale`` the fixed exposure's reference per render unit."""

    sun_dir: NDArray[np.float32]
    sun_rgb: NDArray[np.float32]
    sky_rgb: NDArray[np.float32]
    visibility_m: float
    render_scale: float
    fixed_scale: float


def light_arrays(lt: Any) -> Lights:
    """The CPU camera's lights of a :class:`~marsscene.lighting.Lighting` (module doc)."""
    e_dn, e_dif = float(lt.direct_normal_w_m2), float(lt.diffuse_horizontal_w_m2)
    k = 0.95 / max(e_dn + e_dif, 1.2 * e_dif / ALBEDO_SCALE, 1e-6)
    sun = np.asarray(lt.sun_direction_enu, dtype=np.float64)
    lit = sun[2] > 0.0
    vis = float(lt.visibility_m) if math.isfinite(lt.visibility_m) else 1e9
    return Lights(
        sun_dir=(sun / np.linalg.norm(sun)).astype(np.float32),
        sun_rgb=(k * e_dn * np.asarray(lt.sun_color_rgb) / ALBEDO_SCALE * lit).astype(
            np.float32),
        sky_rgb=(k * e_dif * np.asarray(lt.sky_color_rgb) / ALBEDO_SCALE).astype(np.float32),
        visibility_m=min(vis, 1e9), render_scale=k,
        fixed_scale=1.0 / (FIXED_REFERENCE_W_M2 * k))


@dataclass(frozen=True, eq=False)
class Appearance:
    """The ground's albedo: ``tile_rgb`` (n, n, 3) linear albedo times the micro-relief's
    shading and its mip levels (n/2, n/4, ...), ``tile_texel_m`` level 0's texel; ``gain``
    (W, rows, cols) ``exp(log_gain)`` every ``GAIN_STEP_M`` from each world's corner
    ``gain_origin_xy_m`` (W, 2), world coordinates; the generator
    left for the rocks (the CPU camera draws them next)."""

    tile_rgb: list[NDArray[np.float32]]
    tile_texel_m: float
    gain: NDArray[np.float32]
    gain_origin_xy_m: NDArray[np.float64]
    rng: np.random.Generator


def appearance(batch: Any, lighting: Any, *, seeds: Any, texture_seed: int,
               tile_m: float, tile_px: int) -> Appearance:
    """The ground appearance of every world of ``batch`` (a
    :class:`~marsscene.env.batch.worlds.WorldBatch`): one detail tile from ``texture_seed``
    (the CPU camera's ``stage_rng(seed, "texture")``), each world's albedo field from its
    scene seed in ``seeds``."""
    from marsscene.seeding import stage_rng
    from marsscene.terrain.albedo_field import albedo_field
    from marsscene.terrain.appearance import bump_shading, regolith_tile

    rng = stage_rng(int(texture_seed), "texture")
    tile = regolith_tile(size_px=int(tile_px), tile_m=float(tile_m), rng=rng)
    share = lighting.direct_horizontal_w_m2 / max(lighting.global_horizontal_w_m2, 1e-9)
    shade = bump_shading(tile, lighting.sun_direction_enu, share)
    sx, sy = batch.size_m
    nx, ny = math.ceil(sx / GAIN_STEP_M) + 2, math.ceil(sy / GAIN_STEP_M) + 2
    gains = np.zeros((batch.count, ny, nx), dtype=np.float32)
    corners = np.asarray(batch.origins_xy_m, dtype=np.float64)
    for w in range(batch.count):
        field = albedo_field(rng=stage_rng(int(seeds[w]), "albedo"))
        gx = corners[w, 0] + np.arange(nx) * GAIN_STEP_M
        gy = corners[w, 1] + np.arange(ny) * GAIN_STEP_M
        gains[w] = np.exp(field.log_gain(*np.meshgrid(gx, gy)))
    return Appearance(mip_levels((tile.albedo_rgb * shade[..., None]).astype(np.float32)),
                      tile.texel_m, gains, corners, rng)


def mip_levels(tile: NDArray[np.float32]) -> list[NDArray[np.float32]]:
    """The tile and its 2 x 2 means down to 8 x 8 texels (a texture's mipmaps)."""
    out = [tile]
    while out[-1].shape[0] >= 16 and out[-1].shape[0] % 2 == 0:
        t = out[-1]
        m = t.shape[0] // 2
        out.append(t.reshape(m, 2, m, 2, 3).mean(axis=(1, 3)).astype(np.float32))
    return out


def rock_mesh(batch: Any, offsets_xy_m: Any, rng: np.random.Generator,
              catalogue: Any = None, assets: Any = None
              ) -> tuple[NDArray[np.float32], NDArray[np.int32], NDArray[np.float32],
                         NDArray[np.float32]]:
    """Every rock of ``batch`` and of ``catalogue`` as one mesh in the tile frame (world +
    ``offsets_xy_m[w]``): vertices (V, 3), faces (F, 3), vertex normals (V, 3), face albedo
    (F, 3). ``catalogue``: per world, catalogue rocks (N, 6) as
    :func:`~marsscene.sensors.camera_rocks.read_rock_catalog` reads them, drawn as the CPU
    camera draws them (:func:`~marsscene.sensors.camera_rocks.rock_arrays`: 80 faces from
    ``PEBBLE_MAX_M`` up, 20 below; their atlas colour and speckle per face). The looks come
    from ``rng`` in the CPU camera's order (:func:`~marsscene.sensors.camera_rocks.rock_look`).
    ``assets``: per world, its placed assets' :class:`~marsscene.sim.world.AssetMesh` (or
    None), flat-shaded in their material's colour. A batch without rocks gets one tiny
    triangle far below its terrain (a Warp mesh needs one)."""
    look = rock_look(rng)
    parts = []
    if len(batch.rock_radius_m):
        parts.append(_batch_rocks(batch, offsets_xy_m, look.lods[0], rng))
    off = np.asarray(offsets_xy_m, dtype=np.float64).reshape(-1, 2)
    for w, rocks in enumerate(catalogue or ()):
        parts += _catalogue_rocks(np.asarray(rocks, dtype=np.float64).reshape(-1, 6), off[w],
                                  look)
    for w, mesh in enumerate(assets or ()):
        if mesh is not None and len(mesh.faces):
            parts.append(_asset_part(mesh, off[w]))
    if not parts:
        deep = float(np.min(batch.posts_z_m)) - 100.0
        v = np.array([[0, 0, deep], [1e-3, 0, deep], [0, 1e-3, deep]], dtype=np.float32)
        return (v, np.array([[0, 1, 2]], np.int32), np.tile([0, 0, 1.0], (3, 1)).astype(
            np.float32), np.zeros((1, 3), np.float32))
    starts = np.cumsum([0] + [len(p[0]) for p in parts[:-1]])
    return (np.concatenate([p[0] for p in parts]).astype(np.float32),
            np.concatenate([p[1] + k for p, k in zip(parts, starts, strict=True)]).astype(
                np.int32),
            np.concatenate([p[2] for p in parts]).astype(np.float32),
            np.concatenate([p[3] for p in parts]).astype(np.float32))


def _catalogue_rocks(rocks: NDArray[np.float64], offset_xy_m: NDArray[np.float64],
                     look: RockLook) -> list[tuple[Any, Any, Any, Any]]:
    """One world's catalogue rocks as mesh parts (vertices, faces, normals, face albedo)."""
    big = rocks[:, 4] >= PEBBLE_MAX_M
    parts = []
    for lod, idx in zip(look.lods, (np.flatnonzero(big), np.flatnonzero(~big)), strict=True):
        if not len(idx):
            continue
        lod.capacity = len(idx)
        v, n, uv, f = rock_arrays(lod, rocks, idx, hidden_z_m=0.0, shadow=None)
        v = v + np.array([offset_xy_m[0], offset_xy_m[1], 0.0])
        ids = np.repeat(rocks[idx, 0].astype(np.int64), len(lod.faces))
        parts.append((v, f, n, look.face_albedo(ids, uv[f].mean(axis=1))))
    return parts


def _asset_part(mesh: Any, offset_xy_m: NDArray[np.float64]) -> tuple[Any, Any, Any, Any]:
    """One world's assets as a flat-shaded mesh part: each face its own three vertices with the
    face's normal, its material colour as the CPU camera renders it (a texture value of 1 is
    ``ALBEDO_SCALE``)."""
    tri = np.asarray(mesh.vertices_m, dtype=np.float64)[np.asarray(mesh.faces)]  # (F, 3, 3)
    tri = tri + np.array([offset_xy_m[0], offset_xy_m[1], 0.0])
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
    nf = len(tri)
    return (tri.reshape(-1, 3), np.arange(3 * nf).reshape(nf, 3), np.repeat(normal, 3, axis=0),
            np.asarray(mesh.rgb, dtype=np.float64) * ALBEDO_SCALE)


def _batch_rocks(batch: Any, offsets_xy_m: Any, lod: RockLOD, rng: np.random.Generator
                 ) -> tuple[Any, Any, Any, Any]:
    """The batch's (MJCF) rocks: ``lod``'s icospheres at each rock's footprint radius and
    exposed height, the CPU camera's MJCF rock albedo times a speckle per face."""
    n = len(batch.rock_radius_m)
    xy = np.asarray(batch.rock_xy_m, dtype=np.float64)
    world = np.asarray(batch.rock_world, dtype=np.int64)
    z = np.zeros(n)
    for w in range(batch.count):
        z[world == w] = batch.heightfield(w).sample(*xy[world == w].T)
    h = np.asarray(batch.rock_height_m, dtype=np.float64)
    full = h / (1.0 - BURIED_FRACTION)
    r = np.asarray(batch.rock_radius_m, dtype=np.float64) * RADIUS_PER_BOUND
    ids = np.arange(n)
    scale = np.c_[r, r, full / 2.0]
    centre = np.c_[xy + np.asarray(offsets_xy_m, dtype=np.float64)[world],
                   z + h - full / 2.0]
    yaw = (ids * 0.6180339887) % 1.0 * 2 * np.pi
    c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    local = lod.v[ids % len(lod.v)] * scale[:, None, :]
    v = np.stack([c * local[..., 0] - s * local[..., 1], s * local[..., 0] + c * local[..., 1],
                  local[..., 2]], axis=-1) + centre[:, None, :]
    ln = lod.n[ids % len(lod.n)] / scale[:, None, :]
    nrm = np.stack([c * ln[..., 0] - s * ln[..., 1], s * ln[..., 0] + c * ln[..., 1],
                    ln[..., 2]], axis=-1)
    nrm /= np.linalg.norm(nrm, axis=-1, keepdims=True)
    nv, nf = lod.v.shape[1], len(lod.faces)
    faces = (lod.faces[None] + (ids * nv)[:, None, None]).reshape(-1, 3)
    speck = np.exp(SPECKLE_SIGMA * rng.standard_normal(n * nf))
    albedo = np.asarray(ROCK_GEOM_ALBEDO_RGB)[None, :] * speck[:, None]
    return v.reshape(-1, 3), faces, nrm.reshape(-1, 3), albedo
