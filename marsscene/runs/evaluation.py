"""Trajectory evaluation: ATE and RPE after timestamp association and Umeyama alignment.

* Association: every pose of the shorter trajectory is paired with the nearest stamp of the
  other within ``max_dt_s`` (the TUM RGB-D benchmark rule, as in ``evo``).
* Alignment: Umeyama (1991, doi:10.1109/34.88573) least-squares SE(3) (``align="se3"``) or
  Sim(3) for monocular estimates (``align="sim3"``) of the estimate onto ground truth.
* ATE: RMSE of translation differences after alignment (Sturm et al. 2012,
  doi:10.1109/IROS.2012.6385773). RPE: translation and rotation of
  ``(gt_i^-1 gt_j)^-1 (est_i^-1 est_j)`` for ``j = i + delta`` frames.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from marsscene._validate import check_choice, plain
from marsscene.errors import RuntimeSimError
from marsscene.runs.tum import Trajectory
from marsscene.transforms import quat_to_matrix

__all__ = ["ErrorStats", "associate", "ate", "rpe", "umeyama"]


@dataclass(frozen=True)
class ErrorStats:
    """Statistics of per-pose errors (in m, or deg for rotations)."""

    rmse: float
    mean: float
    median: float
    std: float
    min: float
    max: float
    n: int
    errors: NDArray[np.float64]

    @classmethod
    def of(cls, e: NDArray[np.float64]) -> ErrorStats:
        e = np.asarray(e, dtype=np.float64)
        return cls(
            float(np.sqrt(np.mean(e**2))),
            float(e.mean()),
            float(np.median(e)),
            float(e.std()),
            float(e.min()),
            float(e.max()),
            len(e),
            e,
        )

    def as_dict(self) -> dict[str, float]:
        return {k: getattr(self, k) for k in ("rmse", "mean", "median", "std", "min", "max", "n")}


def associate(
    est: Trajectory, gt: Trajectory, *, max_dt_s: float = 0.01
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Index pairs ``(i_est, i_gt)`` with ``|t_est - t_gt| <= max_dt_s`` (nearest stamp)."""
    short, long_ = (est, gt) if len(est) <= len(gt) else (gt, est)
    ts, tl = short.timestamps_s, long_.timestamps_s
    hi = np.clip(np.searchsorted(tl, ts, side="right"), 0, len(tl) - 1)
    lo = np.maximum(hi - 1, 0)
    d_hi = tl[hi] - ts
    d_lo = np.where(hi > 0, ts - tl[lo], np.inf)
    use_hi = (d_hi <= max_dt_s) & (d_hi < d_lo)
    use_lo = ~use_hi & (d_lo <= max_dt_s) & (d_lo <= np.abs(d_hi))
    inside = (ts >= tl[0] - max_dt_s) & (ts <= tl[-1] + max_dt_s)
    ok = (use_hi | use_lo) & inside
    i_short = np.flatnonzero(ok)
    i_long = np.where(use_hi, hi, lo)[ok]
    if len(i_short) == 0:
        raise RuntimeSimError(
            f"no matching timestamps between estimate ({est.timestamps_s[0]:.3f}.."
            f"{est.timestamps_s[-1]:.3f} s) and ground truth ({gt.timestamps_s[0]:.3f}.."
            f"{gt.timestamps_s[-1]:.3f} s) within max_dt_s = {max_dt_s}"
        )
    return (i_short, i_long) if short is est else (i_long, i_short)


def umeyama(
    src: NDArray[np.float64], dst: NDArray[np.float64], *, with_scale: bool = False
) -> tuple[NDArray[np.float64], NDArray[np.float64], float]:
    """Least-squares ``(R, t, s)`` minimising ``sum |dst - (s R src + t)|^2`` (Umeyama 1991).

    ``src``, ``dst`` have shape (N, 3); ``R`` is (3, 3), ``t`` (3,), ``s`` a scalar.
    """
    src = np.asarray(src, dtype=np.float64)
    dst = np.asarray(dst, dtype=np.float64)
    if src.shape != dst.shape or src.ndim != 2 or src.shape[0] < 3:
        raise RuntimeSimError(f"Umeyama alignment needs >= 3 paired points; got {src.shape}")
    mu_s, mu_d = src.mean(0), dst.mean(0)
    xs, xd = src - mu_s, dst - mu_d
    var_s = float((xs**2).sum() / len(src))
    cov = xd.T @ xs / len(src)
    u, d, vt = np.linalg.svd(cov)
    s_mat = np.eye(3)
    if np.linalg.det(u) * np.linalg.det(vt) < 0:
        s_mat[2, 2] = -1.0
    rot = u @ s_mat @ vt
    scale = float(np.trace(np.diag(d) @ s_mat) / var_s) if with_scale else 1.0
    return rot, mu_d - scale * rot @ mu_s, scale


_Paired = tuple[
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
    tuple[NDArray[np.float64], NDArray[np.float64], float],
]


def _paired(est: Trajectory, gt: Trajectory, max_dt_s: float, align: str) -> _Paired:
    check_choice("align", align, ("se3", "sim3", "none"))
    ie, ig = associate(est, gt, max_dt_s=max_dt_s)
    pe, pg = est.xyz_m[ie], gt.xyz_m[ig]
    re, rg = quat_to_matrix(est.quat_wxyz[ie]), quat_to_matrix(gt.quat_wxyz[ig])
    rot, t, s = np.eye(3), np.zeros(3), 1.0
    if align != "none":
        rot, t, s = umeyama(pe, pg, with_scale=align == "sim3")
        pe = s * pe @ rot.T + t
        re = rot @ re
    return pe, pg, re, rg, (rot, t, s)


@dataclass(frozen=True)
class ATEResult:
    """Absolute trajectory error (translation, in m) and the alignment used."""

    stats: ErrorStats
    rotation: NDArray[np.float64]
    translation_m: NDArray[np.float64]
    scale: float


def ate(
    est: Trajectory, gt: Trajectory, *, align: str = "se3", max_dt_s: float = 0.01
) -> ATEResult:
    """Absolute trajectory error of ``est`` against ``gt``.

    Poses are associated by time stamp, the estimate is aligned onto the ground truth, and the
    translation errors of the aligned poses are summarised, as ``evo_ape`` does
    (:doc:`/science/evaluation`).

    Parameters
    ----------
    est, gt : Trajectory
        Estimate and ground truth (e.g. from :func:`marsscene.runs.read_tum`, or a drive's
        ``run.gt`` and ``run.odom``).
    align : {"se3", "sim3", "none"}
        Umeyama alignment of the estimate onto ground truth (``sim3`` also fits scale).
    max_dt_s : float
        Largest stamp difference for association (in s).

    Returns
    -------
    ATEResult
        ``stats`` (``rmse``, ``mean``, ``median``, ``max``, ... in m, and the per-pose
        ``errors``), and the alignment: ``rotation`` (3, 3), ``translation_m`` (3,), ``scale``.

    Raises
    ------
    RuntimeSimError
        Too few poses associated within ``max_dt_s``.

    Examples
    --------
    A ground truth along x, and an estimate shifted by 0.5 m and with 1 cm of noise:

    >>> import numpy as np
    >>> from marsscene.runs import Trajectory, ate, rpe
    >>> t = np.arange(100) * 0.1
    >>> xyz = np.column_stack([t, np.zeros_like(t), np.zeros_like(t)])
    >>> quat = np.tile([0.0, 0.0, 0.0, 1.0], (100, 1))
    >>> gt = Trajectory(t, xyz, quat)
    >>> noise = np.random.default_rng(0).normal(0.0, 0.01, xyz.shape)
    >>> est = Trajectory(t, xyz + [0.5, 0.0, 0.0] + noise, quat)

    The alignment removes the offset, leaving the noise:

    >>> result = ate(est, gt)
    >>> bool(result.stats.rmse < 0.03), result.stats.n
    (True, 100)
    >>> round(float(result.translation_m[0]), 1)
    -0.5
    >>> round(ate(est, gt, align="none").stats.rmse, 1)
    0.5

    A run's odometry against its ground truth (a folder written by :func:`marsscene.drive`):
    ``ate(read_tum(run_dir / "odom.tum"), read_tum(run_dir / "gt.tum"))``.
    """
    pe, pg, _, _, (rot, t, s) = _paired(est, gt, max_dt_s, align)
    return ATEResult(ErrorStats.of(np.linalg.norm(pe - pg, axis=1)), rot, t, s)


@dataclass(frozen=True)
class RPEResult:
    """Relative pose error: translation (in m) and rotation (in deg) per pair."""

    translation: ErrorStats
    rotation_deg: ErrorStats
    delta_frames: int


def rpe(
    est: Trajectory,
    gt: Trajectory,
    *,
    delta_frames: int = 1,
    align: str = "none",
    max_dt_s: float = 0.01,
) -> RPEResult:
    """Relative pose error over ``delta_frames`` associated poses (drift per step).

    For each pair of associated poses ``delta_frames`` apart, the error of the estimate's
    relative motion against the ground truth's (:doc:`/science/evaluation`).

    Parameters
    ----------
    est, gt : Trajectory
        Estimate and ground truth.
    delta_frames : int
        Distance between the poses of a pair, in associated poses (>= 1).
    align : {"none", "se3", "sim3"}
        Alignment of the estimate first (a rigid one does not change the RPE).
    max_dt_s : float
        Largest stamp difference for association (in s).

    Returns
    -------
    RPEResult
        ``translation`` (in m) and ``rotation_deg`` statistics over the pairs.

    Raises
    ------
    RuntimeSimError
        ``delta_frames`` < 1, or no more associated poses than ``delta_frames``.

    Examples
    --------
    A ground truth along x, and an estimate shifted by 0.5 m and with 1 cm of noise:

    >>> import numpy as np
    >>> from marsscene.runs import Trajectory, ate, rpe
    >>> t = np.arange(100) * 0.1
    >>> xyz = np.column_stack([t, np.zeros_like(t), np.zeros_like(t)])
    >>> quat = np.tile([0.0, 0.0, 0.0, 1.0], (100, 1))
    >>> gt = Trajectory(t, xyz, quat)
    >>> noise = np.random.default_rng(0).normal(0.0, 0.01, xyz.shape)
    >>> est = Trajectory(t, xyz + [0.5, 0.0, 0.0] + noise, quat)

    A constant offset is no relative error; the noise is:

    >>> result = rpe(est, gt, delta_frames=10)
    >>> bool(result.translation.rmse < 0.03), result.translation.n
    (True, 90)
    """
    if int(delta_frames) < 1:
        raise RuntimeSimError(f"delta_frames = {plain(delta_frames)!r} must be >= 1")
    pe, pg, re, rg, _ = _paired(est, gt, max_dt_s, align)
    d = int(delta_frames)
    if len(pe) <= d:
        raise RuntimeSimError(f"RPE needs more than delta_frames = {d} associated poses")
    # relative motions: R_i^T R_j, R_i^T (p_j - p_i)
    rel_g_r = np.einsum("nji,njk->nik", rg[:-d], rg[d:])
    rel_g_t = np.einsum("nji,nj->ni", rg[:-d], pg[d:] - pg[:-d])
    rel_e_r = np.einsum("nji,njk->nik", re[:-d], re[d:])
    rel_e_t = np.einsum("nji,nj->ni", re[:-d], pe[d:] - pe[:-d])
    # E = rel_g^-1 rel_e: rotation Rg^T Re, translation Rg^T (te - tg)
    err_r = np.einsum("nji,njk->nik", rel_g_r, rel_e_r)
    err_t = np.einsum("nji,nj->ni", rel_g_r, rel_e_t - rel_g_t)
    cos = (np.trace(err_r, axis1=1, axis2=2) - 1.0) / 2.0
    axis = np.stack(
        [
            err_r[:, 2, 1] - err_r[:, 1, 2],
            err_r[:, 0, 2] - err_r[:, 2, 0],
            err_r[:, 1, 0] - err_r[:, 0, 1],
        ],
        axis=1,
    )
    angle = np.arctan2(0.5 * np.linalg.norm(axis, axis=1), cos)  # accurate near 0 and pi
    return RPEResult(
        ErrorStats.of(np.linalg.norm(err_t, axis=1)), ErrorStats.of(np.degrees(angle)), d
    )
