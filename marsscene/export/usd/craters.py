"""Craters in USD: ground-truth labels as a ``UsdGeom.Points`` prim ``/World/Craters``.

The prim lives in the binary crate layer ``assets/craters.usdc`` (payloaded at
``/World/Craters``), so the text root layer holds no large arrays.

One point per crater at its centre on the stamped terrain (``points``), ``widths`` = rim
diameter, and per-point primvars in the ``marsscene:crater`` namespace (``diameter_m``,
``depth_m``, ``rimHeight_m``, ``age_ga``, ``axisRatio``, ``azimuth_deg``, ``profile``,
``inScene``); float primvars are indexed (``values`` = the sorted distinct values,
``indices`` per crater; read them with ``ComputeFlattened()``). The prim has
``purpose = guide`` so renderers do not draw it. Prim-level attributes record the count, the
chronology system and the surface age.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pxr import Gf, Sdf, UsdGeom, Vt

from marsscene.export.usd.stage import WORLD, create_asset_stage

__all__ = ["CRATERS_ASSET", "CRATERS_PATH", "author_craters"]

CRATERS_PATH = f"{WORLD}/Craters"
CRATERS_ASSET = "assets/craters.usdc"


def _primvar(geom: UsdGeom.Points, name: str, vtype: Any, values: Any) -> None:
    pv = UsdGeom.PrimvarsAPI(geom.GetPrim()).CreatePrimvar(
        f"marsscene:crater:{name}", vtype, UsdGeom.Tokens.vertex
    )
    pv.Set(values)


def _indexed(geom: UsdGeom.Points, name: str, values: np.ndarray) -> None:
    """A float primvar stored as distinct values + per-point indices (Asset Validator VG_009)."""
    distinct, inverse = np.unique(values.astype(np.float32), return_inverse=True)
    pv = UsdGeom.PrimvarsAPI(geom.GetPrim()).CreatePrimvar(
        f"marsscene:crater:{name}", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.vertex
    )
    pv.Set(Vt.FloatArray.FromNumpy(distinct))
    pv.SetIndices(Vt.IntArray.FromNumpy(inverse.astype(np.int32).ravel()))


def author_craters(stage: Any, scene: Any, assets: dict[str, Any]) -> None:
    """Author the scene's craters (nothing when the stage is disabled)."""
    if scene.craters is None:
        return
    asset = create_asset_stage("Craters", kind=None)
    _author_points(asset, Sdf.Path("/Craters"), scene)
    assets[CRATERS_ASSET] = asset  # a stage: its root layer is exported straight to its file
    stage.DefinePrim(Sdf.Path(CRATERS_PATH)).GetPayloads().AddPayload(f"./{CRATERS_ASSET}")


def _author_points(stage: Any, path: Sdf.Path, scene: Any) -> None:
    from marsscene.craters.morphology import PROFILE_MODELS

    t = scene.craters
    hf = scene.heightfield
    x, y = t.center_xy_m[:, 0], t.center_xy_m[:, 1]
    z = hf.sample(x, y)
    pts = UsdGeom.Points.Define(stage, path)
    pts.CreatePurposeAttr(UsdGeom.Tokens.guide)
    xyz = np.stack([x, y, z], axis=1).astype(np.float32)
    widths = t.diameter_m.astype(np.float32)
    pts.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(xyz)))
    pts.CreateWidthsAttr(Vt.FloatArray.FromNumpy(widths))
    if len(xyz):
        r = widths[:, None] / 2
        lo, hi = (xyz - r).min(axis=0).tolist(), (xyz + r).max(axis=0).tolist()
        pts.CreateExtentAttr(Vt.Vec3fArray([Gf.Vec3f(*lo), Gf.Vec3f(*hi)]))
    f = Sdf.ValueTypeNames
    for name, col in (("diameter_m", t.diameter_m), ("depth_m", t.depth_m),
                      ("rimHeight_m", t.rim_height_m), ("age_ga", t.age_ga),
                      ("axisRatio", t.axis_ratio), ("azimuth_deg", t.azimuth_deg)):
        _indexed(pts, name, np.asarray(col))
    _primvar(pts, "profile", f.IntArray, Vt.IntArray.FromNumpy(t.profile.astype(np.int32)))
    _primvar(pts, "inScene", f.BoolArray, Vt.BoolArray.FromNumpy(np.asarray(hf.contains(x, y))))
    prim = pts.GetPrim()
    cfg = scene.config.craters
    prim.CreateAttribute("marsscene:crater:count", f.Int, custom=True).Set(len(t))
    prim.CreateAttribute("marsscene:crater:system", f.String, custom=True).Set(cfg.system)
    prim.CreateAttribute("marsscene:crater:surfaceAge_ga", f.Double, custom=True).Set(
        float(cfg.age_ga))
    prim.CreateAttribute("marsscene:crater:profileModels", f.StringArray, custom=True).Set(
        Vt.StringArray(list(PROFILE_MODELS)))
    prim.SetDocumentation("Crater ground-truth labels (one point per crater centre); "
                          "widths = rim diameter (m)")
