"""Aerial and ground views of one place: a team's scout images paired with its rovers' navcam
frames (``crossview.csv`` in the team's folder), for cross-view localization.

Both sides are in the one map frame. A pair is a scout image and the rover frame whose rover
stood nearest the point below the scout (its ground-truth x, y at the image's stamp), when that
is within ``radius_m``: the rover is then inside the scout image's footprint (a 160 x 120 nadir
camera at 10 m sees about 14 m x 10 m). Columns::

    scout, scout_image, scout_t_s, scout_x_m, scout_y_m, scout_z_m,
    rover, rover_image, rover_t_s, rover_x_m, rover_y_m, rover_yaw_rad, distance_m

Image paths are relative to the team's folder; poses are the scout camera's (``images.tum``)
and the rover's ``base_link`` at its frame (``gt.tum``, linearly interpolated).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from marsscene._atomic import write_atomic
from marsscene.runs.runlog import RunLog
from marsscene.runs.tum import read_tum
from marsscene.transforms import yaw_of_quat

__all__ = ["HEADER", "crossview_pairs", "write_crossview"]

HEADER = ("scout,scout_image,scout_t_s,scout_x_m,scout_y_m,scout_z_m,rover,rover_image,"
          "rover_t_s,rover_x_m,rover_y_m,rover_yaw_rad,distance_m")


def _rover_frames(team_dir: Path, rover: str) -> tuple[list[str], np.ndarray] | None:
    """A rover's navcam frames (paths relative to ``team_dir``) and its base pose at each
    ((N, 4): t, x, y, yaw); None without a camera."""
    run = RunLog(team_dir / rover)
    cams = run.camera_streams()
    if not cams or len(cams[0].stamps_s) == 0:
        return None
    cam, gt = cams[0], run.gt
    t = cam.stamps_s
    xy = np.stack([np.interp(t, gt.timestamps_s, gt.xyz_m[:, k]) for k in (0, 1)], axis=1)
    idx = np.clip(np.searchsorted(gt.timestamps_s, t), 0, len(gt.timestamps_s) - 1)
    yaw = np.asarray(yaw_of_quat(gt.quat_wxyz[idx]))
    files = [str(f.relative_to(team_dir)) for f in cam.rgb_files]
    return files, np.column_stack([t, xy, yaw])


def crossview_pairs(team_dir: Path, scouts: Sequence[str], rovers: Sequence[str],
                    radius_m: float = 5.0) -> list[str]:
    """The CSV rows (module docstring) of every scout image with a rover frame within
    ``radius_m`` of the point below it; rows in scout, image order."""
    frames = {r: f for r in rovers if (f := _rover_frames(team_dir, r)) is not None}
    rows = []
    for s in scouts:
        cams = read_tum(team_dir / s / "images.tum")
        for i, (t, p) in enumerate(zip(cams.timestamps_s, cams.xyz_m, strict=True)):
            best: tuple[float, str, int] | None = None
            for rover, (_, pose) in frames.items():
                d = np.hypot(pose[:, 1] - p[0], pose[:, 2] - p[1])
                j = int(np.argmin(d))
                if d[j] <= radius_m and (best is None or d[j] < best[0]):
                    best = (float(d[j]), rover, j)
            if best is None:
                continue
            d, rover, j = best
            files, pose = frames[rover]
            rows.append(f"{s},{s}/images/{i:06d}.png,{t:.6f},{p[0]:.4f},{p[1]:.4f},{p[2]:.4f},"
                        f"{rover},{files[j]},{pose[j, 0]:.6f},{pose[j, 1]:.4f},{pose[j, 2]:.4f},"
                        f"{pose[j, 3]:.5f},{d:.4f}")
    return rows


def write_crossview(team_dir: Path, scouts: Sequence[str], rovers: Sequence[str],
                    radius_m: float = 5.0) -> int:
    """Write ``team_dir/crossview.csv``; the number of pairs."""
    rows = crossview_pairs(team_dir, scouts, rovers, radius_m)
    write_atomic(team_dir / "crossview.csv", "\n".join([HEADER, *rows]) + "\n")
    return len(rows)
