"""The mast camera at a low sun and at twilight (issue 25).

Default scene (seed 7), ~10 m straight east at 0.3 m/s from (20, 20), 640x480 RGB-D at 10 Hz,
shadows on, auto exposure, dust tau = 0.1 (at the default 0.5 the direct sun at 2 deg is
0.2 W m^-2: no shadows to see), sun in the north-north-east (azimuth 30 deg: ahead and to the
left; rock shadows across the view, the terrain's ridges shadowing bands of it). Sun
elevations 13 deg (the default scene's), 5, 2 and -3 deg (twilight: sky only).
Reports per elevation: sim/wall ratio (camera start included, and excluded), camera start
(terrain shadows of the whole heightfield + texture bakes), render time per frame, and the
image figures of ``perf/bench_camera.py`` (Shi-Tomasi corners, consecutive pairs with
>= 30 PnP inliers, RGB-D VO drift, mean intensity, saturation). Target: >= 1x real time on
the 2-core CPU at a low sun.

Run: ``python perf/run.py camera_low_sun``. ``--scene PATH`` uses an already built scene;
``--seconds`` shortens the drive; ``--elevations 2,-3`` picks elevations; ``--figure docs/img``
also writes one frame per elevation (the docs figure).
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path
from typing import Any

os.environ.setdefault("MUJOCO_GL", "egl")

from perf._measure import measure
from perf.fidelity.bench_camera import SCENE
from perf.suite import Param, floats, optional

PARAMS = (Param("seconds", float, "simulated seconds of each drive", quick=4.0, full=34.0),
          Param("elevations", floats, "sun elevations (deg), comma-separated", quick=(2.0,),
                full=(13.0, 5.0, 2.0, -3.0)),
          Param("scene", optional(Path), "an already built scene folder (none: the camera "
                "benchmark's default scene, built once)", quick=None, full=None),
          Param("figure", optional(Path), "folder to write one frame per elevation into",
                quick=None, full=None))
TAU = 0.1
SUN_AZIMUTH_DEG = 30.0
START_XY_M = (20.0, 20.0)
_RUN = Path(tempfile.gettempdir()) / "marsscene_bench_camera_low_sun_run"
_SET: dict[str, Any] = {"seconds": 34.0, "scene": SCENE, "figure": None, "elevation": 13.0}
"""Set by main before each measured call (forked child processes inherit it)."""


def _build() -> None:
    import marsscene as ms

    ms.write_scene(ms.build_scene(seed=7), _SET["scene"], formats=("mjcf",))


def _camera() -> object:
    from marsscene.runtime import CameraConfig

    return CameraConfig(sun_elevation_deg=_SET["elevation"], sun_azimuth_deg=SUN_AZIMUTH_DEG,
                        tau=TAU)


def _drive() -> dict[str, float]:
    import numpy as np

    from marsscene.runtime import RunConfig
    from marsscene.seeding import stage_rng
    from marsscene.sim.driver import drive_sim
    from marsscene.sim.rover_sim import RoverSim

    corridor = np.array([START_XY_M, (START_XY_M[0] + 12.0, START_XY_M[1])])
    sim = RoverSim(_SET["scene"], run=RunConfig(camera=_camera()), start_xy_m=START_XY_M,
                   contact_corridor_xy_m=corridor, contact_corridor_m=30.0)
    t0 = time.perf_counter()
    renderer = sim.make_renderer()
    init = time.perf_counter() - t0
    times = []
    for _ in range(10):  # render cost alone, warm (RGB + depth, one pass)
        renderer._sync(sim)
        t0 = time.perf_counter()
        renderer._render(renderer.camera_id, True)
        times.append(time.perf_counter() - t0)
    if _SET["figure"]:
        from PIL import Image

        rgb, _ = sim.render(renderer)
        elevation = _SET["elevation"]
        name = f"camera_low_sun_{'m' if elevation < 0 else ''}{abs(elevation):g}deg.png"
        Image.fromarray(rgb).save(Path(_SET["figure"]) / name)
    renderer.close()
    t0 = time.perf_counter()
    seconds = _SET["seconds"]
    drive_sim(sim, command=(0.3, 0.0), seconds=seconds, out_dir=_RUN, rng=stage_rng(0, "sensors"))
    wall = time.perf_counter() - t0
    return {"ratio": seconds / wall, "ratio_no_start": seconds / max(wall - init, 1e-9),
            "wall_s": wall, "camera_init_s": init, "rgbd_ms": 1e3 * float(np.median(times))}


def _quality() -> dict[str, float]:
    import numpy as np

    from perf.fidelity.bench_camera import rgbd_vo_of_run

    vo, rgb = rgbd_vo_of_run(_RUN)
    mean = np.array([im.mean() / 255 for im in rgb])
    sat = np.array([(im.max(axis=-1) >= 255).mean() for im in rgb])
    return {"corners_median": float(np.median(vo.corners_per_frame)),
            "corners_min": float(vo.corners_per_frame.min()),
            "pairs_tracked_30": float((vo.inliers_per_pair >= 30).mean()),
            "vo_drift_pct": 100 * vo.drift_fraction,
            "mean_min": float(mean.min()), "mean_max": float(mean.max()),
            "saturated_max_pct": 100 * float(sat.max())}


def main(seconds: float, elevations: tuple[float, ...], scene: Path | None,
         figure: Path | None) -> list[dict[str, Any]]:
    _SET.update(seconds=seconds, scene=scene or SCENE, figure=figure)
    figures: list[dict[str, Any]] = []
    if not (_SET["scene"] / "mjcf" / "scene.xml").is_file():
        wall, peak, _ = measure(_build)
        print(f"camera_low_sun: build default scene seed 7 {wall:.1f} s, peak {peak:.0f} MB")
    for elevation in elevations:
        _SET["elevation"] = elevation
        _, peak, r = measure(_drive)
        _, _, q = measure(_quality)
        print(f"camera_low_sun: sun {elevation:g} deg (tau {TAU}, azimuth {SUN_AZIMUTH_DEG:g}),"
              f" 640x480: {r['ratio']:.2f}x real time ({seconds:.0f} sim s in {r['wall_s']:.1f} s;"
              f" {r['ratio_no_start']:.2f}x without the camera start of "
              f"{r['camera_init_s']:.1f} s), RGB-D {r['rgbd_ms']:.0f} ms per frame, load "
              f"{os.getloadavg()[0]:.1f}, peak {peak:.0f} MB; corners median "
              f"{q['corners_median']:.0f} (min {q['corners_min']:.0f}), pairs >= 30 inliers "
              f"{100 * q['pairs_tracked_30']:.1f} %, VO drift {q['vo_drift_pct']:.2f} %, mean "
              f"{q['mean_min']:.3f}-{q['mean_max']:.3f}, saturated <= "
              f"{q['saturated_max_pct']:.2f} %", flush=True)
        figures.append({"elevation_deg": elevation, **r, "peak_rss_mb": peak, **q})
    return figures

