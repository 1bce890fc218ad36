"""Lighting in MJCF: a directional sun, sky ambient (headlight), a gradient skybox and dust fog.

Mapping (MuJoCo light colours are unitless OpenGL factors):

* sun ``<light directional>``: ``dir`` = the direction sunlight travels (``-sun_direction_enu``),
  ``diffuse = sun_rgb * min(E_direct_normal / MJCF_REFERENCE_W_M2, 1)``;
* sky: ``<visual><headlight ambient>`` = ``sky_rgb * min(E_diffuse_horizontal / ref, 1)``
  (headlight diffuse/specular 0: the sky is not a camera-mounted lamp);
* dust: ``<visual><map fogstart="0" fogend>`` with ``fogend`` = meteorological visibility
  (2 % contrast, ``3.912 H / tau``) divided by the model extent (MuJoCo measures fog in units of
  ``stat.extent``; estimated here as ``2 sqrt(hx^2 + hy^2 + dz^2)`` of the terrain, as MuJoCo
  computes it for the terrain-only scene); ``<rgba fog haze>`` = sky colour (sRGB).
  Fog is drawn when the viewer's Fog render flag is on.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from typing import Any

from marsscene.export.mjcf.hfield import hfield_spec

__all__ = ["MJCF_REFERENCE_W_M2", "add_lighting", "model_extent_m"]

#: Irradiance mapped to a light colour of 1 (about a clear midday global irradiance on Mars).
MJCF_REFERENCE_W_M2 = 300.0


def _fmt(values: Any, digits: int = 6) -> str:
    out = []
    for v in values if isinstance(values, tuple | list) else [values]:
        s = f"{float(v):.{digits}g}"
        out.append("0" if s in ("-0", "0") else s)
    return " ".join(out)


def _srgb(rgb: tuple[float, float, float]) -> tuple[float, ...]:
    return tuple(12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055 for c in rgb)


def model_extent_m(scene: Any) -> float:
    """MuJoCo's ``stat.extent`` of the terrain: twice the distance from the hfield's base
    centre to its farthest top corner."""
    spec = hfield_spec(scene.heightfield)
    hx, hy = spec.radius_xy_m
    return 2.0 * math.sqrt(hx * hx + hy * hy + spec.elevation_range_m ** 2)


def add_lighting(root: ET.Element, assets: dict[str, bytes], scene: Any) -> None:
    """Add the sun and sky (a neutral headlight and a default sun when lighting is disabled)."""
    visual = root.find("visual")
    world = root.find("worldbody")
    asset = root.find("asset")
    assert visual is not None and world is not None
    lt = scene.lighting
    if lt is None:
        ET.SubElement(visual, "headlight", ambient="0.3 0.3 0.3", diffuse="0.6 0.6 0.6",
                      specular="0 0 0")
        ET.SubElement(world, "light", name="sun", directional="true", pos="0 0 100",
                      dir="-0.5 -0.5 -0.707107", diffuse="0.8 0.75 0.7", castshadow="true")
        return
    sun_gain = min(lt.direct_normal_w_m2 / MJCF_REFERENCE_W_M2, 1.0)
    sky_gain = min(lt.diffuse_horizontal_w_m2 / MJCF_REFERENCE_W_M2, 1.0)
    extent = model_extent_m(scene)
    sky_srgb = _srgb(lt.sky_color_rgb)
    ET.SubElement(visual, "headlight", ambient=_fmt(tuple(c * sky_gain for c in lt.sky_color_rgb)),
                  diffuse="0 0 0", specular="0 0 0")
    fog_end = lt.visibility_m / extent if math.isfinite(lt.visibility_m) else 1e6
    ET.SubElement(visual, "map", fogstart="0", fogend=_fmt(min(fog_end, 1e6)))
    ET.SubElement(visual, "rgba", fog=_fmt((*sky_srgb, 1.0)), haze=_fmt((*sky_srgb, 1.0)))
    if asset is not None:
        zenith = tuple(c * 0.75 for c in sky_srgb)
        ET.SubElement(asset, "texture", name="sky", type="skybox", builtin="gradient",
                      rgb1=_fmt(zenith), rgb2=_fmt(sky_srgb), width="64", height="64")
    s = lt.sun_direction_enu
    ET.SubElement(
        world, "light", name="sun", directional="true",
        pos=_fmt(tuple(c * extent for c in s)), dir=_fmt(tuple(-c for c in s)),
        diffuse=_fmt(tuple(c * sun_gain for c in lt.sun_color_rgb)), specular="0.1 0.1 0.1",
        castshadow="true",
    )
