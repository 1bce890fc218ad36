"""A small OpenCV visual front end and RGB-D visual odometry, scored against ground truth.

Shi-Tomasi corners, KLT tracking with a forward-backward check, PnP-RANSAC on back-projected
depth, and the VO drift (end-point error of the composed camera motion over the camera's path
length). The camera tests judge rendered drives with it and ``perf/fidelity/bench_camera.py``
prints its figures. Needs OpenCV (the extra ``bench``), imported on first use.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from marsscene.errors import missing_dependency
from marsscene.rover.config import RoverConfig
from marsscene.transforms import quat_to_matrix

__all__ = ["VOResult", "camera_poses", "corners", "gray", "pnp_step", "rgbd_vo"]


def _cv2() -> Any:
    """OpenCV, typed ``Any`` (its stubs reject the numpy arrays passed here)."""
    try:
        import cv2
    except ImportError as err:
        raise missing_dependency("cv2", "bench") from err
    return cv2


def gray(rgb: np.ndarray) -> np.ndarray:
    """Grey image of an RGB frame (H, W, 3) uint8."""
    cv2 = _cv2()
    return cv2.cvtColor(np.ascontiguousarray(rgb), cv2.COLOR_RGB2GRAY)


def corners(img: np.ndarray, max_corners: int = 3000) -> np.ndarray:
    """Shi-Tomasi corners (N, 2) float32 (quality 0.01, min distance 5 px)."""
    pts = _cv2().goodFeaturesToTrack(gray(img), max_corners, 0.01, 5)
    return np.zeros((0, 2), np.float32) if pts is None else pts.reshape(-1, 2)


def _k(intr: dict) -> np.ndarray:
    return np.array([[intr["fx"], 0, intr["cx"]], [0, intr["fy"], intr["cy"]], [0, 0, 1.0]])


def pnp_step(
    rgb0: np.ndarray, depth0: np.ndarray, rgb1: np.ndarray, intr: dict
) -> tuple[int, np.ndarray | None]:
    """Track corners of frame 0 into frame 1; PnP-RANSAC on frame-0 depth.

    Returns (inlier count, 4x4 transform of frame-0 points into frame 1, or None).
    """
    cv2 = _cv2()
    g0, g1 = gray(rgb0), gray(rgb1)
    p0 = corners(rgb0)
    if len(p0) < 6:
        return 0, None
    p1, st, _ = cv2.calcOpticalFlowPyrLK(g0, g1, p0[:, None], None, winSize=(21, 21), maxLevel=3)
    pb, stb, _ = cv2.calcOpticalFlowPyrLK(g1, g0, p1, None, winSize=(21, 21), maxLevel=3)
    fb = np.linalg.norm(pb.reshape(-1, 2) - p0, axis=1)
    ok = (st.ravel() == 1) & (stb.ravel() == 1) & (fb < 0.5)
    u = np.clip(np.rint(p0[:, 0]).astype(int), 0, depth0.shape[1] - 1)
    v = np.clip(np.rint(p0[:, 1]).astype(int), 0, depth0.shape[0] - 1)
    z = depth0[v, u].astype(np.float64)
    ok &= (z > 0.1) & (z < 40.0)
    if ok.sum() < 6:
        return 0, None
    k = _k(intr)
    xyz = np.c_[(p0[ok, 0] - k[0, 2]) * z[ok] / k[0, 0], (p0[ok, 1] - k[1, 2]) * z[ok] / k[1, 1],
                z[ok]]
    found, rvec, tvec, inl = cv2.solvePnPRansac(
        xyz, p1.reshape(-1, 2)[ok].astype(np.float64), k, None, reprojectionError=1.0,
        iterationsCount=200, confidence=0.999, flags=cv2.SOLVEPNP_ITERATIVE)
    if not found or inl is None:
        return 0, None
    t = np.eye(4)
    t[:3, :3] = cv2.Rodrigues(rvec)[0]
    t[:3, 3] = tvec.ravel()
    return len(inl), t


def camera_poses(gt_xyz: np.ndarray, gt_quat_xyzw: np.ndarray, rover: RoverConfig,
                 tilt_deg: float = 20.0) -> np.ndarray:
    """World poses (N, 4, 4) of the navcam optical frame from base_link ground truth."""
    s, c = math.sin(math.radians(tilt_deg)), math.cos(math.radians(tilt_deg))
    x, y = np.array([0.0, -1.0, 0.0]), np.array([s, 0.0, c])
    r_mj = np.column_stack([x, y, np.cross(x, y)])
    r_opt = r_mj @ np.diag([1.0, -1.0, -1.0])
    off = np.array([0.75, 0.0, rover.mast_height_m - rover.ride_height_m])
    wxyz = np.c_[gt_quat_xyzw[:, 3], gt_quat_xyzw[:, :3]]
    rb = quat_to_matrix(wxyz)
    out = np.tile(np.eye(4), (len(gt_xyz), 1, 1))
    out[:, :3, :3] = rb @ r_opt
    out[:, :3, 3] = gt_xyz + rb @ off
    return out


@dataclass
class VOResult:
    """Figures of a frame-to-frame VO run: corners per frame, PnP inliers per consecutive
    pair, end-point drift as a fraction of the camera path, and that path's length (m)."""

    corners_per_frame: np.ndarray
    inliers_per_pair: np.ndarray
    drift_fraction: float
    path_m: float


def rgbd_vo(rgbs: list, depths: list, intr: dict, cam_world: np.ndarray) -> VOResult:
    """Frame-to-frame RGB-D VO; drift = |end-point error| / camera path length."""
    n_corners = np.array([len(corners(im)) for im in rgbs])
    pose = np.eye(4)  # camera k in camera 0
    inliers = []
    for i in range(len(rgbs) - 1):
        n, t = pnp_step(rgbs[i], depths[i], rgbs[i + 1], intr)
        inliers.append(n)
        if t is not None:
            pose = pose @ np.linalg.inv(t)
    rel_gt = np.linalg.inv(cam_world[0]) @ cam_world[-1]
    err = float(np.linalg.norm(pose[:3, 3] - rel_gt[:3, 3]))
    path = float(np.linalg.norm(np.diff(cam_world[:, :3, 3], axis=0), axis=1).sum())
    return VOResult(n_corners, np.array(inliers), err / max(path, 1e-9), path)
