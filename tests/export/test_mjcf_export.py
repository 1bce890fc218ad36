"""MJCF: compiles, steps without warnings, and the hfield matches the heightfield."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import marsscene as ms
from marsscene.export.mjcf import validate_mjcf

mujoco = pytest.importorskip("mujoco")


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> tuple[ms.Scene, Path]:
    cfg = ms.SceneConfig.from_dict(
        {"terrain": {"source": "procedural", "size_m": [24.0, 16.0], "post_m": 0.25,
                     "rms_height_m": 0.4},
         "export": {"formats": ["mjcf"]},
         "rocks": {"enabled": False}, "craters": {"enabled": False}}
    )
    scene = ms.build_scene(cfg, seed=5)
    out = tmp_path_factory.mktemp("mjcf") / "scene"
    ms.write_scene(scene, out)
    return scene, out / "mjcf" / "scene.xml"


def test_compiles_and_steps_without_warnings(written: tuple[ms.Scene, Path]) -> None:
    _, xml = written
    model, data = validate_mjcf(xml, seconds=1.0)
    assert model.opt.gravity[2] == pytest.approx(-3.72)
    assert data.time == pytest.approx(1.0, abs=model.opt.timestep)


def test_hfield_heights_match_heightfield(written: tuple[ms.Scene, Path]) -> None:
    scene, xml = written
    model = mujoco.MjModel.from_xml_path(str(xml))
    hf = scene.heightfield
    nrow, ncol = int(model.hfield_nrow[0]), int(model.hfield_ncol[0])
    assert (nrow, ncol) == hf.shape
    sx, sy, sz, _ = model.hfield_size[0]
    assert (2 * sx, 2 * sy) == pytest.approx(hf.size_m)
    geom = model.geom("terrain")
    z = model.hfield_data.reshape(nrow, ncol) * sz + geom.pos[2]
    np.testing.assert_allclose(z, hf.z_m, atol=2e-4 * sz + 1e-5)


def _drop_box_xml(scene_xml: Path, x: float, y: float, z0: float) -> str:
    root = ET.parse(scene_xml).getroot()
    world = root.find("worldbody")
    assert world is not None
    body = ET.SubElement(world, "body", name="box", pos=f"{x} {y} {z0}")
    ET.SubElement(body, "freejoint")
    ET.SubElement(body, "geom", name="box", type="box", size="0.15 0.15 0.1", mass="5")
    return ET.tostring(root, encoding="unicode")


@pytest.fixture(scope="module")
def gentle(tmp_path_factory: pytest.TempPathFactory) -> tuple[ms.Scene, Path]:
    cfg = ms.SceneConfig.from_dict(
        {"terrain": {"source": "procedural", "size_m": [24.0, 16.0], "post_m": 0.25,
                     "rms_height_m": 0.3, "hurst": 0.95},
         "export": {"formats": ["mjcf"]},
         "rocks": {"enabled": False}, "craters": {"enabled": False}}
    )
    scene = ms.build_scene(cfg, seed=8)
    out = tmp_path_factory.mktemp("mjcf") / "gentle"
    ms.write_scene(scene, out)
    return scene, out / "mjcf" / "scene.xml"


@pytest.mark.parametrize("xy", [(0.0, 0.0), (-7.3, 4.1), (9.6, -5.2)])
def test_dropped_box_rests_at_the_predicted_height(
    gentle: tuple[ms.Scene, Path], xy: tuple[float, float]
) -> None:
    scene, xml = gentle
    hf = scene.heightfield
    x, y = xy
    text = _drop_box_xml(xml, x, y, float(hf.sample(x, y)) + 0.25)
    assets = {"assets/terrain.bin": (xml.parent / "assets/terrain.bin").read_bytes()}
    model = mujoco.MjModel.from_xml_string(text, assets)
    data = mujoco.MjData(model)
    # 0.37 s fall, then settling: a box that lands on a 20 degree slope slides a little first
    for _ in range(int(3.0 / model.opt.timestep)):
        mujoco.mj_step(model, data)
    assert not any(w.number for w in data.warning)
    assert np.linalg.norm(data.qvel[:3]) < 0.03  # came to rest (soft-contact creep only)
    # Centre of the box's bottom face, in world coordinates, sits on the heightfield surface.
    rot = data.geom("box").xmat.reshape(3, 3)
    bottom = data.geom("box").xpos - rot[:, 2] * 0.1
    assert bottom[2] == pytest.approx(float(hf.sample(bottom[0], bottom[1])), abs=0.02)
