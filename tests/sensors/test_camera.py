"""Camera imagery a visual front end can use: statistics, tracking, RGB-D VO, stereo, rocks."""

from __future__ import annotations

import json

import numpy as np
import pytest

cv2 = pytest.importorskip("cv2")

import marsscene as ms  # noqa: E402
from marsscene.errors import RuntimeSimError  # noqa: E402
from marsscene.runtime import CameraConfig, RunConfig, read_tum  # noqa: E402
from marsscene.seeding import stage_rng  # noqa: E402
from marsscene.sim.driver import drive_sim  # noqa: E402
from marsscene.sim.rover_sim import RoverSim  # noqa: E402
from marsscene.testing.vision import camera_poses, corners, rgbd_vo  # noqa: E402

_ROCKY = {
    "terrain": {"source": "procedural", "size_m": [40, 40], "post_m": 0.25, "rms_height_m": 0.05},
    "craters": {"enabled": False},
    "rocks": {"enabled": True, "k": 0.05, "d_min_m": 0.1},
}
_SMALL = {"width_px": 320, "height_px": 240, "texture_px": 512, "texture_tile_m": 4.0}


@pytest.fixture(scope="module")
def rocky_scene(tmp_path_factory: pytest.TempPathFactory):
    scene = ms.build_scene(ms.SceneConfig.from_dict(_ROCKY), seed=5)
    out = tmp_path_factory.mktemp("rocky") / "scene"
    ms.write_scene(scene, out, formats=("mjcf",))
    return out


def _renderer(sim: RoverSim):
    try:
        return sim.make_renderer()
    except RuntimeSimError as err:
        pytest.skip(f"no headless OpenGL (EGL/OSMesa) here: {err}")


@pytest.fixture(scope="module")
def drive_run(rocky_scene, tmp_path_factory):
    """2.4 m straight at 0.3 m/s, 320x240 RGB-D at 10 Hz, logged to a run folder."""
    run = RunConfig(camera=CameraConfig(**_SMALL, stereo=True))
    sim = RoverSim(rocky_scene, run=run, start_xy_m=(-6.0, 1.0))
    _renderer(sim).close()
    out = tmp_path_factory.mktemp("run") / "r"
    drive_sim(sim, command=(0.3, 0.0), seconds=8.0, out_dir=out, rng=stage_rng(1, "sensors"))
    return out


def _frames(run_dir):
    from PIL import Image

    rows = [r.split(",") for r in (run_dir / "camera/stamps.csv").read_text().splitlines()[1:]]
    t = np.array([float(r[0]) for r in rows])
    rgb = [np.asarray(Image.open(run_dir / "camera" / r[1])) for r in rows]
    depth = [np.asarray(Image.open(run_dir / "camera" / r[2])).astype(np.float32) / 1000
             for r in rows]
    return t, rgb, depth


def test_image_statistics_tracking_and_rgbd_vo(drive_run) -> None:
    t, rgb, depth = _frames(drive_run)
    intr = json.loads((drive_run / "camera/intrinsics.json").read_text())
    assert {"fx", "fy", "cx", "cy", "depth_unit_m"} <= intr.keys() and len(rgb) == 81
    mean = np.array([im.mean() / 255 for im in rgb])
    sat = np.array([(im.max(axis=-1) >= 255).mean() for im in rgb])
    assert np.all((mean > 0.3) & (mean < 0.6)), mean
    assert sat.max() < 0.02
    gt = read_tum(drive_run / "gt.tum")
    idx = np.searchsorted(gt.timestamps_s, t - 1e-9)
    cam_world = camera_poses(gt.xyz_m[idx], gt.quat_xyzw[idx], ms.runtime.RoverConfig())
    vo = rgbd_vo(rgb, depth, intr, cam_world)
    # 320x240 has a quarter of the 640x480 pixels: the benchmark checks >= 300 at 640x480
    assert np.median(vo.corners_per_frame) >= 150, vo.corners_per_frame
    assert (vo.inliers_per_pair >= 30).mean() >= 0.95, vo.inliers_per_pair
    assert vo.path_m > 2.0
    assert vo.drift_fraction <= 0.02, vo.drift_fraction


def test_stereo_pair_is_rectified_with_navcam_baseline(drive_run) -> None:
    from PIL import Image

    side = {s: json.loads((drive_run / f"camera/{s}/intrinsics.json").read_text())
            for s in ("left", "right")}
    assert side["right"]["baseline_m"] == pytest.approx(0.424)
    k = 10
    left = np.asarray(Image.open(drive_run / f"camera/left/rgb/{k:06d}.png"))
    right = np.asarray(Image.open(drive_run / f"camera/right/rgb/{k:06d}.png"))
    g0, g1 = (cv2.cvtColor(im, cv2.COLOR_RGB2GRAY) for im in (left, right))
    p0 = corners(left)
    p1, st, _ = cv2.calcOpticalFlowPyrLK(g0, g1, p0[:, None], None, winSize=(21, 21), maxLevel=4)
    ok = st.ravel() == 1
    d = p0[ok] - p1.reshape(-1, 2)[ok]
    assert ok.sum() > 100
    assert np.median(np.abs(d[:, 1])) < 0.3  # rectified: no vertical disparity
    # horizontal disparity = f b / Z, Z from the centre camera's depth (same rows, 0.2 m off)
    _, _, depth = _frames(drive_run)
    u = np.rint(p0[ok, 0]).astype(int)
    v = np.rint(p0[ok, 1]).astype(int)
    z = depth[k][v, u]
    good = z > 0
    expect = side["left"]["fx"] * 0.424 / z[good]
    np.testing.assert_allclose(np.median(d[good, 0] / expect), 1.0, atol=0.08)


def test_visual_rocks_render_but_never_collide(rocky_scene) -> None:
    run = RunConfig(camera=CameraConfig(**_SMALL))
    sim = RoverSim(rocky_scene, run=run, start_xy_m=(-6.0, 1.0))
    cam = _renderer(sim)
    import mujoco

    m = cam.model
    for name in ("cam_terrain", "cam_rocks", "cam_pebbles"):
        gid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, name)
        assert m.geom_contype[gid] == 0 and m.geom_conaffinity[gid] == 0
        assert mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_GEOM, name) == -1
    cat = np.loadtxt(rocky_scene / "rocks.csv", delimiter=",", skiprows=1)
    in_mjcf = cat[:, -1] == 1
    # every catalogue rock is drawn: the MJCF collision geoms plus all the others as visuals
    assert len(cam.world.rocks) == (~in_mjcf).sum() > in_mjcf.sum() > 0
    assert cam.world.rocks[:, 4].min() < 0.2  # pebbles below the MJCF cut are drawn
    # 80-face rocks: only rocks >= 0.15 m inside the near square; every other window rock
    # is in the 20-face mesh (each window rock in exactly one of them)
    hi, lo = cam.world._split()
    g = cam.world.ground
    x0, y0 = sim.heightfield.xy_of(*g.near_origin)
    x1, y1 = sim.heightfield.xy_of(g.near_origin[0] + g.nn_r - 1, g.near_origin[1] + g.nn_c - 1)
    rk = cam.world.rocks
    assert hi.size > 0 and rk[hi, 4].min() >= 0.15
    assert (rk[hi, 1].min() >= x0) and (rk[hi, 1].max() <= x1)
    assert (rk[hi, 2].min() >= y0) and (rk[hi, 2].max() <= y1)
    assert np.intersect1d(hi, lo).size == 0 and lo.size > hi.size
    # depth with rocks stands above the bare terrain somewhere in view
    _, depth = sim.render(cam)
    cam.close()
    hf = sim.heightfield
    cid = sim.camera_id
    pos = sim.data.cam_xpos[cid]
    rot = sim.data.cam_xmat[cid].reshape(3, 3)
    intr = sim.camera_intrinsics()
    vv, uu = np.mgrid[120:240:4, 0:320:4]
    rays = np.stack([(uu - intr["cx"]) / intr["fx"], -(vv - intr["cy"]) / intr["fy"],
                     -np.ones_like(uu, dtype=float)], axis=-1) @ rot.T
    from marsscene.sensors.raycast import ray_heightfield

    dist, _ = ray_heightfield(hf, pos, (rays / np.linalg.norm(rays, axis=-1, keepdims=True))
                             .reshape(-1, 3), (0.1, 60.0))
    zdepth = dist * (1 / np.linalg.norm(rays, axis=-1)).ravel()
    d = depth[vv, uu].ravel()
    valid = np.isfinite(zdepth) & (d > 0)
    closer = (zdepth[valid] - d[valid]) > 0.03
    assert 0.002 < closer.mean() < 0.3  # rocks occlude some terrain, not most of it


def test_camera_images_are_deterministic_and_dust_darkens(rocky_scene) -> None:
    out = {}
    for tau in (0.3, 3.0):
        for rep in range(2 if tau == 0.3 else 1):
            run = RunConfig(camera=CameraConfig(**_SMALL, exposure="fixed", tau=tau))
            sim = RoverSim(rocky_scene, run=run, start_xy_m=(-6.0, 1.0))
            cam = _renderer(sim)
            out[(tau, rep)] = sim.render(cam)[0]
            cam.close()
    np.testing.assert_array_equal(out[(0.3, 0)], out[(0.3, 1)])  # same seed: same bytes
    clear, dusty = out[(0.3, 0)].astype(float), out[(3.0, 0)].astype(float)
    assert dusty.mean() < 0.8 * clear.mean()  # fixed exposure: tau = 3 is darker
    from marsscene.sensors.camera import scene_lighting

    for tau, img in ((0.3, clear), (3.0, dusty)):  # sky colour is the lighting stage's
        lin = img[:10].reshape(-1, 3).mean(axis=0) / 255.0  # top rows: sky
        lin = np.where(lin <= 0.04045, lin / 12.92, ((lin + 0.055) / 1.055) ** 2.4)
        model = scene_lighting(rocky_scene, tau=tau).sky_color_rgb
        np.testing.assert_allclose(lin / lin[0], np.asarray(model) / model[0], rtol=0.08)


def test_camera_size_option_errors(rocky_scene, tmp_path) -> None:
    from click.testing import CliRunner

    from marsscene.cli import main

    wp = tmp_path / "wp.txt"
    wp.write_text("-6 1\n-2 1\n")
    res = CliRunner().invoke(main, ["drive", str(rocky_scene), "--waypoints", str(wp), "--camera",
                                    "--camera-size", "640by480", "--out", str(tmp_path / "o")])
    assert res.exit_code != 0 and "--camera-size '640by480' must be WIDTHxHEIGHT" in res.output
    assert "Traceback" not in res.output


def test_sensor_noise_is_seeded(rocky_scene) -> None:
    imgs = []
    for seed in (3, 3, None):
        run = RunConfig(camera=CameraConfig(**_SMALL, exposure="fixed", sensor_noise=True))
        sim = RoverSim(rocky_scene, run=run, start_xy_m=(-6.0, 1.0), settle_s=0.2)
        try:
            cam = sim.make_renderer(rng=None if seed is None else np.random.default_rng(seed))
        except RuntimeSimError as err:
            pytest.skip(f"no headless OpenGL (EGL/OSMesa) here: {err}")
        imgs.append(sim.render(cam)[0].astype(float))
        cam.close()
    np.testing.assert_array_equal(imgs[0], imgs[1])
    diff = imgs[0] - imgs[2]  # noisy minus noise-free: zero-mean, a few codes of spread
    assert abs(diff.mean()) < 0.5 and 0.5 < diff.std() < 8.0


def test_stereo_drive_becomes_stereo_bag_topics(drive_run, tmp_path) -> None:
    """The camera's stereo run-folder layout is what the bag writer reads: both images arrive
    on /rover/stereo/{left,right}, the right camera_info carries Tx = -fx * baseline, and the
    pair's images equal the logged PNGs."""
    pytest.importorskip("rosbags")
    import json

    from PIL import Image
    from rosbags.highlevel import AnyReader

    from marsscene.runs.export.bag import write_bag

    bag_dir = tmp_path / "bag"
    write_bag(drive_run, bag_dir, sensors=("camera", "stereo"), images="raw")
    intr = json.loads((drive_run / "camera/right/intrinsics.json").read_text())
    rows = (drive_run / "camera/left/stamps.csv").read_text().splitlines()[1:]
    first_left = np.asarray(Image.open(drive_run / "camera/left" / rows[0].split(",")[1]))
    with AnyReader([bag_dir]) as reader:
        topics = {c.topic: c for c in reader.connections}
        for side in ("left", "right"):
            assert f"/rover/stereo/{side}/image_raw" in topics
            assert topics[f"/rover/stereo/{side}/image_raw"].msgcount == len(rows)
        conn = topics["/rover/stereo/right/camera_info"]
        _, _, raw = next(reader.messages(connections=[conn]))
        info = reader.deserialize(raw, conn.msgtype)
        assert info.p[3] == pytest.approx(-info.p[0] * intr["baseline_m"], rel=1e-9)
        conn = topics["/rover/stereo/left/image_raw"]
        _, _, raw = next(reader.messages(connections=[conn]))
        img = reader.deserialize(raw, conn.msgtype)
        got = np.frombuffer(img.data, np.uint8).reshape(img.height, img.width, -1)
        np.testing.assert_array_equal(got[..., :3], first_left[..., :3])


def test_camera_ground_follows_the_draped_ortho(tmp_path) -> None:
    """A scene's orthoimage modulates the camera's ground at large scale: in the baked far
    texture (block means correlate with the image) and in the rendered frame (ground seen
    where the image is dark renders darker), with the image's north up."""
    import dataclasses

    import mujoco
    from scipy.ndimage import gaussian_filter

    cfg = {**_ROCKY, "rocks": {"enabled": False}}
    scene = ms.build_scene(ms.SceneConfig.from_dict(cfg), seed=5)
    cols = scene.heightfield.shape[1]
    rng = np.random.default_rng(2)
    blob = gaussian_filter(rng.standard_normal((cols, cols)), 16, mode="wrap")
    lum = 128 * np.exp(0.1 * blob / blob.std())
    lum[: cols // 2] *= 0.5  # image rows 0.. = north: the northern half is darker
    img = np.repeat(np.clip(lum, 0, 255).astype(np.uint8)[..., None], 3, axis=-1)
    out = tmp_path / "scene"
    ms.write_scene(dataclasses.replace(scene, texture_rgb=img), out, formats=("mjcf",))
    sim = RoverSim(out, run=RunConfig(camera=CameraConfig(**_SMALL)), start_xy_m=(0.0, -8.0),
                   start_yaw_rad=np.pi / 2)  # looking north, across the boundary at y = 0
    cam = _renderer(sim)
    m = cam.model
    tid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_TEXTURE, "cam_ground_far")
    h, w = int(m.tex_height[tid]), int(m.tex_width[tid])
    adr = int(m.tex_adr[tid])
    tex = m.tex_data[adr : adr + h * w * 3].reshape(h, w, 3).astype(np.float64).mean(axis=-1)
    g = cam.world.ground
    x0, y0 = scene.heightfield.xy_of(*g.origin)
    k = 8  # compare 8 x 8 blocks of the far texture with the image at the same ground
    bt = tex[: h // k * k, : w // k * k].reshape(k, h // k, k, w // k).mean(axis=(1, 3))
    bx = x0 + (np.arange(k) + 0.5) * (w // k) * (g.far_texel_m)
    by = y0 + (np.arange(k) + 0.5) * (h // k) * (g.far_texel_m)
    hf = scene.heightfield
    px = (hf.size_m[0]) / cols
    ci = ((bx - hf.xy_of(0, 0)[0]) / px).astype(int)
    ri = (cols - 1 - ((by - hf.xy_of(0, 0)[1]) / px)).astype(int)  # image row 0 = north
    bi = lum[np.ix_(ri, ci)]
    assert np.corrcoef(np.log(bt).ravel(), np.log(bi).ravel())[0, 1] > 0.8
    rgb, depth = sim.render(cam)
    cam.close()
    # back-project ground pixels to world y: north of y = 1 m is darker than south of -1 m
    intr = sim.camera_intrinsics()
    cid = sim.camera_id
    vv, uu = np.mgrid[0:240, 0:320]
    rays = np.stack([(uu - intr["cx"]) / intr["fx"], -(vv - intr["cy"]) / intr["fy"],
                     -np.ones(uu.shape)], axis=-1) @ sim.data.cam_xmat[cid].reshape(3, 3).T
    world_y = sim.data.cam_xpos[cid][1] + rays[..., 1] * depth
    grey = rgb.astype(np.float64).mean(axis=-1)
    north = grey[(depth > 0) & (world_y > 1.0)].mean()
    south = grey[(depth > 0) & (world_y < -1.0)].mean()
    # the image's brightness ratios are rescaled to the decametre albedo spread (std 0.09 in
    # log albedo): the 2x step becomes ~ +-0.09, ~ 0.92 in sRGB; flipped north/south gives ~1.09
    assert north < 0.95 * south


def test_one_pass_depth_equals_mujoco_renderer_depth(rocky_scene) -> None:
    """Depth read from the lit RGB pass is mujoco.Renderer's depth pass, sky (0) included."""
    import mujoco

    sim = RoverSim(rocky_scene, run=RunConfig(camera=CameraConfig(**_SMALL)),
                   start_xy_m=(-6.0, 1.0), start_yaw_rad=0.3)
    cam = _renderer(sim)
    rgb, depth = sim.render(cam)
    ref = mujoco.Renderer(cam.model, height=240, width=320)
    ref.enable_depth_rendering()
    ref.update_scene(cam.data, camera=cam.camera_id)
    expect = ref.render()
    ref.close()
    cam.close()
    far = cam.model.vis.map.zfar * cam.model.stat.extent
    expect = np.where(expect < 0.999 * far, expect, 0.0)
    assert depth is not None and 0.05 < (depth == 0).mean() < 0.8  # sky and ground in view
    np.testing.assert_array_equal(depth == 0, expect == 0)
    np.testing.assert_allclose(depth, expect, rtol=1e-5, atol=1e-5)
    assert rgb[depth == 0].mean() > 0  # the sky is drawn in the RGB image of the same pass
