"""The batched LiDAR and depth camera (marsscene.sensors.batch) on Warp's CPU device: three
worlds of one small model (a heightfield, a box rock, the rover), each rover at its own pose,
against the CPU LiDAR and MuJoCo's own renderer on the same model and poses.

Warp compiles MuJoCo Warp's BVH, ray and render kernels on first use: the file takes 43 s on the
2-core machine with an empty kernel cache (its longest test 10 s), 14 s once cached. The depth
test renders with MuJoCo's OpenGL renderer (the slow tier, as the CPU camera's render tests).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

pytest.importorskip("warp", reason='needs marsscene[gpu] (warp-lang)')
pytest.importorskip("mujoco_warp", reason='needs marsscene[gpu] (mujoco-warp)')

import mujoco
import mujoco_warp as mjw
import warp as wp

from marsscene.errors import ConfigError
from marsscene.rover.config import CameraConfig
from marsscene.rover.lidar import LidarConfig
from marsscene.sensors.batch import BatchDepthCamera, BatchLidar
from marsscene.sensors.lidar import Lidar
from marsscene.sim.rover_model import rover_mjcf
from marsscene.sim.rover_sim import PREFIX
from marsscene.terrain.heightfield import Heightfield

N = 3
POST_M = 0.25
POSTS = 121  # a 30 m square


def _terrain() -> np.ndarray:
    y, x = np.mgrid[0:POSTS, 0:POSTS] * POST_M
    rough = np.random.default_rng(0).standard_normal((POSTS, POSTS))
    return np.asarray(0.5 * np.sin(x / 3.0) * np.cos(y / 4.0) + 0.04 * rough + 0.02 * x)


def _model(z: np.ndarray) -> Any:
    """The heightfield (group 0; x, y from 0), a box rock (group 1) and the rover."""
    spec = mujoco.MjSpec()
    spec.compiler.degree = False
    lo, hi = float(z.min()), float(z.max())
    half = (POSTS - 1) * POST_M / 2.0
    hf = spec.add_hfield(name="terrain", size=[half, half, hi - lo, 1.0], nrow=POSTS,
                         ncol=POSTS)
    hf.userdata = ((z - lo) / (hi - lo)).astype(np.float32).ravel()
    spec.worldbody.add_geom(name="terrain", type=mujoco.mjtGeom.mjGEOM_HFIELD,
                            hfieldname="terrain", pos=[half, half, lo])
    spec.worldbody.add_geom(name="rock", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.6, 0.4, 0.7],
                            pos=[17.0, 12.0, 0.4], group=1)
    spec.attach(mujoco.MjSpec.from_string(rover_mjcf()), prefix=PREFIX,
                frame=spec.worldbody.add_frame())
    return spec.compile()


class Batch:
    """The model, each world's qpos and qvel, MuJoCo Warp's copy on the CPU device with the
    kinematics, camera poses and body velocities computed."""

    def __init__(self) -> None:
        self.z = _terrain()
        self.mj = _model(self.z)
        rng = np.random.default_rng(1)
        self.qpos = np.tile(self.mj.qpos0, (N, 1))
        self.qvel = np.zeros((N, self.mj.nv))
        for w in range(N):
            yaw = rng.uniform(-np.pi, np.pi)
            self.qpos[w, :7] = [11.0 + 2.0 * w, 10.0 + w, 1.6, np.cos(yaw / 2), 0.0, 0.0,
                                np.sin(yaw / 2)]
            self.qvel[w, :6] = [0.3, -0.2, 0.05, 0.1, -0.15, 0.6]  # linear, angular
        wp.init()
        with wp.ScopedDevice("cpu"):
            self.model = mjw.put_model(self.mj)
            self.data = self.put(N)

    def put(self, n: int) -> Any:
        data = mjw.put_data(self.mj, mujoco.MjData(self.mj), nworld=n)
        wp.copy(data.qpos, wp.array(self.qpos[:n].astype(np.float32), device="cpu"))
        wp.copy(data.qvel, wp.array(self.qvel[:n].astype(np.float32), device="cpu"))
        for step in (mjw.kinematics, mjw.com_pos, mjw.camlight, mjw.com_vel):
            step(self.model, data)
        return data

    def cpu_data(self, w: int) -> Any:
        """World ``w`` in MuJoCo C (float32 state, as the batch holds it)."""
        d = mujoco.MjData(self.mj)
        d.qpos[:] = self.qpos[w].astype(np.float32)
        d.qvel[:] = self.qvel[w].astype(np.float32)
        mujoco.mj_forward(self.mj, d)
        return d

    def heightfield(self) -> Heightfield:
        """The terrain as the CPU LiDAR's caster sees it: MuJoCo's heightfield posts."""
        m = self.mj
        lo = float(m.geom_pos[0, 2])
        z = lo + m.hfield_data.reshape(POSTS, POSTS).astype(np.float64) * m.hfield_size[0, 2]
        return Heightfield(z.astype(np.float32), POST_M)


@pytest.fixture(scope="module")
def batch() -> Batch:
    return Batch()


def _by_ray(scan: dict[str, np.ndarray], key: str) -> dict[int, Any]:
    return dict(zip(scan["ray"].tolist(), scan[key], strict=True))


def _compare(cpu: dict[str, np.ndarray], gpu: dict[str, np.ndarray]) -> np.ndarray:
    """Range differences on the rays both returned; the returned sets nearly agree."""
    a, b = set(cpu["ray"].tolist()), set(gpu["ray"].tolist())
    assert len(a) > 200 and len(a ^ b) <= 0.002 * len(a), (len(a), len(b), len(a ^ b))
    common = sorted(a & b)
    rc, rg = _by_ray(cpu, "range_m"), _by_ray(gpu, "range_m")
    xc, xg = _by_ray(cpu, "xyz_m"), _by_ray(gpu, "xyz_m")
    np.testing.assert_allclose([xg[i] for i in common], [xc[i] for i in common], atol=0.01)
    ic, ig = _by_ray(cpu, "intensity"), _by_ray(gpu, "intensity")
    off = np.abs(np.array([ig[i] - ic[i] for i in common])) > 1e-3
    assert off.mean() < 0.002  # a ray on a triangle's edge may take the neighbour's normal
    return np.array([rg[i] - rc[i] for i in common])


@pytest.mark.parametrize("model", ["simple", "os1-64"])
def test_lidar_ranges_match_the_cpu_lidar(batch: Batch, model: str) -> None:
    cfg = LidarConfig(model=model, horizontal_samples=512 if model != "simple" else None,
                      range_noise_sigma_m=0.0)
    lidar = BatchLidar(batch.mj, batch.model, N, cfg)
    scan = lidar.scan(batch.data)
    rays = lidar.rays_per_scan
    assert scan.range_m.shape == (N, rays) and scan.xyz_m.shape == (N, rays)
    assert scan.valid.dtype == wp.bool and len(scan.t_s) == len(scan.ring) == rays
    cpu = Lidar(cfg)
    for w in range(N):
        ref = cpu.scan(batch.mj, batch.cpu_data(w), lidar.site)  # MuJoCo C's mj_multiRay
        got = scan.returns(w)
        tc, tg = _by_ray(ref, "t_s"), _by_ray(got, "t_s")
        assert all(tg[i] == t for i, t in tc.items() if i in tg)  # per-point time
        diff = _compare(ref, got)
        assert np.abs(diff).max() < 0.01, np.abs(diff).max()


def test_motion_distortion_and_twist_match_the_cpu_lidar(batch: Batch) -> None:
    pytest.importorskip("embreex")  # the CPU LiDAR's exact per-ray origins
    cfg = LidarConfig(model="vlp16", horizontal_samples=600, range_noise_sigma_m=0.0)
    lidar = BatchLidar(batch.mj, batch.model, N, cfg)
    twist = lidar.site_twist(batch.data)
    cpu, hf = Lidar(cfg), batch.heightfield()
    still = lidar.scan(batch.data).returns(0)
    for w in range(N):
        d = batch.cpu_data(w)
        expect = np.zeros(6)
        mujoco.mj_objectVelocity(batch.mj, d, mujoco.mjtObj.mjOBJ_SITE, lidar.site, expect, 0)
        np.testing.assert_allclose(twist.numpy()[w], expect, atol=1e-4)
    scan = lidar.scan(batch.data, twist=twist)
    for w in range(N):
        d = batch.cpu_data(w)
        ref = cpu.scan(batch.mj, d, lidar.site, hf, twist=twist.numpy()[w].astype(np.float64))
        diff = _compare(ref, scan.returns(w))
        assert np.abs(diff).max() < 0.01, np.abs(diff).max()
    moved = _by_ray(scan.returns(0), "range_m")
    assert max(abs(moved[i] - r) for i, r in _by_ray(still, "range_m").items() if i in moved) \
        > 0.05  # the sweep's motion shows


def test_noise_and_dropouts_are_the_cpu_models(batch: Batch) -> None:
    clean = BatchLidar(batch.mj, batch.model, N, LidarConfig(model="simple"))
    cfg = LidarConfig(model="simple", range_noise_sigma_m=0.05, dropout_probability=0.2)
    noisy = BatchLidar(batch.mj, batch.model, N, cfg, seed=3)
    c = clean.scan(batch.data)
    hit = c.valid.numpy()
    r0 = c.range_m.numpy().copy()
    n = noisy.scan(batch.data)
    kept = n.valid.numpy()
    assert not (kept & ~hit).any()
    lost = 1.0 - kept[hit].mean()
    assert abs(lost - 0.2) < 4 * np.sqrt(0.2 * 0.8 / hit.sum()), lost
    err = (n.range_m.numpy() - r0)[kept]
    assert abs(err.mean()) < 4 * 0.05 / np.sqrt(err.size)
    assert abs(err.std() / 0.05 - 1.0) < 0.06, err.std()
    xyz = n.xyz_m.numpy()[kept]
    np.testing.assert_allclose(np.linalg.norm(xyz, axis=1), n.range_m.numpy()[kept], rtol=1e-5)


def _bounds(batch: Batch) -> np.ndarray:
    """Each world's rectangle: 5 m around its rover (the edge of a smaller tile)."""
    xy = batch.qpos[:, :2]
    return np.concatenate([xy - 5.0, xy + 5.0], axis=1)


def _outside(p: np.ndarray, bounds: np.ndarray, margin_m: float) -> np.ndarray:
    """-1 inside by more than the margin, 1 outside by more, 0 within it of an edge."""
    gap = np.max([bounds[0] - p[..., 0], bounds[1] - p[..., 1], p[..., 0] - bounds[2],
                  p[..., 1] - bounds[3]], axis=0)
    return np.where(gap < -margin_m, -1, np.where(gap > margin_m, 1, 0))


def test_hits_outside_a_worlds_rectangle_are_no_returns(batch: Batch) -> None:
    cfg = LidarConfig(model="os1-64", horizontal_samples=256, range_noise_sigma_m=0.0)
    lidar = BatchLidar(batch.mj, batch.model, N, cfg)  # noise off: the points are the hits
    bounds = _bounds(batch)
    full = lidar.scan(batch.data)
    valid, xyz = full.valid.numpy().copy(), full.xyz_m.numpy().copy()
    clipped = lidar.scan(batch.data, bounds_xy_m=wp.array(bounds, dtype=float, device="cpu"))
    kept = clipped.valid.numpy()
    pos, rot = batch.data.site_xpos.numpy(), batch.data.site_xmat.numpy()
    for w in range(N):
        hit = pos[w, lidar.site] + xyz[w] @ rot[w, lidar.site].T
        side = _outside(hit, bounds[w], 1e-3)
        assert (side[valid[w]] == 1).sum() > 100  # the rectangle cuts the scan
        np.testing.assert_array_equal(kept[w][side == -1], valid[w][side == -1])
        assert not kept[w][side == 1].any()
    np.testing.assert_array_equal(clipped.range_m.numpy()[kept], full.range_m.numpy()[kept])


def _bytes(lidar: BatchLidar, data: Any, worlds: int) -> bytes:
    s = lidar.scan(data)
    return b"".join(a.numpy()[:worlds].tobytes() for a in (s.range_m, s.xyz_m, s.intensity,
                                                             s.valid))


def test_a_batch_scan_is_deterministic_per_world_seed(batch: Batch) -> None:
    cfg = LidarConfig(model="simple", range_noise_sigma_m=0.05, dropout_probability=0.1)
    a = BatchLidar(batch.mj, batch.model, N, cfg, seed=5)
    b = BatchLidar(batch.mj, batch.model, N, cfg, seed=5)
    first = _bytes(a, batch.data, N)
    assert first == _bytes(b, batch.data, N)
    assert _bytes(a, batch.data, N) != first  # the next scan draws anew
    a.restart(5)
    assert _bytes(a, batch.data, N) == first
    with wp.ScopedDevice("cpu"):
        two = batch.put(2)
    small = BatchLidar(batch.mj, batch.model, 2, cfg, seed=5)  # worlds 0, 1 of a smaller batch
    assert _bytes(small, two, 2) == _bytes(BatchLidar(batch.mj, batch.model, N, cfg, seed=5),
                                           batch.data, 2)
    assert _bytes(BatchLidar(batch.mj, batch.model, N, cfg, seed=6), batch.data, N) != first
    firing = BatchLidar(batch.mj, batch.model, N, cfg, seed=5, cast_order="firing")
    assert _bytes(firing, batch.data, N) == first  # the order rays are traced in is unseen


def test_bad_arguments_say_what_is_wrong(batch: Batch) -> None:
    cfg = LidarConfig(model="simple")
    with pytest.raises(ConfigError, match="no site"):
        BatchLidar(batch.mj, batch.model, N, cfg, site="rover/nothing")
    lidar = BatchLidar(batch.mj, batch.model, 2, cfg)
    with pytest.raises(ConfigError, match="2 worlds"):
        lidar.scan(batch.data)
    lidar = BatchLidar(batch.mj, batch.model, N, cfg)
    with pytest.raises(ConfigError, match="twist"):
        lidar.scan(batch.data, twist=wp.zeros((N, 3), dtype=float, device="cpu"))
    with pytest.raises(ConfigError, match="bounds_xy_m"):
        lidar.scan(batch.data, bounds_xy_m=wp.zeros((N, 2), dtype=float, device="cpu"))
    with pytest.raises(ConfigError, match="world 3"):
        lidar.scan(batch.data).returns(N)
    with pytest.raises(ConfigError, match="cast_order"):
        BatchLidar(batch.mj, batch.model, N, cfg, cast_order="random")
    with pytest.raises(ConfigError, match="no camera"):
        BatchDepthCamera(batch.mj, batch.model, N, camera="rover/nothing")


@pytest.mark.slow
@pytest.mark.parametrize("size", [(64, 64), (160, 120)])
def test_depth_matches_mujocos_renderer(batch: Batch, size: tuple[int, int]) -> None:
    """The CPU camera's depth is mujoco.Renderer's (tests/sensors/test_camera.py); on the
    same model, poses and intrinsics the batch camera's planar depth agrees with it."""
    w_px, h_px = size
    cam = BatchDepthCamera(batch.mj, batch.model, N,
                           CameraConfig(width_px=w_px, height_px=h_px, fovy_deg=70.0))
    depth = cam.depth(batch.data).numpy()
    assert depth.shape == (N, h_px, w_px)
    fx, fy, cx, cy = cam.intrinsics()
    assert fx == fy and (cx, cy) == (w_px / 2, h_px / 2)
    host = _with_fovy(batch.mj, cam.camera_id, 70.0)
    ref = mujoco.Renderer(host, height=h_px, width=w_px)
    ref.enable_depth_rendering()
    far = host.vis.map.zfar * host.stat.extent
    try:
        for w in range(N):
            ref.update_scene(batch.cpu_data(w), camera=cam.camera_id)
            expect = ref.render()
            expect = np.where(expect < 0.999 * far, expect, 0.0)  # the sky: 0, as the batch's
            seen = (depth[w] > 0) & (expect > 0)
            assert (depth[w] > 0).mean() > 0.3 and ((depth[w] > 0) != (expect > 0)).mean() < 0.01
            near = seen & (expect < 20.0)
            assert np.median(np.abs(depth[w] - expect)[near]) < 0.02
            assert np.percentile(np.abs(depth[w] - expect)[near], 99) < 0.05
    finally:
        ref.close()


def test_depth_outside_a_worlds_rectangle_is_nothing_seen(batch: Batch) -> None:
    cam = BatchDepthCamera(batch.mj, batch.model, N, CameraConfig(width_px=48, height_px=32))
    full = cam.depth(batch.data).numpy().copy()
    bounds = _bounds(batch)
    clipped = cam.depth(batch.data, bounds_xy_m=wp.array(bounds, dtype=float, device="cpu"))
    clipped = clipped.numpy()
    fx, fy, cx, cy = cam.intrinsics()
    v, u = np.mgrid[0:32, 0:48] + 0.5
    ray = np.stack([(u - cx) / fx, -(v - cy) / fy, -np.ones_like(u)], axis=-1)  # camera frame
    pos, rot = batch.data.cam_xpos.numpy(), batch.data.cam_xmat.numpy()
    for w in range(N):
        seen = pos[w, cam.camera_id] + (ray * full[w][..., None]) @ rot[w, cam.camera_id].T
        side = np.where(full[w] > 0, _outside(seen, bounds[w], 1e-3), 1)
        assert (side == 1).mean() > 0.05 and (side == -1).mean() > 0.05
        np.testing.assert_array_equal(clipped[w][side == -1], full[w][side == -1])
        assert not clipped[w][side == 1].any()


def _with_fovy(model: Any, camera_id: int, fovy_deg: float) -> Any:
    import copy

    out = copy.copy(model)
    out.cam_fovy[camera_id] = fovy_deg
    return out


def test_a_worlds_noise_stream_is_keyed_by_its_stream_not_its_slot() -> None:
    """``world_seeds``: world w's seed depends on (seed, streams[w]) only, so a batch drive's
    LiDAR noise is the same in any slot (streams = the drives' seeds); by default the stream is
    the world's index; a count that does not match is a one-line error."""
    from marsscene.sensors.batch.lidar import world_seeds

    a = world_seeds(5, 3, streams=[7, 9, 7])
    assert a[0] == a[2] != a[1]
    np.testing.assert_array_equal(world_seeds(5, 2, streams=[9, 7]), a[[1, 0]])
    np.testing.assert_array_equal(world_seeds(5, 3), world_seeds(5, 3, streams=range(3)))
    assert world_seeds(6, 1, streams=[7])[0] != a[0]  # the batch's seed still counts
    with pytest.raises(ConfigError, match="2 noise streams for 3 worlds"):
        world_seeds(5, 3, streams=[1, 2])
