"""Blender check (optional): import the stage with Blender's USD importer, render the Navcam
with Cycles and check the exposure: neither blown out nor black, sky brighter than shadows.

Runs when ``bpy`` imports in this interpreter, or with ``MARSSCENE_BPY_PYTHON`` pointing to a
Python that has it (bpy pins numpy 1.26, so it often lives in its own venv); skipped otherwise.
"""

from __future__ import annotations

import importlib.util
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import marsscene as ms

pxr = pytest.importorskip("pxr")
from pxr import Gf, Usd, UsdGeom  # noqa: E402

SCRIPT = Path(__file__).resolve().parents[2] / "examples" / "blender_render.py"


def _bpy_python() -> str:
    env = os.environ.get("MARSSCENE_BPY_PYTHON")
    if env:
        return env
    if importlib.util.find_spec("bpy") is None:
        pytest.skip("bpy is not installed (optional: pip install bpy, Python 3.11)")
    return sys.executable


def test_blender_renders_a_correctly_exposed_navcam_image(tmp_path: Path) -> None:
    python = _bpy_python()
    from PIL import Image

    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "procedural", "size_m": [60, 60], "post_m": 0.25,
                    "rms_height_m": 0.1},
        "rocks": {"k": 0.08, "d_min_m": 0.2},
        "craters": {"enabled": False},
    })
    ms.write_scene(ms.build_scene(cfg, seed=4), tmp_path / "s", formats=("usd",))
    stage_path = tmp_path / "s" / "scene.usda"
    stage = Usd.Stage.Open(str(stage_path))
    cam = UsdGeom.Camera(stage.GetPrimAtPath("/World/Cameras/Navcam"))
    exposure = cam.ComputeLinearExposureScale()
    # the top image row looks above the horizon (the top rows are sky)
    xf = np.asarray(cam.ComputeLocalToWorldTransform(Usd.TimeCode.Default()))
    gf = cam.GetCamera(Usd.TimeCode.Default())
    half_fovy = math.radians(gf.GetFieldOfView(Gf.Camera.FOVVertical) / 2)
    top_ray = -xf[2, :3] * math.cos(half_fovy) + xf[1, :3] * math.sin(half_fovy)
    assert top_ray[2] > 0.05
    out = tmp_path / "navcam.png"
    run = subprocess.run(
        [python, str(SCRIPT), str(stage_path), str(out), "--exposure", repr(exposure),
         "--size", "160", "120", "--samples", "16"],
        capture_output=True, text=True, timeout=300, check=False)
    assert run.returncode == 0, run.stderr[-2000:]
    img = np.asarray(Image.open(out).convert("RGB"), dtype=np.float64) / 255.0
    assert 0.15 < img.mean() < 0.7
    assert (img.min(axis=2) >= 0.999).mean() < 0.02  # not blown out to white
    grey = img.mean(axis=2)
    sky = grey[:10].mean()
    shadows = np.percentile(grey[60:], 5)  # darkest ground pixels (rock shadows)
    assert sky > shadows + 0.1
    assert img[:10, :, 0].mean() > img[:10, :, 2].mean()  # butterscotch sky, not grey or blue
