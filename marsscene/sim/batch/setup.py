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
from numpy.typing import NDArray

from marsscene.errors import ConfigError
from marsscene.rover.config import RoverConfig, RunConfig
from marsscene.runs.tum import read_tum
from marsscene.sim.batch.spec import BatchDrive
from marsscene.sim.driver import _time_limit_s
from marsscene.sim.mission import DriveOptions, _check_inside
from marsscene.sim.route import Route, author_route

__all__ = ["CameraWorlds", "DriveSim", "PreparedDrive", "camera_worlds", "prepare_drives"]


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
    obstacles: Any = None  # the scene's rocks (the camera draws them)
    assets: Any = None  # the scene's placed assets' meshes (sim.world.AssetMesh)


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
                                 _time_limit_s(route, d.seconds), world.rocks, world.assets))
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


@dataclass(frozen=True, eq=False)
class CameraWorlds:
    """What the batch camera draws: each distinct scene of the drives once (``batch``, a
    :class:`~marsscene.env.batch.worlds.WorldBatch` without episodes), drive ``i`` on world
    ``world[i]``; world ``w`` sits on the tile of its first drive (``offsets_xy_m[w]``), and a
    camera pose in drive ``i``'s tile moves by ``shift_xy_m[i]`` into its world's tile."""

    batch: Any
    world: NDArray[np.int32]
    offsets_xy_m: NDArray[np.float64]
    shift_xy_m: NDArray[np.float32]
    seeds: list[int]
    scenes: list[Path]
    catalogue: list[NDArray[np.float64]] = field(default_factory=list)
    """Per world, the catalogue rocks the camera draws besides the MJCF rocks
    (:func:`route_rocks`)."""
    assets: list[Any] = field(default_factory=list)
    """Per world, its placed assets' meshes (:class:`~marsscene.sim.world.AssetMesh` or
    None)."""


def route_rocks(scene_dir: Path, routes_xy_m: list[NDArray[np.float64]], reach_m: float
                ) -> NDArray[np.float64]:
    """The scene's catalogue rocks that are not MJCF geoms (``read_rock_catalog``'s rows)
    within ``reach_m`` of any of the routes: what the CPU camera's terrain window brings into
    view at some point of those drives."""
    from scipy.spatial import cKDTree

    from marsscene.sensors.camera_rocks import read_rock_catalog
    from marsscene.sim.route import resample_xy

    rocks = read_rock_catalog(Path(scene_dir))
    if not len(rocks):
        return rocks
    points = np.concatenate([resample_xy(xy, 0.5) for xy in routes_xy_m])
    gap, _ = cKDTree(points).query(rocks[:, 1:3], distance_upper_bound=reach_m)
    return rocks[np.isfinite(gap)]


def camera_worlds(prepared: list[PreparedDrive], tile_offsets_xy_m: Any,
                  reach_m: float | None = None) -> CameraWorlds:
    """The distinct scenes of ``prepared`` for the batch camera (one copy of a scene however
    many drives run on it), on the tiled model's tiles ``tile_offsets_xy_m`` (N, 2); with
    ``reach_m``, each scene's catalogue rocks within it of its drives' routes
    (:func:`route_rocks`)."""
    from marsscene.env.batch.worlds import WorldBatch
    from marsscene.sensors.camera_scene import scene_seed

    first: dict[Path, int] = {}
    world = np.zeros(len(prepared), dtype=np.int32)
    for i, p in enumerate(prepared):
        world[i] = first.setdefault(Path(p.drive.scene).resolve(), len(first))
    lead = [next(i for i in range(len(prepared)) if world[i] == w) for w in range(len(first))]
    tiles = np.asarray(tile_offsets_xy_m, dtype=np.float64)
    rocks = [prepared[i].obstacles for i in lead]
    none = np.zeros((len(lead), 0, 2))
    batch = WorldBatch(
        posts_z_m=np.stack([np.asarray(prepared[i].heightfield.z_m, np.float32) for i in lead]),
        cell_m=float(prepared[0].heightfield.cell_size_m),
        origins_xy_m=np.array([prepared[i].heightfield.origin_xy_m for i in lead], np.float64),
        rock_xy_m=np.concatenate([r.xy_m for r in rocks]).reshape(-1, 2),
        rock_radius_m=np.concatenate([r.radius_m for r in rocks]),
        rock_height_m=np.concatenate([r.height_m for r in rocks]),
        rock_world=np.concatenate([np.full(len(r.radius_m), w) for w, r in enumerate(rocks)]
                                  ).astype(np.int64),
        starts_xy_m=none, yaws_rad=none[..., 0], goals_xy_m=none)
    scenes = [Path(prepared[i].drive.scene) for i in lead]
    catalogue = [] if reach_m is None else [
        route_rocks(scene, [p.route.xy_m for i, p in enumerate(prepared) if world[i] == w],
                    reach_m) for w, scene in enumerate(scenes)]
    return CameraWorlds(batch, world, tiles[lead], (tiles[lead][world] - tiles).astype(
        np.float32), [scene_seed(s) for s in scenes], scenes, catalogue,
        [prepared[i].assets for i in lead])


def scene_camera_world(scene_dir: str | Path) -> tuple[Any, list[Any], list[Any]]:
    """One built scene as the batch camera draws it, in world coordinates: its
    :class:`~marsscene.env.batch.worlds.WorldBatch` (terrain and MJCF rocks, no episodes),
    its catalogue rocks and its placed assets' meshes, one world each (``BatchCamera``'s
    ``batch``, ``catalogue`` and ``assets``)."""
    from marsscene.env.batch.worlds import WorldBatch
    from marsscene.sensors.camera_rocks import read_rock_catalog
    from marsscene.sim.world import load_world

    folder = Path(scene_dir)
    world = load_world(folder)
    hf, rocks, none = world.heightfield, world.rocks, np.zeros((1, 0, 2))
    batch = WorldBatch(posts_z_m=np.asarray(hf.z_m, np.float32)[None], cell_m=hf.cell_size_m,
                       origins_xy_m=np.array([hf.origin_xy_m], np.float64),
                       rock_xy_m=rocks.xy_m.reshape(-1, 2), rock_radius_m=rocks.radius_m,
                       rock_height_m=rocks.height_m,
                       rock_world=np.zeros(len(rocks.radius_m), np.int64), starts_xy_m=none,
                       yaws_rad=none[..., 0], goals_xy_m=none)
    return batch, [read_rock_catalog(folder)], [world.assets]
