"""A batch of drives set up: each drive's world (terrain, rocks), route and start, and the one
MuJoCo Warp model of them all (:func:`marsscene.env.batch.model.tiled_model`: each world a tile
of one heightfield, its rocks as relief).

Routes are read or authored as :func:`marsscene.drive` does (:func:`~marsscene.sim.route.
author_route` on the scene's terrain and rocks; a route off the terrain is a one-line error), the
rover starts at the route's first point facing along it, and the time limit is the CPU drive's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from marsscene.errors import ConfigError
from marsscene.rover.config import RoverConfig, RunConfig
from marsscene.runs.tum import read_tum
from marsscene.sim.batch.spec import BatchDrive
from marsscene.sim.driver import _time_limit_s
from marsscene.sim.mission import DriveOptions, _check_inside
from marsscene.sim.route import Route, author_route

__all__ = ["DriveSim", "PreparedDrive", "prepare_drives"]


@dataclass(frozen=True, eq=False)
class PreparedDrive:
    """One drive ready to go: its world, route, start and time limit."""

    drive: BatchDrive
    heightfield: Any
    terrain: Any  # the heightfield with the rocks on it (the tile's surface)
    route: Route
    start_xy_m: tuple[float, float]
    start_yaw_rad: float
    limit_s: float


@dataclass(eq=False)
class DriveSim:
    """What the run writer and ``route.tum`` read of a drive's simulator (a CPU drive's
    :class:`~marsscene.sim.rover_sim.RoverSim` holds the same)."""

    run: RunConfig
    rover: RoverConfig
    dt_physics_s: float
    heightfield: Any
    rocks_kept: tuple[int, int] = (0, 0)
    wheel_soil: Any = None
    soil_map: Any = None
    scene_dir: Path = field(default_factory=Path)

    def camera_intrinsics(self, side: str | None = None) -> dict[str, Any]:
        """The mast camera's pinhole intrinsics (:meth:`RoverSim.camera_intrinsics`)."""
        from types import SimpleNamespace

        from marsscene.rover.config import CameraConfig
        from marsscene.sim.rover_sim import RoverSim

        fovy = (self.run.camera or CameraConfig()).fovy_deg
        view = SimpleNamespace(run=self.run, camera_id=0,
                               model=SimpleNamespace(cam_fovy=[fovy]))
        return RoverSim.camera_intrinsics(view, side)  # type: ignore[arg-type]


def _route(drive: BatchDrive, world: Any, options: DriveOptions) -> Route:
    if isinstance(drive.route, Route):
        route = drive.route
    elif drive.route is not None:
        route = Route.from_trajectory(read_tum(drive.route))
    else:
        route = author_route(np.asarray(drive.waypoints, dtype=np.float64), world.heightfield,
                             max_slope_deg=options.max_slope_deg, obstacles=world.obstacles)
    _check_inside(route, world.heightfield)
    return route


def _route_once(d: BatchDrive, world: Any, options: DriveOptions, routes: dict[Any, Route],
                scene: Path) -> Route:
    """``_route``, authored once per scene and waypoints (a batch of many drives often repeats
    them)."""
    if d.route is not None:
        return _route(d, world, options)
    way = np.asarray(d.waypoints, dtype=np.float64)
    key = (scene, way.shape, way.tobytes())
    if key not in routes:
        routes[key] = _route(d, world, options)
    return routes[key]


def prepare_drives(drives: list[BatchDrive], options: DriveOptions) -> list[PreparedDrive]:
    """Every drive's world, route and start (each scene loaded once)."""
    from marsscene.env.observe import rock_terrain
    from marsscene.sim.world import load_world

    if not drives:
        raise ConfigError("a batch needs at least one drive")
    worlds: dict[Path, tuple[Any, Any]] = {}
    routes: dict[Any, Route] = {}
    out: list[PreparedDrive] = []
    for i, d in enumerate(drives):
        if d.out_dir is None:
            raise ConfigError(f"drive {i} on {d.scene}: a batch drive needs a run folder (out)")
        key = Path(d.scene).resolve()
        if key not in worlds:
            world = load_world(key)
            worlds[key] = (world, rock_terrain(world.heightfield, world.obstacles))
        world, terrain = worlds[key]
        route = _route_once(d, world, options, routes, key)
        a, b = route.xy_m[0], route.xy_m[min(5, len(route.xy_m) - 1)]
        out.append(PreparedDrive(d, world.heightfield, terrain, route,
                                 (float(a[0]), float(a[1])),
                                 math.atan2(b[1] - a[1], b[0] - a[0]),
                                 _time_limit_s(route, d.seconds)))
    _check_sizes(out)
    return out


def _check_sizes(prepared: list[PreparedDrive]) -> None:
    """One heightfield tiles the worlds: one terrain size and post spacing."""
    h0 = prepared[0].heightfield
    for i, p in enumerate(prepared):
        hf = p.heightfield
        if hf.z_m.shape != h0.z_m.shape or abs(hf.cell_size_m - h0.cell_size_m) > 1e-9:
            raise ConfigError(f"drive {i} on {p.drive.scene}: terrain {hf.z_m.shape} posts at "
                              f"{hf.cell_size_m:g} m; a batch needs one size and spacing "
                              f"(drive 0: {h0.z_m.shape} at {h0.cell_size_m:g} m)")


def batch_model(prepared: list[PreparedDrive], *, rover: RoverConfig, physics_hz: float,
                physics: Any) -> Any:
    """The tiled MuJoCo model of the drives' worlds (one tile a drive)."""
    from marsscene.env.batch.model import tiled_model

    post_m = physics.post_m if physics.post_m is not None else prepared[0].heightfield.cell_size_m
    return tiled_model([p.terrain for p in prepared], [p.heightfield for p in prepared],
                       rover=rover, physics_hz=physics_hz, post_m=post_m, physics=physics)
