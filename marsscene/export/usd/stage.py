"""Stage creation: metrics, default prim, provenance and the physics scene (cf. usd-exchange
``createStage``/``configureStage``: always author upAxis, metersPerUnit, kilogramsPerUnit and
the default prim)."""

from __future__ import annotations

from typing import Any

import numpy as np
from pxr import Gf, Kind, Sdf, Usd, UsdGeom, UsdPhysics, Vt

from marsscene._version import __version__
from marsscene.units import MARS_GRAVITY_M_S2

__all__ = [
    "WORLD",
    "author_tri_mesh",
    "crate_bytes",
    "create_asset_stage",
    "create_stage",
    "provenance_layer_data",
    "root_layer",
    "set_kind",
]

WORLD = "/World"


def set_kind(prim: Usd.Prim, kind: str) -> None:
    """Author the model ``kind`` (``assembly``, ``group``, ``component``) so tools can select
    whole parts of the scene (``/World`` assembly; lights and cameras groups; terrain, rocks
    components)."""
    Usd.ModelAPI(prim).SetKind(getattr(Kind.Tokens, kind))


def provenance_layer_data(scene: Any) -> dict[str, Any]:
    """The provenance stored in the root layer's ``customLayerData`` (no timings: stable)."""
    prov = scene.provenance
    frame = prov.frame
    data: dict[str, Any] = {
        "creator": f"marsscene {__version__}",
        "marsscene:seed": int(scene.seed),
        "marsscene:configHash": scene.config.config_hash(),
        "marsscene:datum_m": float(frame.datum_m),
        "marsscene:zScale": float(frame.z_scale),
        "marsscene:models": Vt.StringArray(
            [f"{m.stage}: {m.name} — {m.citation}" for m in prov.models]
        ),
    }
    if frame.origin_lonlat_deg is not None:
        data["marsscene:originLonLat_deg"] = Gf.Vec2d(*frame.origin_lonlat_deg)
    if frame.origin_projected_xy_m is not None:
        data["marsscene:originProjectedXY_m"] = Gf.Vec2d(*frame.origin_projected_xy_m)
    if frame.crs_wkt:
        data["marsscene:crsWkt"] = frame.crs_wkt
    return data


def create_stage(scene: Any) -> Usd.Stage:
    """An in-memory stage: Z-up, metres, kilograms, ``/World`` default prim, provenance,
    and a ``UsdPhysics.Scene`` with Mars gravity."""
    stage = Usd.Stage.CreateInMemory(load=Usd.Stage.LoadNone)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    UsdPhysics.SetStageKilogramsPerUnit(stage, 1.0)
    world = UsdGeom.Xform.Define(stage, Sdf.Path(WORLD))
    set_kind(world.GetPrim(), "assembly")
    stage.SetDefaultPrim(world.GetPrim())
    layer = stage.GetRootLayer()
    layer.customLayerData = provenance_layer_data(scene)
    layer.documentation = "Mars scene authored by marsscene (x east, y north, z up; metres)"
    physics = UsdPhysics.Scene.Define(stage, Sdf.Path(f"{WORLD}/PhysicsScene"))
    physics.CreateGravityDirectionAttr(Gf.Vec3f(0.0, 0.0, -1.0))
    physics.CreateGravityMagnitudeAttr(MARS_GRAVITY_M_S2)
    return stage


def create_asset_stage(default_prim: str, kind: str | None = "component") -> Usd.Stage:
    """An in-memory stage for a heavy asset layer (written as ``.usdc`` and payloaded from the
    root layer), with the same metrics as the root stage and its root prim of model ``kind``."""
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    UsdPhysics.SetStageKilogramsPerUnit(stage, 1.0)
    root = UsdGeom.Xform.Define(stage, Sdf.Path(f"/{default_prim}"))
    if kind is not None:
        set_kind(root.GetPrim(), kind)
    stage.SetDefaultPrim(root.GetPrim())
    stage.GetRootLayer().customLayerData = {"creator": f"marsscene {__version__}"}
    return stage


def root_layer(asset: Usd.Stage | Sdf.Layer) -> Sdf.Layer:
    """The layer to export for an in-memory asset: a stage's root layer, or the layer itself."""
    return asset if isinstance(asset, Sdf.Layer) else asset.GetRootLayer()


def crate_bytes(stage: Usd.Stage) -> bytes:
    """Serialise a stage's root layer as ``.usdc`` bytes (deterministic for the same content)."""
    import os
    import tempfile

    fd, tmp = tempfile.mkstemp(suffix=".usdc")
    os.close(fd)
    try:
        if not stage.GetRootLayer().Export(tmp):
            raise OSError("could not serialise a USD layer")
        with open(tmp, "rb") as fh:
            return fh.read()
    finally:
        os.unlink(tmp)


def author_tri_mesh(stage: Usd.Stage, path: Sdf.Path, mesh: Any, *,
                    faceted: bool) -> UsdGeom.Mesh:
    """A triangle mesh (trimesh-like ``vertices``/``faces``) with normals and extent:
    ``faceted`` gives one flat normal per face corner (rocks), else smooth vertex normals."""
    geom = UsdGeom.Mesh.Define(stage, path)
    v = np.asarray(mesh.vertices, dtype=np.float32)
    f = np.asarray(mesh.faces, dtype=np.int32)
    geom.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(v))
    geom.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(f), 3, np.int32)))
    geom.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(f.ravel()))
    if faceted:
        normals = np.repeat(np.asarray(mesh.face_normals, dtype=np.float32), 3, axis=0)
        interpolation = UsdGeom.Tokens.faceVarying
    else:
        normals = np.asarray(mesh.vertex_normals, dtype=np.float32)
        interpolation = UsdGeom.Tokens.vertex
    geom.CreateNormalsAttr(Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(normals)))
    geom.SetNormalsInterpolation(interpolation)
    geom.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    geom.CreateOrientationAttr(UsdGeom.Tokens.rightHanded)
    geom.CreateExtentAttr(Vt.Vec3fArray([Gf.Vec3f(*v.min(axis=0).tolist()),
                                         Gf.Vec3f(*v.max(axis=0).tolist())]))
    return geom
