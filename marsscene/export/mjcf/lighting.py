"""Lighting in MJCF: a directional sun, sky ambient/headlight and dust fog."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any

__all__ = ["add_lighting"]


def add_lighting(root: ET.Element, assets: dict[str, bytes], scene: Any) -> None:
    """Add the sun and sky (a neutral headlight and a default sun when lighting is disabled)."""
    visual = root.find("visual")
    world = root.find("worldbody")
    assert visual is not None and world is not None
    if scene.lighting is None:
        ET.SubElement(visual, "headlight", ambient="0.3 0.3 0.3", diffuse="0.6 0.6 0.6",
                      specular="0 0 0")
        ET.SubElement(world, "light", name="sun", directional="true", pos="0 0 100",
                      dir="-0.5 -0.5 -0.707107", diffuse="0.8 0.75 0.7", castshadow="true")
        return
