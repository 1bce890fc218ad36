"""Craters in USD: ground-truth labels as a ``UsdGeom.Points`` prim ``/World/Craters``.

One point per crater at its centre on the stamped terrain (``points``), ``widths`` = rim
diameter, and per-point primvars in the ``marsscene:crater`` namespace (``diameter_m``,
``depth_m``, ``rimHeight_m``, ``age_ga``, ``axisRatio``, ``azimuth_deg``, ``profile``,
``inScene``). The prim has ``purpose = guide`` so renderers do not draw it. Prim-level
attributes record the count, the chronology system and the surface age.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pxr import Sdf, UsdGeom, Vt

from marsscene.export.usd.stage import WORLD

__all__ = ["CRATERS_PATH", "author_craters"]

CRATERS_PATH = f"{WORLD}/Craters"


def _primvar(geom: UsdGeom.Points, name: str, vtype: Any, values: Any) -> None:
    pv = UsdGeom.PrimvarsAPI(geom.GetPrim()).CreatePrimvar(
        f"marsscene:crater:{name}", vtype, UsdGeom.Tokens.vertex
    )
    pv.Set(values)


def author_craters(stage: Any, scene: Any, assets: dict[str, bytes]) -> None:
    """Author the scene's craters (nothing when the stage is disabled)."""
    if scene.craters is None:
        return
    from marsscene.craters.morphology import PROFILE_MODELS

    t = scene.craters
    hf = scene.heightfield
    x, y = t.center_xy_m[:, 0], t.center_xy_m[:, 1]
    z = hf.sample(x, y)
    pts = UsdGeom.Points.Define(stage, Sdf.Path(CRATERS_PATH))
    pts.CreatePurposeAttr(UsdGeom.Tokens.guide)
    xyz = np.stack([x, y, z], axis=1).astype(np.float32)
    pts.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(xyz)))
    pts.CreateWidthsAttr(Vt.FloatArray.FromNumpy(t.diameter_m.astype(np.float32)))
    f = Sdf.ValueTypeNames
    _primvar(pts, "diameter_m", f.FloatArray,
             Vt.FloatArray.FromNumpy(t.diameter_m.astype(np.float32)))
    _primvar(pts, "depth_m", f.FloatArray, Vt.FloatArray.FromNumpy(t.depth_m.astype(np.float32)))
    _primvar(pts, "rimHeight_m", f.FloatArray,
             Vt.FloatArray.FromNumpy(t.rim_height_m.astype(np.float32)))
    _primvar(pts, "age_ga", f.FloatArray, Vt.FloatArray.FromNumpy(t.age_ga.astype(np.float32)))
    _primvar(pts, "axisRatio", f.FloatArray,
             Vt.FloatArray.FromNumpy(t.axis_ratio.astype(np.float32)))
    _primvar(pts, "azimuth_deg", f.FloatArray,
             Vt.FloatArray.FromNumpy(t.azimuth_deg.astype(np.float32)))
    _primvar(pts, "profile", f.IntArray, Vt.IntArray.FromNumpy(t.profile.astype(np.int32)))
    _primvar(pts, "inScene", f.BoolArray, Vt.BoolArray([bool(v) for v in hf.contains(x, y)]))
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
