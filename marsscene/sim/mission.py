"""Set up a drive the way ``marsscene drive`` and sweeps do: route, rock corridor, start pose.

One function, :func:`prepare_drive`, shared by the command line and
:func:`marsscene.sweep.drive.drive_cell`, so both drive a scene identically.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from marsscene.errors import RuntimeSimError
from marsscene.rover.config import RunConfig
from marsscene.sim.route import Route, author_route

__all__ = ["prepare_drive"]


def _check_inside(route: Route, hf: Any) -> None:
    inside = hf.contains(route.xy_m[:, 0], route.xy_m[:, 1])
    if not inside.all():
        i = int((~inside).argmax())
        x0, y0, x1, y1 = hf.bounds_xy_m
        raise RuntimeSimError(
            f"route point {i} ({route.xy_m[i, 0]:.2f}, {route.xy_m[i, 1]:.2f}) m is "
            f"outside the terrain x [{x0:.2f}, {x1:.2f}], y [{y0:.2f}, {y1:.2f}] m"
        )


def prepare_drive(
    scene_dir: str | Path,
    run: RunConfig,
    *,
    route: Route | None = None,
    waypoints_xy_m: ArrayLike | None = None,
    max_slope_deg: float = 20.0,
    corridor_m: float = 15.0,
    settle_s: float = 3.0,
) -> tuple[Any, Route]:
    """Load a scene for a drive and place the rover at the start of its route.

    Parameters
    ----------
    scene_dir : path
        A built scene folder (``mjcf/scene.xml``).
    run : RunConfig
        Sensors and noise.
    route, waypoints_xy_m
        Exactly one: a route to follow, or waypoints (N, 2) through which a smooth route
        avoiding slopes above ``max_slope_deg`` and rocks is authored.
    corridor_m : float
        Only the MJCF rocks within this distance of the route are simulated, widened to the
        LiDAR range and half the camera's terrain window when those sensors are on.
    settle_s : float
        Settling time of the rover at the start pose (its wheels on the ground).

    Returns
    -------
    sim : RoverSim
        Reset at the route's start, facing along it.
    route : Route
    """
    from marsscene.sim.rover_sim import RoverSim, scene_obstacles

    if (route is None) == (waypoints_xy_m is None):
        raise RuntimeSimError("give exactly one of a route or waypoints")
    sim = RoverSim(scene_dir, run=run, settle_s=0.0)
    if route is not None:
        _check_inside(route, sim.heightfield)
    else:
        route = author_route(np.asarray(waypoints_xy_m, dtype=np.float64), sim.heightfield,
                             max_slope_deg=max_slope_deg, obstacles=scene_obstacles(sim))
    if sim.rocks_kept[1]:  # simulate only the rocks the rover can meet or sense
        if run.lidar is not None:
            corridor_m = max(corridor_m, run.lidar.spec.range_m[1])
        if run.camera is not None:
            corridor_m = max(corridor_m, run.camera.terrain_window_m / 2.0)
        sim = RoverSim(scene_dir, run=run, settle_s=0.0, contact_corridor_xy_m=route.xy_m,
                       contact_corridor_m=corridor_m)
    a, b = route.xy_m[0], route.xy_m[min(5, len(route.xy_m) - 1)]
    sim.settle_s = settle_s
    sim.reset(xy_m=(float(a[0]), float(a[1])), yaw_rad=math.atan2(b[1] - a[1], b[0] - a[0]))
    return sim, route
