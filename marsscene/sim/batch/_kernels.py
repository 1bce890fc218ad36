# mypy: ignore-errors
"""Warp kernels of :mod:`marsscene.sim.batch`: ``PurePursuit.command`` per thread
(:mod:`.pursuit`), the camera poses moved onto their scenes' tiles (:mod:`.loop`)."""

from __future__ import annotations

import warp as wp


@wp.func
def _search(s: wp.array2d(dtype=wp.float64), i: int, n: int, value: wp.float64) -> int:
    """``np.searchsorted(s[i, :n], value)`` (side left): the first index with s >= value."""
    lo = int(0)  # noqa: UP018, RUF046 - Warp: a variable the loop changes
    hi = n
    while lo < hi:
        mid = (lo + hi) // 2
        if s[i, mid] < value:
            lo = mid + 1
        else:
            hi = mid
    return lo


@wp.func
def _command(i: int, x: wp.float64, y: wp.float64, yaw: wp.float64,
             rx: wp.array2d(dtype=wp.float64), ry: wp.array2d(dtype=wp.float64),
             s: wp.array2d(dtype=wp.float64), length: wp.array(dtype=int),
             index: wp.array(dtype=int), done: wp.array(dtype=int),
             cfg: wp.array2d(dtype=wp.float64), v_out: wp.array(dtype=wp.float64),
             w_out: wp.array(dtype=wp.float64)) -> None:
    zero = wp.float64(0.0)
    v_out[i] = zero
    w_out[i] = zero
    if done[i] != 0:
        return
    look, v_max, w_max, tol, slow = cfg[i, 0], cfg[i, 1], cfg[i, 2], cfg[i, 3], cfg[i, 4]
    n = length[i]
    k = index[i]
    ahead = wp.min(wp.float64(3.0) * look + wp.float64(1.0), wp.float64(0.5) * s[i, n - 1])
    hi = _search(s, i, n, s[i, k] + ahead)
    last = wp.min(hi, n - 1)
    best = k
    best_d = wp.float64(1.0e300)
    for j in range(k, last + 1):
        d = wp.sqrt((rx[i, j] - x) * (rx[i, j] - x) + (ry[i, j] - y) * (ry[i, j] - y))
        if d < best_d:
            best_d = d
            best = j
    k = best
    index[i] = k
    to_go = s[i, n - 1] - s[i, k]
    gx = x - rx[i, n - 1]
    gy = y - ry[i, n - 1]
    if to_go < look and wp.sqrt(gx * gx + gy * gy) < tol:
        done[i] = 1
        return
    j = wp.min(_search(s, i, n, s[i, k] + look), n - 1)
    dx = rx[i, j] - x
    dy = ry[i, j] - y
    c = wp.cos(yaw)
    sn = wp.sin(yaw)
    bx = c * dx + sn * dy
    by = -sn * dx + c * dy
    dist = wp.sqrt(bx * bx + by * by)
    if dist < wp.float64(1.0e-6):
        return
    alpha = wp.atan2(by, bx)
    if wp.abs(alpha) > wp.float64(wp.pi) / wp.float64(2.0):  # target behind: turn in place
        w_out[i] = wp.where(alpha < zero, -w_max, w_max)
        return
    kappa = wp.float64(2.0) * wp.sin(alpha) / dist
    v = v_max
    if slow > zero:
        v = v * wp.min(wp.float64(1.0), wp.max(to_go, zero) / slow + wp.float64(0.1))
    omega = v * kappa
    if wp.abs(omega) > w_max:
        v = w_max / wp.abs(kappa)
        omega = wp.where(kappa < zero, -w_max, w_max)
    v_out[i] = wp.min(wp.max(v, zero), v_max)
    w_out[i] = wp.max(-w_max, wp.min(w_max, omega))


@wp.kernel
def _from_poses(x: wp.array(dtype=wp.float64), y: wp.array(dtype=wp.float64),
                yaw: wp.array(dtype=wp.float64), rx: wp.array2d(dtype=wp.float64),
                ry: wp.array2d(dtype=wp.float64), s: wp.array2d(dtype=wp.float64),
                length: wp.array(dtype=int), index: wp.array(dtype=int),
                done: wp.array(dtype=int), cfg: wp.array2d(dtype=wp.float64),
                v_out: wp.array(dtype=wp.float64), w_out: wp.array(dtype=wp.float64)):
    i = wp.tid()
    _command(i, x[i], y[i], yaw[i], rx, ry, s, length, index, done, cfg, v_out, w_out)


@wp.kernel
def _from_qpos(qpos: wp.array2d(dtype=float), root: int, offset: wp.array2d(dtype=wp.float64),
               rx: wp.array2d(dtype=wp.float64), ry: wp.array2d(dtype=wp.float64),
               s: wp.array2d(dtype=wp.float64), length: wp.array(dtype=int),
               index: wp.array(dtype=int), done: wp.array(dtype=int),
               cfg: wp.array2d(dtype=wp.float64), v_out: wp.array(dtype=wp.float64),
               w_out: wp.array(dtype=wp.float64)):
    i = wp.tid()
    x = wp.float64(qpos[i, root]) - offset[i, 0]
    y = wp.float64(qpos[i, root + 1]) - offset[i, 1]
    qw = wp.float64(qpos[i, root + 3])
    qx = wp.float64(qpos[i, root + 4])
    qy = wp.float64(qpos[i, root + 5])
    qz = wp.float64(qpos[i, root + 6])
    yaw = wp.atan2(wp.float64(2.0) * (qw * qz + qx * qy),
                   wp.float64(1.0) - wp.float64(2.0) * (qy * qy + qz * qz))
    _command(i, x, y, yaw, rx, ry, s, length, index, done, cfg, v_out, w_out)


@wp.kernel
def shift_cameras(cam_xpos: wp.array2d(dtype=wp.vec3), shift: wp.array(dtype=wp.vec2),
                  out: wp.array2d(dtype=wp.vec3)):
    """Camera ``c`` of drive ``i`` moved by ``shift[i]`` in x and y."""
    i, c = wp.tid()
    s = shift[i]
    out[i, c] = cam_xpos[i, c] + wp.vec3(s[0], s[1], 0.0)
