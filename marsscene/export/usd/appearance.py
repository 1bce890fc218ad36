"""Regolith appearance in USD: the camera's detail albedo and normal map on the terrain.

The same model as the MuJoCo camera (:mod:`marsscene.terrain.appearance`, drawn from the
scene seed's ``"texture"`` stream): a seamless detail tile of ``DETAIL_TILE_M`` metres,
repeated over the terrain through a ``UsdTransform2d`` on the terrain's ``st``:

* ``textures/regolith_detail_albedo.png`` (sRGB) drives ``diffuseColor`` when the scene has
  no orthoimage (with one, the orthoimage stays the diffuse colour: UsdPreviewSurface has no
  multiply node to modulate it);
* ``textures/regolith_detail_normal.png`` (raw, tangent space, ``scale 2 / bias -1``) drives
  ``normal`` in both cases, so Isaac Sim / Blender renders show the micro-relief.

The tile here is 1024 px (7.8 mm texels); the runtime camera draws 2048 px from the same
generator, so USD and MuJoCo share the statistics, not every texel.
"""

from __future__ import annotations

import io
from typing import Any

import numpy as np
from pxr import Gf, Sdf, UsdShade

from marsscene.seeding import stage_rng
from marsscene.terrain.appearance import normal_map_rgb, regolith_tile

__all__ = ["ALBEDO_TEXTURE", "DETAIL_TILE_M", "NORMAL_TEXTURE", "author_regolith_detail"]

DETAIL_TILE_M = 8.0
DETAIL_PX = 1024
ALBEDO_TEXTURE = "textures/regolith_detail_albedo.png"
NORMAL_TEXTURE = "textures/regolith_detail_normal.png"


def _png(rgb: np.ndarray) -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    # zlib level 1: 5x faster than the default 6 on these noisy tiles, ~3 % larger
    Image.fromarray(np.ascontiguousarray(rgb, dtype=np.uint8)).save(buf, format="PNG",
                                                                    compress_level=1)
    return buf.getvalue()


def _srgb_u8(linear: np.ndarray) -> np.ndarray:
    x = np.clip(linear.astype(np.float64), 0.0, 1.0)
    s = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.rint(s * 255.0).astype(np.uint8)


def _texture(stage: Any, path: str, file: str, st: Any, color_space: str) -> Any:
    tex = UsdShade.Shader.Define(stage, Sdf.Path(path))
    tex.CreateIdAttr("UsdUVTexture")
    tex.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(f"../{file}")
    tex.CreateInput("sourceColorSpace", Sdf.ValueTypeNames.Token).Set(color_space)
    tex.CreateInput("wrapS", Sdf.ValueTypeNames.Token).Set("repeat")
    tex.CreateInput("wrapT", Sdf.ValueTypeNames.Token).Set("repeat")
    tex.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(st, "result")
    return tex


def author_regolith_detail(
    stage: Any, material_path: str, surface: Any, scene: Any, assets: dict[str, bytes]
) -> None:
    """Add the detail normal map (and albedo, without an orthoimage) to ``surface``.

    ``surface`` is the material's UsdPreviewSurface shader; the terrain's ``st`` spans the
    whole terrain in [0, 1], so the detail coordinates are ``st * size / DETAIL_TILE_M``.
    """
    tile = regolith_tile(size_px=DETAIL_PX, tile_m=DETAIL_TILE_M,
                         rng=stage_rng(scene.seed, "texture"))
    # image files store the top row first; the tile's row 0 is at v = 0 (the bottom)
    assets[NORMAL_TEXTURE] = _png(normal_map_rgb(tile))
    reader = UsdShade.Shader.Define(stage, Sdf.Path(f"{material_path}/DetailStReader"))
    reader.CreateIdAttr("UsdPrimvarReader_float2")
    reader.CreateInput("varname", Sdf.ValueTypeNames.String).Set("st")
    xform = UsdShade.Shader.Define(stage, Sdf.Path(f"{material_path}/DetailTransform"))
    xform.CreateIdAttr("UsdTransform2d")
    width_m, height_m = scene.heightfield.size_m
    xform.CreateInput("scale", Sdf.ValueTypeNames.Float2).Set(
        Gf.Vec2f(width_m / DETAIL_TILE_M, height_m / DETAIL_TILE_M))
    xform.CreateInput("in", Sdf.ValueTypeNames.Float2).ConnectToSource(
        reader.ConnectableAPI(), "result")
    st = xform.ConnectableAPI()
    normal = _texture(stage, f"{material_path}/DetailNormal", NORMAL_TEXTURE, st, "raw")
    normal.CreateInput("scale", Sdf.ValueTypeNames.Float4).Set(Gf.Vec4f(2, 2, 2, 1))
    normal.CreateInput("bias", Sdf.ValueTypeNames.Float4).Set(Gf.Vec4f(-1, -1, -1, 0))
    # UsdUVTexture's outputs are float3 (the validator checks the declared type)
    surface.CreateInput("normal", Sdf.ValueTypeNames.Normal3f).ConnectToSource(
        normal.CreateOutput("rgb", Sdf.ValueTypeNames.Float3))
    if scene.texture_rgb is None:
        assets[ALBEDO_TEXTURE] = _png(_srgb_u8(tile.albedo_rgb[::-1]))
        albedo = _texture(stage, f"{material_path}/DetailAlbedo", ALBEDO_TEXTURE, st, "sRGB")
        surface.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).ConnectToSource(
            albedo.CreateOutput("rgb", Sdf.ValueTypeNames.Float3))
