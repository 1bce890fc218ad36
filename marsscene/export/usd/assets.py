"""Assets in USD: ``/World/Assets/<name>`` (habitats, landers). Reading a user's USD asset for
placement is :mod:`marsscene.assets.usd` (the input side).

Each placed asset is an Xform at its base centre ``(x, y, base_z)``:

* mesh assets (procedural habitat, .obj/.glb files): one ``UsdGeom.Mesh`` per part with
  normals, a grey material and ``UsdPhysics.CollisionAPI`` with a ``convexHull``
  approximation (as in MJCF);
* USD files: copied beside the stage (``assets/<name>.<ext>``) and referenced under
  ``<name>/Model`` with the translation, Y-up rotation and unit scale that put the asset's base
  centre on the pad; a ``Collision`` box (guide purpose) carries the collision.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pxr import Gf, Sdf, UsdGeom, UsdPhysics, UsdShade

from marsscene.export.usd.stage import author_tri_mesh

__all__ = ["author_assets"]

#: Painted-metal grey (linear sRGB).
ASSET_ALBEDO_RGB = (0.7, 0.7, 0.68)


def _material(stage: Any, root: Sdf.Path) -> UsdShade.Material:
    UsdGeom.Scope.Define(stage, root.AppendChild("Looks"))
    mat = UsdShade.Material.Define(stage, root.AppendChild("Looks").AppendChild("Painted"))
    shader = UsdShade.Shader.Define(stage, mat.GetPath().AppendChild("PreviewSurface"))
    shader.CreateIdAttr("UsdPreviewSurface")
    shader.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set(
        Gf.Vec3f(*ASSET_ALBEDO_RGB))
    shader.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(0.5)
    mat.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
    return mat


def _mesh(stage: Any, path: Sdf.Path, mesh: Any) -> UsdGeom.Mesh:
    geom = author_tri_mesh(stage, path, mesh, faceted=False)
    UsdPhysics.CollisionAPI.Apply(geom.GetPrim())
    UsdPhysics.MeshCollisionAPI.Apply(geom.GetPrim()).CreateApproximationAttr(
        UsdPhysics.Tokens.convexHull)
    return geom


def _reference(stage: Any, path: Sdf.Path, placed: Any, assets: dict[str, bytes]) -> None:
    model = placed.model
    rel = f"assets/{model.name}{Path(model.source_path).suffix.lower()}"
    assets[rel] = Path(model.source_path).read_bytes()
    xf = UsdGeom.Xform.Define(stage, path.AppendChild("Model"))
    xf.AddTranslateOp().Set(Gf.Vec3d(*model.usd_offset_m))
    xf.AddRotateXOp().Set(float(model.usd_rotate_x_deg))
    xf.AddScaleOp().Set(Gf.Vec3f(float(model.usd_scale)))
    xf.GetPrim().GetReferences().AddReference(f"./{rel}", Sdf.Path(model.usd_root))
    box = _mesh(stage, path.AppendChild("Collision"), model.parts[0])
    box.CreatePurposeAttr(UsdGeom.Tokens.guide)


def author_assets(stage: Any, scene: Any, assets: dict[str, bytes]) -> None:
    """Author ``/World/Assets`` (nothing when the scene has no assets)."""
    placed_assets = getattr(scene, "assets", None)
    if not placed_assets:
        return
    root = Sdf.Path("/World/Assets")
    UsdGeom.Scope.Define(stage, root)
    material = _material(stage, root)
    for placed in placed_assets:
        path = root.AppendChild(placed.model.name)
        xf = UsdGeom.Xform.Define(stage, path)
        xf.AddTranslateOp().Set(Gf.Vec3d(placed.xy_m[0], placed.xy_m[1], placed.base_z_m))
        prim = xf.GetPrim()
        prim.CreateAttribute("marsscene:padRadius_m", Sdf.ValueTypeNames.Double).Set(
            float(placed.pad_radius_m))
        if placed.model.source_path:
            prim.CreateAttribute("marsscene:source", Sdf.ValueTypeNames.String).Set(
                Path(placed.model.source_path).name)
        if placed.model.usd_root is not None:
            _reference(stage, path, placed, assets)
            continue
        for i, part in enumerate(placed.model.parts):
            geom = _mesh(stage, path.AppendChild(f"part_{i}"), part)
            UsdShade.MaterialBindingAPI.Apply(geom.GetPrim()).Bind(material)
