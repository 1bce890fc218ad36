"""Where a teleport puts the rover down so that ``base_link`` lands where it was asked.

:func:`marsscene.rover.spawn.spawn_pose` sets ``base_link`` at the ride height along the
normal of the plane fitted under the footprint, from the spawn point's terrain, and turns the
heading into that plane; on a slope of angle a that moves x, y downhill by the ride height
times sin a (0.2 m at 15 degrees) and turns the heading a little (2 degrees). A teleport
(``SetEntityState``, ``/marsscene/teleport``, a reset to the start pose) asks for ``base_link``'s
x, y and heading, so it spawns where those come out right: a fixed point, found in a few
passes (the fitted plane hardly changes over the 0.2 m).
"""

from __future__ import annotations

import math
from typing import Any

from marsscene.rover.spawn import spawn_pose
from marsscene.transforms import yaw_of_quat

__all__ = ["spawn_point_for"]

_TOL_M, _TOL_RAD, _PASSES = 1e-5, 1e-7, 8


def spawn_point_for(hf: Any, cfg: Any, xy: tuple[float, float],
                    yaw: float) -> tuple[tuple[float, float], float]:
    """The spawn point and heading (for :func:`~marsscene.rover.spawn.spawn_pose`) that put
    ``base_link`` at ``xy`` (m) facing ``yaw`` (rad, the heading of its x axis seen from
    above).

    Parameters
    ----------
    hf : Heightfield
    cfg : RoverConfig
    xy : tuple of float
    yaw : float

    Returns
    -------
    ((x, y), yaw)

    Raises
    ------
    RuntimeSimError
        When a footprint on the way leaves the terrain (as :func:`spawn_pose`).
    """
    x, y = float(xy[0]), float(xy[1])
    sx, sy, syaw = x, y, float(yaw)
    for _ in range(_PASSES):
        pose = spawn_pose(hf, (sx, sy), syaw, cfg)
        ex, ey = x - float(pose[0]), y - float(pose[1])
        eyaw = math.remainder(float(yaw) - float(yaw_of_quat(pose[3:])), math.tau)
        if math.hypot(ex, ey) < _TOL_M and abs(eyaw) < _TOL_RAD:
            break
        sx, sy, syaw = sx + ex, sy + ey, syaw + eyaw
    return (sx, sy), syaw
