"""Regolith appearance in USD: large-scale albedo as the diffuse colour, detail as normals.

The same model as the MuJoCo camera (:mod:`marsscene.terrain.appearance`, tile from the
scene seed's ``"texture"`` stream; :mod:`marsscene.terrain.albedo_field` from its ``"albedo"``
stream). UsdPreviewSurface has no multiply node, so the camera's product "detail tile x
large-scale gain" cannot be authored; USD gets its two halves on two inputs:

* ``diffuseColor``: without an orthoimage, ``textures/regolith_albedo_large.png`` (sRGB) over
  the whole terrain: the detail tile's mean albedo times the seeded large-scale gain (metre
  and decametre bands), texels of ``max(1 m, size / 4096)``; with an orthoimage, the
  orthoimage (as before; its brightness is the large-scale pattern);
* ``normal``: ``textures/regolith_detail_normal.png`` (raw, tangent space, ``scale 2 /
  bias -1``), the seamless detail tile of ``DETAIL_TILE_M`` metres repeated through a
  ``UsdTransform2d`` on the terrain's ``st``, so Isaac Sim / Blender renders show the
  pebbles and micro-relief by shading.

So USD renders lack the centimetre albedo mottling and the pebbles' own albedo that the MuJoCo
camera draws (they show in USD as relief only). The tile here is 1024 px (7.8 mm texels); the
runtime camera draws 2048 px from the same generator: USD and MuJoCo share the statistics.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from functools import lru_cache
from types import SimpleNamespace
from typing import Any

import numpy as np
from pxr import Gf, Sdf, UsdShade

from marsscene.seeding import stage_rng
from marsscene.terrain.appearance import normal_map_rgb, regolith_tile

__all__ = ["DETAIL_TILE_M", "LARGE_ALBEDO_TEXTURE", "NORMAL_TEXTURE", "RegolithTextures",
           "author_regolith_detail", "large_scale_albedo", "regolith_textures"]

DETAIL_TILE_M = 8.0
DETAIL_PX = 1024
LARGE_ALBEDO_TEXTURE = "textures/regolith_albedo_large.png"
NORMAL_TEXTURE = "textures/regolith_detail_normal.png"
LARGE_TEXEL_MIN_M = 1.0
LARGE_MAX_PX = 4096


def _png(rgb: np.ndarray, *, compress_level: int = 1) -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    # zlib level 1 for the generated tiles: 5x faster than the default 6 on these noisy
    # tiles, ~3 % larger
    Image.fromarray(np.ascontiguousarray(rgb, dtype=np.uint8), mode="RGB").save(
        buf, format="PNG", compress_level=compress_level)
    return buf.getvalue()


def _srgb_u8(linear: np.ndarray) -> np.ndarray:
    x = np.clip(linear.astype(np.float64), 0.0, 1.0)
    s = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.rint(s * 255.0).astype(np.uint8)


def large_scale_albedo(heightfield: Any, mean_albedo_rgb: np.ndarray, seed: int
                       ) -> np.ndarray:
    """Linear albedo (rows, cols, 3) over the terrain footprint, image order (row 0 = north).

    ``mean_albedo_rgb`` times ``exp(log_gain)`` of the scene's albedo field at texel centres;
    texels of ``max(LARGE_TEXEL_MIN_M, size / LARGE_MAX_PX)``.
    """
    from marsscene.terrain.albedo_field import albedo_field

    field = albedo_field(rng=stage_rng(seed, "albedo"))
    width_m, height_m = heightfield.size_m
    texel = max(LARGE_TEXEL_MIN_M, width_m / LARGE_MAX_PX, height_m / LARGE_MAX_PX)
    cols, rows = max(round(width_m / texel), 1), max(round(height_m / texel), 1)
    x0, y0 = heightfield.xy_of(0, 0)
    xs = x0 + (np.arange(cols) + 0.5) * width_m / cols
    ys = y0 + (np.arange(rows)[::-1] + 0.5) * height_m / rows  # row 0 = north
    out = np.zeros((rows, cols, 3), dtype=np.float32)
    for a in range(0, rows, 256):  # bounded memory on big terrains
        xx, yy = np.meshgrid(xs, ys[a : a + 256])
        gain = np.exp(field.log_gain(xx, yy))
        out[a : a + 256] = gain[..., None] * np.asarray(mean_albedo_rgb, dtype=np.float32)
    return out


@lru_cache(maxsize=4)
def _detail_normal_png(seed: int) -> tuple[bytes, tuple[float, float, float]]:
    """The detail normal map (PNG) and the tile's mean albedo: a function of the seed alone,
    so a sweep over lighting or rocks encodes it once per process."""
    tile = regolith_tile(size_px=DETAIL_PX, tile_m=DETAIL_TILE_M,
                         rng=stage_rng(seed, "texture"))
    mean = tile.albedo_rgb.reshape(-1, 3).mean(axis=0)
    return _png(normal_map_rgb(tile)), (float(mean[0]), float(mean[1]), float(mean[2]))


@lru_cache(maxsize=4)
def _large_albedo_png(seed: int, size_m: tuple[float, float], sw_xy_m: tuple[float, float],
                      mean_rgb: tuple[float, float, float]) -> bytes:
    """The large-scale albedo PNG of a footprint (cached like the normal map)."""
    hf = SimpleNamespace(size_m=size_m, xy_of=lambda r, c: sw_xy_m)
    linear = large_scale_albedo(hf, np.asarray(mean_rgb), seed)
    srgb = np.zeros(linear.shape, dtype=np.uint8)
    for a in range(0, len(linear), 256):  # float64 temporaries of 256 rows at a time
        srgb[a:a + 256] = _srgb_u8(linear[a:a + 256])
    return _png(srgb)


@dataclass(frozen=True)
class RegolithTextures:
    """The terrain material's image files (PNG bytes), made without pxr so that
    :func:`regolith_textures` can run on a background thread while tiles are authored."""

    normal_png: bytes
    mean_albedo_rgb: tuple[float, float, float]
    large_albedo_png: bytes | None  # None where an orthoimage is the diffuse colour
    ortho_png: bytes | None  # the draped orthoimage, where there is one


def regolith_textures(scene: Any) -> RegolithTextures:
    """Encode the detail normal map, the large-scale albedo (without an orthoimage) and the
    orthoimage (with one) of ``scene``. numpy and Pillow only: safe off the main thread."""
    normal, mean = _detail_normal_png(int(scene.seed))
    large = ortho = None
    if scene.texture_rgb is None:
        hf = scene.heightfield
        x0, y0 = hf.xy_of(0, 0)
        large = _large_albedo_png(int(scene.seed), tuple(hf.size_m), (float(x0), float(y0)),
                                  mean)
    else:
        ortho = _png(scene.texture_rgb, compress_level=6)
    return RegolithTextures(normal, mean, large, ortho)


def _texture(stage: Any, path: str, file: str, st: Any, color_space: str,
             wrap: str = "repeat") -> Any:
    tex = UsdShade.Shader.Define(stage, Sdf.Path(path))
    tex.CreateIdAttr("UsdUVTexture")
    tex.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(f"../{file}")
    tex.CreateInput("sourceColorSpace", Sdf.ValueTypeNames.Token).Set(color_space)
    tex.CreateInput("wrapS", Sdf.ValueTypeNames.Token).Set(wrap)
    tex.CreateInput("wrapT", Sdf.ValueTypeNames.Token).Set(wrap)
    tex.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(st, "result")
    return tex


def author_regolith_detail(
    stage: Any, material_path: str, surface: Any, scene: Any, assets: dict[str, bytes],
    textures: RegolithTextures,
) -> None:
    """Add the detail normal map (and large-scale albedo, without an orthoimage) to ``surface``.

    ``surface`` is the material's UsdPreviewSurface shader; the terrain's ``st`` spans the
    whole terrain in [0, 1], so the detail coordinates are ``st * size / DETAIL_TILE_M``.
    """
    # image files store the top row first; the tile's row 0 is at v = 0 (the bottom)
    assets[NORMAL_TEXTURE] = textures.normal_png
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
    if textures.large_albedo_png is not None:
        assets[LARGE_ALBEDO_TEXTURE] = textures.large_albedo_png
        albedo = _texture(stage, f"{material_path}/LargeAlbedo", LARGE_ALBEDO_TEXTURE,
                          reader.ConnectableAPI(), "sRGB", wrap="clamp")
        surface.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).ConnectToSource(
            albedo.CreateOutput("rgb", Sdf.ValueTypeNames.Float3))
