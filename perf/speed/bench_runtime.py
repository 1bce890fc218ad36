"""Rover runtime speed on the default scene (bundled Gale DEM, 0.25 m posts).

Sim-time / wall-time ratio for 20 s of driving (0.5 m/s, 0.05 rad/s, 50 Hz control, IMU
100 Hz): physics only, + 16 x 360 LiDAR at 10 Hz, + 320 x 240 RGB-D camera at 10 Hz.
Targets (issue 7): >= 20x real time physics only, >= 1x with the camera.
Run: ``python perf/run.py runtime [--sim-s S]``.
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

from perf._measure import measure
from perf.suite import Param

PARAMS = (Param("sim_s", float, "simulated seconds of each drive", quick=2.0, full=20.0),)
_SIM = {"s": 20.0}  # set by main before the measured calls (forked children inherit it)
_SCENE = Path(tempfile.gettempdir()) / "marsscene_bench_runtime_scene"


def _build() -> None:
    import marsscene as ms

    ms.write_scene(ms.build_scene(seed=0), _SCENE, formats=("mjcf",))


def _drive(kind: str) -> dict[str, float]:
    import numpy as np

    from marsscene.runtime import CameraConfig, LidarConfig, RoverConfig, RunConfig
    from marsscene.seeding import stage_rng
    from marsscene.sim.driver import drive_sim
    from marsscene.sim.rover_sim import RoverSim

    rover = RoverConfig(wheel_collision="sphere" if kind == "sphere" else "cylinder")
    # "corridor": as `marsscene drive` does with a route, simulate only the MJCF rocks the
    # rover can meet (here: within 25 m of the start; it drives ~10 m in 20 s).
    corridor = np.zeros((1, 2)) if kind in ("corridor", "sphere", "lidar", "camera") else None
    run = RunConfig(
        lidar=LidarConfig(model="simple") if kind == "lidar" else None,
        camera=CameraConfig(width_px=320, height_px=240) if kind == "camera" else None,
    )
    t0 = time.perf_counter()
    sim = RoverSim(_SCENE, run=run, rover=rover, contact_corridor_xy_m=corridor,
                   contact_corridor_m=25.0)
    load = time.perf_counter() - t0
    t0 = time.perf_counter()
    res = drive_sim(sim, command=(0.5, 0.05), seconds=_SIM["s"], rng=stage_rng(0, "sensors"))
    wall = time.perf_counter() - t0
    return {
        "load_s": load,
        "wall_s": wall,
        "ratio": _SIM["s"] / wall,
        "dist_m": float(np.linalg.norm(res.gt.xyz_m[-1] - res.gt.xyz_m[0])),
        "rocks": sim.rocks_kept,
    }


def _physics() -> dict[str, float]:
    return _drive("physics")


def _corridor() -> dict[str, float]:
    return _drive("corridor")


def _sphere() -> dict[str, float]:
    return _drive("sphere")


def _lidar() -> dict[str, float]:
    return _drive("lidar")


def _camera() -> dict[str, float]:
    return _drive("camera")


def _raw_steps() -> dict[str, float]:
    import mujoco

    from marsscene.sim.rover_sim import RoverSim

    sim = RoverSim(_SCENE)
    sim.apply(0.5, 0.05)
    t0 = time.perf_counter()
    mujoco.mj_step(sim.model, sim.data, nstep=5000)
    return {"steps_per_s": 5000 / (time.perf_counter() - t0)}


def main(sim_s: float) -> list[dict[str, object]]:
    _SIM["s"] = sim_s
    wall, peak, _ = measure(_build)
    print(f"default scene build + MJCF write: {wall:.2f} s, peak {peak:.0f} MB")
    _, _, raw = measure(_raw_steps)
    print(
        f"raw mj_step (rover on default scene): {raw['steps_per_s']:.0f} steps/s "
        f"= {raw['steps_per_s'] * 0.002:.1f}x real time"
    )
    figures: list[dict[str, object]] = [
        {"case": "build + MJCF write", "wall_s": wall, "peak_rss_mb": peak},
        {"case": "raw mj_step", "steps_per_s": raw["steps_per_s"],
         "ratio": raw["steps_per_s"] * 0.002}]
    for name, fn in (
        ("physics only, all rocks", _physics),
        ("physics only, corridor", _corridor),
        ("corridor, sphere wheels", _sphere),
        ("+ LiDAR 16x360 @10 Hz", _lidar),
        ("+ RGB-D 320x240 @10 Hz", _camera),
    ):
        try:
            wall, peak, r = measure(fn)
        except Exception as err:  # e.g. no headless GL for the camera
            print(f"{name:>24}: failed: {err}")
            continue
        print(
            f"{name:>24}: {sim_s:.0f} sim s in {r['wall_s']:.2f} s wall = {r['ratio']:.1f}x "
            f"real time (load+settle {r['load_s']:.2f} s, drove {r['dist_m']:.1f} m, "
            f"peak {peak:.0f} MB, MJCF rocks simulated {r['rocks'][0]}/{r['rocks'][1]})"
        )
        figures.append({"case": name, **r, "peak_rss_mb": peak})
    return figures

