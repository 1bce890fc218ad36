"""The batched sensors (marsscene.sensors.batch) on a GPU: LiDAR scans a second and depth frames
a second for thousands of rovers, on a tiled heightfield of the batch environment's shape.

Usage::

    python perf/run.py batch_sensors [--envs 256,1024,4096] [--lidars os1-64,os1-128]
        [--cast-orders beam,firing] [--camera-envs 1024,4096] [--sizes 64x64,640x480]
        [--device cuda:0]
    python perf/run.py batch_sensors --as-env 4096   # as an environment calls them
    python perf/run.py batch_sensors --envs none --camera-envs none \
        --rgbd-envs 1024,4096,8192 --rgbd-sizes 64x64,128x128,640x480   # RGB-D only

The model is the batch environment's (:mod:`marsscene.env.batch.model`): W = 16 worlds as tiles
of one heightfield, 60 m at 0.25 m posts, 2 m apart, with the rover attached; here the tiles
are seeded fractal relief with rock domes (no scene builds: the script needs only mujoco,
mujoco-warp and warp-lang). Rover i stands on tile i mod W at a seeded pose. Each figure times
``repeat`` calls after one warm-up (the first call compiles and builds), the device synchronised
before and after: a LiDAR scan is ray generation + ``mujoco_warp.rays`` (render-context BVH) +
the returns' kernel; a depth frame is ``refit_bvh`` + ``render``. Building the render context
(its heightfield mesh is built in Python) is timed apart. Each RGB-D figure also renders its
frame twice more, the exposure restarted, and says whether the bytes (RGB, depth,
segmentation; the first 512 cameras') were the same: the device's determinism, measured.

An RGB-D frame is :class:`~marsscene.sensors.batch.BatchCamera`'s ``render`` (terrain, rock
meshes, albedo, sun shadow ray, sky, fog, auto exposure, sRGB): the same tiles as its worlds
(their domes as terrain) with ``ROCKS`` seeded rock meshes a world, default lighting; its
depth-only cousin above (MuJoCo Warp's renderer) at the same sizes is the measured case for
ray tracing the camera's world in Warp instead of post-processing that renderer's frames.
"""

from __future__ import annotations

import gc
import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from perf.suite import Param, ints, names, optional

WORLDS, TILE_M, POST_M, GAP_M = 16, 60.0, 0.25, 2.0
#: Rock meshes per world in the RGB-D figures (a ``rocks`` world of 60 m has about 300 MJCF rocks).
ROCKS = 300
#: Cameras whose frame bytes the determinism check compares.
DIGEST_CAMERAS = 512


def frame_sizes(text: str) -> tuple[str, ...]:
    """A comma-separated list of image sizes ``WIDTHxHEIGHT`` (``"64x64,640x480"``)."""
    out = names(text)
    for size in out:
        w, sep, h = size.partition("x")
        if not (sep and w.isdigit() and h.isdigit() and int(w) > 0 and int(h) > 0):
            raise ValueError(f"not WIDTHxHEIGHT: {size!r}")
    return out


PARAMS = (
    Param("envs", ints, "rovers a LiDAR batch scans", quick=(16,), full=(256, 1024, 4096)),
    Param("lidars", names, "LiDAR models", quick=("simple",), full=("os1-64", "os1-128")),
    Param("cast_orders", names, "ray orders (beam, firing)", quick=("beam",), full=("beam",)),
    Param("camera_envs", ints, "rovers a depth batch renders", quick=(16,), full=(1024, 4096)),
    Param("sizes", frame_sizes, "depth image sizes (WIDTHxHEIGHT)", quick=("64x64",),
          full=("64x64", "640x480")),
    Param("rgbd_envs", ints, "rovers an RGB-D batch renders", quick=(4,),
          full=(1024, 4096, 8192)),
    Param("rgbd_sizes", frame_sizes, "RGB-D image sizes (WIDTHxHEIGHT)", quick=("64x64",),
          full=("64x64", "128x128", "640x480")),
    Param("repeat", int, "timed calls per figure (after one warm-up)", quick=2, full=10),
    Param("as_env", int, "instead: this many rovers' sensors as an environment calls them "
          "(0: no)", quick=0, full=0),
    Param("device", optional(str), "Warp device (none: cuda:0 where there is a GPU, else "
          "cpu)", quick=None, full=None),
)


def tile(rng: np.random.Generator, posts: int) -> np.ndarray:
    """Fractal relief (1/f^2 spectrum, about 1 m rms) with rock domes of 0.2 to 0.8 m."""
    f = np.fft.fftfreq(posts)
    k = np.hypot(*np.meshgrid(f, f))
    spectrum = (rng.standard_normal((posts, posts)) + 1j * rng.standard_normal((posts, posts)))
    z = np.real(np.fft.ifft2(spectrum / np.maximum(k, 1.0 / posts) ** 2))
    z *= 1.0 / max(z.std(), 1e-9)
    y, x = np.mgrid[0:posts, 0:posts] * POST_M
    for cx, cy, d in zip(*rng.uniform(0, TILE_M, (2, 120)), rng.uniform(0.2, 0.8, 120),
                         strict=True):
        r2 = ((x - cx) ** 2 + (y - cy) ** 2) / (d / 2) ** 2
        z += np.where(r2 < 1, 0.5 * d * np.sqrt(np.clip(1 - r2, 0, 1)), 0.0)
    return z


def tiled_model(seed: int = 0) -> tuple[Any, np.ndarray, np.ndarray]:
    """The worlds as tiles of one heightfield (tiled_model's layout) with the rover attached;
    the offset of each tile's origin (W, 2); the posts' heights (rows along y, from 0)."""
    import mujoco

    from marsscene.sim.rover_model import rover_mjcf
    from marsscene.sim.rover_sim import PREFIX

    rng = np.random.default_rng(seed)
    posts = round(TILE_M / POST_M) + 1
    per_row, gap = math.ceil(math.sqrt(WORLDS)), math.ceil(GAP_M / POST_M)
    pitch = posts + gap
    rows = math.ceil(WORLDS / per_row)
    z = np.full((rows * pitch - gap, per_row * pitch - gap), -4.0)
    offsets = np.zeros((WORLDS, 2))
    for w in range(WORLDS):
        r, c = divmod(w, per_row)
        z[r * pitch:r * pitch + posts, c * pitch:c * pitch + posts] = tile(rng, posts)
        offsets[w] = (c * pitch * POST_M, r * pitch * POST_M)
    lo, hi = float(z.min()), float(z.max())
    spec = mujoco.MjSpec()
    spec.compiler.degree = False
    rx, ry = (z.shape[1] - 1) * POST_M / 2.0, (z.shape[0] - 1) * POST_M / 2.0
    hf = spec.add_hfield(name="terrain", size=[rx, ry, hi - lo, 1.0], nrow=z.shape[0],
                         ncol=z.shape[1])
    hf.userdata = ((z - lo) / (hi - lo)).astype(np.float32).ravel()
    spec.worldbody.add_geom(name="terrain", type=mujoco.mjtGeom.mjGEOM_HFIELD,
                            hfieldname="terrain", pos=[rx, ry, lo])
    spec.attach(mujoco.MjSpec.from_string(rover_mjcf()), prefix=PREFIX,
                frame=spec.worldbody.add_frame())
    return spec.compile(), offsets, z


@dataclass(frozen=True)
class Tiles:
    """The host model, its device copy, each tile's offset (W, 2) and the posts' heights."""

    mj: Any
    model: Any
    offsets: np.ndarray
    z: np.ndarray


def batch_data(t: Tiles, n: int) -> Any:
    """N rovers, rover i on tile i mod W at a seeded pose, its base 1 m above the ground, with
    the kinematics and camera poses computed."""
    import mujoco
    import mujoco_warp as mjw
    import warp as wp

    rng = np.random.default_rng(n)
    qpos = np.tile(t.mj.qpos0, (n, 1))
    xy = t.offsets[np.arange(n) % WORLDS] + rng.uniform(10, TILE_M - 10, (n, 2))
    yaw = rng.uniform(-np.pi, np.pi, n)
    ground = t.z[np.rint(xy[:, 1] / POST_M).astype(int), np.rint(xy[:, 0] / POST_M).astype(int)]
    qpos[:, 0:2], qpos[:, 2] = xy, ground + 1.0
    qpos[:, 3], qpos[:, 6] = np.cos(yaw / 2), np.sin(yaw / 2)
    data = mjw.put_data(t.mj, mujoco.MjData(t.mj), nworld=n)
    wp.copy(data.qpos, wp.array(qpos.astype(np.float32)))
    for step in (mjw.kinematics, mjw.com_pos, mjw.camlight):
        step(t.model, data)
    return data


def timed(call: Any, repeat: int) -> float:
    """Seconds per call (after one warm-up call)."""
    import warp as wp

    call()
    wp.synchronize()
    t0 = time.perf_counter()
    for _ in range(repeat):
        call()
    wp.synchronize()
    return (time.perf_counter() - t0) / repeat


def rays_only(lidar: Any, data: Any) -> None:
    """``mujoco_warp.rays`` alone on the scan's last rays (the rest of a scan is two kernels)."""
    import mujoco_warp as mjw

    mjw.rays(lidar.model, data, lidar._pnt, lidar._vec, lidar.groups, True, lidar._exclude,
             lidar._dist, lidar._geom, lidar._normal, lidar.rc)


def bench_lidar(t: Tiles, envs: tuple[int, ...], lidars: tuple[str, ...],
                orders: tuple[str, ...], repeat: int) -> list[dict[str, Any]]:
    import mujoco_warp as mjw

    from marsscene.rover.lidar import LidarConfig
    from marsscene.sensors.batch import BatchLidar

    rows = []
    for n in envs:
        data = batch_data(t, n)
        t0 = time.perf_counter()
        rc = mjw.create_render_context(t.mj, nworld=n, cam_active=[], render_rgb=False,
                                       render_depth=False, use_textures=False,
                                       enabled_geom_groups=[0, 1])
        build_s = time.perf_counter() - t0
        for name, order in [(name, order) for name in lidars for order in orders]:
            lidar = BatchLidar(t.mj, t.model, n, LidarConfig(model=name), render_context=rc,
                               cast_order=order)
            s = timed(lambda lidar=lidar, data=data: lidar.scan(data), repeat)
            ray_s = timed(lambda lidar=lidar, data=data: rays_only(lidar, data), repeat)
            hit = float(lidar.out.valid.numpy().mean())
            rows.append({"sensor": name, "cast_order": order, "envs": n,
                         "rays": lidar.rays_per_scan, "s_per_batch": s, "scans_per_s": n / s,
                         "grays_per_s": n * lidar.rays_per_scan / s / 1e9,
                         "rays_share": ray_s / s, "returns": hit, "context_build_s": build_s})
            print(f"{name:8s} {order:6s} N={n:5d}  {n / s:9.0f} scans/s  "
                  f"{n * lidar.rays_per_scan / s / 1e9:5.2f} G rays/s  ({s * 1e3:7.1f} ms a "
                  f"batch, rays() {100 * ray_s / s:3.0f} % of it; {100 * hit:4.1f} % of rays "
                  f"return; context {build_s:.1f} s)", flush=True)
            del lidar
            gc.collect()
        del rc, data
        gc.collect()
    return rows


def bench_depth(t: Tiles, envs: tuple[int, ...], sizes: tuple[tuple[int, int], ...],
                repeat: int) -> list[dict[str, Any]]:
    from marsscene.rover.config import CameraConfig
    from marsscene.sensors.batch import BatchDepthCamera

    rows = []
    for n in envs:
        data = batch_data(t, n)
        for w_px, h_px in sizes:
            t0 = time.perf_counter()
            cam = BatchDepthCamera(t.mj, t.model, n, CameraConfig(width_px=w_px, height_px=h_px))
            build_s = time.perf_counter() - t0
            s = timed(lambda cam=cam, data=data: cam.depth(data), repeat)
            seen = float((cam.depth(data).numpy() > 0).mean())
            rows.append({"sensor": f"depth {w_px}x{h_px}", "envs": n, "s_per_batch": s,
                         "frames_per_s": n / s, "gpixels_per_s": n * w_px * h_px / s / 1e9,
                         "seen": seen, "context_build_s": build_s})
            print(f"depth {w_px}x{h_px:<4d} N={n:5d}  {n / s:9.0f} frames/s  "
                  f"{n * w_px * h_px / s / 1e9:5.2f} G px/s  ({s * 1e3:7.1f} ms a batch; "
                  f"{100 * seen:4.1f} % of pixels see ground; context {build_s:.1f} s)",
                  flush=True)
            del cam
            gc.collect()
        del data
        gc.collect()
    return rows


def world_batch(t: Tiles, seed: int = 0) -> Any:
    """The tiles as a :class:`~marsscene.env.batch.worlds.WorldBatch` (world coordinates from
    each tile's corner) with ``ROCKS`` seeded rocks a world."""
    from marsscene.env.batch import WorldBatch

    rng = np.random.default_rng(seed)
    posts = round(TILE_M / POST_M) + 1
    z = np.stack([t.z[round(oy / POST_M):round(oy / POST_M) + posts,
                      round(ox / POST_M):round(ox / POST_M) + posts] for ox, oy in t.offsets])
    n = WORLDS * ROCKS
    return WorldBatch(
        posts_z_m=z.astype(np.float32), cell_m=POST_M, origins_xy_m=np.zeros((WORLDS, 2)),
        rock_xy_m=rng.uniform(1.0, TILE_M - 1.0, (n, 2)),
        rock_radius_m=rng.uniform(0.3, 1.0, n), rock_height_m=rng.uniform(0.1, 0.5, n),
        rock_world=np.repeat(np.arange(WORLDS), ROCKS), starts_xy_m=np.zeros((WORLDS, 1, 2)),
        yaws_rad=np.zeros((WORLDS, 1)), goals_xy_m=np.zeros((WORLDS, 1, 2)))


def bench_rgbd(t: Tiles, envs: tuple[int, ...], sizes: tuple[tuple[int, int], ...],
               repeat: int) -> list[dict[str, Any]]:
    import mujoco
    import warp as wp

    from marsscene.rover.config import CameraConfig
    from marsscene.sensors.batch import BatchCamera

    rows: list[dict[str, Any]] = []
    if not envs or not sizes:
        return rows
    batch = world_batch(t)
    cid = mujoco.mj_name2id(t.mj, mujoco.mjtObj.mjOBJ_CAMERA, "rover/navcam")
    for n in envs:
        data = batch_data(t, n)
        world = wp.array((np.arange(n) % WORLDS).astype(np.int32), dtype=int)
        for w_px, h_px in sizes:
            t0 = time.perf_counter()
            cam = BatchCamera(batch, n, config=CameraConfig(width_px=w_px, height_px=h_px),
                              offsets_xy_m=t.offsets)
            build_s = time.perf_counter() - t0
            s = timed(lambda cam=cam, data=data, world=world:
                      cam.render_data(data, world, cid), repeat)
            frame = [frame_digest(cam, data, world, cid) for _ in range(2)]
            seg = cam.segmentation.numpy()
            rows.append({"sensor": f"rgbd {w_px}x{h_px}", "envs": n, "s_per_batch": s,
                         "frames_per_s": n / s, "gpixels_per_s": n * w_px * h_px / s / 1e9,
                         "seen": float((seg > 0).mean()), "rock_px": float((seg == 2).mean()),
                         "build_s": build_s, "digest": frame[0],
                         "same_bytes_twice": frame[0] == frame[1]})
            print(f"rgbd  {w_px}x{h_px:<4d} N={n:5d}  {n / s:9.0f} frames/s  "
                  f"{n * w_px * h_px / s / 1e9:5.2f} G px/s  ({s * 1e3:7.1f} ms a batch; "
                  f"{100 * (seg > 0).mean():4.1f} % ground or rock, {100 * (seg == 2).mean():4.1f}"
                  f" % rock; built in {build_s:.1f} s; frame {frame[0][:12]}, the same bytes "
                  f"twice: {frame[0] == frame[1]})", flush=True)
            del cam, seg
            gc.collect()
        del data
        gc.collect()
    return rows


def frame_digest(cam: Any, data: Any, world: Any, cid: int) -> str:
    """SHA-256 of one frame's RGB, depth and segmentation bytes (the first ``DIGEST_CAMERAS``
    cameras'), the exposure restarted."""
    import hashlib

    cam.restart()
    cam.render_data(data, world, cid)
    h = hashlib.sha256()
    for a in (cam.rgb, cam.depth, cam.segmentation):
        h.update(a[:min(DIGEST_CAMERAS, a.shape[0])].numpy().tobytes())
    return h.hexdigest()


def tile_bounds(t: Tiles, n: int) -> Any:
    """Each rover's tile rectangle (x0, y0, x1, y1) in the model frame, (n, 4) on the device."""
    import warp as wp

    lo = t.offsets[np.arange(n) % WORLDS]
    return wp.array(np.concatenate([lo, lo + TILE_M], axis=1), dtype=float)


def graph_of(call: Any) -> Any:
    """``call`` captured as a CUDA graph: a function that replays it."""
    import warp as wp

    call()  # compile and allocate outside the capture
    with wp.ScopedCapture() as cap:
        call()
    return lambda: wp.capture_launch(cap.graph)


def bench_as_env(t: Tiles, n: int, repeat: int) -> list[dict[str, Any]]:
    """The sensors as an environment would call them: an OS1-128 scan with motion distortion
    (the site's twist) and 64 x 64 depth, both clipped to each rover's tile; eagerly and as
    CUDA graphs; and whether two LiDARs of one seed (and two frames) give the same bytes."""
    import hashlib

    import warp as wp

    from marsscene.rover.config import CameraConfig
    from marsscene.rover.lidar import LidarConfig
    from marsscene.sensors.batch import BatchDepthCamera, BatchLidar

    data, bounds = batch_data(t, n), tile_bounds(t, n)
    lidar = BatchLidar(t.mj, t.model, n, LidarConfig(model="os1-128"), seed=1)
    cam = BatchDepthCamera(t.mj, t.model, n, CameraConfig(width_px=64, height_px=64))
    calls = {"os1-128 scan, twist, tile bounds":
             lambda: lidar.scan(data, twist=lidar.site_twist(data), bounds_xy_m=bounds),
             "depth 64x64, tile bounds": lambda: cam.depth(data, bounds_xy_m=bounds)}
    rows, cuda = [], wp.get_device().is_cuda
    for name, call in calls.items():
        modes = {"eager": call}
        if cuda:
            try:
                modes["graph"] = graph_of(call)
            except Exception as err:  # a figure of the report, not a failure
                print(f"{name}: CUDA graph capture failed: {err}", flush=True)
        for mode, run in modes.items():
            s = timed(run, repeat)
            rows.append({"sensor": name, "mode": mode, "envs": n, "per_s": n / s})
            print(f"{name:34s} {mode} N={n:5d}  {n / s:9.0f} a second ({s * 1e3:7.1f} ms)",
                  flush=True)

    def digest(arrays: Any) -> str:
        return hashlib.sha256(b"".join(a.numpy().tobytes() for a in arrays)).hexdigest()[:16]

    scans = []
    for _ in range(2):
        other = BatchLidar(t.mj, t.model, n, LidarConfig(model="os1-128"), seed=1,
                           render_context=lidar.rc)
        s_ = other.scan(data, bounds_xy_m=bounds)
        scans.append(digest([s_.range_m, s_.intensity, s_.valid]))
        del other
    frames = [digest([cam.depth(data, bounds_xy_m=bounds)]) for _ in range(2)]
    print(f"same bytes: LiDAR of one seed {scans[0] == scans[1]} ({scans[0]}), depth "
          f"{frames[0] == frames[1]} ({frames[0]})", flush=True)
    return [*rows, {"sensor": "same bytes", "envs": n, "lidar_same": scans[0] == scans[1],
                    "depth_same": frames[0] == frames[1]}]


def main(envs: tuple[int, ...], lidars: tuple[str, ...], cast_orders: tuple[str, ...],
         camera_envs: tuple[int, ...], sizes: tuple[str, ...], rgbd_envs: tuple[int, ...],
         rgbd_sizes: tuple[str, ...], repeat: int, as_env: int,
         device: str | None) -> list[dict[str, Any]]:
    import mujoco_warp as mjw
    import warp as wp

    wp.init()
    device = device or ("cuda:0" if wp.is_cuda_available() else "cpu")
    frames = tuple((int(w), int(h)) for w, _, h in (s.partition("x") for s in sizes))
    with wp.ScopedDevice(device):
        t0 = time.perf_counter()
        mj, offsets, z = tiled_model()
        tiles = Tiles(mj, mjw.put_model(mj), offsets, z)
        name = wp.get_device(device).name
        print(f"{name}: {WORLDS} tiles of {TILE_M:.0f} m at {POST_M} m "
              f"({mj.hfield_nrow[0]} x {mj.hfield_ncol[0]} posts), model in "
              f"{time.perf_counter() - t0:.1f} s", flush=True)
        if as_env:
            rows = bench_as_env(tiles, as_env, repeat)
        else:
            rows = bench_lidar(tiles, envs, lidars, cast_orders, repeat)
            rows += bench_depth(tiles, camera_envs, frames, repeat)
            rows += bench_rgbd(tiles, rgbd_envs, tuple(
                (int(w), int(h)) for w, _, h in (s.partition("x") for s in rgbd_sizes)),
                repeat)
    return [{"device": name, **row} for row in rows]
