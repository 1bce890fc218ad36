"""Batched drives (marsscene.sim.batch.drive_batch) on a GPU: drives a second and the real-time
factor per rover for batches of drives, each writing its whole run folder.

Usage::

    python perf/run.py batch_drives [--drives 6,64,1024] [--sensors state,rgbd+lidar]
        [--seconds 20] [--image 640x480] [--lidar os1-64] [--device cuda:0]

Each drive follows a straight route of ``route_m`` across one procedural scene (built once,
``size_m`` square; drive i offset sideways so the routes differ) with the LN-200S noise.
``state``: ground truth, odometry, wheels, IMU; ``rgbd+lidar``: those plus RGB-D at ``image``
at 10 Hz and the ``lidar`` model at 10 Hz. The wall time is ``drive_batch``'s loop and the
writing (the model build and settling apart); drives/s is drives over that wall time, the
real-time factor sim seconds over it. Disk is the run folders' bytes.
"""

from __future__ import annotations

import shutil
import tempfile
import time
from pathlib import Path
from typing import Any

from perf.suite import Param, ints, names, optional

PARAMS = (
    Param("drives", ints, "drives in a batch", quick=(2,), full=(6, 64, 1024)),
    Param("sensors", names, "state, rgbd+lidar", quick=("state", "rgbd+lidar"),
          full=("state", "rgbd+lidar")),
    Param("seconds", float, "sim seconds of each drive", quick=0.4, full=20.0),
    Param("image", str, "depth image size (WIDTHxHEIGHT)", quick="32x24", full="640x480"),
    Param("lidar", str, "LiDAR model", quick="vlp16", full="os1-64"),
    Param("size_m", float, "scene side (m)", quick=20.0, full=40.0),
    Param("physics_hz", float, "physics rate (Hz)", quick=100.0, full=500.0),
    Param("device", optional(str), "Warp device (none: cuda:0 where there is a GPU, else cpu)",
          quick=None, full=None),
    Param("scene", optional(str), "a built scene folder to drive on, at least size_m square "
          "(none: build the procedural one; a folder lets a machine without the build's "
          "libraries run it)", quick=None, full=None),
)


def _scene(size_m: float, folder: Path, built: str | None = None) -> Path:
    """The scene the drives run on: ``built`` where given, else a procedural one built into
    ``folder``."""
    if built is not None:
        return Path(built)
    from marsscene.env import WorldSampler

    base = {"terrain": {"source": "procedural", "size_m": [size_m, size_m], "post_m": 0.25,
                        "rms_height_m": 0.05},
            "craters": {"enabled": False}, "rocks": {"k": 0.05, "mjcf_min_diameter_m": 0.3}}
    return WorldSampler(base=base, count=1, seed=3, cache_dir=str(folder)).path(0)


def _config(sensors: str, size: str, lidar: str, physics_hz: float) -> Any:
    import marsscene as ms

    w, _, h = size.partition("x")
    extra: dict[str, Any] = {}
    if sensors == "rgbd+lidar":
        extra = {"camera": ms.CameraConfig(width_px=int(w), height_px=int(h), rate_hz=10.0),
                 "lidar": ms.LidarConfig(model=lidar)}
    elif sensors != "state":
        raise ValueError(f"sensors {sensors!r}: state or rgbd+lidar")
    return ms.RunConfig(physics_hz=physics_hz, noise=ms.NoiseConfig(profile="ln200s"), **extra)


def _disk(paths: list[Path]) -> int:
    return sum(f.stat().st_size for p in paths for f in p.rglob("*") if f.is_file())


def main(drives: tuple[int, ...], sensors: tuple[str, ...], seconds: float, image: str,
         lidar: str, size_m: float, physics_hz: float, device: str | None,
         scene: str | None) -> list[dict[str, Any]]:
    import marsscene as ms
    from marsscene.sim.batch import BatchDrive, drive_batch

    root = Path(tempfile.mkdtemp(prefix="bench_batch_drives_"))
    rows = []
    try:
        scene_dir = _scene(size_m, root / "scenes", scene)
        half = size_m / 2 - 3.0
        for kind in sensors:
            for n in drives:
                out = root / f"{kind}-{n}"
                batch = [BatchDrive(scene=scene_dir, out_dir=out / f"{i:05d}", seed=i,
                                    seconds=seconds,
                                    waypoints=[[-half, (i % 7 - 3) * 1.0],
                                               [half, (i % 7 - 3) * 1.0]])
                         for i in range(n)]
                t0 = time.perf_counter()
                run = drive_batch(batch, config=_config(kind, image, lidar, physics_hz),
                                  device=device, options=ms.DriveOptions(settle_s=1.0))
                total = time.perf_counter() - t0
                row = {"device": run.device, "sensors": kind, "drives": n,
                       "sim_s": run.sim_s, "drive_wall_s": round(run.wall_s, 3),
                       "setup_s": round(total - run.wall_s, 3),
                       "drives_per_s": round(n / run.wall_s, 4),
                       "realtime_factor": round(run.realtime_factor, 4),
                       "rover_sim_s_per_s": round(n * run.realtime_factor, 3),
                       "disk_mb": round(_disk(run.out_dirs) / 1e6, 3),
                       "lidar_scans": run.summaries[0]["lidar_scans"],
                       "camera_frames": run.summaries[0]["camera_frames"]}
                print(row, flush=True)
                rows.append(row)
                shutil.rmtree(out, ignore_errors=True)  # disk flat across batches
    finally:
        shutil.rmtree(root, ignore_errors=True)
    return rows
