"""Assemble the MJCF element tree of a scene (terrain, gravity, ground material, stages)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any

from marsscene._format import fmt
from marsscene._version import __version__
from marsscene.export.mjcf.assets import add_assets
from marsscene.export.mjcf.common import (
    HFIELD_ASSET,
    INTEGRATOR,
    REGOLITH_FRICTION,
    TEXTURE_ASSET,
    png_bytes,
)
from marsscene.export.mjcf.hfield import hfield_spec
from marsscene.export.mjcf.lighting import add_lighting
from marsscene.export.mjcf.rocks import add_rocks
from marsscene.export.mjcf.terrain_lod import add_outer_terrain
from marsscene.rover.rates import PHYSICS_HZ
from marsscene.units import MARS_GRAVITY_M_S2

__all__ = ["build_mjcf", "fmt"]

def build_mjcf(scene: Any) -> tuple[ET.Element, dict[str, bytes]]:
    """Return the ``<mujoco>`` root element and the assets it references."""
    root = ET.Element("mujoco", model="marsscene")
    ET.SubElement(root, "compiler", angle="radian", autolimits="true")
    ET.SubElement(
        root, "option", timestep=fmt(1.0 / PHYSICS_HZ), gravity=fmt((0.0, 0.0, -MARS_GRAVITY_M_S2)),
        integrator=INTEGRATOR,
    )
    size_info = ET.SubElement(root, "custom")
    ET.SubElement(size_info, "text", name="marsscene",
                  data=f"marsscene {__version__} seed {scene.seed}")
    if getattr(scene, "soil", None) is not None:  # read by marsscene.sim.rover_sim.RoverSim
        ET.SubElement(size_info, "text", name="marsscene_soil_map",
                      data="../soil/soils.json: the soil under the wheels (Wong-Reece "
                      "parameters by index; soil_map.png beside it, north row first)")
    ET.SubElement(root, "visual")
    asset = ET.SubElement(root, "asset")
    world = ET.SubElement(root, "worldbody")

    spec = hfield_spec(scene.heightfield)
    ET.SubElement(asset, "hfield", name="terrain", file=HFIELD_ASSET, size=fmt(spec.size, 9))
    assets = {HFIELD_ASSET: spec.bin_bytes}
    if scene.texture_rgb is not None:
        # Orthoimage draped once over the whole hfield (texuniform false, texrepeat 1 1): image
        # row 0 (north) lands on +y, column 0 (west) on -x (checked by a rendering test).
        assets[TEXTURE_ASSET] = png_bytes(scene.texture_rgb)
        ET.SubElement(asset, "texture", name="regolith_tex", type="2d", file=TEXTURE_ASSET)
        ET.SubElement(asset, "material", name="regolith", texture="regolith_tex",
                      texrepeat="1 1", texuniform="false", rgba="1 1 1 1", specular="0.05",
                      shininess="0.1")
    else:
        ET.SubElement(asset, "texture", name="regolith_tex", type="2d", builtin="flat",
                      rgb1="0.62 0.42 0.28", width="16", height="16")
        ET.SubElement(asset, "material", name="regolith", texture="regolith_tex",
                      rgba="1 1 1 1", specular="0.05", shininess="0.1")
    ET.SubElement(
        world, "geom", name="terrain", type="hfield", hfield="terrain",
        pos=fmt(spec.pos, 9), material="regolith", friction=fmt(REGOLITH_FRICTION),
        condim="3", contype="1", conaffinity="1",
    )
    for add in (add_outer_terrain, add_rocks, add_assets, add_lighting):
        add(root, assets, scene)
    return root, assets
