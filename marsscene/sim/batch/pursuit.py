"""Pure pursuit of every drive of a batch on the Warp device: the law, constants and goal test of
:class:`marsscene.sim.pursuit.PurePursuit` (Coulter 1992, CMU-RI-TR-92-01), one thread a drive,
in float64.

Each drive's route is a row of padded (N, L) arrays (its ``Route.xy_m`` and ``s_m``, ``length``
points); the follower's progress index and ``done`` flag stay on the device. The steps are
``PurePursuit.command``'s: the nearest route point in the forward window (``3 * lookahead + 1``
m ahead of the last one, at most half the route), the stop within ``goal_tolerance_m``
(:data:`~marsscene.sim.pursuit.STOP_RADIUS_M`) of the end by
:func:`~marsscene.sim.goal.goal_reached`'s strict test, the lookahead point, the turn in place
for a target behind, the slow-down, the bounded turn rate.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import warp as wp

from marsscene.sim.batch._kernels import _from_poses, _from_qpos
from marsscene.sim.pursuit import PursuitConfig

__all__ = ["DevicePursuit"]


class DevicePursuit:
    """The pure-pursuit followers of N routes on a Warp device.

    Parameters
    ----------
    routes : list of Route
        One a drive (world frame).
    config : PursuitConfig, optional
        The followers' (one for the batch).
    lookaheads_m : sequence of float or None, optional
        A drive's own lookahead where given (None: the config's).
    device : str
        The Warp device.
    """

    def __init__(self, routes: list[Any], config: PursuitConfig | None = None, *,
                 lookaheads_m: Any = None, device: str = "cpu") -> None:
        self.config = cfg = config if config is not None else PursuitConfig()
        n, width = len(routes), max(len(r.s_m) for r in routes)
        rx, ry, s = (np.zeros((n, width)) for _ in range(3))
        for i, r in enumerate(routes):
            m = len(r.s_m)
            rx[i, :m], ry[i, :m], s[i, :m] = r.xy_m[:, 0], r.xy_m[:, 1], r.s_m
            rx[i, m:], ry[i, m:], s[i, m:] = rx[i, m - 1], ry[i, m - 1], s[i, m - 1]
        f64 = wp.float64
        self.n, self.device = n, device
        self.route: list[Any] = [wp.array(a, dtype=f64, device=device) for a in (rx, ry, s)]
        self.length: Any = wp.array(np.array([len(r.s_m) for r in routes], np.int32), dtype=int,
                               device=device)
        self.index: Any = wp.zeros(n, dtype=int, device=device)
        self.done: Any = wp.zeros(n, dtype=int, device=device)
        rows = np.tile([cfg.lookahead_m, cfg.v_max_m_s, cfg.omega_max_rad_s,
                        cfg.goal_tolerance_m, cfg.slow_down_m], (n, 1))
        for i, look in enumerate(lookaheads_m if lookaheads_m is not None else ()):
            if look is not None:
                rows[i, 0] = float(look)
        self.cfg: Any = wp.array(rows, dtype=f64, device=device)
        self.v: Any = wp.zeros(n, dtype=f64, device=device)
        self.w: Any = wp.zeros(n, dtype=f64, device=device)

    def _tail(self) -> list[Any]:
        return [*self.route, self.length, self.index, self.done, self.cfg]

    def command(self, x_m: Any, y_m: Any, yaw_rad: Any) -> tuple[Any, Any]:
        """``(v, omega)`` (N,) float64 Warp arrays for poses given as (N,) arrays."""
        xs: list[Any] = [wp.array(np.asarray(a, np.float64), dtype=wp.float64, device=self.device)
              for a in (x_m, y_m, yaw_rad)]
        wp.launch(_from_poses, dim=self.n, inputs=[*xs, *self._tail()],
                  outputs=[self.v, self.w], device=self.device)
        return self.v, self.w

    def command_qpos(self, qpos: Any, root: int, offsets_xy_m: Any) -> tuple[Any, Any]:
        """``(v, omega)`` from the batch's ``qpos`` (N, nq) (root joint at ``root``; world
        frame = model frame minus ``offsets_xy_m`` (N, 2) float64 Warp array)."""
        wp.launch(_from_qpos, dim=self.n, inputs=[qpos, int(root), offsets_xy_m,
                                                  *self._tail()],
                  outputs=[self.v, self.w], device=self.device)
        return self.v, self.w
