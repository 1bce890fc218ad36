"""USD cameras and photometry: the Navcam prim equals the runtime's MuJoCo mast camera
(intrinsics and spawn pose), exposure gives middle grey, the DomeLight's sky texture resolves."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest

import marsscene as ms
from marsscene.runtime import CameraConfig, RunConfig

pxr = pytest.importorskip("pxr")
from pxr import Gf, Usd, UsdGeom, UsdLux  # noqa: E402

CFG = {
    "terrain": {"source": "procedural", "size_m": [40, 40], "post_m": 0.25,
                "rms_height_m": 0.05},
    "craters": {"enabled": False},
    "rocks": {"enabled": False},
}


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> tuple[ms.Scene, Path]:
    scene = ms.build_scene(ms.SceneConfig.from_dict(CFG), seed=3)
    out = tmp_path_factory.mktemp("cams") / "scene"
    ms.write_scene(scene, out)
    return scene, out


def test_navcam_equals_the_runtime_camera(written: tuple[ms.Scene, Path]) -> None:
    pytest.importorskip("mujoco")
    os.environ.setdefault("MUJOCO_GL", "egl")
    from marsscene.sim.rover_sim import RoverSim

    _, out = written
    stage = Usd.Stage.Open(str(out / "scene.usda"))
    cam = UsdGeom.Camera(stage.GetPrimAtPath("/World/Cameras/Navcam"))
    sim = RoverSim(out, run=RunConfig(camera=CameraConfig()))
    sim.reset()  # spawn at the terrain centre, yaw 0, settle
    k = sim.camera_intrinsics()
    gf = cam.GetCamera(Usd.TimeCode.Default())
    w, h = cam.GetPrim().GetAttribute("marsscene:camera:resolution_px").Get()
    assert (w, h) == (k["width"], k["height"])
    fy = h / 2 / math.tan(math.radians(gf.GetFieldOfView(Gf.Camera.FOVVertical)) / 2)
    fx = w / 2 / math.tan(math.radians(gf.GetFieldOfView(Gf.Camera.FOVHorizontal)) / 2)
    assert fx == pytest.approx(k["fx"], rel=1e-5) and fy == pytest.approx(k["fy"], rel=1e-5)
    assert gf.aspectRatio == pytest.approx(k["width"] / k["height"], rel=1e-6)
    # pose: the settled MuJoCo camera is within a few cm / a fraction of a degree
    xf = np.asarray(cam.ComputeLocalToWorldTransform(Usd.TimeCode.Default()))
    mj = sim.data.cam_xmat[sim.camera_id].reshape(3, 3)
    np.testing.assert_allclose(xf[3, :3], sim.data.cam_xpos[sim.camera_id], atol=0.05)
    for axis in range(3):  # rows of the USD matrix = columns of MuJoCo's camera frame
        cos = float(xf[axis, :3] @ mj[:, axis]) / np.linalg.norm(xf[axis, :3])
        assert cos > math.cos(math.radians(1.0))


def test_exposure_puts_a_grey_card_at_middle_grey(written: tuple[ms.Scene, Path]) -> None:
    scene, out = written
    lt = scene.lighting
    assert lt is not None
    stage = Usd.Stage.Open(str(out / "scene.usda"))
    sun = UsdLux.DistantLight(stage.GetPrimAtPath("/World/Lights/Sun"))
    sky = UsdLux.DomeLight(stage.GetPrimAtPath("/World/Lights/Sky"))
    # horizontal illuminance from the stage itself: sun * cos(zenith) + sky on a horizontal plane
    sun_lux = sun.GetIntensityAttr().Get() * math.sin(math.radians(lt.sun_elevation_deg))
    from marsscene.export.usd.lighting import sky_texture

    sky_lux = sky.GetIntensityAttr().Get() * sky_texture(lt)[1]
    for name in ("Navcam", "Overview"):
        cam = UsdGeom.Camera(stage.GetPrimAtPath(f"/World/Cameras/{name}"))
        scale = cam.ComputeLinearExposureScale()
        grey = scale * 0.18 * (sun_lux + sky_lux) / math.pi  # Lambertian albedo 0.18
        assert grey == pytest.approx(0.18, rel=1e-3)
        assert 1e-4 < cam.GetExposureTimeAttr().Get() < 0.1  # a real shutter time


def test_dome_texture_exists_and_resolves(written: tuple[ms.Scene, Path]) -> None:
    _, out = written
    stage = Usd.Stage.Open(str(out / "scene.usda"))
    sky = UsdLux.DomeLight(stage.GetPrimAtPath("/World/Lights/Sky"))
    asset = sky.GetTextureFileAttr().Get()
    assert not Path(asset.path).is_absolute()  # relative, travels with the folder
    resolved = Path(asset.resolvedPath)
    assert resolved.is_file() and resolved.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sky.GetTextureFormatAttr().Get() == UsdLux.Tokens.latlong


def test_overview_sees_the_terrain_centre(written: tuple[ms.Scene, Path]) -> None:
    scene, out = written
    stage = Usd.Stage.Open(str(out / "scene.usda"))
    cam = UsdGeom.Camera(stage.GetPrimAtPath("/World/Cameras/Overview"))
    frustum = cam.GetCamera(Usd.TimeCode.Default()).frustum
    x0, y0, x1, y1 = scene.heightfield.bounds_xy_m
    corners = [(x, y) for x in (x0, x1) for y in (y0, y1)] + [(0.0, 0.0)]
    for x, y in corners:  # the whole footprint is in view
        z = float(scene.heightfield.sample(x, y))
        assert frustum.Intersects(Gf.Vec3d(x, y, z))
