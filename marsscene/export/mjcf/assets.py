"""Assets in MJCF: each part of a placed asset as a static mesh geom (MuJoCo collides with its
convex hull), placed at the asset's base centre (world geoms: static, like the rocks).

Mesh assets (procedural habitat, .obj/.glb files) export each part as
``assets/asset_<name>_<i>.obj``; a referenced USD file exports its bounding box.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any

from marsscene.export.mjcf.common import TORSION_ROLL_FRICTION
from marsscene.export.mjcf.rocks import obj_bytes

__all__ = ["ASSET_FRICTION", "add_assets"]

#: Metal/composite structure on regolith or wheel (sliding, torsional, rolling).
ASSET_FRICTION = (0.8, *TORSION_ROLL_FRICTION)


def add_assets(root: ET.Element, assets: dict[str, bytes], scene: Any) -> None:
    """Add ``asset_<name>_<i>`` geoms (nothing when the scene has no assets)."""
    placed_assets = getattr(scene, "assets", None)
    if not placed_assets:
        return
    from marsscene.export.mjcf.common import fmt

    asset_el = root.find("asset")
    world = root.find("worldbody")
    assert asset_el is not None and world is not None
    ET.SubElement(asset_el, "material", name="asset_paint", rgba="0.7 0.7 0.68 1",
                  specular="0.3", shininess="0.3")
    for placed in placed_assets:
        name = f"asset_{placed.model.name}"
        pos = fmt((*placed.xy_m, placed.base_z_m), 9)
        for i, part in enumerate(placed.model.parts):
            file = f"assets/{name}_{i}.obj"
            assets[file] = obj_bytes(part.vertices, part.faces)
            ET.SubElement(asset_el, "mesh", name=f"{name}_{i}", file=file)
            ET.SubElement(world, "geom", name=f"{name}_{i}", type="mesh", mesh=f"{name}_{i}",
                          pos=pos, material="asset_paint", friction=fmt(ASSET_FRICTION),
                          contype="1", conaffinity="1", condim="3")
