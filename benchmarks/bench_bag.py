"""ROS 2 bag writing and dataset export for a 60 s drive with 640 x 480 RGB-D and LiDAR at 10 Hz.

Issue 11 target: writing the bag adds < 20 % to the drive's wall time. The drive runs on a
100 m x 100 m procedural scene (0.25 m posts, rocks) at 0.5 m/s, 0.05 rad/s, with a
640 x 480 RGB-D camera and a 16 x 360 LiDAR at 10 Hz; then the run folder is written as an
MCAP bag, a sqlite3 bag and a TUM RGB-D folder. Set BENCH_BAG_SECONDS for a shorter drive.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

from _measure import measure

SIM_S = float(os.environ.get("BENCH_BAG_SECONDS", "60"))
_ROOT = Path(tempfile.gettempdir()) / "marsscene_bench_bag"
_SCENE, _RUN = _ROOT / "scene", _ROOT / "run"


def _build() -> None:
    import marsscene as ms

    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "procedural", "size_m": [100, 100], "post_m": 0.25,
                    "rms_height_m": 0.3},
        "export": {"formats": ["mjcf"]},
    })
    ms.write_scene(ms.build_scene(cfg, seed=1), _SCENE, formats=("mjcf",), overwrite=True)


def _drive() -> dict[str, float]:
    from marsscene.runtime import CameraConfig, LidarConfig, RunConfig
    from marsscene.seeding import stage_rng
    from marsscene.sim.driver import drive
    from marsscene.sim.rover_sim import RoverSim

    shutil.rmtree(_RUN, ignore_errors=True)
    run = RunConfig(camera=CameraConfig(width_px=640, height_px=480),
                    lidar=LidarConfig(model="simple"))
    sim = RoverSim(_SCENE, run=run, start_xy_m=(-20.0, -10.0))
    t0 = time.perf_counter()
    drive(sim, command=(0.5, 0.05), seconds=SIM_S, out_dir=_RUN, rng=stage_rng(0, "sensors"))
    return {"wall_s": time.perf_counter() - t0}


def _size_mb(path: Path) -> float:
    return sum(p.stat().st_size for p in path.rglob("*") if p.is_file()) / 1e6


def _bag(storage: str) -> dict[str, float]:
    from marsscene.runs.export.bag import write_bag

    t0 = time.perf_counter()
    res = write_bag(_RUN, _ROOT / f"bag_{storage}", storage=storage, overwrite=True)
    return {"wall_s": time.perf_counter() - t0, "mb": res.size_bytes / 1e6,
            "messages": sum(res.counts.values())}


def _bag_mcap() -> dict[str, float]:
    return _bag("mcap")


def _bag_sqlite() -> dict[str, float]:
    return _bag("sqlite3")


def _tum() -> dict[str, float]:
    from marsscene.runs.export.datasets import export_dataset

    t0 = time.perf_counter()
    out = export_dataset(_RUN, "tum-rgbd", _ROOT / "tum", overwrite=True)
    return {"wall_s": time.perf_counter() - t0, "mb": _size_mb(out)}


def main() -> None:
    _ROOT.mkdir(parents=True, exist_ok=True)
    wall, _, _ = measure(_build)
    print(f"scene (100 m, 0.25 m posts): {wall:.1f} s")
    _, peak, d = measure(_drive)
    print(f"drive {SIM_S:.0f} sim s, RGB-D 640x480 + LiDAR 16x360 @ 10 Hz: {d['wall_s']:.1f} s "
          f"wall, peak {peak:.0f} MB, run folder {_size_mb(_RUN):.0f} MB")
    for name, fn in (("bag mcap", _bag_mcap), ("bag sqlite3", _bag_sqlite)):
        _, peak, b = measure(fn)
        print(f"{name:>12}: {b['wall_s']:.1f} s ({100 * b['wall_s'] / d['wall_s']:.1f} % of the "
              f"drive), {b['mb']:.0f} MB, {b['messages']:.0f} messages, peak {peak:.0f} MB")
    _, peak, t = measure(_tum)
    print(f"    tum-rgbd: {t['wall_s']:.1f} s, {t['mb']:.0f} MB, peak {peak:.0f} MB")


if __name__ == "__main__":
    main()
