"""``ortho-match``: the camera's ground image, projected with its depth, matched against the
orthoimage (OpenCV's masked normalised cross-correlation, ``cv2.matchTemplate`` with
``TM_CCOEFF_NORMED``) over position and heading.

Each frame's pixels with a depth return are lifted to 3-D with the pinhole intrinsics, posed in
the local frame (``local/camera/poses.tum``) and binned onto the orthoimage's pixel size:
a ground image of grey levels (the mean of the sRGB channels) over the ground the camera saw.
For each heading of a sweep around the prior's, that image is rasterised north-up and
correlated with the orthoimage around the prior; the best (heading, shift) is refined by a
parabola. The match ignores the photometric difference between a rover's view and an orbiter's
(sun, shadows, dust): NCC takes out only gain and offset, which is what the benchmark measures.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from marsscene.errors import ConfigError

__all__ = ["ground_points", "match_ortho"]


def ground_points(camera_dir: Path, max_range_m: float = 30.0) -> NDArray[np.float64]:
    """(n, 3) local x, y and grey level of every pixel with a depth return within range."""
    from marsscene.runs.runlog import read_image
    from marsscene.runs.tum import read_tum

    k = json.loads((camera_dir / "intrinsics.json").read_text(encoding="utf-8"))
    poses = read_tum(camera_dir / "poses.tum")
    out = []
    for i in range(len(poses.timestamps_s)):
        rgb = read_image(camera_dir / f"{i:06d}_rgb.png").astype(np.float64)
        depth = read_image(camera_dir / f"{i:06d}_depth.png").astype(np.float64) \
            * float(k["depth_unit_m"])
        v, u = np.nonzero((depth > 0) & (depth < max_range_m))
        z = depth[v, u]
        p = np.column_stack([(u - k["cx"]) / k["fx"] * z, (v - k["cy"]) / k["fy"] * z, z])
        rot = Rotation.from_quat(poses.quat_xyzw[i]).as_matrix()
        w = p @ rot.T + poses.xyz_m[i]
        out.append(np.column_stack([w[:, :2], rgb[v, u].mean(axis=1) / 255.0]))
    if not out or sum(len(o) for o in out) == 0:
        raise ConfigError(f"{camera_dir}: no camera pixel with a depth return")
    return np.concatenate(out)


def _raster(pts: NDArray[np.float64], yaw: float, px: float, half: int
            ) -> tuple[NDArray[np.float32], NDArray[np.uint8]]:
    c, s = math.cos(yaw), math.sin(yaw)
    x, y = c * pts[:, 0] - s * pts[:, 1], s * pts[:, 0] + c * pts[:, 1]
    col, row = np.rint(x / px).astype(np.int64) + half, np.rint(y / px).astype(np.int64) + half
    n = 2 * half + 1
    ok = (col >= 0) & (col < n) & (row >= 0) & (row < n)
    flat = row[ok] * n + col[ok]
    cnt = np.bincount(flat, minlength=n * n)
    val = np.bincount(flat, weights=pts[ok, 2], minlength=n * n) / np.maximum(cnt, 1)
    return val.reshape(n, n).astype(np.float32), (cnt >= 1).reshape(n, n).astype(np.uint8)


def _parabola(a: float, b: float, c: float) -> float:
    d = a - 2.0 * b + c
    return 0.0 if d >= 0 else float(np.clip(0.5 * (a - c) / d, -0.5, 0.5))


def match_ortho(pts: NDArray[np.float64], image: NDArray[np.floating[Any]], pixel_m: float,
                origin_xy_m: tuple[float, float], prior_xy_yaw: tuple[float, float, float], *,
                search_radius_m: float, yaw_window_deg: float, yaw_step_deg: float = 1.0,
                reach_m: float = 30.0) -> tuple[float, float, float, float]:
    """(x_m, y_m, yaw_rad, peak NCC) of the local frame that best matches ``image``."""
    import cv2

    half = math.ceil(reach_m / pixel_m)
    img = np.nan_to_num(np.asarray(image, dtype=np.float32), nan=float(np.nanmean(image)))
    r_lo = max(math.floor((prior_xy_yaw[1] - search_radius_m - origin_xy_m[1]) / pixel_m)
               - half, 0)
    c_lo = max(math.floor((prior_xy_yaw[0] - search_radius_m - origin_xy_m[0]) / pixel_m)
               - half, 0)
    span = 2 * (half + math.ceil(search_radius_m / pixel_m)) + 1
    crop = img[r_lo:r_lo + span, c_lo:c_lo + span]
    if min(crop.shape) <= 2 * half + 1:
        raise ConfigError("the orthoimage tile does not hold the search window")
    n = math.floor(yaw_window_deg / yaw_step_deg + 1e-9)
    yaws = prior_xy_yaw[2] + np.radians(yaw_step_deg * np.arange(-n, n + 1))
    surfaces = []
    for yaw in yaws:
        t, m = _raster(pts, float(yaw), pixel_m, half)
        res = cv2.matchTemplate(crop, t, cv2.TM_CCOEFF_NORMED, mask=m)
        surfaces.append(np.nan_to_num(res, nan=-1.0, posinf=-1.0, neginf=-1.0))
    stack = np.stack(surfaces)
    k, r, c = (int(v) for v in np.unravel_index(int(np.argmax(stack)), stack.shape))
    s = stack[k]
    dr = _parabola(*s[r - 1:r + 2, c]) if 0 < r < s.shape[0] - 1 else 0.0
    dc = _parabola(*s[r, c - 1:c + 2]) if 0 < c < s.shape[1] - 1 else 0.0
    per_yaw = stack.reshape(len(yaws), -1).max(axis=1)
    dk = _parabola(*per_yaw[k - 1:k + 2]) if 0 < k < len(yaws) - 1 else 0.0
    x = origin_xy_m[0] + (c_lo + c + dc + half) * pixel_m
    y = origin_xy_m[1] + (r_lo + r + dr + half) * pixel_m
    return float(x), float(y), float(yaws[k] + dk * math.radians(yaw_step_deg)), float(s[r, c])
