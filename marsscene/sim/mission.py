"""Set a drive up on a scene: route authoring, the rock corridor, the start pose.

:class:`DriveOptions` holds how (slope limit, corridor, settling, the follower, the start pose
of a drive without a route); :func:`prepare_drive` loads the scene and places the rover, the
first step of every drive (:func:`marsscene.drive`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from marsscene._validate import check_range, dataclass_from_mapping
from marsscene.errors import ConfigError, RuntimeSimError
from marsscene.rover.config import RoverConfig, RunConfig
from marsscene.rover.spawn import SETTLE_S
from marsscene.sim.corridor import CORRIDOR_M
from marsscene.sim.pursuit import PursuitConfig
from marsscene.sim.route import MAX_SLOPE_DEG, Route, author_route

__all__ = ["DriveOptions", "prepare_drive"]


@dataclass(frozen=True, kw_only=True)
class DriveOptions:
    """How a drive is set up on its scene.

    Parameters
    ----------
    max_slope_deg : float
        Route authoring from waypoints: the steepest slope allowed.
    corridor_m : float
        Only the MJCF rocks within this distance of the route are simulated, widened to the
        LiDAR range and half the camera's terrain window when those sensors are on (a drive
        without a route keeps every rock).
    settle_s : float
        Settling time of the rover at its start pose (wheels on the ground, brakes on).
    pursuit : PursuitConfig
        The pure-pursuit route follower (lookahead, speed and turn-rate bounds).
    start_xy_m : (float, float), optional
        Start of a drive without a route (default: the terrain centre); a route starts at its
        first point, facing along it.
    start_yaw_rad : float
        Heading of a drive without a route, counter-clockwise from east.
    route_note : str, optional
        Header line of the run's ``route.tum``; ``{length_m:.1f}`` in it is replaced by the
        route's length.
    stop_on_interrupt : bool
        Ctrl-C ends the drive as its time limit would: the run is finished, exported and
        returned (a live session's usual end), instead of raising ``DriveInterrupted``
        without exports.
    """

    max_slope_deg: float = MAX_SLOPE_DEG
    corridor_m: float = CORRIDOR_M
    settle_s: float = SETTLE_S
    pursuit: PursuitConfig = field(default_factory=PursuitConfig)
    start_xy_m: tuple[float, float] | None = None
    start_yaw_rad: float = 0.0
    route_note: str | None = None
    stop_on_interrupt: bool = False

    def __post_init__(self) -> None:
        check_range("drive.max_slope_deg", self.max_slope_deg, 0.0, 90.0, lo_open=True)
        check_range("drive.corridor_m", self.corridor_m, 1.0, 1e6)
        check_range("drive.settle_s", self.settle_s, 0.0, 60.0)
        check_range("drive.start_yaw_rad", self.start_yaw_rad)
        if self.start_xy_m is not None:
            xy = tuple(self.start_xy_m)
            if len(xy) != 2:
                raise ConfigError(f"drive.start_xy_m = {self.start_xy_m!r} must be (x, y) in m")
            for i, v in enumerate(xy):
                check_range(f"drive.start_xy_m[{i}]", v)
            object.__setattr__(self, "start_xy_m", (float(xy[0]), float(xy[1])))

    @classmethod
    def from_dict(cls, mapping: Mapping[str, Any]) -> DriveOptions:
        """From a TOML/JSON table (``pursuit`` a nested table); unknown keys are an error."""
        return dataclass_from_mapping(cls, mapping, "drive")


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
    options: DriveOptions | None = None,
    rover: RoverConfig | None = None,
) -> tuple[Any, Route | None]:
    """Load a scene for a drive and place the rover at its start.

    Parameters
    ----------
    scene_dir : path
        A built scene folder (``mjcf/scene.xml``).
    run : RunConfig
        Sensors and noise.
    route, waypoints_xy_m
        At most one: a route to follow, or waypoints (N, 2) through which a smooth route
        avoiding slopes above ``options.max_slope_deg`` and rocks is authored. With neither,
        the rover starts at ``options.start_xy_m``.
    options : DriveOptions, optional
    rover : RoverConfig, optional
        The rover type (default: the Perseverance-class :class:`RoverConfig`).

    Returns
    -------
    sim : RoverSim
        Reset at the route's start, facing along it (or at the start pose).
    route : Route or None
    """
    from marsscene.sim.rover_sim import RoverSim

    opt = options if options is not None else DriveOptions()
    if route is not None and waypoints_xy_m is not None:
        raise RuntimeSimError("give a route or waypoints, not both")
    if waypoints_xy_m is not None:  # planned on the scene alone; the rover's sim is built once
        from marsscene.sim.world import load_world

        world = load_world(scene_dir)
        route = author_route(np.asarray(waypoints_xy_m, dtype=np.float64), world.heightfield,
                             max_slope_deg=opt.max_slope_deg, obstacles=world.obstacles)
    sim = RoverSim(scene_dir, rover=rover, run=run, settle_s=0.0,  # the corridor's rocks only
                   contact_corridor_xy_m=None if route is None else route.xy_m,
                   contact_corridor_m=_corridor_m(opt, run))
    sim.settle_s = opt.settle_s
    if route is None:
        sim.reset(xy_m=opt.start_xy_m, yaw_rad=opt.start_yaw_rad)
        return sim, None
    _check_inside(route, sim.heightfield)
    a, b = route.xy_m[0], route.xy_m[min(5, len(route.xy_m) - 1)]
    sim.reset(xy_m=(float(a[0]), float(a[1])), yaw_rad=math.atan2(b[1] - a[1], b[0] - a[0]))
    return sim, route


def _corridor_m(opt: DriveOptions, run: RunConfig) -> float:
    """Half width of the rock corridor: ``opt.corridor_m``, widened to what the sensors see (the
    LiDAR's range, half the camera's terrain window); only the rocks inside are simulated."""
    corridor_m = opt.corridor_m
    if run.lidar is not None:
        corridor_m = max(corridor_m, run.lidar.spec.range_m[1])
    if run.camera is not None:
        corridor_m = max(corridor_m, run.camera.terrain_window_m / 2.0)
    return corridor_m
