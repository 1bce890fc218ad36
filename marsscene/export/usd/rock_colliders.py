"""Rock colliders in USD: one native instance per rock, which every physics loader sees.

The render rocks stay one ``UsdGeom.PointInstancer`` (:mod:`marsscene.export.usd.rocks`), but
OpenUSD's physics parser (``UsdPhysics.LoadUsdPhysicsFromRange``, used by Newton and anything
built on it) skips ``PointInstancer`` subtrees, so collision lives apart, as native instancing
(``instanceable = true``) that both that parser and PhysX follow. Layout of
``assets/rock_colliders.usdc``, payloaded at ``/World/RockColliders``::

    /RockColliders                   Xform, kind component
      Looks/RockPhysics              physics material (the MJCF rock friction)
      Prototypes                     class: never drawn nor simulated itself
        rock_NN                      class Xform, instanceable, xformOpOrder
          part_M                     Mesh (guide): CollisionAPI, MeshCollisionAPI
                                     approximation "convexHull", physics material
      rock_<i>                       one prim per rock: references Prototypes/rock_NN and
                                     holds its xformOp:transform (scale, rotation, position)

``<i>`` is the rock's row in the scene's rock table (``rocks.csv``), as in the MJCF geom names.
The instances carry only their transform: type, ``instanceable`` and ``xformOpOrder`` come
from the prototype through the reference, so a rock costs one prim spec and one attribute spec
(about 155 bytes in the crate file). One matrix instead of translate / orient / scale ops
halves the authoring, export and stage-open times for 1.6x the bytes. USD has no bulk prim
API, so the prims are authored one by one with the ``Sdf`` API inside one change block.
Merged static meshes per terrain tile were the alternative: measured in ``docs/usd.md``
(``perf/bench_rock_colliders.py``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pxr import Sdf, UsdGeom, UsdPhysics, Vt

from marsscene.export.usd.physics import (
    ROCK_PHYSICS,
    author_physics_material,
    bind_physics_material,
)
from marsscene.export.usd.stage import WORLD, author_tri_mesh, create_asset_stage, set_kind

__all__ = ["COLLIDERS_ASSET", "COLLIDERS_PATH", "author_collider_layer", "author_rock_colliders"]

COLLIDERS_ASSET = "assets/rock_colliders.usdc"
COLLIDERS_PATH = f"{WORLD}/RockColliders"
_ORDER = ("xformOp:transform",)


def _prototypes(stage: Any, root: Sdf.Path, prototypes: tuple[Any, ...],
                used: set[int]) -> list[Sdf.Path]:
    """Class prims ``root/Prototypes/rock_NN`` with the convex collision parts."""
    UsdGeom.Scope.Define(stage, root.AppendChild("Looks"))
    physics = author_physics_material(stage, root.AppendChild("Looks"), ROCK_PHYSICS)
    scope = root.AppendChild("Prototypes")
    stage.CreateClassPrim(scope)
    paths = []
    for k, proto in enumerate(prototypes):  # a handful of prototypes
        path = scope.AppendChild(proto.name)
        paths.append(path)
        if k not in used:
            continue
        xform = UsdGeom.Xform.Define(stage, path)
        prim = xform.GetPrim()
        prim.SetSpecifier(Sdf.SpecifierClass)
        prim.SetInstanceable(True)
        xform.CreateXformOpOrderAttr(Vt.TokenArray(_ORDER))
        for i, part in enumerate(proto.collision):
            geom = author_tri_mesh(stage, path.AppendChild(f"part_{i}"), part, faceted=True)
            geom.CreatePurposeAttr(UsdGeom.Tokens.guide)
            UsdPhysics.CollisionAPI.Apply(geom.GetPrim())
            UsdPhysics.MeshCollisionAPI.Apply(geom.GetPrim()).CreateApproximationAttr(
                UsdPhysics.Tokens.convexHull
            )
            bind_physics_material(geom.GetPrim(), physics)
    return paths


def _instances(layer: Sdf.Layer, root: Sdf.Path, rocks: Any, index: Any,
               protos: list[Sdf.Path]) -> None:
    """One ``def`` prim per rock under ``root`` (Sdf API, one change block)."""
    from marsscene.transforms import quat_to_matrix

    parent = layer.GetPrimAtPath(root)
    refs = [Sdf.Reference("", p) for p in protos]
    matrix4d = Sdf.ValueTypeNames.Matrix4d
    n = len(rocks)
    # USD matrices act on row vectors: rows 0-2 are the scaled rotated axes, row 3 the position
    m = np.zeros((n, 4, 4))
    rot = quat_to_matrix(np.asarray(rocks.orientation_wxyz, dtype=np.float64))
    m[:, :3, :3] = np.swapaxes(rot, 1, 2) * np.asarray(rocks.scale_xyz_m)[:, :, None]
    m[:, 3, :3] = rocks.position_xyz_m
    m[:, 3, 3] = 1.0
    matrices = Vt.Matrix4dArray.FromNumpy(m)  # one copy; indexing it is faster than lists
    kind = np.asarray(rocks.prototype, dtype=np.int64).tolist()
    names = [f"rock_{i}" for i in np.asarray(index, dtype=np.int64).tolist()]
    with Sdf.ChangeBlock():
        for j, name in enumerate(names):  # no vectorised prim creation in USD: a spec per rock
            spec = Sdf.PrimSpec(parent, name, Sdf.SpecifierDef)
            spec.referenceList.Prepend(refs[kind[j]])
            Sdf.AttributeSpec(spec, _ORDER[0], matrix4d).default = matrices[j]


def author_collider_layer(rocks: Any, index: Any, prototypes: tuple[Any, ...]) -> Sdf.Layer:
    """The collider asset layer of ``rocks`` (rows ``index`` of the scene's rock table).

    Parameters
    ----------
    rocks : RockTable
    index : array_like of int, shape (N,)
        Row of each rock in the scene's rock table (names the prims ``rock_<row>``).
    prototypes : tuple of RockPrototype
        Shapes in the unit frame; their ``collision`` parts become the prototypes' meshes.

    Returns
    -------
    pxr.Sdf.Layer
        Default prim ``/RockColliders``; export it to a ``.usdc`` file and payload it.
    """
    root = Sdf.Path("/RockColliders")
    stage = create_asset_stage("RockColliders")
    used = set(np.unique(np.asarray(rocks.prototype, dtype=np.int64)).tolist())
    protos = _prototypes(stage, root, tuple(prototypes), used)
    # the instances go to a bare layer: no stage recomposes 10^5 prims as they are authored
    layer = Sdf.Layer.CreateAnonymous(".usdc")
    layer.TransferContent(stage.GetRootLayer())
    _instances(layer, root, rocks, index, protos)
    return layer


def _payload(stage: Any, path: Sdf.Path, rel: str, count: int) -> Any:
    prim = UsdGeom.Xform.Define(stage, path).GetPrim()
    set_kind(prim, "component")
    prim.GetPayloads().AddPayload(f"./{rel}")
    prim.CreateAttribute("marsscene:rockCount", Sdf.ValueTypeNames.Int).Set(count)
    return prim


def author_rock_colliders(stage: Any, scene: Any, assets: dict[str, Any]) -> None:
    """Author ``/World/RockColliders``: a payload of :data:`COLLIDERS_ASSET`, or in
    level-of-detail scenes a group of one payload per rock part
    (``assets/rock_colliders/<part>.usdc``, the parts of ``/World/Rocks``); nothing without
    rocks or prototypes."""
    if scene.rocks is None or len(scene.rocks) == 0 or not scene.rock_prototypes:
        return
    protos = tuple(scene.rock_prototypes)
    min_d = scene.config.export.rock_collider_min_diameter_m
    wide = np.asarray(scene.rocks.diameter_m) >= min_d
    if not wide.any():
        return
    if scene.outer is None:
        keep = np.flatnonzero(wide)
        assets[COLLIDERS_ASSET] = author_collider_layer(scene.rocks.take(keep), keep, protos)
        _payload(stage, Sdf.Path(COLLIDERS_PATH), COLLIDERS_ASSET, len(keep))
        return
    from marsscene.export.usd.rocks import rock_tile_parts
    from marsscene.export.usd.terrain_lod import LOD_ATTR

    group = UsdGeom.Xform.Define(stage, Sdf.Path(COLLIDERS_PATH)).GetPrim()
    set_kind(group, "group")
    group.CreateAttribute("marsscene:rockCount", Sdf.ValueTypeNames.Int).Set(int(wide.sum()))
    for name, idx, level in rock_tile_parts(scene):  # a few tiles
        idx = idx[wide[idx]]
        if len(idx) == 0:
            continue
        rel = f"assets/rock_colliders/{name}.usdc"
        assets[rel] = author_collider_layer(scene.rocks.take(idx), idx, protos)
        prim = _payload(stage, group.GetPath().AppendChild(name), rel, len(idx))
        prim.CreateAttribute(LOD_ATTR, Sdf.ValueTypeNames.Int, custom=True).Set(level)
