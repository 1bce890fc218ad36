"""The display-referred sibling layers (``scene_display.usda``, ``scene_blender.usda``): they
compose the whole scene, scale every light by pi / E and give the cameras a neutral exposure,
so a plain import into a client that ignores camera exposure renders a middle-grey ground."""

from __future__ import annotations

import math
import subprocess
import textwrap
from pathlib import Path

import numpy as np
import pytest

import marsscene as ms

pytest.importorskip("pxr")
from pxr import Usd, UsdGeom, UsdLux

from marsscene.export.usd.display import BLENDER_SUN_IMPORT_FACTOR
from marsscene.lighting.usd_units import usd_light_intensity


@pytest.fixture(scope="module")
def scene_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "procedural", "size_m": [40, 40], "post_m": 0.25,
                    "rms_height_m": 0.1},
        "rocks": {"k": 0.08, "d_min_m": 0.2}, "craters": {"enabled": False}})
    out = tmp_path_factory.mktemp("display") / "s"
    ms.write_scene(ms.build_scene(cfg, seed=4), out, formats=("usd",))
    return out


def _intensity(stage: Usd.Stage, path: str) -> float:
    return float(UsdLux.LightAPI(stage.GetPrimAtPath(path)).GetIntensityAttr().Get())


@pytest.mark.parametrize(("name", "sun_factor"), [("scene_display.usda", 1.0),
                                                  ("scene_blender.usda",
                                                   1.0 / BLENDER_SUN_IMPORT_FACTOR)])
def test_display_layers_rescale_lights_and_neutralise_exposure(scene_dir, name, sun_factor):
    import json

    base = Usd.Stage.Open(str(scene_dir / "scene.usda"))
    disp = Usd.Stage.Open(str(scene_dir / name))
    assert disp.GetRootLayer().subLayerPaths == ["./scene.usda"]
    assert disp.GetDefaultPrim().GetPath() == "/World"
    assert UsdGeom.GetStageUpAxis(disp) == "Z" and UsdGeom.GetStageMetersPerUnit(disp) == 1.0
    # the whole scene composes through it, but for the rock colliders (physics only)
    colliders = "/World/RockColliders"
    assert base.GetPrimAtPath(colliders).IsActive()
    assert not disp.GetPrimAtPath(colliders).IsActive()
    assert [p.GetPath() for p in disp.Traverse()] == [
        p.GetPath() for p in base.Traverse() if not str(p.GetPath()).startswith(colliders)]
    # E from the manifest's lighting summary, independently of the writer
    summary = json.loads((scene_dir / "manifest.json").read_text())
    lt = ms.build_scene(ms.SceneConfig.from_dict(summary["config"]), seed=4).lighting
    e = usd_light_intensity(lt.global_horizontal_w_m2, units=lt.usd_units,
                            luminous_efficacy_lm_per_w=lt.luminous_efficacy_lm_per_w)
    sun = _intensity(disp, "/World/Lights/Sun") / _intensity(base, "/World/Lights/Sun")
    sky = _intensity(disp, "/World/Lights/Sky") / _intensity(base, "/World/Lights/Sky")
    assert sun == pytest.approx(math.pi / e * sun_factor, rel=1e-6)
    assert sky == pytest.approx(math.pi / e, rel=1e-6)
    # camera exposure: the physical stage's scale pi / E, the display layer's 1
    for cam in ("Navcam", "Overview"):
        physical = UsdGeom.Camera(base.GetPrimAtPath(f"/World/Cameras/{cam}"))
        neutral = UsdGeom.Camera(disp.GetPrimAtPath(f"/World/Cameras/{cam}"))
        assert physical.ComputeLinearExposureScale() == pytest.approx(math.pi / e, rel=1e-6)
        assert neutral.ComputeLinearExposureScale() == pytest.approx(1.0)
    # a horizontal card's irradiance from the display sun is pi times the direct share of the
    # global horizontal irradiance (and the sky brings the rest: a grey card renders at albedo)
    el = math.radians(lt.sun_elevation_deg)
    direct = _intensity(disp, "/World/Lights/Sun") / sun_factor * math.sin(el)
    share = lt.direct_normal_w_m2 * math.sin(el) / lt.global_horizontal_w_m2
    assert 0.0 < share < 1.0
    assert direct == pytest.approx(math.pi * share, rel=1e-4)


def test_display_layers_are_deterministic(scene_dir, tmp_path):
    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "procedural", "size_m": [40, 40], "post_m": 0.25,
                    "rms_height_m": 0.1},
        "rocks": {"k": 0.08, "d_min_m": 0.2}, "craters": {"enabled": False}})
    ms.write_scene(ms.build_scene(cfg, seed=4), tmp_path / "again", formats=("usd",))
    for name in ("scene_display.usda", "scene_blender.usda"):
        assert (tmp_path / "again" / name).read_bytes() == (scene_dir / name).read_bytes()


def test_blender_plain_import_of_the_blender_layer_is_not_blown_out(scene_dir, tmp_path):
    """Blender's own importer, no script settings: File > Import > USD of scene_blender.usda."""
    import importlib.util
    import os
    import sys

    python = os.environ.get("MARSSCENE_BPY_PYTHON")
    if not python:
        if importlib.util.find_spec("bpy") is None:
            pytest.skip("bpy is not installed (optional: pip install bpy, Python 3.11)")
        python = sys.executable
    out = tmp_path / "plain.png"
    code = textwrap.dedent(f"""
        import bpy
        bpy.ops.wm.read_homefile(use_empty=True)  # the default scene's World, as a user has
        scene = bpy.context.scene
        scene.world = bpy.data.worlds.new("World")
        bpy.ops.wm.usd_import(filepath={str(scene_dir / "scene_blender.usda")!r})
        scene.camera = bpy.data.objects["Navcam"]
        scene.render.engine = "CYCLES"; scene.cycles.device = "CPU"; scene.cycles.samples = 16
        scene.render.resolution_x, scene.render.resolution_y = 160, 120
        scene.render.resolution_percentage = 100
        scene.render.filepath = {str(out)!r}
        bpy.ops.render.render(write_still=True)
    """)
    run = subprocess.run([python, "-c", code], capture_output=True, text=True, timeout=300,
                         check=False)
    assert run.returncode == 0, run.stderr[-2000:]
    from PIL import Image

    img = np.asarray(Image.open(out).convert("RGB"), dtype=np.float64) / 255.0
    assert 0.1 < img.mean() < 0.8
    assert (img.min(axis=2) >= 0.999).mean() < 0.05  # not the white image of scene.usda
