"""Method adapters of the SLAM benchmark: each turns one cell's logs into an estimate, or into
a status saying why there is none (never an exception).

=================  ==========================================================  ======  =====
kind               estimate                                                    frame   align
=================  ==========================================================  ======  =====
wheel-odometry     the run's ``odom.tum`` (planar: wheel rates and steering)     base    SE(3)
kiss-icp           KISS-ICP fed each scan during the drive (``drive/live/``;     lidar   SE(3)
                   on the run's ROS 2 bag in a benchmark folder made before;
                   ``wheel_prior``: each scan's step predicted by the wheels'
                   travel and the gyro, :class:`.kiss_icp.LiveKissIcp`)
open3d-rgbd        Open3D ``compute_rgbd_odometry``, frame to frame (hybrid;   camera  SE(3)
                   ``wheel_prior``: the same odometry as guess and fallback,
                   :mod:`.rgbd_odometry`)
opencv-mono        :func:`~marsscene.benchmark.slam.mono_vo.mono_vo` on the RGB     camera  Sim(3)
tum-file           a TUM file dropped into the cell (``file`` template)        any     any
command            a command run per cell that writes ``{out_tum}``            any     any
=================  ==========================================================  ======  =====

``camera`` is the navcam optical frame (the TUM RGB-D export's ``groundtruth.txt``), ``lidar``
the ``lidar_link`` frame, ``base`` the rover's ``base_link`` (``gt.tum``).
"""

from __future__ import annotations

import hashlib
import json
import shlex
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from marsscene.benchmark.slam.odometry_prior import PRIOR_MODEL
from marsscene.benchmark.slam.spec import MethodSpec
from marsscene.errors import MarsSceneError, MissingDependencyError
from marsscene.runs.export.datasets import tum_associations
from marsscene.runs.runlog import RunLog, pinhole_k, read_image, run_rover
from marsscene.runs.tum import Trajectory, read_tum

__all__ = ["DRIVE_FILE", "CellData", "Estimate", "estimate"]

#: In a cell's ``drive/``: the drive's key and summary (live methods' counts included).
DRIVE_FILE = "benchmark_drive.json"


@dataclass(frozen=True)
class CellData:
    """Where one cell's data lies, and what it is (scene, tau, seed)."""

    cell_dir: Path
    scene: str
    tau: float
    seed: int

    @property
    def run_dir(self) -> Path:
        return self.cell_dir / "drive"

    @property
    def paths(self) -> dict[str, str]:
        """Placeholders of ``command`` / ``file`` templates (paths as strings)."""
        return {"cell_dir": str(self.cell_dir), "run_dir": str(self.run_dir),
                "tum_rgbd_dir": str(self.run_dir / "tum_rgbd"),
                "euroc_dir": str(self.run_dir / "euroc"), "bag_dir": str(self.run_dir / "bag"),
                "scene_dir": str(self.cell_dir / "scene"), "scene": self.scene,
                "tau": f"{self.tau:g}", "seed": str(self.seed)}

    def ground_truth(self, frame: str) -> Trajectory:
        """Ground truth of ``base``, ``camera`` (navcam optical) or ``lidar`` (lidar_link)."""
        if frame == "camera":
            return read_tum(self.run_dir / "tum_rgbd" / "groundtruth.txt")
        gt = read_tum(self.run_dir / "gt.tum")
        if frame == "lidar":  # from gt.tum and run.json alone: a packed cell has no more
            from marsscene.benchmark.slam.kiss_icp import lidar_ground_truth

            meta = json.loads((self.run_dir / "run.json").read_text(encoding="utf-8"))
            return lidar_ground_truth(gt, run_rover(meta))
        return gt

    def frames(self, sensor: str) -> int:
        """Sensor frames of the run: camera images, LiDAR scans, or ground-truth poses."""
        if sensor == "camera":
            return len(tum_associations(self.run_dir / "tum_rgbd"))
        if sensor == "lidar":
            stamps = RunLog(self.run_dir).lidar_stamps_s  # the scans may be in the bag only
            return 0 if stamps is None else len(stamps)
        return len(read_tum(self.run_dir / "gt.tum"))


@dataclass(frozen=True)
class Estimate:
    """A method's trajectory (None if it gave none), tracked frames, status and note."""

    trajectory: Trajectory | None
    frames_tracked: int | None = None
    status: str = "ok"
    note: str = ""


def _intrinsics(folder: Path) -> dict[str, float]:
    return json.loads((folder / "camera" / "intrinsics.json").read_text(encoding="utf-8"))


def _trajectory(stamps_s: NDArray[np.float64], poses: NDArray[np.float64]) -> Trajectory:
    """Trajectory of camera-to-world 4x4 poses (N, 4, 4)."""
    return Trajectory(stamps_s, poses[:, :3, 3], Rotation.from_matrix(poses[:, :3, :3]).as_quat())


def _open3d_rgbd(cell: CellData, method: MethodSpec, processes: int) -> Estimate:
    from marsscene.benchmark.slam.rgbd_odometry import rgbd_odometry

    opts = {k: method.options[k] for k in ("depth_trunc_m", "wheel_prior", "max_step_dev_m",
                                           "max_step_dev_deg", "gyro", "decimate")
            if k in method.options}
    drive = cell.run_dir / DRIVE_FILE  # a new drive, other options or prior: start over
    key = hashlib.sha256(json.dumps(
        {"options": opts, "drive": drive.read_text(encoding="utf-8") if drive.is_file() else "",
         **({"prior": PRIOR_MODEL} if opts.get("wheel_prior") else {})},
        sort_keys=True).encode()).hexdigest()
    res = rgbd_odometry(cell.run_dir / "tum_rgbd", cell.run_dir, checkpoint_key=key,
                        checkpoint=cell.cell_dir / "estimates" / f".{method.name}.pairs",
                        processes=processes, **opts)
    note = (f"{res.fallbacks} of {len(res.poses) - 1} steps from the odometry"
            if opts.get("wheel_prior") else "")
    return Estimate(_trajectory(res.stamps_s, res.poses), frames_tracked=int(res.visual.sum()),
                    note=note)


def _opencv_mono(cell: CellData, method: MethodSpec) -> Estimate:
    from marsscene.benchmark.slam.mono_vo import mono_vo

    folder = cell.run_dir / "tum_rgbd"
    rows = tum_associations(folder)
    i = _intrinsics(cell.run_dir)
    k = pinhole_k(i)
    weights = np.array([0.299, 0.587, 0.114])
    gray = (np.clip(read_image(folder / r[1])[..., :3] @ weights, 0, 255).astype(np.uint8)
            for r in rows)
    opts = {k_: method.options[k_] for k_ in ("max_corners", "min_parallax_px", "min_inliers")
            if k_ in method.options}
    res = mono_vo(gray, k, **opts)
    stamps = np.array([float(r[0]) for r in rows])[res.tracked]
    traj = _trajectory(stamps, res.poses[res.tracked]) if res.tracked.sum() else None
    return Estimate(traj, frames_tracked=int(res.tracked.sum()), note=res.note)


def _kiss_icp(cell: CellData, method: MethodSpec) -> Estimate:
    live = cell.run_dir / "live" / f"{method.name}.tum"
    if live.is_file():
        if not method.options.get("wheel_prior"):
            return Estimate(read_tum(live))
        summary = json.loads((cell.run_dir / DRIVE_FILE).read_text(encoding="utf-8"))["summary"]
        kept, scans = summary["icp_steps_kept"][method.name]
        return Estimate(read_tum(live), frames_tracked=int(kept),
                        note=f"{kept} of {scans} ICP steps kept, the others the odometry's")
    if method.options.get("wheel_prior"):
        return Estimate(None, status="failed", note="no live KISS-ICP estimate (the wheel "
                        "prior runs during the drive)")
    if not (cell.run_dir / "bag").is_dir():
        return Estimate(None, status="failed", note="no live KISS-ICP estimate and no bag")
    from marsscene.benchmark.slam.kiss_icp import run_kiss_icp

    traj = run_kiss_icp(cell.run_dir / "bag", timeout_s=method.timeout_s)
    return Estimate(traj, status="ok" if traj is not None else "failed",
                    note="" if traj is not None else "KISS-ICP wrote no trajectory")


def _external(cell: CellData, method: MethodSpec, out_tum: Path) -> Estimate:
    fill = {**cell.paths, "method": method.name, "out_tum": str(out_tum)}
    if method.kind == "tum-file":
        path = Path(method.file.format(**fill))
        if not path.is_file():
            return Estimate(None, status="missing", note=f"no estimate at {path}")
        return Estimate(read_tum(path))
    assert method.command is not None
    try:
        argv = [part.format(**fill) for part in shlex.split(method.command)]
    except (KeyError, ValueError, IndexError) as err:
        return Estimate(None, status="failed", note=f"bad command template: {err}")
    out_tum.parent.mkdir(parents=True, exist_ok=True)
    out_tum.unlink(missing_ok=True)
    try:
        done = subprocess.run(argv, cwd=cell.cell_dir, capture_output=True, text=True,
                              timeout=method.timeout_s, check=False)
    except FileNotFoundError:
        return Estimate(None, status="missing", note=f"{argv[0]!r} not found")
    except subprocess.TimeoutExpired:
        return Estimate(None, status="failed", note=f"timed out after {method.timeout_s:g} s")
    if done.returncode != 0 or not out_tum.is_file():
        tail = (done.stderr or done.stdout).strip().splitlines()[-1:] or [""]
        why = f"exit code {done.returncode}" if done.returncode else f"no {out_tum} written"
        return Estimate(None, status="failed", note=f"{why}: {tail[0][:200]}")
    return Estimate(read_tum(out_tum))


def estimate(method: MethodSpec, cell: CellData, out_tum: Path, *,
             processes: int = 1) -> Estimate:
    """Run ``method`` on ``cell``; built-in estimates are also written to ``out_tum``.

    ``processes``: how many processes a method that splits its work may use (Open3D RGB-D's
    frame pairs); the estimate does not depend on it. A missing dependency gives
    ``missing``, any other error ``failed`` (with the reason).
    """
    from marsscene.runs.tum import write_tum

    try:
        if method.kind in ("tum-file", "command"):
            return _external(cell, method, out_tum)
        if method.kind == "wheel-odometry":
            est = Estimate(read_tum(cell.run_dir / "odom.tum"))
        elif method.kind == "kiss-icp":
            est = _kiss_icp(cell, method)
        elif method.kind == "open3d-rgbd":
            est = _open3d_rgbd(cell, method, processes)
        else:
            est = _opencv_mono(cell, method)
    except MissingDependencyError as err:
        return Estimate(None, status="missing", note=str(err))
    except (MarsSceneError, OSError, ValueError, RuntimeError,
            subprocess.TimeoutExpired) as err:
        return Estimate(None, status="failed", note=f"{type(err).__name__}: {err}")
    if est.trajectory is not None and len(est.trajectory):
        out_tum.parent.mkdir(parents=True, exist_ok=True)
        write_tum(out_tum, est.trajectory, header=f"{method.name} ({method.kind}) on {cell.scene}"
                  f" tau={cell.tau:g} seed={cell.seed}")
    return est
