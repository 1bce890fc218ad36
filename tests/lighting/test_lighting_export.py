"""USD and MJCF lights: directions through the real tools, intensities, fog, round trips."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import marsscene as ms
from marsscene.lighting import sun_direction_enu, usd_light_intensity

pxr = pytest.importorskip("pxr")
mujoco = pytest.importorskip("mujoco")

from pxr import Gf, Usd, UsdGeom, UsdLux  # noqa: E402

from marsscene.export.mjcf import validate_mjcf, write_mjcf  # noqa: E402
from marsscene.export.usd import validate_stage, write_usd  # noqa: E402
from marsscene.export.usd.lighting import sky_texture  # noqa: E402

TINY = {"terrain": {"source": "procedural", "size_m": [12.0, 10.0], "post_m": 1.0},
        "craters": {"enabled": False}, "rocks": {"enabled": False}}
CASES = [  # the MarsLab paper's 70/13 and 360/13 cases, a high sun, and landing day at Jezero
    {"sun_azimuth_deg": 70.0, "sun_elevation_deg": 13.0},
    {"sun_azimuth_deg": 360.0, "sun_elevation_deg": 13.0},
    {"sun_azimuth_deg": 200.0, "sun_elevation_deg": 80.0, "tau": 3.0},
    {"utc": "2021-02-18T20:55Z", "tau": 0.6},
]


def _scene(lighting: dict[str, object]) -> ms.Scene:
    return ms.build_scene(ms.SceneConfig.from_dict({**TINY, "lighting": lighting}), seed=0)


def _az_el(v: np.ndarray) -> tuple[float, float]:
    v = v / np.linalg.norm(v)
    return math.degrees(math.atan2(v[0], v[1])) % 360.0, math.degrees(math.asin(v[2]))


def _same_az(a: float, b: float) -> bool:
    return abs((a - b + 180.0) % 360.0 - 180.0) < 1e-4


@pytest.mark.parametrize("lighting", CASES, ids=["70-13", "360-13", "200-80", "landing"])
def test_usd_sun_direction_and_values(lighting: dict[str, object], tmp_path: Path) -> None:
    scene = _scene(lighting)
    lt = scene.lighting
    assert lt is not None
    write_usd(scene, tmp_path)
    stage = Usd.Stage.Open(str(tmp_path / "scene.usda"))
    assert validate_stage(stage) == []
    prim = stage.GetPrimAtPath("/World/Lights/Sun")
    assert prim.IsA(UsdLux.DistantLight)
    xf = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(Usd.TimeCode.Default())
    travel = np.array(xf.TransformDir(Gf.Vec3d(0.0, 0.0, -1.0)))  # the light shines along -Z
    az, el = _az_el(-travel)
    if "utc" not in lighting:
        assert _same_az(az, float(lighting["sun_azimuth_deg"]))  # type: ignore[arg-type]
        assert el == pytest.approx(lighting["sun_elevation_deg"], abs=1e-4)
    assert _same_az(az, lt.sun_azimuth_deg) and el == pytest.approx(lt.sun_elevation_deg, abs=1e-4)
    light = UsdLux.DistantLight(prim)
    assert light.GetIntensityAttr().Get() == pytest.approx(
        usd_light_intensity(lt.direct_normal_w_m2), rel=1e-6)
    assert light.GetAngleAttr().Get() == pytest.approx(lt.sun_angular_diameter_deg, rel=1e-6)
    assert 0.3 < light.GetAngleAttr().Get() < 0.42  # Mars: 0.35 deg at the mean distance
    assert light.GetNormalizeAttr().Get() is True
    lights = stage.GetPrimAtPath("/World/Lights")
    assert lights.GetAttribute("marsscene:atmosphere:tau").Get() == pytest.approx(lt.tau)
    assert lights.GetAttribute("marsscene:atmosphere:visibility_m").Get() == pytest.approx(
        lt.visibility_m)
    assert lights.GetAttribute("marsscene:atmosphere:diffuseHorizontal_w_m2").Get() == (
        pytest.approx(lt.diffuse_horizontal_w_m2))


def test_usd_dome_gives_the_diffuse_irradiance(tmp_path: Path) -> None:
    scene = _scene({"utc": "2021-02-18T20:55Z", "tau": 1.0})
    lt = scene.lighting
    assert lt is not None
    write_usd(scene, tmp_path)
    stage = Usd.Stage.Open(str(tmp_path / "scene.usda"))
    dome = UsdLux.DomeLight(stage.GetPrimAtPath("/World/Lights/Sky"))
    assert dome.GetTextureFormatAttr().Get() == "latlong"
    assert (tmp_path / "textures" / "sky.png").is_file()
    xf = UsdGeom.Xformable(dome.GetPrim()).ComputeLocalToWorldTransform(Usd.TimeCode.Default())
    assert np.allclose(xf.TransformDir(Gf.Vec3d(0, 1, 0)), (0, 0, 1), atol=1e-12)  # Y-up map
    _, integral = sky_texture(lt)
    horizontal = dome.GetIntensityAttr().Get() * integral  # sum L cos(theta) dOmega
    assert horizontal == pytest.approx(usd_light_intensity(lt.diffuse_horizontal_w_m2), rel=1e-5)
    # the aureole: the brightest upper-hemisphere texel lies towards the sun
    from PIL import Image

    img = np.asarray(Image.open(tmp_path / "textures" / "sky.png"), dtype=float)
    h, w, _ = img.shape
    row, col = np.unravel_index(np.argmax(img[: h // 2].sum(axis=-1)), (h // 2, w))
    assert abs(((col + 0.5) / w * 360.0 - lt.sun_azimuth_deg + 180) % 360 - 180) < 360.0 / w
    assert 90.0 - (row + 0.5) / h * 180.0 == pytest.approx(lt.sun_elevation_deg, abs=180.0 / h)


def test_usd_and_mjcf_are_byte_reproducible(tmp_path: Path) -> None:
    for sub in ("a", "b"):
        scene = _scene({"utc": "2021-02-18T20:55Z"})
        write_usd(scene, tmp_path / sub)
        write_mjcf(scene, tmp_path / sub)
    for name in ("scene.usda", "textures/sky.png", "mjcf/scene.xml"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()


@pytest.mark.parametrize("lighting", CASES, ids=["70-13", "360-13", "200-80", "landing"])
def test_mjcf_sun_direction_fog_and_ambient(lighting: dict[str, object], tmp_path: Path) -> None:
    scene = _scene(lighting)
    lt = scene.lighting
    assert lt is not None
    path = write_mjcf(scene, tmp_path)[-1]
    model, _ = validate_mjcf(path, seconds=0.1)
    i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_LIGHT, "sun")
    az, el = _az_el(-np.asarray(model.light_dir[i], dtype=float))
    assert _same_az(az, lt.sun_azimuth_deg) or abs(el) > 89.99
    assert el == pytest.approx(lt.sun_elevation_deg, abs=1e-4)
    np.testing.assert_allclose(-model.light_dir[i], sun_direction_enu(az, el), atol=2e-6)
    fog_end_m = model.vis.map.fogend * model.stat.extent
    assert fog_end_m == pytest.approx(lt.visibility_m, rel=1e-4)
    assert model.vis.map.fogstart == 0.0
    ambient = np.asarray(model.vis.headlight.ambient)
    assert ambient[0] > ambient[1] > ambient[2] > 0.0  # butterscotch sky light
    assert np.all(np.asarray(model.vis.headlight.diffuse) == 0.0)


def test_mjcf_dust_dims_the_sun(tmp_path: Path) -> None:
    diffuse = []
    for tau in (0.3, 3.0):
        path = write_mjcf(_scene({"utc": "2021-02-18T20:55Z", "tau": tau}), tmp_path / str(tau))[-1]
        model, _ = validate_mjcf(path, seconds=0.05)
        diffuse.append(float(model.light_diffuse[0].sum()))
    assert diffuse[1] < 0.3 * diffuse[0]


def test_mjcf_without_lighting_keeps_neutral_lights(tmp_path: Path) -> None:
    path = write_mjcf(_scene({"enabled": False}), tmp_path)[-1]
    model, _ = validate_mjcf(path, seconds=0.05)
    np.testing.assert_allclose(model.vis.headlight.ambient, [0.3, 0.3, 0.3])
    np.testing.assert_allclose(model.light_dir[0], [-0.5, -0.5, -0.707107], atol=1e-5)
