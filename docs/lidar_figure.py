"""Figure for docs/lidar.md: KISS-ICP's trajectory against the ground truth of a run.

Usage: ``python docs/lidar_figure.py RUN_DIR OUT.png [EST.tum]`` (runs ``kiss_icp_pipeline``
on ``RUN_DIR/bag`` unless an estimate is given; needs ``pip install -e '.[bench]'
matplotlib``). Panels: the SE(3)-aligned paths, the aligned error per axis, and the error of
the estimate anchored at the first pose (how the odometry drifts from the start: a method
that stands still while the rover drives shows a ramp).
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from marsscene.benchmark.slam.kiss_icp import lidar_ground_truth, run_kiss_icp, score_lidar_odometry
from marsscene.runs.evaluation import ate
from marsscene.runs.runlog import RunLog
from marsscene.runs.tum import read_tum
from marsscene.transforms import quat_to_matrix


def main(run_dir: Path, out: Path, est_tum: Path | None = None) -> None:
    run = RunLog(run_dir)
    est = read_tum(est_tum) if est_tum else run_kiss_icp(run_dir / "bag")
    if est is None:
        raise SystemExit("KISS-ICP wrote no trajectory")
    gt = lidar_ground_truth(run)
    score = score_lidar_odometry(est, run)
    fit = ate(est, gt)
    e = est.xyz_m @ np.asarray(fit.rotation).T + fit.translation_m
    g = gt.xyz_m[np.searchsorted(gt.timestamps_s, est.timestamps_s - 1e-6)]
    fig, ax = plt.subplots(1, 3, figsize=(15, 4), gridspec_kw={"width_ratios": [1, 1.4, 1.4]})
    ax[0].plot(g[:, 0], g[:, 1], "k-", lw=2, label="ground truth (lidar_link)")
    ax[0].plot(e[:, 0], e[:, 1], "r.-", ms=2, lw=0.6, label="KISS-ICP (SE(3)-aligned)")
    ax[0].set_aspect("equal")
    ax[0].set_xlabel("x east (m)")
    ax[0].set_ylabel("y north (m)")
    ax[0].legend(fontsize=8)
    for k, name in enumerate("xyz"):
        ax[1].plot(est.timestamps_s, e[:, k] - g[:, k], lw=1, label=f"error {name}")
    ax[1].set_xlabel("time (s)")
    ax[1].set_ylabel("m")
    ax[1].legend(fontsize=8)
    ax[1].set_title("SE(3)-aligned error", fontsize=9)
    # anchored at the first pose: the estimate's motion put where the ground truth starts
    i0 = int(np.searchsorted(gt.timestamps_s, est.timestamps_s[0] - 1e-6))
    rot = quat_to_matrix(gt.quat_wxyz[i0:i0 + 1])[0] @ quat_to_matrix(est.quat_wxyz[:1])[0].T
    a = (est.xyz_m - est.xyz_m[0]) @ rot.T + g[0]
    ax[2].plot(est.timestamps_s, np.linalg.norm(a - g, axis=1), "m-", lw=1)
    ax[2].set_xlabel("time (s)")
    ax[2].set_ylabel("m")
    ax[2].set_title("error from the start (anchored at the first pose, not aligned)", fontsize=9)
    fig.suptitle(f"{run_dir.name}: ATE {score.ate_rmse_m:.2f} m ({score.ate_percent:.1f} % of "
                 f"{score.path_m:.0f} m), estimated path {score.estimated_path_m:.0f} m")
    fig.tight_layout()
    fig.savefig(out, dpi=90)


if __name__ == "__main__":
    main(Path(sys.argv[1]), Path(sys.argv[2]), Path(sys.argv[3]) if len(sys.argv) > 3 else None)
