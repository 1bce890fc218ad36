"""Test helper: drop a box into a written MJCF scene and report where it comes to rest."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import mujoco


def drop_box(xml: Path, xyz_m: tuple[float, float, float], seconds: float = 1.5) -> float:
    """Height (in m) of a 0.4 m box's centre after falling from ``xyz_m`` for ``seconds``;
    asserts MuJoCo raised no warning on the way."""
    root = ET.parse(xml).getroot()
    world = root.find("worldbody")
    assert world is not None
    body = ET.SubElement(world, "body", name="box", pos=" ".join(str(v) for v in xyz_m))
    ET.SubElement(body, "freejoint")
    ET.SubElement(body, "geom", name="box", type="box", size="0.2 0.2 0.2", mass="5")
    assets = {str(p.relative_to(xml.parent)): p.read_bytes()
              for p in (xml.parent / "assets").iterdir()}
    model = mujoco.MjModel.from_xml_string(ET.tostring(root, encoding="unicode"), assets)
    data = mujoco.MjData(model)
    for _ in range(int(seconds / model.opt.timestep)):
        mujoco.mj_step(model, data)
    assert not any(w.number for w in data.warning)
    return float(data.body("box").xpos[2])
