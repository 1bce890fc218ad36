"""ROS 2 bag size (MB per minute of drive) and write time: raw vs compressed images, chunk codecs.

A 60 s drive (``--seconds``) with the default 640 x 480 RGB-D camera and the default LiDAR
(os1-128, 10 Hz; ``--lidar simple`` for the 16 x 360 model of issue 11) on a 100 m x 100 m
procedural scene at 0.5 m/s, 0.05 rad/s; or an existing run folder (``--run PATH``: no
drive). Then, per topic group (state: clock, TF, odometry, IMU, joints, URDF; camera: RGB, depth,
camera infos [, depth cloud]; LiDAR: cloud + scan), a bag of that group alone for each image
mode and chunk compression: MB/min (the state bag is subtracted from the sensor ones), write
time and the compression ratio against the uncompressed bag; then whole bags (default
settings, raw images without compression as before issue 23, sqlite3) and the TUM RGB-D
export. Team target (issue 23): <= 120 MB per minute of drive with the default settings.
Run: ``python perf/run.py bag`` (quick: a 5 s drive with the ``simple`` LiDAR).
"""

from __future__ import annotations

import functools
import os
import shutil
import tempfile
import time
from pathlib import Path
from typing import Any

os.environ.setdefault("MUJOCO_GL", "egl")

from perf._measure import measure
from perf.suite import Param, optional

PARAMS = (
    Param("seconds", float, "sim seconds of the drive", quick=5.0, full=60.0),
    Param("lidar", str, "LiDAR model of the drive", quick="simple", full="os1-128"),
    Param("run", optional(Path), "an existing run folder to write bags of (none: drive one)",
          quick=None, full=None),
)

_ROOT = Path(tempfile.gettempdir()) / "marsscene_bench_bag"
_SCENE = _ROOT / "scene"
GROUPS = {"state": [], "camera": ["camera"], "lidar": ["lidar"]}
CODECS = ("none", "lz4", "zstd_fast", "zstd")


def _build() -> None:
    import marsscene as ms

    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "procedural", "size_m": [100, 100], "post_m": 0.25,
                    "rms_height_m": 0.3},
        "export": {"formats": ["mjcf"]},
    })
    ms.write_scene(ms.build_scene(cfg, seed=1), _SCENE, formats=("mjcf",), overwrite=True)


def _drive(run_dir: Path, seconds: float, lidar: str) -> dict[str, float]:
    from marsscene.runtime import CameraConfig, LidarConfig, RunConfig
    from marsscene.seeding import stage_rng
    from marsscene.sim.driver import drive_sim
    from marsscene.sim.rover_sim import RoverSim

    shutil.rmtree(run_dir, ignore_errors=True)
    run = RunConfig(camera=CameraConfig(width_px=640, height_px=480),
                    lidar=LidarConfig(model=lidar))
    sim = RoverSim(_SCENE, run=run, start_xy_m=(-20.0, -10.0))
    t0 = time.perf_counter()
    drive_sim(sim, command=(0.5, 0.05), seconds=seconds, out_dir=run_dir,
              rng=stage_rng(0, "sensors"))
    return {"wall_s": time.perf_counter() - t0}


def _size_mb(path: Path) -> float:
    return sum(p.stat().st_size for p in path.rglob("*") if p.is_file()) / 1e6


def _bag(run_dir: Path, name: str, **kw: Any) -> dict[str, float]:
    from marsscene.runs.export.bag import write_bag

    t0 = time.perf_counter()
    res = write_bag(run_dir, _ROOT / name, overwrite=True, **kw)
    wall = time.perf_counter() - t0
    mb = res.size_bytes / 1e6
    shutil.rmtree(res.path)
    return {"wall_s": wall, "mb": mb, "messages": sum(res.counts.values())}


def _tum(run_dir: Path) -> dict[str, float]:
    from marsscene.runs.export.datasets import export_dataset

    t0 = time.perf_counter()
    out = export_dataset(run_dir, "tum-rgbd", _ROOT / "tum", overwrite=True)
    return {"wall_s": time.perf_counter() - t0, "mb": _size_mb(out)}


def _minutes(run_dir: Path) -> float:
    from marsscene.runs.runlog import RunLog

    t = RunLog(run_dir).gt.timestamps_s
    return float(t[-1] - t[0]) / 60.0


def _groups(run_dir: Path, minutes: float) -> list[dict[str, Any]]:
    images = (("compressed jpeg", {"images": "compressed", "image_codec": "jpeg"}),
              ("compressed png", {"images": "compressed", "image_codec": "png"}),
              ("jpeg + cloud", {"images": "compressed", "depth_cloud": True}),
              ("raw + cloud", {"images": "raw"}))
    print(f"{'group':>7} {'images':>16} {'compression':>11} {'MB/min':>8} {'ratio':>6} "
          f"{'write s':>8}")
    state: dict[str, float] = {}
    rows = []
    for group, sensors in GROUPS.items():
        modes = images if group == "camera" else (("-", {}),)
        for label, kw in modes:
            base = 0.0
            for codec in CODECS:
                _, _, b = measure(functools.partial(_bag, run_dir, f"g_{group}",
                                                    sensors=sensors, compression=codec, **kw))
                mb = b["mb"] - (state[codec] if group != "state" else 0.0)
                if group == "state":
                    state[codec] = b["mb"]
                base = base or mb
                print(f"{group:>7} {label:>16} {codec:>11} {mb / minutes:8.1f} "
                      f"{base / mb:6.2f} {b['wall_s']:8.1f}", flush=True)
                rows.append({"bag": group, "images": label, "compression": codec,
                             "mb_per_min": mb / minutes, "ratio": base / mb,
                             "write_s": b["wall_s"]})
    return rows


def main(seconds: float, lidar: str, run: Path | None) -> list[dict[str, Any]]:
    _ROOT.mkdir(parents=True, exist_ok=True)
    run_dir = run if run is not None else _ROOT / "run"
    drive_s = 0.0
    if run is None:
        wall, _, _ = measure(_build)
        print(f"scene (100 m, 0.25 m posts): {wall:.1f} s")
        _, peak, d = measure(functools.partial(_drive, run_dir, seconds, lidar))
        drive_s = d["wall_s"]
        print(f"drive {seconds:.0f} sim s, RGB-D 640x480 + LiDAR {lidar} @ 10 Hz: "
              f"{drive_s:.1f} s wall, peak {peak:.0f} MB, run folder {_size_mb(run_dir):.0f} MB")
    minutes = _minutes(run_dir)
    print(f"run {run_dir}: {60 * minutes:.1f} s of drive, folder {_size_mb(run_dir):.0f} MB")
    rows = [{"bag": "run", "drive_wall_s": drive_s, "drive_s": 60 * minutes,
             "run_mb": _size_mb(run_dir)}, *_groups(run_dir, minutes)]
    whole: tuple[tuple[str, str, dict[str, Any]], ...] = (
        ("default (jpeg, zstd)", "mcap", {}),
        ("raw + cloud, none", "mcap", {"images": "raw", "compression": "none"}),
        ("default, sqlite3", "sqlite3", {}))
    for name, storage, kw in whole:
        _, peak, b = measure(functools.partial(_bag, run_dir, "bag_whole", storage=storage,
                                               **kw))
        share = f" ({100 * b['wall_s'] / drive_s:.1f} % of the drive)" if drive_s else ""
        print(f"bag {name:>20}: {b['wall_s']:.1f} s{share}, {b['mb']:.0f} MB = "
              f"{b['mb'] / minutes:.0f} MB/min, {b['messages']:.0f} messages, "
              f"peak {peak:.0f} MB", flush=True)
        rows.append({"bag": "whole", "settings": name, "storage": storage,
                     "write_s": b["wall_s"], "mb": b["mb"], "mb_per_min": b["mb"] / minutes,
                     "messages": b["messages"], "peak_mb": peak})
    _, peak, t = measure(functools.partial(_tum, run_dir))
    print(f"    tum-rgbd: {t['wall_s']:.1f} s, {t['mb']:.0f} MB, peak {peak:.0f} MB")
    rows.append({"bag": "tum-rgbd", "write_s": t["wall_s"], "mb": t["mb"], "peak_mb": peak})
    return rows
