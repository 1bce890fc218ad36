"""The camera at a low sun (issue 25): terrain shadows where the terrain casts them, none elsewhere.

The measurement of the issue on a small synthetic scene (64 m square, 0.25 m posts): a hill
outside the camera's terrain window toward the sun, a crater and bumps in view. Each view is
rendered with shadows and without (``CameraConfig.shadows``); the ratio of the two linear
renders per ground pixel says where the renderer put shadows. The truth is a ray march from
each pixel's world point (depth + camera pose) toward the sun over the heightfield, which knows
nothing of :mod:`marsscene.terrain.horizon`, with the sun's 0.35 deg disc: a pixel is fully lit
when the terrain's horizon lies below the disc's lower limb (by 0.05 deg), fully shadowed when
above its upper limb. Counted: ground within 30 m whose sunlit and shadowed brightness differ
enough to tell (predicted shadow ratio < 0.6), not on a boundary in the image (1 px); the
rover's own shadow is not in the heightfield, so the rover casts none in these renders.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import marsscene as ms
from marsscene.errors import RuntimeSimError
from marsscene.runtime import CameraConfig, RunConfig
from marsscene.scene import Provenance, Scene
from marsscene.sim.rover_sim import RoverSim
from marsscene.terrain.from_dem import GeoFrame
from marsscene.terrain.heightfield import Heightfield
from marsscene.testing.shadow_truth import horizon_excess_deg

#: Beyond the sun's disc (radius 0.175 deg) a pixel counts as fully lit or fully shadowed
_MARGIN_DEG = 0.05
_SIZE = {"width_px": 160, "height_px": 120, "texture_px": 256, "texture_tile_m": 4.0,
         "terrain_window_m": 24.0, "tau": 0.05, "sun_azimuth_deg": 90.0}
#: (x, y) m and heading: looking west with the sun behind, and north across it
_VIEWS = (((-3.0, 0.0), math.pi), ((-3.0, -7.0), math.pi), ((-6.0, -10.0), 0.5 * math.pi))


def _terrain() -> np.ndarray:
    from scipy.ndimage import gaussian_filter, zoom

    rng = np.random.default_rng(25)
    n = 257
    x = (np.arange(n) - n // 2) * 0.25
    xx, yy = np.meshgrid(x, x)
    z = gaussian_filter(rng.standard_normal((n, n)), 6.0)
    z *= 0.15 / z.std()
    rough = gaussian_filter(rng.standard_normal((n, n)), 1.5)
    z += rough * (0.03 / rough.std())
    # a 1 m DEM's bilinear facets (as the default scene's Gale DEM at 0.25 m posts): the
    # grazing-sun shadow-map acne of the issue lives on them
    coarse = rng.standard_normal((n // 4 + 1, n // 4 + 1))
    z += 0.06 * zoom(coarse, 4.0, order=1)[:n, :n]
    z += 2.5 * np.exp(-((xx - 22.0) ** 2 + (yy - 2.0) ** 2) / (2 * 5.0**2))  # outside the window
    for cx, cy, h in ((-9.0, -9.0, 0.8), (-14.0, 6.0, 0.6), (-20.0, -4.0, 1.0)):
        z += h * np.exp(-((xx - cx) ** 2 + (yy - cy) ** 2) / (2 * 1.5**2))
    r = np.hypot(xx + 13.0, yy + 1.0) / 5.0  # crater: bowl and rim
    z += np.where(r < 1.0, 1.4 * (r**2 - 1.0), 0.0) + 0.35 * np.exp(-((r - 1.0) / 0.2) ** 2)
    return z.astype(np.float32)


@pytest.fixture(scope="module")
def low_sun_scene(tmp_path_factory: pytest.TempPathFactory) -> Path:
    cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [10, 10]}})
    scene = Scene(heightfield=Heightfield.centered(_terrain(), 0.25), config=cfg, seed=0,
                  provenance=Provenance(frame=GeoFrame(0.0, None, None, "", 1.0)))
    out = tmp_path_factory.mktemp("lowsun") / "scene"
    ms.write_scene(scene, out, formats=("mjcf",))
    return out


def _renderer(sim: RoverSim):
    try:
        cam = sim.make_renderer()
    except RuntimeSimError as err:
        pytest.skip(f"no headless OpenGL (EGL/OSMesa) here: {err}")
    cam.model.geom_castshadow[cam.model.geom_bodyid != 0] = 0  # the rover casts nothing
    return cam


def _world_points(cam, depth_m: np.ndarray) -> np.ndarray:
    m, d, cid = cam.model, cam.data, cam.camera_id
    h, w = depth_m.shape
    f = 0.5 * h / math.tan(math.radians(float(m.cam_fovy[cid])) / 2.0)
    u, v = np.meshgrid(np.arange(w) + 0.5 - w / 2, np.arange(h) + 0.5 - h / 2)
    ray = np.stack([u / f, -v / f, -np.ones_like(u)], axis=-1) * depth_m[..., None]
    return d.cam_xpos[cid] + ray @ d.cam_xmat[cid].reshape(3, 3).T


def _shadow_errors(scene: Path, elevation_deg: float) -> tuple[int, int, int, int]:
    """(fully lit, of those rendered darker than 0.8 of the unshadowed frame, fully shadowed,
    of those rendered lit), with the sun's disc: fully lit = the terrain's horizon more than
    ``_MARGIN_DEG`` below the disc's lower limb, fully shadowed = above its upper limb."""
    from scipy.ndimage import binary_erosion

    sims, cams = [], []
    for shadows in (True, False):
        run = RunConfig(camera=CameraConfig(**_SIZE, sun_elevation_deg=elevation_deg,
                                            shadows=shadows))
        sims.append(RoverSim(scene, run=run, start_xy_m=_VIEWS[0][0], settle_s=0.2))
        cams.append(_renderer(sims[-1]))
    lt = cams[0].lighting
    sun = np.asarray(lt.sun_direction_enu)
    radius_deg = lt.sun_angular_diameter_deg / 2.0 + _MARGIN_DEG
    hf = sims[0].heightfield
    counts = np.zeros(4, dtype=np.int64)
    for xy, yaw in _VIEWS:
        lin = []
        for sim, cam in zip(sims, cams, strict=True):
            sim.reset(xy_m=xy, yaw_rad=yaw)
            cam._sync(sim)
            lin.append(cam._render(cam.camera_id, True))
        (shadowed, depth), (unshadowed, _) = lin
        assert depth is not None
        ground = (depth > 0) & (depth < 30.0)
        p = _world_points(cams[0], depth)[ground]
        facing = np.maximum(hf.normal(p[:, 0], p[:, 1]) @ sun, 0.0)
        sky = lt.diffuse_horizontal_w_m2
        predicted = sky / (sky + lt.direct_normal_w_m2 * facing)  # ratio if shadowed
        lit_sum = unshadowed[ground].sum(axis=-1)
        ratio = shadowed[ground].sum(axis=-1) / np.maximum(lit_sum, 1e-6)
        usable = (predicted < 0.6) & (lit_sum > 8 / 255)
        excess = np.zeros(len(p))
        excess[usable] = horizon_excess_deg(hf, p[usable], sun)
        masks = []
        for truth in (usable & (excess < -radius_deg), usable & (excess > radius_deg)):
            image = np.zeros(ground.shape, dtype=bool)
            image[ground] = truth
            masks.append(binary_erosion(image, np.ones((3, 3), bool))[ground])
        truly_lit, truly_shadowed = masks
        counts += [truly_lit.sum(), (truly_lit & (ratio < 0.8)).sum(), truly_shadowed.sum(),
                   (truly_shadowed & (ratio > (1.0 + predicted) / 2.0)).sum()]
    for cam in cams:
        cam.close()
    return int(counts[0]), int(counts[1]), int(counts[2]), int(counts[3])


@pytest.mark.parametrize("elevation_deg", [2.0, 5.0, 13.0])
def test_shadows_where_the_terrain_casts_them(low_sun_scene, elevation_deg) -> None:
    """Fully lit ground (penumbra-aware) is not rendered darker (ratio < 0.8: the issue-36
    figure, <= 3 %); fully shadowed ground is rendered shadowed."""
    lit, darker, shadowed, missed = _shadow_errors(low_sun_scene, elevation_deg)
    assert lit > 2000 and shadowed > 300, (lit, shadowed)  # the scene shows both
    assert darker <= 0.03 * lit, (darker, lit)
    assert missed <= 0.10 * shadowed, (missed, shadowed)


def test_far_hill_shadows_the_view_at_a_low_sun(low_sun_scene) -> None:
    """The hill 25 m east, outside the camera's 24 m terrain window, darkens the view at 2 deg
    (the previous renderer's shadow map never saw it) and not at 13 deg."""
    means = {}
    for elevation_deg in (2.0, 13.0):
        frames = []
        for shadows in (True, False):
            run = RunConfig(camera=CameraConfig(**_SIZE, sun_elevation_deg=elevation_deg,
                                                shadows=shadows))
            sim = RoverSim(low_sun_scene, run=run, start_xy_m=(-3.0, 2.0),
                           start_yaw_rad=0.5 * math.pi, settle_s=0.2)
            cam = _renderer(sim)
            cam._sync(sim)
            frames.append(cam._render(cam.camera_id, False)[0][60:].sum(axis=-1))
            cam.close()
        means[elevation_deg] = float(np.median(frames[0] / np.maximum(frames[1], 1e-6)))
    assert means[2.0] < 0.7, means  # the ground ahead lies in the hill's shadow
    assert means[13.0] > 0.95, means


def test_low_sun_and_twilight_frames_are_deterministic(low_sun_scene) -> None:
    """Same seed, same bytes; below the horizon the sky alone lights the ground."""
    frames = {}
    for elevation_deg in (2.0, -3.0):
        for rep in range(2):
            run = RunConfig(camera=CameraConfig(**_SIZE, sun_elevation_deg=elevation_deg))
            sim = RoverSim(low_sun_scene, run=run, start_xy_m=_VIEWS[0][0],
                           start_yaw_rad=_VIEWS[0][1], settle_s=0.2)
            cam = _renderer(sim)
            frames[(elevation_deg, rep)] = sim.render(cam)[0]
            if elevation_deg < 0:
                assert cam.lighting.direct_normal_w_m2 == 0.0
                assert cam.lighting.diffuse_horizontal_w_m2 > 0.0
                assert cam.world.sun_shadow is None  # no direct light, nothing to shadow
            cam.close()
    for elevation_deg in (2.0, -3.0):
        np.testing.assert_array_equal(frames[(elevation_deg, 0)], frames[(elevation_deg, 1)])
    twilight = frames[(-3.0, 0)].astype(np.float64) / 255.0
    assert 0.3 < twilight.mean() < 0.6  # auto exposure: a usable frame, not a black one
    assert twilight[60:].std() > 0.02  # the ground's albedo texture is still there


def test_fixed_exposure_at_twilight_is_dark_and_unbanded(low_sun_scene) -> None:
    """Fixed exposure (the dark protocol): twilight at -3 deg is honestly dark, and the render
    keeps its precision (no banding from an 8-bit buffer rendered at the daylight scale)."""
    run = RunConfig(camera=CameraConfig(**_SIZE, sun_elevation_deg=-3.0, exposure="fixed",
                                        exposure_gain=40.0))
    sim = RoverSim(low_sun_scene, run=run, start_xy_m=_VIEWS[0][0],
                   start_yaw_rad=_VIEWS[0][1], settle_s=0.2)
    cam = _renderer(sim)
    rgb = sim.render(cam)[0]
    cam.close()
    ground = rgb[70:, :, 0]
    assert ground.mean() < 0.6 * 255
    assert len(np.unique(ground)) > 20  # many codes on the ground, not a few bands


def test_irradiance_scale_dims_a_fixed_exposure_and_keeps_the_shadows(low_sun_scene) -> None:
    """``irradiance_scale`` (the VPR ``day-dim`` database): the same sun and shadows, every
    pixel's linear value times the factor under a fixed exposure."""
    from marsscene.sensors.exposure import srgb_encode

    decode = np.interp(np.arange(256) / 255.0, srgb_encode(np.linspace(0, 1, 4097)),
                       np.linspace(0, 1, 4097))  # 8-bit sRGB code -> linear
    linear = {}
    for scale in (1.0, 0.25):
        run = RunConfig(camera=CameraConfig(**_SIZE, sun_elevation_deg=20.0, exposure="fixed",
                                            irradiance_scale=scale))
        sim = RoverSim(low_sun_scene, run=run, start_xy_m=_VIEWS[1][0],
                       start_yaw_rad=_VIEWS[1][1], settle_s=0.2)
        cam = _renderer(sim)
        linear[scale] = decode[sim.render(cam)[0][70:]]  # the ground
        assert cam.lighting.sun_elevation_deg == 20.0
        cam.close()
    bright, dim = linear[1.0], linear[0.25]
    usable = (bright > 0.05) & (bright < 0.95)  # above 8-bit quantisation, not clipped
    assert usable.mean() > 0.5
    ratio = dim[usable] / bright[usable]
    assert abs(np.median(ratio) - 0.25) < 0.01
    assert np.percentile(np.abs(ratio - 0.25), 90) < 0.02  # shadows and shading unchanged


def test_shadowed_normals_carry_the_visibility() -> None:
    """Normals turned for the terrain's shadows (terrain, rock vertices): ``n' . s = v n . s``."""
    from marsscene.sensors.camera_shadow import shadowed_normals

    n = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.6, 0.0, 0.8]])
    sun = np.array([math.cos(0.1), 0.0, math.sin(0.1)])
    out = shadowed_normals(n, sun, np.array([0.0, 0.5, 0.0, 1.0]))
    np.testing.assert_allclose(np.linalg.norm(out, axis=1), 1.0)
    np.testing.assert_allclose(out @ sun, [0.0, 0.5 * math.cos(0.1), n[2] @ sun, n[3] @ sun],
                               atol=1e-12)
    np.testing.assert_array_equal(out[2:], n[2:])  # away from the sun, or fully lit: as given
