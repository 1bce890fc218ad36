"""Scene geometry as triangles for the LiDAR's Embree caster: the static MuJoCo geoms (MJCF
rocks, assets; :func:`static_geom_mesh`) and the catalogue rocks (:func:`rock_mesh`).

Catalogue rocks: each rock an ellipsoid (a jittered icosphere,
80 faces from :data:`SMALL_ROCK_M` up, 20 below) of its diameter and height above its buried
base, turned by a yaw from its id, the way the camera draws them
(:mod:`marsscene.sensors.camera_world`).

Rocks smaller than :data:`SMALL_ROCK_M` matter only near the sensor (a 0.1 m rock spans less
than one beam spacing of a 64-beam unit beyond ~20 m): the caster keeps them within
:data:`SMALL_ROCK_REACH_M` of the sensor (at least).
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["SMALL_ROCK_M", "SMALL_ROCK_REACH_M", "rock_mesh", "static_geom_mesh"]

SMALL_ROCK_M = 0.3
SMALL_ROCK_REACH_M = 40.0
_VARIANTS = 8
_JITTER = 0.22  # log-normal radial jitter of the template vertices (as the camera's rocks)
_GOLDEN = 0.6180339887


@lru_cache(maxsize=2)
def _template(detailed: bool) -> tuple[NDArray[np.float64], NDArray[np.int32]]:
    """(variants, vertices, 3) unit jittered icospheres and their faces (a fixed seed)."""
    import trimesh

    ico = trimesh.creation.icosphere(subdivisions=1 if detailed else 0)
    v = np.asarray(ico.vertices, dtype=np.float64)
    rng = np.random.default_rng(np.random.SeedSequence(20261124, spawn_key=(int(detailed),)))
    jitter = np.exp(_JITTER * rng.standard_normal((_VARIANTS, len(v), 1)))
    return v[None] * jitter, np.asarray(ico.faces, dtype=np.int32)


def rock_mesh(rocks: NDArray[np.float64], *, detailed: bool
              ) -> tuple[NDArray[np.float32], NDArray[np.int32]]:
    """Vertices (float32) and faces of ``rocks`` ((N, 6) id, x, y, z of the base, diameter,
    height + burial in m) as one mesh."""
    v, f = _template(detailed)
    n, nv = len(rocks), v.shape[1]
    if n == 0:
        return np.zeros((0, 3), dtype=np.float32), np.zeros((0, 3), dtype=np.int32)
    ids = rocks[:, 0].astype(np.int64)
    d, hb = rocks[:, 4], rocks[:, 5]
    scale = np.stack([d / 2, d / 2, hb / 2], axis=1)
    local = v[ids % _VARIANTS] * scale[:, None, :]
    yaw = (ids * _GOLDEN) % 1.0 * 2 * np.pi
    cy, sy = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    out = np.zeros_like(local)
    out[..., 0] = cy * local[..., 0] - sy * local[..., 1] + rocks[:, 1:2]
    out[..., 1] = sy * local[..., 0] + cy * local[..., 1] + rocks[:, 2:3]
    out[..., 2] = local[..., 2] + (rocks[:, 3] + hb / 2)[:, None]
    faces = (f[None] + (np.arange(n, dtype=np.int32) * nv)[:, None, None]).reshape(-1, 3)
    return out.reshape(-1, 3).astype(np.float32), faces.astype(np.int32)


def static_geom_mesh(model: Any, data: Any, groups: tuple[int, ...] = (0, 1)
                     ) -> tuple[NDArray[np.float32], NDArray[np.int32]]:
    """Every static world geom of a compiled MuJoCo model in ``groups`` (MJCF rocks, assets) as
    world-frame triangles: meshes as they are, primitives tessellated by trimesh."""
    import mujoco
    import trimesh

    verts: list[NDArray[np.float64]] = []
    faces: list[NDArray[np.int32]] = []
    n = 0
    gt = mujoco.mjtGeom
    for g in np.flatnonzero((model.geom_bodyid == 0) & np.isin(model.geom_group, groups)):
        kind, size = int(model.geom_type[g]), model.geom_size[g]
        if kind == gt.mjGEOM_MESH:
            mid = int(model.geom_dataid[g])
            va, nv = int(model.mesh_vertadr[mid]), int(model.mesh_vertnum[mid])
            fa, nf = int(model.mesh_faceadr[mid]), int(model.mesh_facenum[mid])
            v = np.asarray(model.mesh_vert[va:va + nv], dtype=np.float64)
            f = np.asarray(model.mesh_face[fa:fa + nf], dtype=np.int32)
        elif kind == gt.mjGEOM_BOX:
            m = trimesh.creation.box(extents=2 * size[:3])
            v, f = np.asarray(m.vertices), np.asarray(m.faces, dtype=np.int32)
        elif kind in (gt.mjGEOM_SPHERE, gt.mjGEOM_ELLIPSOID):
            m = trimesh.creation.icosphere(subdivisions=2)
            r = size[:3] if kind == gt.mjGEOM_ELLIPSOID else np.full(3, size[0])
            v, f = np.asarray(m.vertices) * r, np.asarray(m.faces, dtype=np.int32)
        elif kind in (gt.mjGEOM_CYLINDER, gt.mjGEOM_CAPSULE):
            make = trimesh.creation.cylinder if kind == gt.mjGEOM_CYLINDER \
                else trimesh.creation.capsule
            m = make(radius=size[0], height=2 * size[1])
            v, f = np.asarray(m.vertices), np.asarray(m.faces, dtype=np.int32)
        else:  # planes and heightfields are the terrain's business
            continue
        rot = np.asarray(data.geom_xmat[g], dtype=np.float64).reshape(3, 3)
        verts.append(v @ rot.T + data.geom_xpos[g])
        faces.append(f + n)
        n += len(v)
    if not verts:
        return np.zeros((0, 3), dtype=np.float32), np.zeros((0, 3), dtype=np.int32)
    return np.concatenate(verts).astype(np.float32), np.concatenate(faces).astype(np.int32)
