"""Long drives: memory over time, the bag per minute of drive, and the paper routes projected.

Run: ``python perf/run.py long_drive [--minutes M] [--out DIR]`` (full: 10 minutes of
simulated driving into a temporary folder). The drive is what ``marsscene drive --camera
--lidar`` does with the default camera (640 x 480 RGB-D, 10 Hz) and LiDAR (os1-128, 10 Hz) on the
default scene, around a loop of laps long enough not to finish, encoding the bag's JPEGs while
it drives as ``marsscene drive --bag`` does. Printed:

- resident memory (VmRSS) at every simulated minute and the peak (VmHWM): flat means nothing
  grows per frame beyond the files;
- the drive's real-time factor;
- ``write_bag`` with its default settings: size per minute of drive, write time and its share
  of the drive's wall time;
- the size and time of the MarsLab paper's three SLAM routes (440, 393 and 648 m) at this
  drive's metres per minute.

``python perf/run.py long_drive --bag-run RUN_DIR`` writes and measures only the bag of an
existing run folder.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any

from perf.suite import Param, optional

os.environ.setdefault("MUJOCO_GL", "egl")
PARAMS = (Param("minutes", float, "simulated minutes of driving", quick=0.25, full=10.0),
          Param("out", optional(Path), "run folder (none: one in the temporary folder)",
                quick=None, full=None),
          Param("bag_run", optional(Path), "measure only the bag of this existing run folder",
                quick=None, full=None))

CACHE = Path(tempfile.gettempdir()) / "marsscene_bench_long_drive"
PAPER_ROUTES_M = {"Mars Base": 440.0, "Main Crater": 393.0, "Grand Canyon": 648.0}


def _status_kb(key: str) -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(key + ":"):
            return float(line.split()[1])
    return float("nan")


def _scene() -> Path:
    out = CACHE / "scene-default"
    if not (out / "mjcf" / "scene.xml").is_file():
        subprocess.run(["marsscene", "build", "--seed", "7", "--out", str(out), "--format",
                        "mjcf"], check=True, capture_output=True)
    return out


def drive(minutes: float, out: Path, jpeg_cache: Any = None) -> tuple[float, float]:
    """Drive ``minutes`` of sim time into ``out``; returns (wall s, metres driven)."""
    import numpy as np

    from marsscene.rover.config import CameraConfig, LidarConfig, RunConfig
    from marsscene.seeding import stage_rng
    from marsscene.sim.driver import DriveProgress
    from marsscene.sim.driver import drive_sim as run_drive
    from marsscene.sim.mission import prepare_drive
    from marsscene.sim.session import SessionOptions

    lap = np.array([[-10.0, -10.0], [10.0, -10.0], [10.0, 10.0], [-10.0, 10.0]])
    laps = max(2, int(minutes * 60 * 0.5 / 80) + 2)  # 80 m a lap; never done before the limit
    waypoints = np.vstack([lap] * laps + [lap[:1]])
    sim, route = prepare_drive(_scene(), RunConfig(camera=CameraConfig(), lidar=LidarConfig()),
                               waypoints_xy_m=waypoints)
    print(f"route {route.length_m:.0f} m ({laps} laps), limit {minutes:g} sim min", flush=True)
    t0 = time.perf_counter()
    marks: list[str] = []

    def sample(p: DriveProgress) -> None:
        if round(p.sim_time_s) % 60 == 0:
            wall = time.perf_counter() - t0
            marks.append(f"{p.sim_time_s / 60:4.0f} min: RSS {_status_kb('VmRSS') / 1024:7.0f} MB"
                         f", {p.distance_m:6.1f} m, wall {wall:6.0f} s, "
                         f"{p.sim_time_s / wall:.2f}x real time")
            print(marks[-1], flush=True)

    res = run_drive(sim, route=route, seconds=minutes * 60.0, out_dir=out,
                    rng=stage_rng(7, "sensors"), progress=sample,
                    session=SessionOptions(jpeg_cache=jpeg_cache))
    wall = time.perf_counter() - t0
    print(f"peak RSS (VmHWM) {_status_kb('VmHWM') / 1024:.0f} MB; "
          f"{res.summary['path_length_m']:.1f} m in {res.summary['sim_time_s']:.0f} sim s, "
          f"wall {wall:.0f} s ({res.summary['sim_time_s'] / wall:.2f}x real time)", flush=True)
    return wall, float(res.summary["path_length_m"])


def bag(run_dir: Path, drive_wall_s: float | None = None,
        jpeg_cache: Any = None) -> dict[str, Any]:
    """Write the run's bag with the default settings and print size and time per minute."""
    from marsscene.runs.export.bag import write_bag
    from marsscene.runs.runlog import RunLog

    run = RunLog(run_dir)
    minutes = float(run.gt.timestamps_s[-1]) / 60.0
    metres = run.gt.path_length_m()
    out = run_dir / "bag"
    shutil.rmtree(out, ignore_errors=True)
    t0 = time.perf_counter()
    res = write_bag(run_dir, jpeg_cache=jpeg_cache)
    wall = time.perf_counter() - t0
    mb = res.size_bytes / 1e6
    print(f"bag: {mb:.0f} MB for {minutes:.1f} min of drive = {mb / minutes:.1f} MB/min "
          f"({sum(res.counts.values())} messages), written in {wall:.1f} s "
          f"= {wall / minutes:.1f} s per minute of drive", flush=True)
    if drive_wall_s:
        print(f"bag writing adds {100 * wall / drive_wall_s:.1f} % to the drive's wall time")
    per_m = mb / max(metres, 1e-9)
    figures: dict[str, Any] = {"drive_min": minutes, "path_m": metres, "bag_mb": mb,
                               "bag_mb_per_min": mb / minutes, "bag_write_s": wall,
                               "messages": sum(res.counts.values())}
    if drive_wall_s:
        figures["drive_wall_s"] = drive_wall_s
    for name, length in PAPER_ROUTES_M.items():
        mins = length / (metres / minutes)
        gb, write_min = per_m * length / 1e3, wall / minutes * mins / 60
        print(f"  {name:13s} {length:4.0f} m: ~{mins:4.0f} min of drive, "
              f"bag ~{gb:5.2f} GB, written in ~{write_min:4.1f} min")
        figures[f"{name} bag_gb"] = gb
    return figures


def main(minutes: float, out: Path | None, bag_run: Path | None) -> dict[str, Any]:
    if bag_run is not None:
        return bag(bag_run)
    out = out or CACHE / f"run-{minutes:g}min"
    shutil.rmtree(out, ignore_errors=True)
    from marsscene.runs.export.bag_images import JpegCache

    out.mkdir(parents=True)
    cache = JpegCache.fresh(out)
    try:
        wall, _ = drive(minutes, out, cache)
        return bag(out, wall, cache)
    finally:
        cache.remove()

