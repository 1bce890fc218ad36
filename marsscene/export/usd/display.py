"""``scene_display.usda``: the scene for display-referred clients (Blender, usdview).

``scene.usda`` keeps physically based lights (the sun in lux, ~26,000 at Jezero noon) and puts
the exposure in the cameras (``exposure:time`` giving a linear scale ``pi / E``, E the global
horizontal illuminance): right for Omniverse / Isaac Sim, but Blender's USD import reads a
DistantLight's intensity as its sun strength and ignores camera exposure, so a plain import
renders pure white. The sibling root layer sublayers ``scene.<ext>`` and overrides only what
differs: every light's intensity times ``pi / E`` and the cameras' exposure time set to a
neutral scale (1). A grey card of albedo 0.18 lying on the ground then renders at linear
0.18 in any client, with no script and no exposure setting. The rock colliders
(``/World/RockColliders``, one prim per rock, physics only) are deactivated there: a renderer
has no use for them and Blender would import each as an object.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from pxr import Sdf, UsdGeom, UsdLux

from marsscene.export.usd.cameras import CAMERAS_PATH, F_STOP, ISO
from marsscene.export.usd.rock_colliders import COLLIDERS_PATH
from marsscene.export.usd.stage import WORLD

__all__ = ["BLENDER_LAYER", "BLENDER_SUN_IMPORT_FACTOR", "DISPLAY_LAYER", "write_display_layers"]

DISPLAY_LAYER = "scene_display.usda"
BLENDER_LAYER = "scene_blender.usda"
#: Blender's USD importer multiplies a DistantLight's intensity by this (Blender 4.1-5.0;
#: examples/blender_render.py divides it back).
BLENDER_SUN_IMPORT_FACTOR = 4.0


def write_display_layers(stage: Any, scene: Any, out_dir: Path, root_name: str) -> list[Path]:
    """Write ``scene_display.usda`` (usdview and other display-referred clients) and
    ``scene_blender.usda`` (the same with the sun divided by Blender's import factor) over
    ``root_name``; nothing without lighting."""
    return [p for p in (
        _write_layer(stage, scene, out_dir / DISPLAY_LAYER, root_name, 1.0),
        _write_layer(stage, scene, out_dir / BLENDER_LAYER, root_name,
                     1.0 / BLENDER_SUN_IMPORT_FACTOR),
    ) if p is not None]


def _write_layer(stage: Any, scene: Any, target: Path, root_name: str,
                 sun_factor: float) -> Path | None:
    from marsscene.lighting.usd_units import usd_light_intensity

    lt = scene.lighting
    if lt is None or lt.global_horizontal_w_m2 <= 0:
        return None
    lux = usd_light_intensity(lt.global_horizontal_w_m2, units=lt.usd_units,
                              luminous_efficacy_lm_per_w=lt.luminous_efficacy_lm_per_w)
    scale = math.pi / lux
    layer = Sdf.Layer.CreateAnonymous(".usda")
    layer.subLayerPaths.append(f"./{root_name}")
    layer.defaultPrim = WORLD.strip("/")
    layer.documentation = (f"Display-referred view of {root_name}: light intensities times "
                           f"pi / E = {scale:.6g} (E = {lux:.6g}, global horizontal "
                           "illuminance), cameras at a neutral exposure"
                           + (f", the sun times {sun_factor:g} for Blender's USD import"
                              if sun_factor != 1.0 else "")
                           + ". For clients that do not apply camera exposure.")
    layer.pseudoRoot.SetInfo(UsdGeom.Tokens.upAxis, UsdGeom.Tokens.z)
    layer.pseudoRoot.SetInfo(UsdGeom.Tokens.metersPerUnit, 1.0)
    for prim in stage.Traverse():  # overs authored as specs: the sublayer is not opened here
        if prim.HasAPI(UsdLux.LightAPI):
            value = float(UsdLux.LightAPI(prim).GetIntensityAttr().Get()) * scale
            if prim.IsA(UsdLux.DistantLight):
                value *= sun_factor
            _over_attr(layer, prim.GetPath(), "inputs:intensity", value)
        elif prim.IsA(UsdGeom.Camera) and str(prim.GetPath()).startswith(CAMERAS_PATH):
            _over_attr(layer, prim.GetPath(), "exposure:time", F_STOP**2 / (ISO / 100.0))
    if stage.GetPrimAtPath(COLLIDERS_PATH):
        spec = Sdf.CreatePrimInLayer(layer, COLLIDERS_PATH)
        for p in [spec, *_ancestors(spec)]:
            p.specifier = Sdf.SpecifierOver
        spec.active = False
    if not layer.Export(str(target)):
        raise OSError(f"could not write {target}")
    return target


def _over_attr(layer: Any, path: Any, name: str, value: float) -> None:
    """An ``over`` of ``path`` (and its ancestors) with a float attribute ``name``."""
    spec = Sdf.CreatePrimInLayer(layer, path)
    for p in [spec, *_ancestors(spec)]:
        p.specifier = Sdf.SpecifierOver
    attr = Sdf.AttributeSpec(spec, name, Sdf.ValueTypeNames.Float)
    attr.default = value


def _ancestors(spec: Any) -> list[Any]:
    out = []
    parent = spec.nameParent
    while parent and parent.path != Sdf.Path.absoluteRootPath:
        out.append(parent)
        parent = parent.nameParent
    return out
