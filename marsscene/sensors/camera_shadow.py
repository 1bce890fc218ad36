"""Terrain shadows in the camera: the whole heightfield's sun visibility, drawn exactly.

MuJoCo's shadow map covers +-20 m around the camera and, at a grazing sun, draws the terrain's
own shadows as saw-tooth acne; terrain farther away never casts. So the camera's terrain meshes
cast no shadow-map shadows (``castshadow`` off): their self-shadowing comes from
:func:`marsscene.terrain.horizon.sun_shadow`, computed once over the whole heightfield, and the
shadow map keeps what only it can draw (rocks' and the rover's shadows).

MuJoCo's classic renderer draws the opaque geoms twice: once with the ambient (sky) light,
then once more per shadow-casting light, adding ``texture * S max(n . s, 0)`` where the shadow
map sees the sun. One texture multiplies both terms, so a baked shadow would darken the sky's
light too. The ground is therefore drawn as **two coincident layers** of the same mesh (equal
depths: the later-drawn geom wins the ambient pass, both add in the sun's pass):

* the **sun layer**: the true normals and the albedo times the sun's visibility per texel
  (:func:`texel_visibility`: the shadow depth interpolated between posts, then the sun's disc,
  so edges fall at the right place between posts); its ambient pass is overdrawn;
* the **sky layer**, drawn after it: the plain albedo and normals turned away from the sun
  (``n = -s``), so it adds nothing in the sun's pass.

A texel then gets ``albedo (A + v S max(n . s, 0) m)``, ``m`` the shadow map's test: a rock's
shadow inside a terrain shadow does not darken it twice. The cost is one more draw of the
ground per pass (about +25 % CPU time per frame on llvmpipe).

Rocks get the visibility through their vertex normals (:func:`shadowed_normals`, normals
turned until ``n' . s = v max(n . s, 0)``): rocks standing in a terrain shadow are not lit.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.ndimage import map_coordinates

from marsscene.terrain.horizon import SunShadow, sun_visibility

__all__ = ["shade_mesh_geoms", "shadowed_normals", "texel_visibility"]


def shadowed_normals(normals: NDArray[Any], sun_direction: NDArray[Any] | tuple[float, ...],
                     visibility: NDArray[Any]) -> NDArray[np.float64]:
    """Unit normals ``n'`` with ``n' . s = visibility * max(n . s, 0)`` (others unchanged).

    ``normals`` (..., 3) unit vectors, ``sun_direction`` unit (3,) toward the sun,
    ``visibility`` (...) in [0, 1]. Normals whose sunlight does not change (fully visible, or
    facing away from the sun) are returned as they are.
    """
    n = np.asarray(normals, dtype=np.float64)
    s = np.asarray(sun_direction, dtype=np.float64)
    cos = n @ s
    target = np.asarray(visibility, dtype=np.float64) * np.maximum(cos, 0.0)
    change = target < cos - 1e-7
    if not change.any():
        return n.copy()
    perp = n - cos[..., None] * s
    size = np.linalg.norm(perp, axis=-1, keepdims=True)
    # a normal along the sun itself: any direction across it
    other = np.cross(s, [1.0, 0.0, 0.0] if abs(s[0]) < 0.9 else [0.0, 1.0, 0.0])
    other /= np.linalg.norm(other)
    across = np.where(size > 1e-9, perp / np.maximum(size, 1e-12), other)
    turned = target[..., None] * s + np.sqrt(1.0 - target * target)[..., None] * across
    return np.where(change[..., None], turned, n)


def texel_visibility(shadow: SunShadow, *, x0_m: float, y0_m: float,
                     size_px: tuple[int, int], texel_m: float, block: int
                     ) -> NDArray[np.float32]:
    """The sun's visibility over a texture, one value per ``block`` x ``block`` texels.

    The texture's texels of ``texel_m`` start at ``(x0_m, y0_m)`` (row 0 at ``y0_m``); values
    are taken at the blocks' centres, shape ``(ceil(rows / block), ceil(cols / block))``.
    """
    hf = shadow.heightfield
    n_r, n_c = -(-size_px[0] // block), -(-size_px[1] // block)
    xc = x0_m + (np.arange(n_c) + 0.5) * block * texel_m
    yc = y0_m + (np.arange(n_r) + 0.5) * block * texel_m
    row_f, col_f = hf.rowcol_of(xc[None, :] + 0 * yc[:, None], yc[:, None] + 0 * xc[None, :])
    coords = np.stack([row_f.ravel(), col_f.ravel()])
    depth = map_coordinates(shadow.depth_m, coords, order=1, mode="nearest")
    dist = map_coordinates(shadow.distance_m, coords, order=0, mode="nearest")
    vis = sun_visibility(depth, dist, sun_radius_rad=shadow.sun_radius_rad)
    return vis.reshape(n_r, n_c).astype(np.float32)


def shade_mesh_geoms(model: Any, geom_ids: NDArray[np.int64], shadow: SunShadow) -> None:
    """Turn the normals of static mesh geoms (the MJCF rocks) for the terrain's shadows.

    Each geom's mesh (its own asset: MJCF rocks do not share meshes) gets normals with
    ``n' . s = v max(n . s, 0)``, ``v`` the sun's visibility at the vertex (world frame from
    ``geom_pos`` / ``geom_quat``: world-body geoms). Edits ``model.mesh_normal`` in place; call
    before the GL context uploads the meshes.
    """
    sun = np.asarray(shadow.sun_direction_enu, dtype=np.float64)
    for gid in np.asarray(geom_ids, dtype=np.int64):
        mid = int(model.geom_dataid[gid])
        if mid < 0:
            continue
        va, nv = int(model.mesh_vertadr[mid]), int(model.mesh_vertnum[mid])
        na, nn = int(model.mesh_normaladr[mid]), int(model.mesh_normalnum[mid])
        fa, nf = int(model.mesh_faceadr[mid]), int(model.mesh_facenum[mid])
        if nv == 0 or nn == 0 or nf == 0:
            continue
        w, x, y, z = (float(c) for c in model.geom_quat[gid])
        rot = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
        # the vertex of each normal (faces pair vertex and normal indices)
        vertex_of = np.zeros(nn, dtype=np.int64)
        vertex_of[model.mesh_facenormal[fa : fa + nf].ravel()] = model.mesh_face[
            fa : fa + nf].ravel()
        world = model.mesh_vert[va : va + nv].astype(np.float64) @ rot.T + model.geom_pos[gid]
        p = world[vertex_of]
        vis = shadow.visibility_at(p[:, 0], p[:, 1], p[:, 2])
        local = model.mesh_normal[na : na + nn].astype(np.float64)
        local /= np.maximum(np.linalg.norm(local, axis=1, keepdims=True), 1e-12)
        model.mesh_normal[na : na + nn] = shadowed_normals(local, rot.T @ sun, vis)
