"""Scores of one SLAM / odometry estimate against ground truth (pure numpy).

* ATE: RMSE of positions after Umeyama alignment (SE(3), or Sim(3) for monocular methods),
  through :func:`marsscene.runs.evaluation.ate`; also as a percentage of the ground-truth path.
* RPE per distance: for every associated pose ``i``, the pose ``j`` at least ``distance_m``
  further along the ground-truth path; translation (m) and rotation (deg) error of the relative
  motion ``i -> j`` (KITTI-style drift per 10 m), after the same alignment (its scale matters
  for Sim(3)).
* Tracked fraction: the share of the method's sensor frames that got a pose.

A method that produced no usable trajectory is a :class:`SlamScore` with a status, not an
exception (:func:`failed_score`).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import NDArray

from marsscene.errors import MarsSceneError
from marsscene.runs.evaluation import associate, umeyama
from marsscene.runs.tum import Trajectory
from marsscene.transforms import quat_to_matrix

__all__ = ["STATUSES", "SlamScore", "aligned_xyz", "failed_score", "rpe_per_distance",
           "score_estimate"]

#: ``ok``; ``lost`` (too few poses, or tracked on less than the spec's minimum fraction);
#: ``failed`` (the method crashed or wrote nothing); ``missing`` (not installed / no file);
#: ``skipped`` (the cell has no data for it, e.g. no LiDAR at this tau).
STATUSES = ("ok", "lost", "failed", "missing", "skipped")

_NAN = float("nan")


@dataclass(frozen=True)
class SlamScore:
    """One method on one cell: the row of ``results.csv`` (without the cell's keys)."""

    status: str
    ate_rmse_m: float = _NAN
    ate_pct_of_path: float = _NAN
    rpe_trans_m: float = _NAN
    """RMSE of the translation error over ``rpe_distance_m`` of path (in m)."""
    rpe_rot_deg: float = _NAN
    tracked_fraction: float = 0.0
    poses: int = 0
    path_m: float = _NAN
    """Ground-truth path length (in m)."""
    scale: float = _NAN
    """Sim(3) scale of the alignment (1 for SE(3))."""
    align: str = "se3"
    note: str = ""

    def as_row(self) -> dict[str, object]:
        row = asdict(self)
        for key, value in row.items():
            if isinstance(value, float) and math.isfinite(value):
                row[key] = round(value, 6)
        return row


def failed_score(status: str, note: str, *, align: str = "se3", path_m: float = _NAN) -> SlamScore:
    """The row of a method that gave no trajectory (``note`` says why, on one line)."""
    return SlamScore(status=status, note=" ".join(note.split()), align=align, path_m=path_m)


def _along(xyz: NDArray[np.float64]) -> NDArray[np.float64]:
    seg = np.linalg.norm(np.diff(xyz, axis=0), axis=1)
    return np.concatenate([[0.0], np.cumsum(seg)])


def rpe_per_distance(
    est_xyz_m: NDArray[np.float64], est_rot: NDArray[np.float64],
    gt_xyz_m: NDArray[np.float64], gt_rot: NDArray[np.float64], distance_m: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Relative errors over ``distance_m`` of ground-truth path (paired, aligned poses).

    Parameters
    ----------
    est_xyz_m, gt_xyz_m : ndarray of shape (N, 3)
    est_rot, gt_rot : ndarray of shape (N, 3, 3)
        Paired poses (the estimate already aligned).
    distance_m : float
        Path length between the two poses of a pair.

    Returns
    -------
    trans_m, rot_deg : ndarray of shape (M,)
        One value per pair ``(i, j)``; empty when the path is shorter than ``distance_m``.
    """
    s = _along(gt_xyz_m)
    j = np.searchsorted(s, s + distance_m)
    i = np.flatnonzero(j < len(s))
    j = j[i]
    rel_g_r = np.einsum("nji,njk->nik", gt_rot[i], gt_rot[j])
    rel_g_t = np.einsum("nji,nj->ni", gt_rot[i], gt_xyz_m[j] - gt_xyz_m[i])
    rel_e_r = np.einsum("nji,njk->nik", est_rot[i], est_rot[j])
    rel_e_t = np.einsum("nji,nj->ni", est_rot[i], est_xyz_m[j] - est_xyz_m[i])
    err_r = np.einsum("nji,njk->nik", rel_g_r, rel_e_r)
    err_t = np.einsum("nji,nj->ni", rel_g_r, rel_e_t - rel_g_t)
    cos = np.clip((np.trace(err_r, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)
    return np.linalg.norm(err_t, axis=1), np.degrees(np.arccos(cos))


def score_estimate(
    est: Trajectory, gt: Trajectory, *, align: str = "se3", frames_total: int | None = None,
    frames_tracked: int | None = None, min_tracked_fraction: float = 0.5, min_poses: int = 10,
    rpe_distance_m: float = 10.0, max_dt_s: float = 0.02,
) -> SlamScore:
    """Score ``est`` against ``gt`` (both in the same body frame, any world frame).

    Parameters
    ----------
    est, gt : Trajectory
    align : {"se3", "sim3"}
        Umeyama alignment of the estimate onto ground truth (``sim3`` fits scale too).
    frames_total, frames_tracked : int, optional
        Sensor frames the method saw and the ones it tracked; default: ``len(est)`` poses
        associated with ground truth out of ``frames_total`` (or of ``len(est)``).
    min_tracked_fraction, min_poses : float, int
        Below either the status is ``lost`` (the ATE is still reported when computable).
    rpe_distance_m : float
        Path length of the RPE pairs (in m).
    max_dt_s : float
        Largest stamp difference when pairing poses (in s).
    """
    path_m = gt.path_length_m()
    if len(est) < 3:
        return failed_score("lost", f"{len(est)} pose(s)", align=align, path_m=path_m)
    try:
        ie, ig = associate(est, gt, max_dt_s=max_dt_s)
    except MarsSceneError as err:
        return failed_score("failed", str(err), align=align, path_m=path_m)
    total = max(frames_total if frames_total is not None else len(est), 1)
    tracked = frames_tracked if frames_tracked is not None else len(ie)
    fraction = min(tracked / total, 1.0)
    if len(ie) < 3:
        return failed_score("lost", f"{len(ie)} pose(s) match ground-truth stamps", align=align,
                            path_m=path_m)
    pe, pg = est.xyz_m[ie], gt.xyz_m[ig]
    rot, t, scale = umeyama(pe, pg, with_scale=align == "sim3")
    pe = scale * pe @ rot.T + t
    dist_m = np.linalg.norm(pe - pg, axis=1)
    ate_m = float(np.sqrt(np.mean(dist_m**2)))
    re = rot @ quat_to_matrix(est.quat_wxyz[ie])
    rg = quat_to_matrix(gt.quat_wxyz[ig])
    rpe_t, rpe_r = rpe_per_distance(pe, re, pg, rg, rpe_distance_m)
    lost = len(ie) < min_poses or fraction < min_tracked_fraction
    note = (f"tracked {100 * fraction:.0f} % of {total} frames" if lost else "")
    return SlamScore(
        status="lost" if lost else "ok",
        ate_rmse_m=ate_m,
        ate_pct_of_path=100.0 * ate_m / max(path_m, 1e-9),
        rpe_trans_m=float(np.sqrt(np.mean(rpe_t**2))) if len(rpe_t) else _NAN,
        rpe_rot_deg=float(np.sqrt(np.mean(rpe_r**2))) if len(rpe_r) else _NAN,
        tracked_fraction=fraction,
        poses=len(ie),
        path_m=path_m,
        scale=scale,
        align=align,
        note=note,
    )


def aligned_xyz(est: Trajectory, gt: Trajectory, *, align: str = "se3",
                max_dt_s: float = 0.02) -> NDArray[np.float64]:
    """All positions of ``est`` (N, 3) moved by its Umeyama alignment onto ``gt`` (for plots);
    ``est`` unchanged when fewer than 3 poses pair up."""
    try:
        ie, ig = associate(est, gt, max_dt_s=max_dt_s)
        rot, t, scale = umeyama(est.xyz_m[ie], gt.xyz_m[ig], with_scale=align == "sim3")
    except MarsSceneError:
        return est.xyz_m.copy()
    return scale * est.xyz_m @ rot.T + t
