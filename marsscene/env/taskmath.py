"""The navigation task's arithmetic, once, for one rover or thousands: numpy or PyTorch arrays
of any batch shape (the Python array API through ``array_api_compat``).

:class:`~marsscene.env.nav.RoverNavEnv` (MuJoCo on a CPU core) calls these functions on arrays
of one rover; :class:`~marsscene.env.batch.BatchNavEnv` (MuJoCo Warp) on (N,) batches, PyTorch
tensors on the GPU. Each takes the state the task reads -- the ``base_link`` position and yaw,
the wheels, the IMU, the goal -- and returns arrays of the same batch shape:

- :func:`observation_vector`: the 17 values of ``observation`` (layout in :mod:`.observe`);
- :func:`scan_heights`: a height scan sampled from one terrain grid, or from a stack of them;
- :func:`failure_code` and :class:`StuckClock`: why an episode ends (the codes of
  :data:`~marsscene.env.terms.TERMINATIONS`).

The reward terms are :mod:`.terms`' table; :mod:`.judgement` judges a step with both.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from array_api_compat import device

from marsscene._xp import clip, namespace
from marsscene.env.terms import FAILURES, GOAL

__all__ = ["StuckClock", "bearing_rad", "failure_code", "goal_in_body", "height_scan",
           "observation_vector", "scan_grid_m", "scan_heights", "up_z"]


def up_z(q_wxyz: Any) -> Any:
    """The z component of the body's up axis in the world (the cosine of its tilt);
    ``q_wxyz`` (..., 4)."""
    x, y = q_wxyz[..., 1], q_wxyz[..., 2]
    return 1.0 - 2.0 * (x * x + y * y)


def goal_in_body(xy_m: Any, yaw_rad: Any, goal_xy_m: Any) -> Any:
    """The goal in the body frame: (..., 5) of x forward, y left (m), distance (m), and the sine
    and cosine of its bearing."""
    xp = namespace(xy_m, goal_xy_m)
    dx, dy = goal_xy_m[..., 0] - xy_m[..., 0], goal_xy_m[..., 1] - xy_m[..., 1]
    c, s = xp.cos(yaw_rad), xp.sin(yaw_rad)
    gx, gy = c * dx + s * dy, -s * dx + c * dy
    bearing = xp.atan2(gy, gx)
    return xp.stack([gx, gy, xp.hypot(gx, gy), xp.sin(bearing), xp.cos(bearing)], axis=-1)


def observation_vector(xy_m: Any, yaw_rad: Any, goal_xy_m: Any, twist: Any, accel_m_s2: Any,
                       gyro_rad_s: Any, last_action: Any) -> Any:
    """The ``observation`` vector, (..., 17) float32: the goal in the body frame, the body twist
    ``(v, omega)`` from the wheels, roll and pitch from the accelerometer, the IMU sample and the
    last (normalised) action."""
    xp = namespace(xy_m, accel_m_s2)
    ax, ay, az = accel_m_s2[..., 0], accel_m_s2[..., 1], accel_m_s2[..., 2]
    roll = xp.atan2(ay, az)
    pitch = xp.atan2(-ax, xp.hypot(ay, az))
    parts = [goal_in_body(xy_m, yaw_rad, goal_xy_m), twist, roll[..., None], pitch[..., None],
             accel_m_s2, gyro_rad_s, last_action]
    return xp.astype(xp.concat([xp.astype(p, xp.float64) for p in parts], axis=-1), xp.float32)


def scan_grid_m(scan: Any) -> tuple[Any, Any]:
    """The (forward, left) offsets (m) of a :class:`~marsscene.env.observe.HeightScan`'s
    points, each (n, n) numpy float64: rows run forward (far first), columns left (left first),
    an image seen from above."""
    n = scan.points
    u = (np.arange(n) - (n - 1) / 2.0) * scan.resolution_m
    fwd, left = np.meshgrid(u[::-1], u[::-1], indexing="ij")
    return fwd, left


def height_scan(grid_z_m: Any, origin_xy_m: Any, cell_m: float, xyz_m: Any, yaw_rad: Any,
                fwd_m: Any, left_m: Any, world: Any = None) -> Any:
    """Height scans (..., n, n) float32: the terrain under the points ``fwd_m``, ``left_m``
    (n, n) around each rover in its heading frame, relative to its ``base_link`` height
    (``xyz_m`` (..., 3)); the grids as :func:`scan_heights` takes them."""
    xp = namespace(xyz_m)
    c, s = xp.cos(yaw_rad)[..., None, None], xp.sin(yaw_rad)[..., None, None]
    x0, y0 = xyz_m[..., 0, None, None], xyz_m[..., 1, None, None]
    x = x0 + c * fwd_m - s * left_m
    y = y0 + s * fwd_m + c * left_m
    z = scan_heights(grid_z_m, origin_xy_m, cell_m, x, y, world)
    return xp.astype(z - xyz_m[..., 2, None, None], xp.float32)


def bearing_rad(xy_m: Any, goal_xy_m: Any, yaw_rad: Any) -> Any:
    """The goal's bearing from the heading (rad, in [-pi, pi))."""
    xp = namespace(xy_m, goal_xy_m)
    ang = xp.atan2(goal_xy_m[..., 1] - xy_m[..., 1], goal_xy_m[..., 0] - xy_m[..., 0]) - yaw_rad
    return (ang + math.pi) % (2.0 * math.pi) - math.pi


def scan_heights(grid_z_m: Any, origin_xy_m: Any, cell_m: float, x_m: Any, y_m: Any,
                 world: Any = None) -> Any:
    """Bilinear heights of a terrain grid at points (clamped to its footprint), float64.

    ``grid_z_m`` (rows, cols) with ``origin_xy_m`` its post (0, 0) and ``world`` None; or a
    stack (W, rows, cols) with (W, 2) origins and ``world`` (N,) the grid of each of the (N, ...)
    points. The rule is :meth:`~marsscene.terrain.heightfield.Heightfield.sample`'s.
    """
    xp = namespace(grid_z_m, x_m)
    rows, cols = grid_z_m.shape[-2], grid_z_m.shape[-1]
    if world is None:
        ox, oy, flat = origin_xy_m[0], origin_xy_m[1], xp.reshape(grid_z_m, (-1,))
    else:
        extra = (None,) * (x_m.ndim - 1)
        ox = origin_xy_m[world, 0][(..., *extra)]
        oy = origin_xy_m[world, 1][(..., *extra)]
        flat = xp.reshape(grid_z_m, (grid_z_m.shape[0], -1))
    r = clip(xp, (y_m - oy) / cell_m, 0.0, rows - 1.0)
    c = clip(xp, (x_m - ox) / cell_m, 0.0, cols - 1.0)
    r0 = clip(xp, xp.astype(xp.floor(r), xp.int64), None, rows - 2)
    c0 = clip(xp, xp.astype(xp.floor(c), xp.int64), None, cols - 2)
    fr, fc = r - xp.astype(r0, r.dtype), c - xp.astype(c0, c.dtype)
    i = r0 * cols + c0
    at = (lambda k: flat[i + k]) if world is None else (
        lambda k: flat[world[(..., *((None,) * (i.ndim - 1)))], i + k])
    z = [xp.astype(at(k), xp.float64) for k in (0, 1, cols, cols + 1)]
    return (z[0] * (1 - fc) + z[1] * fc) * (1 - fr) + (z[2] * (1 - fc) + z[3] * fc) * fr


def failure_code(q_wxyz: Any, xy_m: Any, bounds_xy_m: Any, start_xy_m: Any, goal_xy_m: Any,
                 stuck: Any, task: Any) -> Any:
    """Why each episode fails at this step: 0 none, else the termination code
    (:data:`~marsscene.env.terms.TERMINATIONS`: ``2 +`` the index in
    :data:`~marsscene.env.terms.FAILURES`) of the first failure judged. ``bounds_xy_m``
    (..., 4) is ``x0, y0, x1, y1`` of each terrain."""
    xp = namespace(xy_m)
    x, y = xy_m[..., 0], xy_m[..., 1]
    margin = xp.minimum(xp.minimum(x - bounds_xy_m[..., 0], bounds_xy_m[..., 2] - x),
                        xp.minimum(y - bounds_xy_m[..., 1], bounds_xy_m[..., 3] - y))
    seg = goal_xy_m - start_xy_m
    rel = xy_m - start_xy_m
    seg2 = xp.sum(seg * seg, axis=-1)
    s = clip(xp, xp.sum(rel * seg, axis=-1) / clip(xp, seg2, 1e-9, None), 0.0, 1.0)
    off = rel - s[..., None] * seg
    failed = [up_z(q_wxyz) < math.cos(math.radians(task.max_tilt_deg)),
              margin < task.edge_m,
              xp.hypot(off[..., 0], off[..., 1]) > task.max_stray_m,
              stuck]
    assert len(failed) == len(FAILURES)
    code = xp.zeros(x.shape, dtype=xp.int64, device=device(x))
    for k in range(len(failed) - 1, -1, -1):  # the first failure judged wins
        code = xp.where(failed[k], xp.ones_like(code) * (GOAL + 1 + k), code)
    return code


class StuckClock:
    """Whether rovers commanding motion moved less than ``min_m`` over the last ``window``
    control steps (the task's ``stuck_s`` at the control rate); a step without commanded motion
    restarts the clock. Holds the last ``window + 1`` positions of each rover.

    Parameters
    ----------
    like : array
        An array of the backend and device to use.
    shape : tuple of int
        The batch shape (``()`` for one rover).
    window : int
        Control steps in ``stuck_s``.
    min_m : float
        The distance that counts as moving (``stuck_m``).
    """

    def __init__(self, like: Any, shape: tuple[int, ...], window: int, min_m: float) -> None:
        xp = self.xp = namespace(like)
        dev = device(like)
        self.window, self.min_m, self.head = int(window), float(min_m), 0
        self.track = xp.zeros((self.window + 1, *shape, 2), dtype=xp.float64, device=dev)
        self.run = xp.zeros(shape, dtype=xp.int64, device=dev)

    def restart(self, where: Any = True) -> None:
        """Restart the clock of the rovers in ``where`` (all by default)."""
        self.run = self.xp.where(where, self.run * 0, self.run)

    def __call__(self, xy_m: Any, moving: Any) -> Any:
        """Record this step's positions (..., 2); True where a rover is stuck."""
        xp = self.xp
        self.run = xp.where(moving, self.run + 1, self.run * 0)
        self.track[self.head, ...] = xy_m
        self.head = (self.head + 1) % (self.window + 1)
        then = self.track[self.head, ...]  # ``window`` steps ago
        moved = xp.hypot(xy_m[..., 0] - then[..., 0], xy_m[..., 1] - then[..., 1])
        return (self.run > self.window) & (moved < self.min_m)
