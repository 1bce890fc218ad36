"""Terrain tiles as ``UsdGeom.Mesh`` prims with normals, UVs, a material and collision."""

from __future__ import annotations

from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any

import numpy as np
from pxr import Gf, Sdf, UsdGeom, UsdPhysics, UsdShade, Vt

from marsscene._threads import prefetch, worth_a_thread
from marsscene.export.usd.appearance import (
    RegolithTextures,
    author_regolith_detail,
    regolith_textures,
)
from marsscene.export.usd.physics import (
    REGOLITH_PHYSICS,
    author_physics_material,
    bind_physics_material,
)
from marsscene.export.usd.stage import WORLD, create_asset_stage, set_kind
from marsscene.terrain.mesh import iter_heightfield_tiles

__all__ = ["REGOLITH_ALBEDO_RGB", "author_terrain"]

#: Mars regolith base colour (linear sRGB) when no orthoimage is given. Bright dusty soil has a
#: visible albedo of ~0.25 with a red slope (Bell et al. 2008, "Mars surface colour", in *The
#: Martian Surface*, CUP, doi:10.1017/CBO9780511536076.004).
REGOLITH_ALBEDO_RGB = (0.42, 0.24, 0.14)

TEXTURE_PATH = "textures/terrain_albedo.png"
TERRAIN_ASSET = "assets/terrain.usdc"


def _material(stage: Any, material: Any, scene: Any, assets: dict[str, bytes],
              textures: RegolithTextures) -> None:
    path = material.GetPath()
    shader = UsdShade.Shader.Define(stage, path.AppendChild("PreviewSurface"))
    shader.CreateIdAttr("UsdPreviewSurface")
    shader.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(0.95)
    shader.CreateInput("metallic", Sdf.ValueTypeNames.Float).Set(0.0)
    diffuse = shader.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f)
    if textures.ortho_png is not None:
        assets[TEXTURE_PATH] = textures.ortho_png
        reader = UsdShade.Shader.Define(stage, path.AppendChild("StReader"))
        reader.CreateIdAttr("UsdPrimvarReader_float2")
        reader.CreateInput("varname", Sdf.ValueTypeNames.String).Set("st")
        tex = UsdShade.Shader.Define(stage, path.AppendChild("Albedo"))
        tex.CreateIdAttr("UsdUVTexture")
        tex.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(f"../{TEXTURE_PATH}")
        tex.CreateInput("sourceColorSpace", Sdf.ValueTypeNames.Token).Set("sRGB")
        tex.CreateInput("wrapS", Sdf.ValueTypeNames.Token).Set("clamp")
        tex.CreateInput("wrapT", Sdf.ValueTypeNames.Token).Set("clamp")
        tex.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(
            reader.ConnectableAPI(), "result"
        )
        diffuse.ConnectToSource(tex.ConnectableAPI(), "rgb")
    else:
        diffuse.Set(Gf.Vec3f(*REGOLITH_ALBEDO_RGB))
    author_regolith_detail(stage, str(path), shader, scene, assets, textures)
    material.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")


def author_terrain(stage: Any, scene: Any, assets: dict[str, Any], *,
                   textures: Future[RegolithTextures] | None = None) -> None:
    """Author ``/World/Terrain`` (a ``component``): a payload of ``assets/terrain.usdc`` holding
    the ``tile_i_j`` meshes, the regolith material, static triangle-mesh collision
    (approximation ``none``) and the regolith physics material (``physics`` purpose).

    The heavy geometry lives in a binary crate layer so that ``scene.usda`` stays small and
    readable; a ``.usdz`` package carries both. ``textures``: the material's images, if
    already started (:func:`marsscene.export.usd.start_textures`).
    """
    asset_stage = create_asset_stage("Terrain")
    _author_tiles(asset_stage, scene, assets, textures)
    assets[TERRAIN_ASSET] = asset_stage  # a stage: its root layer is exported straight to its file
    prim = UsdGeom.Xform.Define(stage, Sdf.Path(f"{WORLD}/Terrain")).GetPrim()
    set_kind(prim, "component")
    prim.GetPayloads().AddPayload(f"./{TERRAIN_ASSET}")


def _done(fn: Any, *args: Any) -> Future[Any]:
    """``fn(*args)`` run now, as a finished future."""
    fut: Future[Any] = Future()
    fut.set_result(fn(*args))
    return fut


def _author_tiles(stage: Any, scene: Any, assets: dict[str, Any],
                  textures: Future[RegolithTextures] | None) -> None:
    cfg = scene.config.export
    terrain = UsdGeom.Xform.Get(stage, Sdf.Path("/Terrain"))
    looks = Sdf.Path("/Terrain/Looks")
    UsdGeom.Scope.Define(stage, looks)
    material = UsdShade.Material.Define(stage, looks.AppendChild("Regolith"))
    physics = author_physics_material(stage, looks, REGOLITH_PHYSICS)
    # tiles of one shape share one face-index array: convert it to Vt once (VtArrays are
    # copy-on-write, so every tile's attribute holds the same buffer)
    topology: dict[int, tuple[Vt.IntArray, Vt.IntArray]] = {}
    # Background threads (numpy and Pillow only, never pxr; see marsscene._threads) encode
    # the textures (unless the caller started them) and mesh the next tiles while this thread
    # hands arrays to pxr.
    threaded = worth_a_thread(scene.heightfield.z_m.size)
    with ThreadPoolExecutor(max_workers=1, thread_name_prefix="marsscene-textures") as pool:
        if textures is None:
            textures = (pool.submit if threaded else _done)(regolith_textures, scene)
        tiles = iter_heightfield_tiles(scene.heightfield, max_tile_posts=cfg.max_tile_posts)
        for tile in prefetch(tiles, depth=2, name="marsscene-tiles") if threaded else tiles:
            mesh = UsdGeom.Mesh.Define(stage, terrain.GetPath().AppendChild(tile.name))
            faces = tile.face_vertex_indices
            if id(faces) not in topology:  # the generator keeps each shared array alive
                topology[id(faces)] = (Vt.IntArray.FromNumpy(np.full(len(faces), 3, np.int32)),
                                       Vt.IntArray.FromNumpy(faces.ravel()))
            counts, indices = topology[id(faces)]
            mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(tile.points_m))
            mesh.CreateFaceVertexCountsAttr(counts)
            mesh.CreateFaceVertexIndicesAttr(indices)
            mesh.CreateNormalsAttr(Vt.Vec3fArray.FromNumpy(tile.normals))
            mesh.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
            mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
            mesh.CreateOrientationAttr(UsdGeom.Tokens.rightHanded)
            mesh.CreateDoubleSidedAttr(False)
            pts = tile.points_m  # a regular grid: x, y bounds are its first and last posts
            z = pts[:, 2]
            lo = (min(pts[0, 0], pts[-1, 0]), min(pts[0, 1], pts[-1, 1]), z.min())
            hi = (max(pts[0, 0], pts[-1, 0]), max(pts[0, 1], pts[-1, 1]), z.max())
            mesh.CreateExtentAttr(Vt.Vec3fArray([Gf.Vec3f(*map(float, lo)),
                                                 Gf.Vec3f(*map(float, hi))]))
            st = UsdGeom.PrimvarsAPI(mesh).CreatePrimvar(
                "st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.vertex
            )
            st.Set(Vt.Vec2fArray.FromNumpy(tile.st))
            UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(material)
            UsdPhysics.CollisionAPI.Apply(mesh.GetPrim())
            UsdPhysics.MeshCollisionAPI.Apply(mesh.GetPrim()).CreateApproximationAttr(
                UsdPhysics.Tokens.none
            )
            bind_physics_material(mesh.GetPrim(), physics)
        _material(stage, material, scene, assets, textures.result())
