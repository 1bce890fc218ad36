"""Open3D RGB-D odometry's frame pairs shared out over processes (issue 47): wall time, time
per pair, speed-up, and whether the steps match one process's.

Run: ``python perf/run.py rgbd_processes --run-dir RUN_DIR [--pairs N] [--processes 1,2]
[--chunk N]``

* ``--run-dir``: a drive with a TUM RGB-D export in ``tum_rgbd/`` (a SLAM benchmark cell's
  ``drive/`` before its images are removed, or ``marsscene drive ... --dataset tum-rgbd``);
* ``--pairs``: the first this many frame pairs (full 400);
* ``--processes``: process counts, comma-separated (full ``1,2``);
* ``--chunk``: pairs per chunk (full 100; the benchmark's is 500, for cells of thousands).

Every run is the benchmark's row: the wheel odometry (wheels' travel, gyro's rotation) as
each pair's guess and fallback, full-size images. Idle cores are what ``--method-processes``
uses, so measure on a machine that is otherwise idle.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from perf.suite import Param, ints, optional

PARAMS = (Param("run_dir", optional(Path), "a drive folder with a TUM RGB-D export (needed)",
                quick=None, full=None),
          Param("pairs", int, "the first this many frame pairs", quick=20, full=400),
          Param("processes", ints, "process counts, comma-separated", quick=(1, 2), full=(1, 2)),
          Param("chunk", int, "pairs per chunk", quick=10, full=100))


def _first_pairs(run_dir: Path, pairs: int, out: Path) -> Path:
    """A TUM RGB-D folder of the run's first ``pairs + 1`` frames (links to its images)."""
    src = run_dir / "tum_rgbd"
    lines = [ln for ln in (src / "associations.txt").read_text(encoding="utf-8").splitlines()
             if ln.strip() and not ln.startswith("#")][: pairs + 1]
    out.mkdir()
    (out / "associations.txt").write_text("\n".join(lines) + "\n", encoding="utf-8")
    shutil.copy(src / "orbslam3_rgbd.yaml", out / "orbslam3_rgbd.yaml")
    for sub in ("rgb", "depth"):
        (out / sub).mkdir()
    for ln in lines:
        for rel in ln.split()[1::2]:
            os.symlink((src / rel).resolve(), out / rel)
    return out


def main(run_dir: Path | None, pairs: int, processes: tuple[int, ...],
         chunk: int) -> list[dict[str, float]]:
    from marsscene.benchmark.slam.rgbd_odometry import rgbd_odometry

    if run_dir is None:
        raise SystemExit("rgbd_processes: --run-dir DRIVE (a drive with tum_rgbd/) is needed")
    counts = processes
    rows = []
    print(f"{run_dir}: {pairs} pairs in chunks of {chunk}, {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory(prefix="bench-rgbd-") as tmp:
        folder = _first_pairs(run_dir, pairs, Path(tmp) / "tum_rgbd")
        first = None
        for n in counts:
            t0 = time.perf_counter()
            res = rgbd_odometry(folder, run_dir, wheel_prior=True, checkpoint_every=chunk,
                                processes=n)
            wall = time.perf_counter() - t0
            done = len(res.poses) - 1
            steps = np.linalg.inv(res.poses[:-1]) @ res.poses[1:]
            if first is None:
                first = (wall, steps)
            same = int((np.abs(steps - first[1]).max(axis=(1, 2)) < 1e-6).sum())
            print(f"processes {n}: {wall:7.1f} s wall, {wall / done:.3f} s a pair, "
                  f"speed-up {first[0] / wall:.2f}x, {same} of {done} steps as with "
                  f"{counts[0]}, {res.fallbacks} from the odometry")
            rows.append({"processes": n, "wall_s": wall, "s_per_pair": wall / done,
                         "speedup": first[0] / wall, "same_steps": same, "pairs": done,
                         "fallbacks": res.fallbacks})
    return rows

