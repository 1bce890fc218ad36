"""A monocular visual-odometry baseline (OpenCV): KLT tracks, essential-matrix start,
PnP tracking and keyframe triangulation. Its scale is arbitrary, so it is scored after Sim(3)
alignment, as monocular SLAM is.

* Start: Shi-Tomasi corners of the first frame are tracked (pyramidal Lucas-Kanade) until their
  median displacement reaches ``min_parallax_px``; the essential matrix (RANSAC) and
  ``recoverPose`` give the relative pose with a unit baseline, which fixes the map's scale, and
  the inliers are triangulated into landmarks (world = the first camera frame).
* Tracking: landmarks are tracked frame to frame and the camera pose comes from
  ``solvePnPRansac``; only its inliers stay in the map.
* Mapping: new corners are detected at a keyframe and tracked; once their median displacement
  reaches ``min_parallax_px`` they are triangulated between the keyframe and the current pose.
* Loss: fewer than ``min_inliers`` PnP inliers ends tracking (no relocalisation); the frames
  after it have no pose. Frames before the start have none either.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.errors import missing_dependency

__all__ = ["MonoVOResult", "mono_vo"]


@dataclass(frozen=True)
class MonoVOResult:
    """Camera poses (N, 4, 4; camera-to-world, arbitrary scale) and which frames have one."""

    poses: NDArray[np.float64]
    tracked: NDArray[np.bool_]
    note: str = ""


def _cv() -> Any:
    try:
        import cv2
    except ImportError:
        raise missing_dependency("cv2", "bench") from None
    return cv2


def _pose(rot: NDArray[np.float64], t: NDArray[np.float64]) -> NDArray[np.float64]:
    """Camera-to-world 4x4 from a world-to-camera rotation and translation."""
    out = np.eye(4)
    out[:3, :3] = rot.T
    out[:3, 3] = -rot.T @ t.reshape(3)
    return out


def mono_vo(
    frames: Iterable[NDArray[np.uint8]], k: NDArray[np.float64], *, max_corners: int = 600,
    min_parallax_px: float = 12.0, min_inliers: int = 25, start_within: int = 50,
) -> MonoVOResult:
    """Run the monocular VO on grayscale ``frames`` (H, W) uint8 with intrinsics ``k`` (3, 3).

    Parameters
    ----------
    max_corners : int
        Corners detected per keyframe.
    min_parallax_px : float
        Median corner displacement that triggers the start and each triangulation.
    min_inliers : int
        Fewest PnP (or essential-matrix) inliers to keep tracking.
    start_within : int
        Frames within which the start must succeed, else tracking is lost.
    """
    vo = _VO(_cv(), np.asarray(k, dtype=np.float64), max_corners, min_parallax_px, min_inliers)
    poses: list[NDArray[np.float64]] = []
    tracked: list[bool] = []
    for i, img in enumerate(frames):
        if vo.prev is None:
            pose, ok = vo.first(img), True
        elif vo.state == "start":
            searching = len(vo.cand) > 0  # without corners the start is not attempted
            pose, ok = vo.start(img)
            if searching and vo.state == "start" and i >= start_within:
                vo.state, vo.note = "lost", f"no start within {start_within} frames"
        elif vo.state == "track":
            pose, ok = vo.track(img)
            if not ok:
                vo.state, vo.note = "lost", f"tracking lost at frame {i} of the run"
        else:
            pose, ok = np.full((4, 4), np.nan), False
        poses.append(pose)
        tracked.append(ok)
        vo.prev = img
    if vo.state == "start":
        vo.note = "never started (too little parallax or texture)"
    return MonoVOResult(np.array(poses).reshape(-1, 4, 4), np.array(tracked, bool), vo.note)


class _VO:
    """The tracker's state between frames: keyframe projection, candidate corners (for the
    next triangulation) and the tracked map points with their image positions."""

    def __init__(self, cv: Any, k: NDArray[np.float64], max_corners: int,
                 min_parallax_px: float, min_inliers: int) -> None:
        self.cv, self.k, self.max_corners = cv, k, max_corners
        self.min_parallax_px, self.min_inliers = min_parallax_px, min_inliers
        self.lk = {"winSize": (21, 21), "maxLevel": 3,
                   "criteria": (cv.TERM_CRITERIA_EPS | cv.TERM_CRITERIA_COUNT, 30, 0.01)}
        self.prev: NDArray[np.uint8] | None = None
        self.state, self.note = "start", ""
        self.world_xyz = np.zeros((0, 3))
        self.pts = np.zeros((0, 1, 2), np.float32)
        self.cand_kf = self.cand = np.zeros((0, 1, 2), np.float32)
        self.kf_proj = np.zeros((3, 4))

    def _parallax(self) -> float:
        if not len(self.cand):
            return 0.0
        return float(np.median(np.linalg.norm((self.cand - self.cand_kf).reshape(-1, 2),
                                              axis=1)))

    def first(self, img: NDArray[np.uint8]) -> NDArray[np.float64]:
        """The first frame: its corners, the identity pose."""
        self.cand_kf = self.cand = _detect(self.cv, img, self.max_corners, None)
        self.kf_proj = self.k @ np.eye(4)[:3]
        return np.eye(4)

    def start(self, img: NDArray[np.uint8]) -> tuple[NDArray[np.float64], bool]:
        """Two-view start once the parallax suffices (essential matrix, triangulation)."""
        cv, k, n_min = self.cv, self.k, self.min_inliers
        pose, ok = np.full((4, 4), np.nan), False
        if not len(self.cand):
            return pose, ok
        assert self.prev is not None
        self.cand_kf, self.cand = _track(cv, self.prev, img, self.cand_kf, self.cand, self.lk)
        if len(self.cand) >= n_min and self._parallax() >= self.min_parallax_px:
            e, mask = cv.findEssentialMat(self.cand_kf, self.cand, k, method=cv.RANSAC,
                                          prob=0.999, threshold=1.0)
            if e is not None and e.shape == (3, 3):
                n, rot, t, mask = cv.recoverPose(e, self.cand_kf, self.cand, k, mask=mask)
                if n >= n_min:
                    cur_proj = k @ np.hstack([rot, t.reshape(3, 1)])
                    self.world_xyz, self.pts = _triangulate(
                        cv, self.kf_proj, cur_proj, self.cand_kf, self.cand, mask.ravel() > 0)
                    if len(self.world_xyz) >= n_min:
                        pose, ok, self.state = _pose(rot, t), True, "track"
                        self.kf_proj = cur_proj
                        self.cand_kf = self.cand = _detect(cv, img, self.max_corners, self.pts)
        return pose, ok

    def track(self, img: NDArray[np.uint8]) -> tuple[NDArray[np.float64], bool]:
        """PnP on the tracked map points; new points triangulated at enough parallax."""
        cv, k, n_min = self.cv, self.k, self.min_inliers
        pose, ok = np.full((4, 4), np.nan), False
        nxt, st, _ = cv.calcOpticalFlowPyrLK(self.prev, img, self.pts, None, **self.lk)
        good = st.ravel() == 1
        self.world_xyz, nxt = self.world_xyz[good], nxt[good]
        if len(nxt) < n_min:
            return pose, ok
        found, rvec, tvec, inl = cv.solvePnPRansac(
            self.world_xyz, nxt, k, None, reprojectionError=2.0, iterationsCount=100,
            confidence=0.999, flags=cv.SOLVEPNP_ITERATIVE)
        if not (found and inl is not None and len(inl) >= n_min):
            return pose, ok
        idx = inl.ravel()
        self.world_xyz, self.pts = self.world_xyz[idx], nxt[idx]
        rot = cv.Rodrigues(rvec)[0]
        pose, ok = _pose(rot, tvec), True
        cur_proj = k @ np.hstack([rot, tvec.reshape(3, 1)])
        assert self.prev is not None
        self.cand_kf, self.cand = _track(cv, self.prev, img, self.cand_kf, self.cand, self.lk)
        if self._parallax() >= self.min_parallax_px or len(self.cand) < n_min:
            new_xyz, new_pts = _triangulate(cv, self.kf_proj, cur_proj, self.cand_kf,
                                            self.cand, np.ones(len(self.cand), bool))
            self.world_xyz = np.vstack([self.world_xyz, new_xyz])
            self.pts = np.concatenate([self.pts, new_pts]).astype(np.float32)
            self.kf_proj = cur_proj
            self.cand_kf = self.cand = _detect(cv, img, self.max_corners, self.pts)
        return pose, ok


def _detect(cv: Any, img: NDArray[np.uint8], n: int,
            avoid: NDArray[np.float32] | None) -> NDArray[np.float32]:
    mask = np.full(img.shape[:2], 255, np.uint8)
    if avoid is not None and len(avoid):
        for x, y in avoid.reshape(-1, 2).astype(int):
            cv.circle(mask, (int(x), int(y)), 8, 0, -1)
    found = cv.goodFeaturesToTrack(img, n, 0.01, 8, mask=mask)
    return (found if found is not None else np.zeros((0, 1, 2))).astype(np.float32)


def _track(cv: Any, prev: NDArray[np.uint8], img: NDArray[np.uint8],
           kf: NDArray[np.float32], cur: NDArray[np.float32], lk: dict[str, object]
           ) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
    if not len(cur):
        return kf, cur
    nxt, st, _ = cv.calcOpticalFlowPyrLK(prev, img, cur, None, **lk)
    good = st.ravel() == 1
    return kf[good], nxt[good]


def _triangulate(cv: Any, p0: NDArray[np.float64], p1: NDArray[np.float64],
                 a: NDArray[np.float32], b: NDArray[np.float32], keep: NDArray[np.bool_]
                 ) -> tuple[NDArray[np.float64], NDArray[np.float32]]:
    """World points seen at ``a`` (projection ``p0``) and ``b`` (``p1``), in front of both
    cameras and reprojecting within 2 px; with their image points in the second view."""
    a2, b2 = a.reshape(-1, 2)[keep], b.reshape(-1, 2)[keep]
    if len(a2) == 0:
        return np.zeros((0, 3)), np.zeros((0, 1, 2), np.float32)
    h = cv.triangulatePoints(p0, p1, a2.T.astype(np.float64), b2.T.astype(np.float64))
    xyz = (h[:3] / np.where(np.abs(h[3]) > 1e-12, h[3], 1e-12)).T
    hom = np.column_stack([xyz, np.ones(len(xyz))])
    good = np.ones(len(xyz), bool)
    for proj, obs in ((p0, a2), (p1, b2)):
        uvw = hom @ proj.T
        good &= uvw[:, 2] > 1e-6
        uv = uvw[:, :2] / np.where(good, uvw[:, 2], 1.0)[:, None]
        good &= np.linalg.norm(uv - obs, axis=1) < 2.0
    return xyz[good], b2[good].reshape(-1, 1, 2).astype(np.float32)
