"""Lighting in USD: ``/World/Lights`` with a ``UsdLux.DistantLight`` sun, a ``UsdLux.DomeLight``
sky (lat-long texture ``textures/sky.png``) and the atmosphere values as ``marsscene:*``
attributes.

* Sun: the light shines along its local -Z axis; an ``xformOp:orient`` quaternion turns local +Z
  onto the direction towards the sun (ENU, z up), so the world -Z of the light is the direction
  the sunlight travels. ``inputs:normalize = true``, so ``intensity`` is the illuminance on a
  surface facing the sun (``usd_light_intensity``; see ``marsscene/lighting/usd_units.py``).
* Sky: a DomeLight rotated +90 deg about X (its lat-long map is Y-up per OpenEXR; the stage is
  Z-up). Texture column u = azimuth / 360 (clockwise from north), row v = 0 at the zenith.
  The intensity is scaled so the textured dome gives ``k * E_diffuse_horizontal`` on a
  horizontal surface.
"""

from __future__ import annotations

import io
import math
from typing import Any

import numpy as np
from pxr import Gf, Sdf, UsdGeom, UsdLux

from marsscene.export.usd.stage import WORLD, set_kind
from marsscene.lighting.usd_units import usd_light_intensity

__all__ = ["SKY_TEXTURE", "author_lighting", "sky_texture", "sun_orientation_quat"]

SKY_TEXTURE = "textures/sky.png"
_SKY_W, _SKY_H = 128, 64


def sun_orientation_quat(direction_enu: tuple[float, float, float]) -> tuple[float, ...]:
    """Quaternion ``(w, x, y, z)`` rotating +Z onto ``direction_enu`` (shortest arc)."""
    s = np.asarray(direction_enu, dtype=np.float64)
    s = s / np.linalg.norm(s)
    axis = np.cross([0.0, 0.0, 1.0], s)
    sin_t = float(np.linalg.norm(axis))
    cos_t = float(s[2])
    if sin_t < 1e-12:
        return (1.0, 0.0, 0.0, 0.0) if cos_t > 0 else (0.0, 1.0, 0.0, 0.0)
    theta = math.atan2(sin_t, cos_t)
    a = axis / sin_t * math.sin(theta / 2.0)
    return (math.cos(theta / 2.0), float(a[0]), float(a[1]), float(a[2]))


def _srgb_encode(linear: np.ndarray) -> np.ndarray:
    c = np.clip(linear, 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)


def _srgb_decode(encoded: np.ndarray) -> np.ndarray:
    return np.where(encoded <= 0.04045, encoded / 12.92, ((encoded + 0.055) / 1.055) ** 2.4)


def sky_texture(lighting: Any) -> tuple[np.ndarray, float]:
    """The lat-long sky image (``(64, 128, 3)`` uint8, sRGB) and its cosine-weighted luminance
    integral over the upper hemisphere, ``sum Y cos(theta) dOmega`` (sr)."""
    lat = math.pi / 2 - (np.arange(_SKY_H) + 0.5) / _SKY_H * math.pi
    lon = math.pi - (np.arange(_SKY_W) + 0.5) / _SKY_W * 2 * math.pi
    la, lo = np.meshgrid(lat, lon, indexing="ij")
    # Z-up world direction of each texel (dome rotated +90 deg about X): lon 0 -> -Y (south).
    d = np.stack([np.cos(la) * np.sin(lo), -np.cos(la) * np.cos(lo), np.sin(la)], axis=-1)
    cos_gamma = np.clip(d @ np.asarray(lighting.sun_direction_enu), -1.0, 1.0)
    gamma_deg = np.degrees(np.arccos(cos_gamma))
    w = np.exp(-gamma_deg / 15.0)[..., None]  # aureole: forward-scattering peak
    horizon = 1.0 + 0.3 * (1.0 - np.clip(np.sin(la), 0.0, 1.0))[..., None]
    sky = np.asarray(lighting.sky_color_rgb) * horizon
    aureole = np.asarray(lighting.sky_aureole_rgb) * 2.5
    rgb = sky * (1.0 - w) + aureole * w
    rgb = np.where(la[..., None] < 0.0, np.asarray(lighting.sky_color_rgb) * 0.35, rgb)
    rgb = rgb / rgb.max()
    img = np.round(_srgb_encode(rgb) * 255.0).astype(np.uint8)
    lin = _srgb_decode(img.astype(np.float64) / 255.0)
    lum = lin @ np.array([0.2126, 0.7152, 0.0722])
    d_omega = np.cos(la) * (math.pi / _SKY_H) * (2 * math.pi / _SKY_W)
    integral = float(np.sum(lum * np.clip(np.sin(la), 0.0, None) * d_omega))
    return img, integral


def _png(img: np.ndarray) -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(img), mode="RGB").save(buf, format="PNG", optimize=False)
    return buf.getvalue()


def _attr(prim: Any, name: str, type_name: Any, value: Any) -> None:
    prim.CreateAttribute(f"marsscene:{name}", type_name, custom=True).Set(value)


def _atmosphere_attributes(prim: Any, lt: Any) -> None:
    d, s = Sdf.ValueTypeNames.Double, Sdf.ValueTypeNames.String
    for name, value in (
        ("atmosphere:tau", lt.tau), ("atmosphere:visibility_m", lt.visibility_m),
        ("atmosphere:extinction_per_m", lt.extinction_per_m),
        ("atmosphere:dustScaleHeight_m", lt.dust_scale_height_m),
        ("atmosphere:toa_w_m2", lt.toa_w_m2),
        ("atmosphere:directNormal_w_m2", lt.direct_normal_w_m2),
        ("atmosphere:directHorizontal_w_m2", lt.direct_horizontal_w_m2),
        ("atmosphere:diffuseHorizontal_w_m2", lt.diffuse_horizontal_w_m2),
        ("atmosphere:globalHorizontal_w_m2", lt.global_horizontal_w_m2),
        ("atmosphere:shadowContrast", lt.shadow_contrast),
        ("sun:azimuth_deg", lt.sun_azimuth_deg), ("sun:elevation_deg", lt.sun_elevation_deg),
        ("sun:distance_au", lt.distance_au),
        ("sun:angularDiameter_deg", lt.sun_angular_diameter_deg),
        ("usd:luminousEfficacy_lmPerW", lt.luminous_efficacy_lm_per_w),
    ):
        _attr(prim, name, d, float(value))
    _attr(prim, "atmosphere:skyColor", Sdf.ValueTypeNames.Color3f, Gf.Vec3f(*lt.sky_color_rgb))
    _attr(prim, "atmosphere:diffuseModel", s, lt.diffuse_model)
    _attr(prim, "sun:mode", s, lt.sun_mode)
    _attr(prim, "usd:intensityUnits", s, lt.usd_units)
    optional = (("sun:ls_deg", lt.ls_deg), ("sun:ltst_h", lt.ltst_h),
                ("site:lat_deg", lt.site_lat_deg), ("site:lonEast_deg", lt.site_lon_east_deg))
    for name, value in optional:
        if value is not None:
            _attr(prim, name, d, float(value))
    if lt.utc is not None:
        _attr(prim, "sun:utc", s, lt.utc)


def author_lighting(stage: Any, scene: Any, assets: dict[str, Any]) -> None:
    """Author ``/World/Lights`` (nothing when the lighting stage is disabled)."""
    lt = scene.lighting
    if lt is None:
        return
    lights = UsdGeom.Xform.Define(stage, Sdf.Path(f"{WORLD}/Lights"))
    set_kind(lights.GetPrim(), "group")
    _atmosphere_attributes(lights.GetPrim(), lt)
    units = {"units": lt.usd_units, "luminous_efficacy_lm_per_w": lt.luminous_efficacy_lm_per_w}

    sun = UsdLux.DistantLight.Define(stage, Sdf.Path(f"{WORLD}/Lights/Sun"))
    w, x, y, z = sun_orientation_quat(lt.sun_direction_enu)
    sun.AddOrientOp(UsdGeom.XformOp.PrecisionDouble).Set(Gf.Quatd(w, Gf.Vec3d(x, y, z)))
    sun.CreateIntensityAttr(usd_light_intensity(lt.direct_normal_w_m2, **units))
    sun.CreateExposureAttr(0.0)
    sun.CreateNormalizeAttr(True)
    sun.CreateAngleAttr(float(lt.sun_angular_diameter_deg))
    sun.CreateColorAttr(Gf.Vec3f(*lt.sun_color_rgb))

    img, integral = sky_texture(lt)
    assets[SKY_TEXTURE] = _png(img)
    sky = UsdLux.DomeLight.Define(stage, Sdf.Path(f"{WORLD}/Lights/Sky"))
    sky.AddRotateXOp().Set(90.0)
    target = usd_light_intensity(lt.diffuse_horizontal_w_m2, **units)
    sky.CreateIntensityAttr(target / integral if integral > 0 else 0.0)
    sky.CreateExposureAttr(0.0)
    sky.CreateNormalizeAttr(True)
    sky.CreateColorAttr(Gf.Vec3f(1.0, 1.0, 1.0))
    sky.CreateTextureFileAttr(Sdf.AssetPath(f"./{SKY_TEXTURE}"))
    sky.CreateTextureFormatAttr(UsdLux.Tokens.latlong)
