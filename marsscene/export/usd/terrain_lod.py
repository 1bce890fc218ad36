"""The outer terrain of a level-of-detail scene as USD tile payloads (with a focus hole).

Layout (only for scenes with :attr:`Scene.outer <marsscene.Scene.outer>`)::

    /World/Terrain              the focus square at full resolution, ``marsscene:lod = 0``
    /World/TerrainLod1/tile_i_j one payload per tile, ``assets/terrain_lod1/tile_i_j.usdc``,
                                ``marsscene:lod = 1``; tiles wholly inside the focus are absent

Each outer tile is a ``UsdGeom.Mesh`` of the coarse posts without the cells inside the focus
square (the hole the focus terrain fills: the coarse and fine meshes share the border, see
:mod:`marsscene.terrain.lod`), with normals, ``st`` over the whole footprint, the plain
regolith colour and static triangle-mesh collision with the regolith physics material.
Scenes without level of detail are unchanged.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
from pxr import Gf, Sdf, UsdGeom, UsdPhysics, UsdShade, Vt

from marsscene._threads import prefetch, worth_a_thread
from marsscene.export.usd.physics import (
    REGOLITH_PHYSICS,
    author_physics_material,
    bind_physics_material,
)
from marsscene.export.usd.stage import WORLD, create_asset_stage, set_kind
from marsscene.terrain.mesh import grid_faces, tile_ranges

__all__ = ["LOD_ATTR", "author_outer_terrain"]

LOD_ATTR = "marsscene:lod"
OUTER_DIR = "assets/terrain_lod1"


def _lod_attr(prim: Any, level: int) -> None:
    prim.CreateAttribute(LOD_ATTR, Sdf.ValueTypeNames.Int, custom=True).Set(level)


_Arrays = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def _outer_tiles(outer: Any, max_posts: int) -> Iterator[tuple[str, _Arrays]]:
    """``(name, (points, normals, st, faces))`` of every outer tile that is not wholly inside
    the focus; numpy only, so it can run on a helper thread (:func:`marsscene._threads.prefetch`).
    """
    hf = outer.heightfield
    rows, cols = hf.shape
    xs, ys = hf.grid_xy()
    normals = hf.grid_normals()
    s_all = ((xs - xs[0]) / (xs[-1] - xs[0])).astype(np.float32)
    t_all = ((ys - ys[0]) / (ys[-1] - ys[0])).astype(np.float32)
    fx0, fy0, fx1, fy1 = outer.focus_bounds_xy_m
    half = hf.cell_size_m / 2.0
    for ti, (r0, r1) in enumerate(tile_ranges(rows, max_posts)):
        for tj, (c0, c1) in enumerate(tile_ranges(cols, max_posts)):
            cx = xs[c0:c1 - 1] + half
            cy = ys[r0:r1 - 1] + half
            hole = (((cy > fy0) & (cy < fy1))[:, None] & ((cx > fx0) & (cx < fx1))[None, :])
            if hole.all():
                continue
            nr, nc = r1 - r0, c1 - c0
            faces = grid_faces(nr, nc)[np.repeat(~hole.ravel(), 2)]
            used = np.zeros(nr * nc, dtype=bool)
            used[faces.ravel()] = True
            remap = np.cumsum(used, dtype=np.int64) - 1
            gx, gy = np.meshgrid(xs[c0:c1], ys[r0:r1])
            pts = np.stack([gx, gy, hf.z_m[r0:r1, c0:c1]], axis=-1).reshape(-1, 3)[used]
            ss, tt = np.meshgrid(s_all[c0:c1], t_all[r0:r1])
            st = np.stack([ss, tt], axis=-1).reshape(-1, 2)[used]
            yield f"tile_{ti}_{tj}", (pts.astype(np.float32),
                                      normals[r0:r1, c0:c1].reshape(-1, 3)[used], st,
                                      remap[faces].astype(np.int32))


def author_outer_terrain(stage: Any, scene: Any, assets: dict[str, Any]) -> None:
    """Author ``/World/TerrainLod1`` tile payloads (nothing for scenes without an outer level).

    The next tiles' arrays are made on a helper thread while pxr takes the current one (big
    outer levels; see :mod:`marsscene._threads`)."""
    outer = scene.outer
    if outer is None:
        return
    from marsscene.export.usd.terrain import REGOLITH_ALBEDO_RGB

    _lod_attr(stage.GetPrimAtPath(f"{WORLD}/Terrain"), 0)
    root = UsdGeom.Xform.Define(stage, Sdf.Path(f"{WORLD}/TerrainLod{outer.level}"))
    set_kind(root.GetPrim(), "group")
    _lod_attr(root.GetPrim(), outer.level)
    tiles = _outer_tiles(outer, scene.config.export.max_tile_posts)
    if worth_a_thread(outer.heightfield.z_m.size):
        tiles = prefetch(tiles, depth=2, name="marsscene-outer-tiles")
    for name, arrays in tiles:
        rel = f"{OUTER_DIR}/{name}.usdc"
        layer = create_asset_stage("Tile")
        pts, normals, st, faces = arrays
        _mesh(layer, pts, normals, st, faces, REGOLITH_ALBEDO_RGB)
        assets[rel] = layer  # a stage: its root layer is exported straight to its file
        prim = UsdGeom.Xform.Define(stage, root.GetPath().AppendChild(name)).GetPrim()
        set_kind(prim, "component")
        prim.GetPayloads().AddPayload(f"./{rel}")
        _lod_attr(prim, outer.level)


def _mesh(stage: Any, pts: np.ndarray, normals: np.ndarray, st: np.ndarray, faces: np.ndarray,
          rgb: tuple[float, float, float]) -> None:
    UsdGeom.Scope.Define(stage, Sdf.Path("/Tile/Looks"))
    mat = UsdShade.Material.Define(stage, Sdf.Path("/Tile/Looks/Regolith"))
    shader = UsdShade.Shader.Define(stage, Sdf.Path("/Tile/Looks/Regolith/PreviewSurface"))
    shader.CreateIdAttr("UsdPreviewSurface")
    shader.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(0.95)
    shader.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(*rgb))
    mat.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
    mesh = UsdGeom.Mesh.Define(stage, Sdf.Path("/Tile/Mesh"))
    physics = author_physics_material(stage, Sdf.Path("/Tile/Looks"), REGOLITH_PHYSICS)
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(pts))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(faces), 3, np.int32)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(faces.ravel()))
    mesh.CreateNormalsAttr(Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(normals)))
    mesh.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
    mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    mesh.CreateOrientationAttr(UsdGeom.Tokens.rightHanded)
    mesh.CreateDoubleSidedAttr(False)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    mesh.CreateExtentAttr(Vt.Vec3fArray([Gf.Vec3f(*lo.tolist()), Gf.Vec3f(*hi.tolist())]))
    primvar = UsdGeom.PrimvarsAPI(mesh).CreatePrimvar(
        "st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.vertex)
    primvar.Set(Vt.Vec2fArray.FromNumpy(np.ascontiguousarray(st)))
    UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(mat)
    UsdPhysics.CollisionAPI.Apply(mesh.GetPrim())
    UsdPhysics.MeshCollisionAPI.Apply(mesh.GetPrim()).CreateApproximationAttr(
        UsdPhysics.Tokens.none)
    bind_physics_material(mesh.GetPrim(), physics)
