"""Camera imagery for visual SLAM on the default scene (issue 10).

Drives ~10 m straight at 0.3 m/s with 640x480 RGB-D at 10 Hz (shadows on, auto-exposure) and
reports: sim/wall ratio, per-frame render times (RGB, depth), mean intensity and saturation,
Shi-Tomasi corners per frame, consecutive pairs tracked with >= 30 PnP-RANSAC inliers, and the
RGB-D VO end-point drift as a fraction of the camera path (the OpenCV front end of
``marsscene.testing.vision``). Targets: median >= 300 corners, >= 95 % pairs, drift <= 2 %,
mean 0.3-0.6, saturation < 2 %, >= 1x real time on the 2-core CPU.

Run: ``python perf/run.py camera``. ``--scene PATH`` uses an already built scene (e.g. on a GPU
machine without rasterio); ``--seconds`` shortens the drive; ``--no-quality`` skips the
image-quality pass (it needs OpenCV); ``--no-variants`` drives 640x480 with shadows only.
"""

from __future__ import annotations

import json
import os
import tempfile
import time
from pathlib import Path
from typing import Any

os.environ.setdefault("MUJOCO_GL", "egl")

from perf._measure import measure
from perf.suite import Param, optional

PARAMS = (Param("seconds", float, "simulated seconds of each drive", quick=4.0, full=34.0),
          Param("scene", optional(Path), "an already built scene folder (none: build the default "
                "scene, seed 7, once into the temporary folder)", quick=None, full=None),
          Param("variants", bool, "also 640x480 without shadows and 320x240", quick=False,
                full=True),
          Param("quality", bool, "the image-quality and RGB-D VO pass (OpenCV)", quick=True,
                full=True))
SCENE = Path(tempfile.gettempdir()) / "marsscene_bench_camera_scene"
_SET: dict[str, Any] = {"seconds": 34.0, "scene": SCENE}  # set by main (forked children)
_RUN = Path(tempfile.gettempdir()) / "marsscene_bench_camera_run"
START_XY_M = (20.0, 20.0)


def _build() -> None:
    import marsscene as ms

    ms.write_scene(ms.build_scene(seed=7), _SET["scene"], formats=("mjcf",))


def _drive(shadows: bool, size: tuple[int, int]) -> dict[str, float]:
    import numpy as np

    from marsscene.runtime import CameraConfig, RunConfig
    from marsscene.seeding import stage_rng
    from marsscene.sim.driver import drive_sim
    from marsscene.sim.rover_sim import RoverSim

    cam = CameraConfig(width_px=size[0], height_px=size[1], shadows=shadows)
    corridor = np.array([START_XY_M, (START_XY_M[0] + 12.0, START_XY_M[1])])
    sim = RoverSim(_SET["scene"], run=RunConfig(camera=cam), start_xy_m=START_XY_M,
                   contact_corridor_xy_m=corridor, contact_corridor_m=30.0)
    t0 = time.perf_counter()
    renderer = sim.make_renderer()
    init = time.perf_counter() - t0
    times: dict[str, list[float]] = {"rgb": [], "rgbd": []}
    for _ in range(10):  # render cost alone, warm, interleaved: RGB only, then RGB + depth
        renderer._sync(sim)
        for key, depth in (("rgb", False), ("rgbd", True)):
            t0 = time.perf_counter()
            renderer._render(renderer.camera_id, depth)
            times[key].append(time.perf_counter() - t0)
    renderer.close()
    t0 = time.perf_counter()
    seconds = _SET["seconds"]
    drive_sim(sim, command=(0.3, 0.0), seconds=seconds, out_dir=_RUN, rng=stage_rng(0, "sensors"))
    wall = time.perf_counter() - t0
    return {"ratio": seconds / wall, "wall_s": wall, "camera_init_s": init,
            "rgb_ms": 1e3 * float(np.median(times["rgb"])),
            "rgbd_ms": 1e3 * float(np.median(times["rgbd"]))}


def rgbd_vo_of_run(run: Path) -> tuple[Any, list[Any]]:
    """The OpenCV RGB-D VO of a run folder's camera frames (:mod:`marsscene.testing.vision`) and the
    RGB frames."""
    import numpy as np
    from PIL import Image

    from marsscene.runtime import RoverConfig, read_tum
    from marsscene.testing.vision import camera_poses, rgbd_vo

    intr = json.loads((run / "camera/intrinsics.json").read_text())
    rows = [r.split(",") for r in (run / "camera/stamps.csv").read_text().splitlines()[1:]]
    t = np.array([float(r[0]) for r in rows])
    rgb = [np.asarray(Image.open(run / "camera" / r[1])) for r in rows]
    depth = [np.asarray(Image.open(run / "camera" / r[2])).astype(np.float32) / 1000
             for r in rows]
    gt = read_tum(run / "gt.tum")
    idx = np.searchsorted(gt.timestamps_s, t - 1e-9)
    vo = rgbd_vo(rgb, depth, intr, camera_poses(gt.xyz_m[idx], gt.quat_xyzw[idx], RoverConfig()))
    return vo, rgb


def _quality() -> dict[str, float]:
    import numpy as np

    vo, rgb = rgbd_vo_of_run(_RUN)
    mean = np.array([im.mean() / 255 for im in rgb])
    sat = np.array([(im.max(axis=-1) >= 255).mean() for im in rgb])
    return {"frames": len(rgb), "path_m": vo.path_m,
            "corners_median": float(np.median(vo.corners_per_frame)),
            "corners_min": float(vo.corners_per_frame.min()),
            "pairs_tracked_30": float((vo.inliers_per_pair >= 30).mean()),
            "inliers_median": float(np.median(vo.inliers_per_pair)),
            "vo_drift_pct": 100 * vo.drift_fraction,
            "mean_min": float(mean.min()), "mean_max": float(mean.max()),
            "saturated_max_pct": 100 * float(sat.max())}


def _shadows_640() -> dict[str, float]:
    return _drive(True, (640, 480))


def _noshadow_640() -> dict[str, float]:
    return _drive(False, (640, 480))


def _shadows_320() -> dict[str, float]:
    return _drive(True, (320, 240))


def main(seconds: float, scene: Path | None, variants: bool,
         quality: bool) -> list[dict[str, Any]]:
    _SET.update(seconds=seconds, scene=scene or SCENE)
    figures: list[dict[str, Any]] = []
    if not (_SET["scene"] / "mjcf" / "scene.xml").is_file():
        wall, peak, _ = measure(_build)
        print(f"camera: build default scene seed 7 {wall:.1f} s, peak {peak:.0f} MB")
    variants = [("640x480 shadows", _shadows_640)]
    if variants:
        variants += [("640x480 no shadows", _noshadow_640), ("320x240 shadows", _shadows_320)]
    for i, (label, fn) in enumerate(variants):
        wall, peak, r = measure(fn)
        print(f"camera: {label}: {r['ratio']:.2f}x real time ({seconds:.0f} sim s in "
              f"{r['wall_s']:.1f} s), RGB {r['rgb_ms']:.0f} ms, RGB + depth (one pass) "
              f"{r['rgbd_ms']:.0f} ms per frame, load {os.getloadavg()[0]:.1f}, camera init "
              f"{r['camera_init_s']:.1f} s, peak {peak:.0f} MB")
        figures.append({"case": label, **r, "peak_rss_mb": peak})
        if i == 0 and quality:
            _, _, q = measure(_quality)
            print(f"camera: quality ({q['frames']} frames, {q['path_m']:.2f} m camera path): "
                  f"corners median {q['corners_median']:.0f} (min {q['corners_min']:.0f}), "
                  f"pairs with >= 30 PnP inliers {100 * q['pairs_tracked_30']:.1f} % "
                  f"(median {q['inliers_median']:.0f}), RGB-D VO drift "
                  f"{q['vo_drift_pct']:.2f} % of path, mean intensity "
                  f"{q['mean_min']:.3f}-{q['mean_max']:.3f}, saturated <= "
                  f"{q['saturated_max_pct']:.2f} %")
            figures.append({"case": f"{label}: quality", **q})
    return figures

