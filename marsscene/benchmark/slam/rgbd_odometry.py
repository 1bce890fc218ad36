"""RGB-D odometry baselines with Open3D: frame to frame, plain or with the wheel odometry.

Both run Open3D's ``compute_rgbd_odometry`` (Steinbrücker et al. 2011 photometric term plus
Park et al. 2017 depth term, ``RGBDOdometryJacobianFromHybridTerm``) from each frame to the
next on the TUM RGB-D export and chain the steps.

* ``open3d-rgbd`` (plain): every pair starts from the identity; a pair Open3D reports as failed
  keeps the previous step (constant velocity).
* ``open3d-rgbd`` with ``options.wheel_prior = true``: the rover's odometry, what RTAB-Map
  receives as ``odom_topic`` in the paper's RGB-D + wheel-odometry setup, gives each pair's
  **initial guess**, the camera's motion between the two frames, and its **fallback**: where
  Open3D fails, or its step departs from the odometry's by more than ``max_step_dev_m``
  (translation) or ``max_step_dev_deg`` (rotation), the odometry's step is used. Tracked frames
  are those whose visual step was kept. The odometry is the LiDAR baseline's prior
  (:mod:`.odometry_prior`): the travel from the wheels (``odom.tum``, planar, from the wheel
  rates and steering) and the rotation from the gyro (``imu.csv``), so a fallback across a
  crater rim keeps the rover's tilt change; ``options.gyro = false`` takes the rotation from
  the planar wheel odometry too.

``decimate = 2`` runs on images halved in each direction (colour and depth averaged over 2 x 2
pixels, a block with a missing depth has none; intrinsics halved): a quarter of the pixels,
about a quarter of the time.

With a ``checkpoint`` file the chained poses so far are saved every ``checkpoint_every``
pairs (whole or not at all), and a call with the same file and key continues from them: a
benchmark stopped during a 13,000-frame cell loses at most that many pairs of work. The file
is removed once the last pair is done.

Open3D's result is not bit-reproducible run to run: the same pair gives transforms that
differ by ~1e-14 between calls, with one OpenMP thread too (``OMP_NUM_THREADS=1``; no setting
of the Python API removes it), and over thousands of pairs the rare pair near a convergence
or success threshold then ends differently (1.049 vs 1.054 m ATE on one cell's data). Every
other baseline of the benchmark is deterministic.
"""

from __future__ import annotations

import io
import json
import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene._atomic import write_atomic
from marsscene.errors import RuntimeSimError, missing_dependency
from marsscene.runs.runlog import RunLog, read_image

__all__ = ["RgbdOdometry", "rgbd_odometry", "step_deviation", "wheel_camera_steps"]

log = logging.getLogger("marsscene")


@dataclass(frozen=True)
class RgbdOdometry:
    """Camera-to-world poses (N, 4, 4) at ``stamps_s`` (N,); ``visual[k]``: frame k's pose
    came from a kept visual step (frame 0: True)."""

    stamps_s: NDArray[np.float64]
    poses: NDArray[np.float64]
    visual: NDArray[np.bool_]

    @property
    def fallbacks(self) -> int:
        """Pairs whose step was not Open3D's (failed, or departing from the wheel prior)."""
        return int((~self.visual[1:]).sum())


def _associations(folder: Path) -> list[list[str]]:
    text = (folder / "associations.txt").read_text(encoding="utf-8")
    return [ln.split() for ln in text.splitlines() if ln.strip() and not ln.startswith("#")]


def wheel_camera_steps(run_dir: Path, stamps_s: NDArray[np.float64], *,
                       gyro: bool = True) -> NDArray[np.float64]:
    """The navcam's motion between consecutive frames from the rover's odometry: (N - 1, 4, 4),
    the pose of frame k in the optical frame of frame k - 1 (the wheels' travel and the gyro's
    rotation, or with ``gyro=False`` the planar ``odom.tum`` alone, at the frames' stamps,
    composed with the navcam's mount)."""
    from marsscene.benchmark.slam.odometry_prior import stored_steps
    from marsscene.runs.export.frames import camera_frame, frame_in_base, static_transforms

    run = RunLog(run_dir)
    odom = run.odom
    idx = np.clip(np.searchsorted(odom.timestamps_s, stamps_s - 1e-6), 0, len(odom) - 1)
    if np.abs(odom.timestamps_s[idx] - stamps_s).max(initial=0.0) > 0.011:
        raise RuntimeSimError(f"{run_dir}: odom.tum has no pose at some camera frames")
    name = run.camera_streams()[0].name
    mount = frame_in_base(static_transforms(run.rover, {}), camera_frame(name))
    return stored_steps(run, stamps_s, mount, gyro=gyro)


def step_deviation(a: NDArray[np.float64], b: NDArray[np.float64]) -> tuple[float, float]:
    """Translation (m) and rotation (deg) between two rigid steps."""
    d = np.linalg.inv(a) @ b
    cos = np.clip((np.trace(d[:3, :3]) - 1.0) / 2.0, -1.0, 1.0)
    return float(np.linalg.norm(a[:3, 3] - b[:3, 3])), float(np.degrees(np.arccos(cos)))


def _halve(img: NDArray[Any], times: int) -> NDArray[Any]:
    """``img`` averaged over blocks of ``2 ** times`` pixels a side (depth: 0 where any is)."""
    for _ in range(times):
        h, w = img.shape[0] // 2 * 2, img.shape[1] // 2 * 2
        blocks = img[:h, :w].reshape(h // 2, 2, w // 2, 2, *img.shape[2:]).astype(np.float64)
        mean = blocks.mean(axis=(1, 3))
        if img.ndim == 2:  # depth: a block with a missing return has none
            mean = np.where((blocks > 0).all(axis=(1, 3)), mean, 0.0)
        img = np.rint(mean).astype(img.dtype)
    return img


def _save_checkpoint(path: Path, key: str, n_rows: int, poses: list[NDArray[Any]],
                     visual: list[bool], step: NDArray[Any]) -> None:
    buf = io.BytesIO()
    np.savez(buf, key=np.array(key), n_rows=np.array(n_rows), poses=np.array(poses),
             visual=np.array(visual), step=step)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_atomic(path, buf.getvalue())


def _load_checkpoint(path: Path, key: str, n_rows: int) -> dict[str, NDArray[Any]] | None:
    """The saved poses, visual flags and last step, if ``path`` holds this key's run."""
    try:
        with np.load(path, allow_pickle=False) as z:
            saved = {k: z[k] for k in ("key", "n_rows", "poses", "visual", "step")}
    except (OSError, ValueError, KeyError):
        return None  # none yet, or not one of ours: start over
    if str(saved["key"]) != key or int(saved["n_rows"]) != n_rows \
            or not 1 <= len(saved["poses"]) <= n_rows:
        return None
    return saved


def _frame_reader(o3d: Any, folder: Path, halvings: int, depth_trunc_m: float) -> Any:
    """A function from an associations row to Open3D's RGB-D image (halved ``halvings``
    times)."""
    from marsscene.runs.export.datasets import tum_depth_per_m

    depth_scale = tum_depth_per_m(folder)

    def frame(row: list[str]) -> Any:
        rgb = np.ascontiguousarray(_halve(read_image(folder / row[1])[..., :3], halvings))
        depth = np.ascontiguousarray(_halve(read_image(folder / row[3]).astype(np.uint16),
                                            halvings))
        image: Any = o3d.geometry.Image
        return o3d.geometry.RGBDImage.create_from_color_and_depth(
            image(rgb), image(depth), depth_scale=depth_scale, depth_trunc=depth_trunc_m,
            convert_rgb_to_intensity=True)

    return frame


def _start(checkpoint: Path | None, key: str, n_rows: int
           ) -> tuple[list[NDArray[Any]], list[bool], NDArray[Any]]:
    """Poses, visual flags and last step to start from: the checkpoint's, or the first
    frame's."""
    saved = None if checkpoint is None else _load_checkpoint(checkpoint, key, n_rows)
    if saved is None:
        return [np.eye(4)], [True], np.eye(4)
    log.info("open3d-rgbd: continuing from frame %d of %d (%s)", len(saved["poses"]), n_rows,
             checkpoint)
    return list(saved["poses"]), [bool(v) for v in saved["visual"]], saved["step"]


def rgbd_odometry(folder: Path, run_dir: Path, *, depth_trunc_m: float = 12.0,
                  wheel_prior: bool = False, max_step_dev_m: float = 0.02,
                  max_step_dev_deg: float = 1.0, gyro: bool = True, decimate: int = 1,
                  checkpoint: Path | None = None, checkpoint_key: str = "",
                  checkpoint_every: int = 500) -> RgbdOdometry:
    """Frame-to-frame Open3D RGB-D odometry over a TUM RGB-D folder (module doc).

    Parameters
    ----------
    folder : Path
        The TUM RGB-D export (its depth scale from ``orbslam3_rgbd.yaml``).
    run_dir : Path
        The run folder (intrinsics; ``odom.tum`` and ``imu.csv`` for the wheel prior).
    depth_trunc_m : float
        Depth beyond this is ignored (m).
    wheel_prior : bool
        Start each pair from the odometry's step and fall back to it (module doc).
    max_step_dev_m, max_step_dev_deg : float
        With ``wheel_prior``: largest departure of a visual step from the wheel step that is
        kept (m, deg).
    gyro : bool
        With ``wheel_prior``: the odometry's rotation from the gyro (False: the planar wheel
        odometry's).
    decimate : {1, 2, 4}
        Image size divisor (module doc).
    checkpoint : Path, optional
        File that holds the poses so far, saved every ``checkpoint_every`` pairs; a call whose
        ``checkpoint_key`` matches the saved one continues from it (module doc).
    checkpoint_key : str
        What the saved poses were computed from (the caller's digest of inputs and options).
    checkpoint_every : int
        Pairs between two saves.
    """
    if decimate not in (1, 2, 4):
        raise RuntimeSimError(f"open3d-rgbd decimate = {decimate!r}; expected 1, 2 or 4")
    halvings = {1: 0, 2: 1, 4: 2}[decimate]
    try:
        import open3d as o3d
    except ImportError:
        raise missing_dependency("open3d", "bench") from None
    rows = _associations(folder)
    i = json.loads((run_dir / "camera" / "intrinsics.json").read_text(encoding="utf-8"))
    d = float(decimate)
    pin = o3d.camera.PinholeCameraIntrinsic(int(i["width"]) // decimate,
                                            int(i["height"]) // decimate, i["fx"] / d,
                                            i["fy"] / d, i["cx"] / d, i["cy"] / d)
    odo = o3d.pipelines.odometry
    stamps = np.array([float(r[0]) for r in rows])
    prior = wheel_camera_steps(run_dir, stamps, gyro=gyro) if wheel_prior else None
    frame = _frame_reader(o3d, folder, halvings, depth_trunc_m)
    jac, opt = odo.RGBDOdometryJacobianFromHybridTerm(), odo.OdometryOption()
    poses, visual, step = _start(checkpoint, checkpoint_key, len(rows))
    pose = poses[-1]
    prev = frame(rows[len(poses) - 1])
    for k in range(len(poses) - 1, len(rows) - 1):  # T maps source (previous) points into
        cur = frame(rows[k + 1])                    # the target
        init = np.eye(4) if prior is None else np.linalg.inv(prior[k])
        success, trans, _ = odo.compute_rgbd_odometry(prev, cur, pin, init, jac, opt)
        kept = bool(success)
        if kept:
            seen = np.linalg.inv(np.asarray(trans, dtype=np.float64))
            if prior is not None:
                dev_m, dev_deg = step_deviation(prior[k], seen)
                kept = dev_m <= max_step_dev_m and dev_deg <= max_step_dev_deg
            if kept:
                step = seen
        if not kept and prior is not None:
            step = prior[k]  # plain: a failed pair keeps the last motion (constant velocity)
        pose = pose @ step
        poses.append(pose)
        visual.append(kept)
        prev = cur
        if checkpoint is not None and (k + 1) % checkpoint_every == 0 and k + 2 < len(rows):
            _save_checkpoint(checkpoint, checkpoint_key, len(rows), poses, visual, step)
            log.info("open3d-rgbd: %d of %d frames", len(poses), len(rows))
    if checkpoint is not None:
        checkpoint.unlink(missing_ok=True)
    return RgbdOdometry(stamps, np.array(poses), np.array(visual))
