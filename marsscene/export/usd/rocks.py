"""Rocks in USD: one ``UsdGeom.PointInstancer`` over a few procedural prototypes.

Layout (the instancer lives in the binary crate layer ``assets/rocks.usdc``, payloaded at
``/World/Rocks``, so ``scene.usda`` stays small even with 10^6 rocks)::

    /World/Rocks                          Xform (payload ./assets/rocks.usdc)
      Looks/Rock                          UsdPreviewSurface (dark basaltic grey-brown)
      Instancer                           PointInstancer: positions, orientations, scales,
                                          protoIndices (one row per rock of Scene.rocks)
        Prototypes/rock_NN                Xform (unit frame: x, y in [-0.5, 0.5], z in [0, 1])
          Visual                          Mesh (render), flat face-varying normals, material

``/World/Rocks`` is a ``component`` model (``kind``). It is for rendering only: the rocks'
colliders are native instances under ``/World/RockColliders``
(:mod:`marsscene.export.usd.rock_colliders`), which OpenUSD's physics parser (Newton) loads as
well as PhysX; a ``PointInstancer`` is skipped by the former.

Level-of-detail scenes (:attr:`Scene.outer <marsscene.Scene.outer>`) split the rocks by where
they matter: ``/World/Rocks`` is a ``group`` of one payload per focus tile
(``assets/rocks/tile_i_j.usdc``, ``marsscene:lod = 0``, the full size-frequency distribution)
and ``outer`` (``assets/rocks/outer.usdc``, ``marsscene:lod = 1``, rocks of at least
``rocks.outer_d_min_m``), each with the layout above under its own root, so a client loads
the rocks of the tiles it shows.

Orientations are authored as ``quath`` (``orientations``, read by every USD version); the
half-precision error is < 0.1 deg.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pxr import Gf, Sdf, UsdGeom, UsdShade, Vt

from marsscene.export.usd.stage import WORLD, author_tri_mesh, create_asset_stage, set_kind

__all__ = ["ROCKS_ASSET", "ROCK_ALBEDO_RGB", "author_rocks", "rock_tile_parts"]

ROCKS_ASSET = "assets/rocks.usdc"
#: Basaltic rock colour (linear sRGB), darker and less red than dusty soil (rock albedo ~0.1-0.2;
#: Bell et al. 2008, doi:10.1017/CBO9780511536076.004).
ROCK_ALBEDO_RGB = (0.20, 0.15, 0.12)


def _material(stage: Any, root: Sdf.Path) -> UsdShade.Material:
    looks = root.AppendChild("Looks")
    UsdGeom.Scope.Define(stage, looks)
    mat = UsdShade.Material.Define(stage, looks.AppendChild("Rock"))
    shader = UsdShade.Shader.Define(stage, mat.GetPath().AppendChild("PreviewSurface"))
    shader.CreateIdAttr("UsdPreviewSurface")
    shader.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(*ROCK_ALBEDO_RGB))
    shader.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(0.8)
    shader.CreateInput("metallic", Sdf.ValueTypeNames.Float).Set(0.0)
    mat.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
    return mat


def _prototypes(stage: Any, instancer: Sdf.Path, prototypes: tuple[Any, ...],
                material: UsdShade.Material) -> list[Sdf.Path]:
    scope = instancer.AppendChild("Prototypes")
    UsdGeom.Scope.Define(stage, scope)
    paths = []
    for proto in prototypes:  # a handful of prototypes
        path = scope.AppendChild(proto.name)
        UsdGeom.Xform.Define(stage, path)
        visual = author_tri_mesh(stage, path.AppendChild("Visual"), proto.visual, faceted=True)
        UsdShade.MaterialBindingAPI.Apply(visual.GetPrim()).Bind(material)
        paths.append(path)
    return paths


def author_instancer(stage: Any, root: Sdf.Path, rocks: Any, prototypes: tuple[Any, ...]) -> None:
    """Author the material, prototypes and the PointInstancer of ``rocks`` under ``root``."""
    material = _material(stage, root)
    inst = UsdGeom.PointInstancer.Define(stage, root.AppendChild("Instancer"))
    inst.CreatePrototypesRel().SetTargets(_prototypes(stage, inst.GetPath(), prototypes,
                                                      material))
    pos = np.asarray(rocks.position_xyz_m, dtype=np.float32)
    q = np.asarray(rocks.orientation_wxyz, dtype=np.float64)
    scale = np.asarray(rocks.scale_xyz_m, dtype=np.float32)
    inst.CreateProtoIndicesAttr(Vt.IntArray.FromNumpy(rocks.prototype.astype(np.int32)))
    inst.CreatePositionsAttr(Vt.Vec3fArray.FromNumpy(pos))
    # Gf quaternions are stored imaginary-first: numpy rows are (x, y, z, w)
    inst.CreateOrientationsAttr(Vt.QuathArray.FromNumpy(q[:, [1, 2, 3, 0]].astype(np.float16)))
    inst.CreateScalesAttr(Vt.Vec3fArray.FromNumpy(scale))
    if len(pos):
        reach = np.linalg.norm(scale, axis=1)[:, None]
        inst.CreateExtentAttr(Vt.Vec3fArray([
            Gf.Vec3f(*(pos - reach).min(axis=0).tolist()),
            Gf.Vec3f(*(pos + reach).max(axis=0).tolist()),
        ]))


def _tile_of_rocks(scene: Any) -> tuple[Any, int]:
    """Focus tile index (row * n + col, or -1 outside the focus) of every rock, and n."""
    lod = scene.provenance.extra.get("lod", {})
    n = int(lod.get("focus_tiles", [1, 1])[0])
    x0, y0, x1, y1 = scene.outer.focus_bounds_xy_m
    tile_m = float(lod.get("focus_tile_m", x1 - x0))
    xy = np.asarray(scene.rocks.position_xyz_m)[:, :2]
    inside = (xy[:, 0] >= x0) & (xy[:, 0] <= x1) & (xy[:, 1] >= y0) & (xy[:, 1] <= y1)
    col = np.clip(np.floor((xy[:, 0] - x0) / tile_m), 0, n - 1).astype(np.int64)
    row = np.clip(np.floor((xy[:, 1] - y0) / tile_m), 0, n - 1).astype(np.int64)
    return np.where(inside, row * n + col, -1), n


def rock_tile_parts(scene: Any) -> list[tuple[str, Any, int]]:
    """Level-of-detail scenes: ``(name, rows of the rock table, lod level)`` of each rock
    payload (one per focus tile, ``tile_i_j``, then ``outer``); empty parts are left out."""
    tile, n = _tile_of_rocks(scene)
    parts = [(f"tile_{i // n}_{i % n}", i, 0) for i in range(n * n)] + [("outer", -1, 1)]
    rows = [(name, np.flatnonzero(tile == index), level) for name, index, level in parts]
    return [(name, idx, level) for name, idx, level in rows if len(idx)]


def _rock_payloads(stage: Any, scene: Any, assets: dict[str, Any]) -> None:
    """Level-of-detail scenes: one rock payload per focus tile, and one for the outer rocks."""
    from marsscene.export.usd.terrain_lod import LOD_ATTR

    group = UsdGeom.Xform.Define(stage, Sdf.Path(f"{WORLD}/Rocks")).GetPrim()
    set_kind(group, "group")
    protos = tuple(scene.rock_prototypes or ())
    for name, idx, level in rock_tile_parts(scene):  # a few tiles, each one vectorised instancer
        rocks = scene.rocks.take(idx)
        rel = f"assets/rocks/{name}.usdc"
        asset = create_asset_stage("Rocks")
        author_instancer(asset, Sdf.Path("/Rocks"), rocks, protos)
        assets[rel] = asset
        prim = UsdGeom.Xform.Define(stage, group.GetPath().AppendChild(name)).GetPrim()
        set_kind(prim, "component")
        prim.GetPayloads().AddPayload(f"./{rel}")
        prim.CreateAttribute(LOD_ATTR, Sdf.ValueTypeNames.Int, custom=True).Set(level)
        prim.CreateAttribute("marsscene:rockCount", Sdf.ValueTypeNames.Int).Set(len(rocks))


def author_rocks(stage: Any, scene: Any, assets: dict[str, Any]) -> None:
    """Author ``/World/Rocks`` (a payload of ``assets/rocks.usdc``, or per tile in
    level-of-detail scenes); nothing when disabled."""
    if scene.rocks is None:
        return
    if scene.outer is not None:
        _rock_payloads(stage, scene, assets)
        prim = stage.GetPrimAtPath(f"{WORLD}/Rocks")
        prim.CreateAttribute("marsscene:rockCount", Sdf.ValueTypeNames.Int).Set(len(scene.rocks))
        prim.CreateAttribute("marsscene:rockPrototypes", Sdf.ValueTypeNames.Int).Set(
            len(scene.rock_prototypes or ()))
        return
    asset = create_asset_stage("Rocks")
    author_instancer(asset, Sdf.Path("/Rocks"), scene.rocks, tuple(scene.rock_prototypes or ()))
    assets[ROCKS_ASSET] = asset  # a stage: its root layer is exported straight to its file
    prim = UsdGeom.Xform.Define(stage, Sdf.Path(f"{WORLD}/Rocks")).GetPrim()
    set_kind(prim, "component")
    prim.GetPayloads().AddPayload(f"./{ROCKS_ASSET}")
    prim.CreateAttribute("marsscene:rockCount", Sdf.ValueTypeNames.Int).Set(len(scene.rocks))
    prim.CreateAttribute("marsscene:rockPrototypes", Sdf.ValueTypeNames.Int).Set(
        len(scene.rock_prototypes or ())
    )
