"""The batch RGB-D camera (marsscene.sensors.batch.BatchCamera) on Warp's CPU device: its
intrinsics; its depth and RGB against the CPU camera (MastCamera, MuJoCo's OpenGL renderer) on
the same 30 m world and pose; the same bytes from the same inputs; a rock's shadow on the far
side from the sun.

The CPU camera renders with headless OpenGL (EGL or OSMesa; skipped without). Warp compiles the
camera's kernels on first use (about 5 s on the 2-core machine), cached afterwards.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("warp", reason="needs marsscene[gpu] (warp-lang)")
pytest.importorskip("mujoco_warp", reason="needs marsscene[gpu] (mujoco-warp)")

import mujoco
import warp as wp

from marsscene.env.batch import WorldBatch
from marsscene.errors import RuntimeSimError
from marsscene.rover.config import CameraConfig, RunConfig
from marsscene.sensors.batch import BatchCamera
from marsscene.sensors.batch.rgbd import camera_rays, scene_lights
from marsscene.sensors.camera_scene import scene_seed
from tests.support.session_cache import shared_folder

_BASE = {"terrain": {"source": "procedural", "size_m": [30.0, 30.0], "post_m": 0.25,
                     "rms_height_m": 0.05},
         "craters": {"enabled": False},
         "rocks": {"k": 0.05, "mjcf_min_diameter_m": 0.3}}
CAM = CameraConfig(width_px=96, height_px=72, texture_px=512, texture_tile_m=4.0)


@pytest.fixture(scope="module")
def world(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from marsscene.env import WorldSampler

    def sampler(folder: Path) -> WorldSampler:
        return WorldSampler(base=_BASE, count=1, seed=3, cache_dir=str(folder))

    folder = shared_folder(tmp_path_factory, "navworld", [_BASE, 3],
                           lambda folder: sampler(folder).path(0))
    return sampler(folder).path(0)


def _pose(pos: Any, mat: Any, n: int = 1) -> tuple[Any, Any]:
    p = np.broadcast_to(np.asarray(pos, np.float32), (n, 1, 3))
    m = np.broadcast_to(np.asarray(mat, np.float32).reshape(3, 3), (n, 1, 3, 3))
    return (wp.array(np.ascontiguousarray(p), dtype=wp.vec3, device="cpu"),
            wp.array(np.ascontiguousarray(m), dtype=wp.mat33, device="cpu"))


def _cpu_frame(scene: Path, start_xy_m: tuple[float, float]) -> tuple[Any, Any, Any]:
    """The CPU camera's RGB and depth from the rover's navcam at ``start_xy_m``, and that
    pose for the batch camera (skipped without headless OpenGL)."""
    from marsscene.sim.rover_sim import RoverSim

    sim = RoverSim(scene, run=RunConfig(camera=CAM), start_xy_m=start_xy_m, settle_s=0.3)
    try:
        renderer = sim.make_renderer()
    except RuntimeSimError as err:
        pytest.skip(f"no headless OpenGL (EGL/OSMesa) here: {err}")
    rgb, depth = sim.render(renderer)
    renderer.close()
    cid = mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_CAMERA, "rover/navcam")
    return rgb, depth, _pose(sim.data.cam_xpos[cid], sim.data.cam_xmat[cid])


@pytest.fixture(scope="module")
def frames(world: Path) -> dict[str, Any]:
    """The CPU camera's frame and the batch camera's from the rover's navcam pose."""
    rgb, depth, pose = _cpu_frame(world, (-5.0, 1.0))
    batch = WorldBatch.build(world, pool=1)
    cam = BatchCamera(batch, 1, config=CAM, lighting=scene_lights(CAM, world),
                      seeds=[scene_seed(world)], device="cpu")
    cam.render(*pose, [0])
    return {"cpu_rgb": rgb, "cpu_depth": depth, "cam": cam, "pose": pose, "batch": batch,
            "rgb": cam.rgb.numpy()[0].transpose(1, 2, 0), "depth": cam.depth.numpy()[0],
            "seg": cam.segmentation.numpy()[0]}


def test_intrinsics_are_the_cpu_cameras() -> None:
    cfg = CameraConfig(width_px=64, height_px=48, fovy_deg=60.0)
    rays = camera_rays(cfg).reshape(48, 64, 3)
    f = 24.0 / math.tan(math.radians(30.0))
    # the top row's centre ray is half a pixel below the frustum's edge; rows go down
    assert rays[0, 32, 1] == pytest.approx((24.0 - 0.5) / f, rel=1e-6)
    assert rays[47, 32, 1] == pytest.approx(-(24.0 - 0.5) / f, rel=1e-6)
    assert rays[10, 0, 0] == pytest.approx(-(32.0 - 0.5) / f, rel=1e-6)
    assert (rays[..., 2] == -1.0).all()


def test_depth_is_the_cpu_cameras_within_2_cm(frames: dict[str, Any]) -> None:
    d, ref = frames["depth"], frames["cpu_depth"]
    both = (d > 0) & (ref > 0) & (ref < 20.0)
    assert both.mean() > 0.5
    assert float(np.median(np.abs(d[both] - ref[both]))) < 0.02
    assert abs(float((d == 0).mean()) - float((ref == 0).mean())) < 0.01  # the sky
    assert frames["cam"].intrinsics() == pytest.approx((62.354, 62.354, 48.0, 36.0), rel=1e-4)


def test_rgb_statistics_are_the_cpu_cameras(frames: dict[str, Any]) -> None:
    rgb, ref, seg = frames["rgb"].astype(float), frames["cpu_rgb"].astype(float), frames["seg"]
    ground = (seg == 1) & (frames["cpu_depth"] > 0)
    sky = (seg == 0) & (frames["cpu_depth"] == 0)
    # mean sRGB of the terrain and of the sky per channel (measured: within 2 and 8 codes)
    np.testing.assert_allclose(rgb[ground].mean(0), ref[ground].mean(0), atol=6.0)
    np.testing.assert_allclose(rgb[sky].mean(0), ref[sky].mean(0), atol=15.0)
    np.testing.assert_allclose(rgb.mean((0, 1)), ref.mean((0, 1)), atol=4.0)
    assert (seg == 2).any()  # rocks in view


def test_the_catalogues_rocks_are_drawn_as_the_cpu_camera_draws_them(
        world: Path, frames: dict[str, Any]) -> None:
    """The catalogue's rocks below the MJCF size (the CPU camera's meshes of them): depth off
    by more than 5 cm on far fewer pixels than with the batch's (MJCF) rocks alone (measured on
    three poses: 5.1 / 3.6 / 4.7 % without, 2.7 / 1.3 / 1.4 % with them)."""
    from marsscene.sensors.camera_rocks import read_rock_catalog

    rocks = read_rock_catalog(world)
    assert len(rocks) > 100  # pebbles and rocks under 0.3 m, not MJCF geoms
    cam = BatchCamera(frames["batch"], 1, config=CAM, lighting=frames["cam"].lighting,
                      seeds=[scene_seed(world)], catalogue=[rocks], device="cpu")
    cam.render(*frames["pose"], [0])
    ref = frames["cpu_depth"]

    def off_5cm(depth: np.ndarray) -> float:
        both = (depth > 0) & (ref > 0) & (ref < 20.0)
        return float((np.abs(depth - ref)[both] > 0.05).mean())

    alone, drawn = off_5cm(frames["depth"]), off_5cm(cam.depth.numpy()[0])
    assert drawn < 0.035 and drawn < 0.6 * alone, (drawn, alone)
    seg = cam.segmentation.numpy()[0]
    assert (seg == 2).sum() > 1.3 * (frames["seg"] == 2).sum()  # more rock pixels


@pytest.mark.parametrize("linear", [0.002, 0.03, 0.2, 0.7])
def test_sensor_noise_is_the_cpu_cameras(linear: float) -> None:
    """A uniform frame through the batch's noisy encoding and the CPU camera's exposure
    (fixed gain 1, the same full well and read noise): the same mean and spread of the 8-bit
    codes; each camera and frame its own noise, the same seed and frame the same bytes."""
    from marsscene.sensors.batch import _expose
    from marsscene.sensors.exposure import FULL_WELL_E, READ_NOISE_E, Exposure

    n, h, w = 2, 48, 64
    lin = wp.array(np.full((n, h * w, 3), linear, np.float32), dtype=wp.vec3, device="cpu")
    gain = wp.array(np.ones(n, np.float32), dtype=float, device="cpu")
    seeds = wp.array(np.array([5, 6], np.int32), dtype=int, device="cpu")

    def batch(frame: int) -> np.ndarray:
        rgb = wp.zeros((n, 3, h, w), dtype=wp.uint8, device="cpu")
        wp.launch(_expose.encode_noisy, dim=(n, h * w), device="cpu",
                  inputs=[lin, gain, w, seeds, frame, FULL_WELL_E, READ_NOISE_E],
                  outputs=[rgb])
        return rgb.numpy().astype(np.float64)

    first, again, second = batch(0), batch(0), batch(1)
    cpu = Exposure("fixed").apply(np.full((h, w, 3), linear, np.float32),
                                  np.random.default_rng(0)).astype(np.float64)
    assert cpu.std() > 0.3  # the noise shows in the codes at every level here
    for frame in (first[0], first[1], second[0]):
        assert frame.mean() == pytest.approx(cpu.mean(), abs=0.05 * cpu.std() + 0.05)
        assert frame.std() == pytest.approx(cpu.std(), rel=0.06)
    assert np.array_equal(first, again)
    assert not np.array_equal(first[0], first[1]) and not np.array_equal(first[0], second[0])


def test_a_noisy_camera_is_seeded_per_camera_and_frame(frames: dict[str, Any]) -> None:
    import dataclasses

    noisy = dataclasses.replace(CAM, sensor_noise=True, exposure="fixed")
    pos, mat = frames["pose"]
    pose = _pose(pos.numpy()[0, 0], mat.numpy()[0, 0], n=2)

    def camera(config: CameraConfig) -> BatchCamera:
        return BatchCamera(frames["batch"], 2, config=config, lighting=frames["cam"].lighting,
                           seeds=[0], noise_seeds=[11, 12], device="cpu")

    one, two = camera(noisy), camera(noisy)
    a, b = (c.render(*pose, [0, 0]).numpy().copy() for c in (one, two))
    later = one.render(*pose, [0, 0]).numpy()
    clean = camera(dataclasses.replace(noisy, sensor_noise=False)).render(*pose, [0, 0]).numpy()
    assert np.array_equal(a, b)  # the same seeds and frame: the same bytes
    assert not np.array_equal(a[0], a[1]) and not np.array_equal(a, later)
    gap = a.astype(float) - clean.astype(float)
    assert abs(gap.mean()) < 0.3 and 0.5 < gap.std() < 5.0  # zero-mean noise of a few codes


_HABITAT = {**_BASE, "terrain": {**_BASE["terrain"], "size_m": [60.0, 60.0]},
            "rocks": {"k": 0.02, "mjcf_min_diameter_m": 0.3},
            "assets": {"habitat": True, "xy_m": [[8.0, 0.0]]}}


@pytest.fixture(scope="module")
def habitat(tmp_path_factory: pytest.TempPathFactory) -> Path:
    import marsscene as ms

    def build(folder: Path) -> Path:
        out = folder / "scene"
        if not (out / "mjcf" / "scene.xml").is_file():
            ms.write_scene(ms.build_scene(ms.SceneConfig.from_dict(_HABITAT), seed=3), out)
        return out

    return build(shared_folder(tmp_path_factory, "habitat", [_HABITAT, 3], build))


def test_a_placed_asset_is_drawn_as_its_mesh(habitat: Path) -> None:
    """The habitat (the scene's placed asset) as its mesh in its paint's colour, not as rock
    domes of its parts' bounding boxes: depth off the CPU camera's by more than 5 cm on under
    1 % of the pixels (measured: 8.1 % as domes, 0.2 % as meshes)."""
    from marsscene.sim.batch.setup import scene_camera_world
    from marsscene.sim.world import load_world

    rgb, ref, pose = _cpu_frame(habitat, (-14.0, 1.0))
    world = load_world(habitat)
    assert len(world.assets.faces) > 100 and len(world.rocks.radius_m) < len(
        world.obstacles.radius_m)  # the habitat's parts are obstacles, not rocks
    batch, catalogue, assets = scene_camera_world(habitat)
    cam = BatchCamera(batch, 1, config=CAM, lighting=scene_lights(CAM, habitat),
                      seeds=[scene_seed(habitat)], catalogue=catalogue, assets=assets,
                      device="cpu")
    cam.render(*pose, [0])
    depth = cam.depth.numpy()[0]
    both = (depth > 0) & (ref > 0) & (ref < 30.0)
    assert (cam.segmentation.numpy()[0] == 2).mean() > 0.05  # the habitat fills the view
    assert float((np.abs(depth - ref)[both] > 0.05).mean()) < 0.01
    assert abs(float((depth == 0).mean()) - float((ref == 0).mean())) < 0.01
    assert float(np.abs(cam.rgb.numpy()[0].transpose(1, 2, 0).astype(float) - rgb).mean()) < 4.0


def test_each_camera_its_own_exposure(frames: dict[str, Any]) -> None:
    import dataclasses

    pos, mat = frames["pose"]
    pose = _pose(pos.numpy()[0, 0], mat.numpy()[0, 0], n=2)

    def gains(exposure: str, fixed: Any = None) -> np.ndarray:
        cam = BatchCamera(frames["batch"], 2, config=dataclasses.replace(CAM, exposure=exposure),
                          lighting=frames["cam"].lighting, seeds=[0], fixed_exposure=fixed,
                          device="cpu")
        cam.render(*pose, [0, 0])
        return cam.gain.numpy().copy()

    auto, fixed, mixed = gains("auto"), gains("fixed"), gains("auto", [True, False])
    assert abs(auto[0] - fixed[0]) > 1e-3 * fixed[0]  # the two modes differ on this frame
    np.testing.assert_array_equal(mixed, [fixed[0], auto[1]])


def test_same_inputs_same_bytes(frames: dict[str, Any]) -> None:
    cam = BatchCamera(frames["batch"], 2, config=CAM, lighting=frames["cam"].lighting,
                      seeds=[0], device="cpu")
    pos, mat = frames["pose"]
    pose = _pose(pos.numpy()[0, 0], mat.numpy()[0, 0], n=2)
    out = []
    for _ in range(2):
        cam.restart()
        cam.render(*pose, [0, 0])
        out.append(cam.rgb.numpy().tobytes() + cam.depth.numpy().tobytes())
    assert out[0] == out[1]
    rgb = cam.rgb.numpy()
    np.testing.assert_array_equal(rgb[0], rgb[1])  # one camera's bytes, whatever the others


def test_a_depth_only_camera_gives_the_same_depth_and_classes(world: Path,
                                                             frames: dict[str, Any]) -> None:
    """``rgb=False`` skips the shading, shadow rays and exposure: the depth and segmentation
    bytes are the shaded camera's, the RGB stays zero."""
    cam = BatchCamera(frames["batch"], 1, config=CAM, lighting=frames["cam"].lighting,
                      seeds=[scene_seed(world)], rgb=False, device="cpu")
    cam.render(*frames["pose"], [0])
    np.testing.assert_array_equal(cam.depth.numpy()[0], frames["depth"])
    np.testing.assert_array_equal(cam.segmentation.numpy()[0], frames["seg"])
    assert (frames["seg"] == 1).mean() > 0.3 and not cam.rgb.numpy().any()


def _flat_world() -> WorldBatch:
    z = np.zeros((1, 41, 41), np.float32)
    return WorldBatch(posts_z_m=z, cell_m=0.25, origins_xy_m=np.zeros((1, 2)),
                      rock_xy_m=np.array([[5.0, 5.0]]), rock_radius_m=np.array([2.0]),
                      rock_height_m=np.array([1.2]), rock_world=np.zeros(1, np.int64),
                      starts_xy_m=np.zeros((1, 1, 2)), yaws_rad=np.zeros((1, 1)),
                      goals_xy_m=np.zeros((1, 1, 2)))


@pytest.mark.parametrize("azimuth_deg", [60.0, 240.0])
def test_a_rocks_shadow_falls_away_from_the_sun(azimuth_deg: float) -> None:
    cfg = CameraConfig(width_px=64, height_px=64, fovy_deg=90.0, exposure="fixed",
                       texture_px=256, texture_tile_m=4.0,
                       sun_elevation_deg=30.0, sun_azimuth_deg=azimuth_deg, tau=0.3)
    lt = scene_lights(cfg)
    cam = BatchCamera(_flat_world(), 1, config=cfg, lighting=lt, device="cpu")
    cam.render(*_pose([5.0, 5.0, 6.0], np.eye(3)), [0])  # looking straight down
    lum, seg = cam.linear.numpy()[0].sum(-1).reshape(64, 64), cam.segmentation.numpy()[0]
    lit = float(np.median(lum[seg == 1]))
    shadow = (seg == 1) & (lum < 0.7 * lit)
    assert 20 < shadow.sum() < 0.5 * (seg == 1).sum()
    rows, cols = np.nonzero(shadow)
    offset = np.array([cols.mean() - 31.5, 31.5 - rows.mean()])  # image x = east, up = north
    sun = np.asarray(lt.sun_direction_enu[:2])
    cos = offset @ sun / np.linalg.norm(offset) / np.linalg.norm(sun)
    assert cos < -0.95
