"""What the batch's physics changes: the same routes driven by the CPU drive (MuJoCo C, the
scene's mesh rocks, cylinder wheels) and by a batch on MuJoCo Warp (sphere wheels, rocks as
heightfield relief), compared by cross-track error and path length (issue 65).

Run: ``python perf/run.py batch_vs_cpu [--routes 4] [--seconds 20] [--device cuda:0]``.
One procedural scene (``size_m`` square, a few rocks) is built once; route i runs straight
across it, offset sideways by i m. Each route is driven once by :func:`marsscene.drive` and
once in one batch (:func:`marsscene.sim.batch.drive_batch`), state only, same seed, same
physics rate, same pure pursuit. Per route: both cross-track RMS and max (m), path lengths (m)
and their ratio, and the final positions' distance (m).
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from perf.speed.bench_batch_drives import _scene
from perf.suite import Param, optional

PARAMS = (
    Param("routes", int, "routes (drives)", quick=2, full=6),
    Param("seconds", float, "sim seconds of each drive", quick=2.0, full=40.0),
    Param("size_m", float, "scene side (m)", quick=20.0, full=40.0),
    Param("physics_hz", float, "physics rate (Hz)", quick=100.0, full=500.0),
    Param("device", optional(str), "Warp device (none: cuda:0 where there is a GPU, else cpu)",
          quick=None, full=None),
    Param("scene", optional(str), "a built scene folder, at least size_m square (none: build "
          "the procedural one)", quick=None, full=None),
)


def main(routes: int, seconds: float, size_m: float, physics_hz: float,
         device: str | None, scene: str | None) -> list[dict[str, Any]]:
    import marsscene as ms
    from marsscene.runs.tum import read_tum
    from marsscene.sim.batch import BatchDrive, drive_batch

    root = Path(tempfile.mkdtemp(prefix="bench_batch_vs_cpu_"))
    try:
        scene_dir = _scene(size_m, root / "scenes", scene)
        half = size_m / 2 - 3.0
        wps = [[[-half, i - routes / 2], [half, i - routes / 2]] for i in range(routes)]
        cfg = ms.RunConfig(physics_hz=physics_hz)
        opts = ms.DriveOptions(settle_s=1.0)
        batch = drive_batch([BatchDrive(scene=scene_dir, waypoints=w, out_dir=root / f"gpu{i}",
                                        seconds=seconds) for i, w in enumerate(wps)],
                            config=cfg, options=opts, device=device)
        rows = []
        for i, w in enumerate(wps):
            cpu = ms.drive(scene_dir, waypoints=w, seconds=seconds, config=cfg, options=opts,
                           out_dir=root / f"cpu{i}")
            g, c = batch.summaries[i], cpu.summary
            end = np.linalg.norm(read_tum(root / f"gpu{i}" / "gt.tum").xyz_m[-1, :2]
                                 - cpu.gt.xyz_m[-1, :2])
            row = {"route": i, "device": batch.device,
                   "cross_track_rms_m": {"cpu": c["cross_track_rms_m"],
                                         "batch": g["cross_track_rms_m"]},
                   "cross_track_max_m": {"cpu": c["cross_track_max_m"],
                                         "batch": g["cross_track_max_m"]},
                   "path_length_m": {"cpu": c["path_length_m"], "batch": g["path_length_m"]},
                   "path_ratio": round(g["path_length_m"] / max(c["path_length_m"], 1e-9), 4),
                   "end_gap_m": round(float(end), 4)}
            print(row, flush=True)
            rows.append(row)
    finally:
        shutil.rmtree(root, ignore_errors=True)
    return rows
