"""What a navigation policy observes: a proprioceptive vector, the goal, a height scan, and on
request the navcam (RGB, depth) and a LiDAR range image.

Every array has a fixed shape (Gymnasium's shared-memory vector environments take Box and
Dict spaces only): the LiDAR is a range image of ``channels x columns`` rays with a mask of the
rays that returned.

The ``observation`` vector (float32), in order:

==========  ==========================================================================
0-1         goal in the body frame (x forward, y left), m, from the pose estimate
2           goal distance, m
3-4         sin and cos of the goal bearing in the body frame
5-6         body speed v (m/s) and yaw rate omega (rad/s) from the wheel encoders
7-8         roll and pitch (rad) from the accelerometer (gravity direction)
9-14        the latest IMU sample: specific force (m/s^2) and angular rate (rad/s)
15-16       the last action (normalised to [-1, 1])
==========  ==========================================================================
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene._validate import check_range
from marsscene.env import taskmath
from marsscene.errors import ConfigError
from marsscene.rover.config import CameraConfig, LidarConfig

__all__ = ["OBSERVATION_SIZE", "HeightScan", "ObsConfig"]

OBSERVATION_SIZE = 17


@dataclass(frozen=True, kw_only=True)
class HeightScan:
    """A square grid of terrain heights around the rover, in its heading frame (x forward),
    relative to ``base_link``: the terrain plus the scene's rocks (as domes of their footprint
    radius and exposed height). RLRoverLab's is 5 m at 0.05 m."""

    size_m: float = 5.0
    resolution_m: float = 0.1

    def __post_init__(self) -> None:
        check_range("height_scan.size_m", self.size_m, 0.5, 100.0)
        check_range("height_scan.resolution_m", self.resolution_m, 0.01, 5.0)
        if self.points > 512:
            raise ConfigError(f"height_scan: {self.points} x {self.points} points; at most "
                              "512 a side")

    @property
    def points(self) -> int:
        return round(self.size_m / self.resolution_m) + 1


@dataclass(frozen=True, kw_only=True)
class ObsConfig:
    """Which observations the environment returns.

    Parameters
    ----------
    height_scan : HeightScan, optional
        ``"height_scan"`` (N, N) float32; None: no scan.
    camera : (width, height), optional
        ``"rgb"`` (H, W, 3) uint8 from the navcam at the control rate (RL sizes: 64-128 px).
    depth : bool
        With ``camera``: also ``"depth"`` (H, W) float32 in m (0: no return).
    rgb : bool
        With ``camera`` and ``depth``: False leaves ``"rgb"`` out (a depth-only policy); the
        batched environment's camera then traces depth alone (no shading, shadow rays or
        exposure: about twice the environment steps a second).
    shadows : bool
        Sun shadows in the camera (costs ~5x the frame time on a CPU renderer).
    lidar : str, optional
        A LiDAR model (``vlp16``, ``os1-64`` ...): ``"lidar_range"`` (channels, columns) float32
        in m (0: no return) and ``"lidar_mask"`` (channels, columns) int8.
    lidar_rate_hz : float
        LiDAR revolutions per second: a scan's sweep lasts one revolution (its rays' times,
        hence its motion distortion); each observation holds a scan started at its instant.
    pose_source : {"truth", "odometry"}
        Where the goal-relative terms come from: the ground truth (as a localization system
        would provide them; RLRoverLab's choice) or the rover's own wheel odometry (it drifts,
        a few % of the distance driven: a 0.5 m goal is then often missed).
    noise_profile : str
        IMU and wheel-encoder noise profile (``none``, ``ln200s``, ``adis16495``).
    """

    height_scan: HeightScan | None = HeightScan()
    camera: tuple[int, int] | None = None
    depth: bool = False
    rgb: bool = True
    shadows: bool = False
    lidar: str | None = None
    lidar_rate_hz: float = 5.0
    pose_source: str = "truth"
    noise_profile: str = "ln200s"

    def __post_init__(self) -> None:
        if self.pose_source not in ("odometry", "truth"):
            raise ConfigError(f"pose_source = {self.pose_source!r}; use odometry or truth")
        if self.camera is not None:
            w, h = (int(v) for v in self.camera)
            if not (16 <= w <= 1024 and 16 <= h <= 1024):
                raise ConfigError(f"camera = {self.camera!r}; give (width, height) in 16..1024")
            object.__setattr__(self, "camera", (w, h))
        if self.depth and self.camera is None:
            raise ConfigError("depth = true needs camera = (width, height)")
        if not self.rgb and not self.depth:
            raise ConfigError("rgb = false needs depth = true (the camera would observe "
                              "nothing)")

    def camera_config(self, control_hz: float, size: tuple[int, int] | None = None
                      ) -> CameraConfig | None:
        """The observed camera's configuration, a frame each control step (None: no camera;
        ``size`` gives one for rendering without observing it)."""
        size = size if self.camera is None else self.camera
        if size is None:
            return None
        return CameraConfig(width_px=size[0], height_px=size[1], rate_hz=control_hz,
                            depth=self.depth, shadows=self.shadows, texture_px=1024)

    def lidar_config(self) -> LidarConfig | None:
        """The observed LiDAR's configuration (None: no LiDAR)."""
        if self.lidar is None:
            return None
        return LidarConfig(model=self.lidar, rate_hz=self.lidar_rate_hz)

    @property
    def lidar_shape(self) -> tuple[int, int] | None:
        """The LiDAR range image's (channels, columns) (None: no LiDAR)."""
        lidar = self.lidar_config()
        return None if lidar is None else (lidar.spec.channels, lidar.spec.horizontal_samples)

    def spaces(self) -> dict[str, Any]:
        """The ``gymnasium.spaces`` of each key."""
        from gymnasium import spaces

        out: dict[str, Any] = {
            "observation": spaces.Box(-np.inf, np.inf, (OBSERVATION_SIZE,), np.float32),
            "achieved_goal": spaces.Box(-np.inf, np.inf, (2,), np.float32),
            "desired_goal": spaces.Box(-np.inf, np.inf, (2,), np.float32),
        }
        if self.height_scan is not None:
            n = self.height_scan.points
            out["height_scan"] = spaces.Box(-np.inf, np.inf, (n, n), np.float32)
        if self.camera is not None:
            w, h = self.camera
            if self.rgb:
                out["rgb"] = spaces.Box(0, 255, (h, w, 3), np.uint8)
            if self.depth:
                out["depth"] = spaces.Box(0.0, np.inf, (h, w), np.float32)
        lidar_shape = self.lidar_shape
        if lidar_shape is not None:
            out["lidar_range"] = spaces.Box(0.0, np.inf, lidar_shape, np.float32)
            out["lidar_mask"] = spaces.Box(0, 1, lidar_shape, np.int8)
        return out


#: Finest grid of the rock-augmented terrain of a :class:`HeightScanner` (m), and its size cap.
_FINE_M, _MAX_CELLS = 0.05, 16_000_000


def rock_terrain(heightfield: Any, obstacles: Any) -> Any:
    """The terrain with the rocks on it, as a :class:`~marsscene.terrain.heightfield.Heightfield`
    at up to 5 cm posts: each rock a dome of its footprint radius and exposed height, raised
    over the ground (built once per world; a scan then only samples it)."""
    from marsscene.terrain.heightfield import Heightfield

    x0, y0, x1, y1 = heightfield.bounds_xy_m
    cell = max(_FINE_M, heightfield.cell_size_m / 8.0,
               math.sqrt((x1 - x0) * (y1 - y0) / _MAX_CELLS))
    cell = min(cell, heightfield.cell_size_m)
    nx, ny = int((x1 - x0) / cell) + 1, int((y1 - y0) / cell) + 1
    gx, gy = np.meshgrid(x0 + np.arange(nx) * cell, y0 + np.arange(ny) * cell)
    z = np.asarray(heightfield.sample(gx, gy), dtype=np.float32)
    r = np.asarray(obstacles.radius_m, dtype=np.float64)
    if len(r):
        k = math.ceil(r.max() / cell)
        off = np.arange(-k, k + 1)
        ci = np.rint((obstacles.xy_m[:, 0] - x0) / cell).astype(np.int64)  # (n,)
        ri = np.rint((obstacles.xy_m[:, 1] - y0) / cell).astype(np.int64)
        cols = ci[:, None, None] + off[None, None, :]  # (n, 1, K)
        rows = ri[:, None, None] + off[None, :, None]  # (n, K, 1)
        dx = x0 + cols * cell - obstacles.xy_m[:, 0, None, None]
        dy = y0 + rows * cell - obstacles.xy_m[:, 1, None, None]
        frac = 1.0 - (dx * dx + dy * dy) / (r * r)[:, None, None]
        dome = np.asarray(obstacles.height_m)[:, None, None] * np.sqrt(np.clip(frac, 0, None))
        rows, cols = np.broadcast_arrays(rows, cols)
        inside = (frac > 0) & (rows >= 0) & (rows < ny) & (cols >= 0) & (cols < nx)
        lift = np.zeros_like(z)
        np.maximum.at(lift, (rows[inside], cols[inside]), dome[inside].astype(np.float32))
        z += lift
    return Heightfield(z, cell, (x0, y0))


class HeightScanner:
    """Samples a :class:`HeightScan` of one world (its terrain with the rocks on it)."""

    def __init__(self, scan: HeightScan, heightfield: Any, obstacles: Any) -> None:
        self.fwd, self.left = taskmath.scan_grid_m(scan)
        self.terrain = rock_terrain(heightfield, obstacles)

    def __call__(self, xyz_m: NDArray[np.float64], yaw_rad: float) -> NDArray[np.float32]:
        t = self.terrain
        return taskmath.height_scan(t.z_m, np.asarray(t.origin_xy_m), t.cell_size_m,
                                    np.asarray(xyz_m, dtype=np.float64), np.float64(yaw_rad),
                                    self.fwd, self.left)


def lidar_image(scan: dict[str, Any] | None, shape: tuple[int, int]
                ) -> tuple[NDArray[np.float32], NDArray[np.int8]]:
    """A scan's returns as a range image (channels, columns) and its mask."""
    channels, columns = shape
    rng = np.zeros(channels * columns, np.float32)
    mask = np.zeros(channels * columns, np.int8)
    if scan is not None and len(scan["ray"]):
        rng[scan["ray"]] = scan["range_m"]
        mask[scan["ray"]] = 1
    # rays run column by column (column * channels + beam): rows are beams
    return rng.reshape(columns, channels).T.copy(), mask.reshape(columns, channels).T.copy()
