"""A query: the rover's short drive to a query place and the query folder a method reads.

The drive (:func:`marsscene.drive`, pure pursuit along the route's piece that ends at the
place) logs ``scans`` LiDAR scans and the camera; :func:`write_query` turns its run folder (any
run folder: the run-folder adapter) into the query folder::

    query.json           stamp, the prior (x_m, y_m, yaw_rad), the search bounds, the sensors
    prior.tum            the prior pose of the local frame in the scene (one TUM line)
    orbital/             the map tile around the prior (SCENE_DIR/orbital/ format, cropped)
    local/points.npy     every scan's points (float32 (n, 3)) in the local frame, deskewed,
                         scan after scan (query.json: lidar.points_per_scan)
    local/scan_poses.tum the LiDAR's pose at each scan stamp in the local frame
    local/camera/        NNNNNN_rgb.png, NNNNNN_depth.png (uint16 mm), poses.tum (optical
                         frame in the local frame), intrinsics.json

The **local frame** is level (z up) at the rover's ``base_link`` at the query stamp, x along its
odometry heading: what a rover knows without a global fix. Poses in it come from the wheel
odometry (x, y, yaw) and the attitude and height a rover's IMU gives (here the ground truth's
roll, pitch and z: an IMU's gravity vector fixes them to a fraction of a degree). The truth
(``truth.json``, beside the folder, never in it) is the local frame's pose in the scene.
"""

from __future__ import annotations

import json
import math
import os
import shutil
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation, Slerp

from marsscene.orbital.grid import OrbitalMap
from marsscene.orbital.io import write_orbital_map
from marsscene.runs.tum import Trajectory, read_tum

__all__ = ["OPTICAL_IN_BODY", "local_poses", "map_tile", "write_query", "yaw_of"]

#: Optical axes (x right, y down, z forward) in the camera body frame (x fwd, y left, z up).
OPTICAL_IN_BODY = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


def yaw_of(quat_xyzw: NDArray[np.float64]) -> NDArray[np.float64]:
    """Heading (rad) of TUM quaternions."""
    return Rotation.from_quat(quat_xyzw).as_euler("ZYX")[..., 0]


def _interp(traj: Trajectory, t_s: NDArray[np.float64]) -> tuple[Any, Rotation]:
    t = np.clip(t_s, traj.timestamps_s[0], traj.timestamps_s[-1])
    xyz = np.column_stack([np.interp(t, traj.timestamps_s, traj.xyz_m[:, k]) for k in range(3)])
    return xyz, Slerp(traj.timestamps_s, Rotation.from_quat(traj.quat_xyzw))(t)


def local_poses(gt: Trajectory, odom: Trajectory, t_s: NDArray[np.float64], t_query_s: float
                ) -> NDArray[np.float64]:
    """``base_link`` in the local frame at ``t_s`` ((m, 4, 4)): odometry x, y, yaw relative to
    the query's, the ground truth's roll, pitch and z (relative to the query's z)."""
    t = np.append(np.asarray(t_s, dtype=np.float64), t_query_s)
    oxyz, orot = _interp(odom, t)
    gxyz, grot = _interp(gt, t)
    oyaw = orot.as_euler("ZYX")[:, 0]
    tilt = Rotation.from_euler("Z", -grot.as_euler("ZYX")[:, :1]) * grot  # roll and pitch
    dyaw = oyaw[:-1] - oyaw[-1]
    c, s = math.cos(oyaw[-1]), math.sin(oyaw[-1])
    d = oxyz[:-1, :2] - oxyz[-1, :2]
    out = np.zeros((len(t) - 1, 4, 4))
    out[:, :3, :3] = (Rotation.from_euler("Z", dyaw[:, None]) * tilt[:-1]).as_matrix()
    out[:, 0, 3], out[:, 1, 3] = c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]
    out[:, 2, 3] = gxyz[:-1, 2] - gxyz[-1, 2]
    out[:, 3, 3] = 1.0
    return out


def _tum_lines(t_s: NDArray[np.float64], poses: NDArray[np.float64], header: str) -> str:
    q = Rotation.from_matrix(poses[:, :3, :3]).as_quat()
    rows = [f"{t:.6f} " + " ".join(f"{v:.6f}" for v in p[:3, 3]) + " "
            + " ".join(f"{v:.9f}" for v in qq) for t, p, qq in zip(t_s, poses, q, strict=True)]
    return f"# {header}\n" + "\n".join(rows) + "\n"


def map_tile(omap: OrbitalMap, cx_m: float, cy_m: float, half_m: float) -> OrbitalMap:
    """The part of ``omap`` (DTM and image) within ``half_m`` of (cx, cy), whole posts."""
    def cut(grid: Any, cell: float, origin: tuple[float, float]) -> tuple[Any, tuple[float, float]]:
        rows, cols = grid.shape
        c0 = max(math.floor((cx_m - half_m - origin[0]) / cell), 0)
        r0 = max(math.floor((cy_m - half_m - origin[1]) / cell), 0)
        c1 = min(math.ceil((cx_m + half_m - origin[0]) / cell) + 1, cols)
        r1 = min(math.ceil((cy_m + half_m - origin[1]) / cell) + 1, rows)
        return (np.ascontiguousarray(grid[r0:r1, c0:c1]),
                (origin[0] + c0 * cell, origin[1] + r0 * cell))

    dem, o = cut(omap.dem_m, omap.cell_m, omap.origin_xy_m)
    img, io = None, None
    if omap.image is not None:
        assert omap.image_pixel_m is not None and omap.image_origin_xy_m is not None
        img, io = cut(omap.image, omap.image_pixel_m, omap.image_origin_xy_m)
    from dataclasses import replace

    return replace(omap, dem_m=dem, origin_xy_m=o, image=img, image_origin_xy_m=io)


def _lidar(run_dir: Path, gt: Trajectory, odom: Trajectory, t_q: float, mount: Any
           ) -> tuple[NDArray[np.float32], list[int], NDArray[np.float64], NDArray[np.float64]]:
    """Every scan's points in the local frame (each point posed at its firing time), in scan
    order, and each scan's point count."""
    from marsscene.runs.runlog import read_ply

    stamps = np.loadtxt(run_dir / "lidar" / "stamps.csv", delimiter=",", skiprows=1,
                        usecols=0, ndmin=1)
    files = sorted((run_dir / "lidar").glob("*.ply"))
    parts = []
    for t0, f in zip(stamps, files, strict=True):
        scan = read_ply(f)
        p = np.column_stack([scan["x"], scan["y"], scan["z"]]).astype(np.float64)
        has_t = "t" in (scan.dtype.names or ())
        tp = t0 + (scan["t"].astype(np.float64) * 1e-9 if has_t else 0.0)
        m = local_poses(gt, odom, np.broadcast_to(tp, (len(p),)), t_q) @ mount
        parts.append(np.einsum("nij,nj->ni", m[:, :3, :3], p) + m[:, :3, 3])
    poses = local_poses(gt, odom, stamps, t_q) @ mount
    return np.concatenate(parts).astype(np.float32), [len(p) for p in parts], stamps, poses


def write_query(run_dir: str | os.PathLike[str], omap: OrbitalMap, query_dir: Path, *,
                prior_error: Any, radius_m: float, position_error_max_m: float,
                heading_error_max_deg: float, meta: dict[str, Any]) -> dict[str, float]:
    """Write the query folder of the drive in ``run_dir``; returns the truth (x_m, y_m, z_m,
    yaw_rad of the local frame in the scene). ``prior_error`` is a :class:`.queries.Prior`."""
    from marsscene.benchmark.slam.kiss_icp import lidar_mount
    from marsscene.rover.geometry import sensor_mounts
    from marsscene.runs.runlog import run_rover

    run = Path(run_dir)
    gt, odom = read_tum(run / "gt.tum"), read_tum(run / "odom.tum")
    rover = run_rover(json.loads((run / "run.json").read_text(encoding="utf-8")))
    t_q = float(gt.timestamps_s[-1])
    g_xyz, g_rot = _interp(gt, np.array([t_q]))
    truth = {"x_m": float(g_xyz[0, 0]), "y_m": float(g_xyz[0, 1]), "z_m": float(g_xyz[0, 2]),
             "yaw_rad": float(g_rot.as_euler("ZYX")[0, 0])}
    prior = (truth["x_m"] + prior_error.dx_m, truth["y_m"] + prior_error.dy_m,
             truth["yaw_rad"] + prior_error.dyaw_rad)
    local = query_dir / "local"
    local.mkdir(parents=True)
    half = position_error_max_m + radius_m + 10.0
    write_orbital_map(map_tile(omap, prior[0], prior[1], half), query_dir)
    doc: dict[str, Any] = {**meta, "stamp_s": t_q, "local_radius_m": radius_m,
                           "prior": {"x_m": prior[0], "y_m": prior[1], "yaw_rad": prior[2]},
                           "search": {"position_error_max_m": position_error_max_m,
                                      "heading_error_max_deg": heading_error_max_deg},
                           "lidar": None, "camera": None}
    if (run / "lidar" / "stamps.csv").is_file():
        pts, counts, stamps, poses = _lidar(run, gt, odom, t_q, lidar_mount(rover))
        np.save(local / "points.npy", pts)
        (local / "scan_poses.tum").write_text(_tum_lines(stamps, poses, "lidar in local frame"))
        doc["lidar"] = {"scans": len(stamps), "points": len(pts),
                        "points_per_scan": [int(n) for n in counts]}
    if (run / "camera" / "stamps.csv").is_file():
        (cx, cy, cz), pitch = sensor_mounts(rover)["camera"]
        mount = np.eye(4)
        mount[:3, :3] = Rotation.from_euler("y", pitch).as_matrix() @ OPTICAL_IN_BODY
        mount[:3, 3] = (cx, cy, cz)
        cam = local / "camera"
        cam.mkdir()
        rows = np.loadtxt(run / "camera" / "stamps.csv", delimiter=",", skiprows=1, dtype=str,
                          ndmin=2)
        stamps = rows[:, 0].astype(np.float64)
        for k, (_, rgb, depth) in enumerate(rows):
            shutil.copyfile(run / "camera" / rgb, cam / f"{k:06d}_rgb.png")
            shutil.copyfile(run / "camera" / depth, cam / f"{k:06d}_depth.png")
        poses = local_poses(gt, odom, stamps, t_q) @ mount
        (cam / "poses.tum").write_text(_tum_lines(stamps, poses, "camera optical frame in "
                                                  "local frame"))
        shutil.copyfile(run / "camera" / "intrinsics.json", cam / "intrinsics.json")
        doc["camera"] = {"frames": len(stamps)}
    (query_dir / "query.json").write_text(json.dumps(doc, indent=1, sort_keys=True) + "\n")
    q = Rotation.from_euler("Z", prior[2]).as_quat()
    (query_dir / "prior.tum").write_text(
        f"# prior pose of the local frame in the scene\n{t_q:.6f} {prior[0]:.6f} "
        f"{prior[1]:.6f} 0.000000 {q[0]:.9f} {q[1]:.9f} {q[2]:.9f} {q[3]:.9f}\n")
    return truth
