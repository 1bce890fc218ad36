"""Rock colliders in USD that every physics loader sees, at a cost that does not grow with a
prim per rock.

The render rocks stay one ``UsdGeom.PointInstancer`` (:mod:`marsscene.export.usd.rocks`), but
OpenUSD's physics parser (``UsdPhysics.LoadUsdPhysicsFromRange``, used by Newton and anything
built on it) skips ``PointInstancer`` subtrees, so collision lives apart, in
``assets/rock_colliders.usdc`` payloaded at ``/World/RockColliders``, in two tiers chosen by
the rover's wheel (:data:`marsscene.rocks.config.CONTACT_MIN_DIAMETER_M`,
:data:`~marsscene.export.config.OBSTACLE_MIN_DIAMETER_M`)::

    /RockColliders                   Xform, kind component, marsscene:rockCount
      Looks/RockPhysics              physics material (the MJCF rock friction)
      Prototypes                     class: never drawn nor simulated itself
        rock_NN                      class Xform, instanceable, xformOpOrder
          part_M                     Mesh (guide): CollisionAPI, MeshCollisionAPI
                                     approximation "convexHull", physics material
      rock_<i>                       obstacle rocks (D >= export.rock_instance_min_diameter_m):
                                     one prim each, referencing Prototypes/rock_NN, holding its
                                     xformOp:transform (scale, rotation, position)
      Merged/rocks_<r>_<c>           the other colliding rocks (D >= export.
                                     rock_collider_min_diameter_m) of a 64 m square: one static
                                     Mesh (guide) of their small hulls, CollisionAPI,
                                     MeshCollisionAPI approximation "none", physics material;
                                     marsscene:rockRows and marsscene:rockFirstFace say which
                                     triangles belong to which rock

``<i>`` and the ``rockRows`` are rows of the scene's rock table (``rocks.csv``), as in the MJCF
geom names. An instance carries only its transform (type, ``instanceable`` and
``xformOpOrder`` come from the prototype through the reference): one prim spec and one
attribute spec, authored with the ``Sdf`` API inside one change block, about 80 us a rock to
write and as much to open, parse and validate; so only the few obstacle rocks get one
(1,610 of the default scene's 120,631 rocks). The merged tiles cost vectorised array work
(:mod:`marsscene.rocks.merged`). The trade-offs are measured in :doc:`/usd_rover`
(``python perf/run.py default_scene``, ``python perf/run.py rocks``).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np
from pxr import Sdf, UsdGeom, UsdPhysics, Vt

from marsscene.export.usd.physics import (
    ROCK_PHYSICS,
    author_physics_material,
    bind_physics_material,
)
from marsscene.export.usd.stage import WORLD, author_tri_mesh, create_asset_stage, set_kind

__all__ = ["COLLIDERS_ASSET", "COLLIDERS_PATH", "FIRST_FACE_ATTR", "ROWS_ATTR",
           "author_collider_layer", "author_rock_colliders"]

COLLIDERS_ASSET = "assets/rock_colliders.usdc"
COLLIDERS_PATH = f"{WORLD}/RockColliders"
#: Merged tiles: each rock's row in the rock table, in mesh order.
ROWS_ATTR = "marsscene:rockRows"
#: Merged tiles: index of each rock's first triangle (its last is the next rock's first - 1).
FIRST_FACE_ATTR = "marsscene:rockFirstFace"
_ORDER = ("xformOp:transform",)


def _prototypes(stage: Any, root: Sdf.Path, prototypes: tuple[Any, ...], used: set[int],
                physics: Any) -> list[Sdf.Path]:
    """Class prims ``root/Prototypes/rock_NN`` with the convex collision parts."""
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


def _tiles(stage: Any, scope: Sdf.Path, tiles: Iterable[Any], physics: Any) -> None:
    """One static triangle-mesh collider per merged tile under ``scope``."""
    UsdGeom.Scope.Define(stage, scope)
    ints = Sdf.ValueTypeNames.IntArray
    for tile in tiles:  # hundreds at most, each a few vectorised arrays
        mesh = UsdGeom.Mesh.Define(stage, scope.AppendChild(tile.name))
        mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(tile.points_m))
        mesh.CreateNormalsAttr(Vt.Vec3fArray.FromNumpy(tile.normals))
        mesh.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
        mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(tile.faces.reshape(-1)))
        mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(
            np.full(len(tile.faces), 3, dtype=np.int32)))
        mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
        mesh.CreateOrientationAttr(UsdGeom.Tokens.rightHanded)
        xyz = np.ascontiguousarray(tile.points_m.T)  # 10x faster reductions than over axis 0
        mesh.CreateExtentAttr(Vt.Vec3fArray.FromNumpy(np.stack([xyz.min(axis=1),
                                                                xyz.max(axis=1)])))
        mesh.CreatePurposeAttr(UsdGeom.Tokens.guide)
        prim = mesh.GetPrim()
        UsdPhysics.CollisionAPI.Apply(prim)
        UsdPhysics.MeshCollisionAPI.Apply(prim).CreateApproximationAttr(UsdPhysics.Tokens.none)
        bind_physics_material(prim, physics)
        prim.CreateAttribute(ROWS_ATTR, ints, custom=True).Set(
            Vt.IntArray.FromNumpy(tile.rows.astype(np.int32)))
        prim.CreateAttribute(FIRST_FACE_ATTR, ints, custom=True).Set(
            Vt.IntArray.FromNumpy(tile.first_face.astype(np.int32)))


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


def author_collider_layer(rocks: Any, index: Any, prototypes: tuple[Any, ...], *,
                          instance_min_diameter_m: float = 0.0,
                          hulls: list[Any] | None = None) -> Sdf.Layer:
    """The collider asset layer of ``rocks`` (rows ``index`` of the scene's rock table).

    Parameters
    ----------
    rocks : RockTable
    index : array_like of int, shape (N,)
        Row of each rock in the scene's rock table (names the prims ``rock_<row>``).
    prototypes : tuple of RockPrototype
        Shapes in the unit frame; their ``collision`` parts become the prototypes' meshes.
    instance_min_diameter_m : float
        Rocks at least this wide become one instance prim each; the others are merged into
        one mesh per :data:`~marsscene.rocks.merged.TILE_M` tile. 0: a prim per rock.
    hulls : list of trimesh.Trimesh, optional
        The merged rocks' hull per prototype (:func:`~marsscene.rocks.merged.small_hulls`
        of ``prototypes`` by default).

    Returns
    -------
    pxr.Sdf.Layer
        Default prim ``/RockColliders``; export it to a ``.usdc`` file and payload it.
    """
    from marsscene.rocks.merged import merge_tiles, small_hulls

    root = Sdf.Path("/RockColliders")
    index = np.asarray(index, dtype=np.int64)
    own = np.asarray(rocks.diameter_m) >= instance_min_diameter_m
    big, small = np.flatnonzero(own), np.flatnonzero(~own)
    stage = create_asset_stage("RockColliders")
    UsdGeom.Scope.Define(stage, root.AppendChild("Looks"))
    physics = author_physics_material(stage, root.AppendChild("Looks"), ROCK_PHYSICS)
    used = set(np.unique(np.asarray(rocks.prototype, dtype=np.int64)[big]).tolist())
    protos = _prototypes(stage, root, tuple(prototypes), used, physics) if len(big) else []
    if len(small):
        hulls = hulls if hulls is not None else small_hulls(tuple(prototypes))
        tiles = merge_tiles(rocks.take(small), index[small], hulls)
        _tiles(stage, root.AppendChild("Merged"), tiles, physics)
    # the instances go to a bare layer: no stage recomposes 10^5 prims as they are authored
    layer = Sdf.Layer.CreateAnonymous(".usdc")
    layer.TransferContent(stage.GetRootLayer())
    if len(big):
        _instances(layer, root, rocks.take(big), index[big], protos)
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
    rocks or prototypes, or when no rock is wide enough to collide."""
    if scene.rocks is None or len(scene.rocks) == 0 or not scene.rock_prototypes:
        return
    protos = tuple(scene.rock_prototypes)
    export = scene.config.export
    wide = np.asarray(scene.rocks.diameter_m) >= export.rock_collider_min_diameter_m
    if not wide.any():
        return
    from marsscene.rocks.merged import small_hulls

    kw = {"instance_min_diameter_m": export.rock_instance_min_diameter_m,
          "hulls": small_hulls(protos)}
    if scene.outer is None:
        keep = np.flatnonzero(wide)
        assets[COLLIDERS_ASSET] = author_collider_layer(scene.rocks.take(keep), keep, protos,
                                                        **kw)
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
        assets[rel] = author_collider_layer(scene.rocks.take(idx), idx, protos, **kw)
        prim = _payload(stage, group.GetPath().AppendChild(name), rel, len(idx))
        prim.CreateAttribute(LOD_ATTR, Sdf.ValueTypeNames.Int, custom=True).Set(level)
