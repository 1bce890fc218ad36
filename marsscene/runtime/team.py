"""``drive_team``: several robots in one world, from a scene to one run folder per robot.

Each :class:`Robot` has its own rover type, sensors, start, route (or controller, or open-loop
command) and noise stream (``"sensors"`` of ``seed``, keyed by the robot's name: adding a robot
never moves another robot's noise); all share one MuJoCo model, so they see and can touch each
other (:mod:`marsscene.sim.team`). The team's folder holds ``team.json`` and a normal run
folder per robot (``OUT/<name>/``: ``gt.tum``, ``odom.tum``, IMU, LiDAR, camera, ``run.json``)
that ``marsscene eval`` and every reader of a single drive read.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from marsscene.errors import ConfigError
from marsscene.rover.config import RunConfig
from marsscene.runs.export.options import ExportOptions
from marsscene.runs.export.topic_table import RosNames
from marsscene.runs.logs import write_json
from marsscene.runtime._steps import check_exports, export_run, scene_dir, started, write_route
from marsscene.runtime.api import DriveRun, _route
from marsscene.runtime.robot import Robot, Scout, read_team_file
from marsscene.seeding import robot_rng
from marsscene.sim.driver import DriveInterrupted, DriveResult
from marsscene.sim.mission import DriveOptions, _check_inside, _corridor_m
from marsscene.sim.route import Route, author_route
from marsscene.sim.session import SessionOptions
from marsscene.sim.team import Placement, TeamSim
from marsscene.sim.team_drive import MemberDrive, TeamProgress, drive_team_sim

if TYPE_CHECKING:
    from marsscene.scene import Scene

__all__ = ["Robot", "Scout", "TeamRun", "drive_team", "read_team_file"]


@dataclass(frozen=True)
class TeamRun:
    """A finished team drive: each robot's :class:`~marsscene.runtime.api.DriveRun` by name.

    ``wall_s`` is the whole team's drive; :attr:`realtime_factor` is the longest robot's sim
    seconds per wall second; ``scouts`` the scouts' flights (:class:`marsscene.scout.Flight`)
    and ``crossview`` the number of scout images paired with a rover frame
    (:mod:`~marsscene.runtime.crossview`).
    """

    out_dir: Path | None
    robots: dict[str, DriveRun] = field(default_factory=dict)
    wall_s: float = float("nan")
    scouts: dict[str, Any] = field(default_factory=dict)
    crossview: int = 0

    @property
    def realtime_factor(self) -> float:
        sim_s = max((r.sim_s for r in self.robots.values()), default=0.0)
        return sim_s / self.wall_s if self.wall_s > 0 else math.nan


def _routes(scene_path: Path, robots: Sequence[Robot], options: DriveOptions) -> list[Any]:
    """Each robot's route: given, read from a TUM file, or authored from its waypoints on the
    scene (planned once for all)."""
    world = None
    out: list[Route | None] = []
    for r in robots:
        if r.waypoints is None:
            out.append(_route(r.route))
            continue
        if world is None:
            from marsscene.sim.world import load_world

            world = load_world(scene_path)
        out.append(author_route(np.asarray(r.waypoints), world.heightfield,
                                max_slope_deg=options.max_slope_deg, obstacles=world.obstacles))
    return out


def _start(robot: Robot, route: Route | None, n: int) -> tuple[tuple[float, float], float]:
    if route is not None:
        a, b = route.xy_m[0], route.xy_m[min(5, len(route.xy_m) - 1)]
        return (float(a[0]), float(a[1])), math.atan2(b[1] - a[1], b[0] - a[0])
    if robot.start_xy_m is None:
        raise ConfigError(f"robot {robot.name!r} needs a route, waypoints or start_xy_m "
                          f"(the {n} robots cannot all start at the centre)")
    return (float(robot.start_xy_m[0]), float(robot.start_xy_m[1])), robot.start_yaw_rad


def drive_team(
    scene: str | os.PathLike[str] | Scene,
    robots: Sequence[Robot],
    *,
    seconds: float | None = None,
    config: RunConfig | None = None,
    options: DriveOptions | None = None,
    out_dir: str | os.PathLike[str] | None = None,
    seed: int = 0,
    progress: Callable[[TeamProgress], None] | None = None,
    keep_sensors: bool = False,
    export: ExportOptions | None = None,
    scouts: Sequence[Scout] = (),
) -> TeamRun:
    """Drive a team of robots in one world, each with its own sensors, noise and run folder.

    Parameters
    ----------
    scene : path or Scene
        A built scene folder, or a :class:`~marsscene.Scene` (written into ``out_dir/scene``).
    robots : sequence of Robot
        1 to 16 robots with different names.
    seconds : float, optional
        Time limit of every robot without its own (default: until its goal).
    config : RunConfig, optional
        Sensors of every robot without its own ``config``.
    options : DriveOptions, optional
        Slope limit, rock corridor, settling and the route follower, for all.
    out_dir : path, optional
        The team's folder: ``team.json`` and ``<name>/`` per robot; in memory without it.
    seed : int
        Seed of the sensor noise (each robot's stream keyed by its name).
    progress : callable, optional
        Called with a :class:`~marsscene.sim.team_drive.TeamProgress` per robot and
        simulated second.
    keep_sensors : bool
        Keep LiDAR scans, images and IMU samples in memory.
    export : ExportOptions, optional
        Each robot's bag and dataset folders, written from its run folder at the end; its
        bag's topics under ``/<name>/`` and its frames prefixed ``<name>/`` (``map`` shared),
        as its ``run.json`` (``"ros"``) says.
    scouts : sequence of Scout
        Helicopter scouts flying over the same terrain after the rovers' drive, each with its
        own run folder (``OUT/<name>/``) and noise stream; with ``out_dir`` and a rover with a
        camera, ``OUT/crossview.csv`` pairs their images with the rovers' frames.

    Examples
    --------
    >>> import marsscene as ms
    >>> cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [24, 24]}})
    >>> scene = ms.build_scene(cfg, seed=1)
    >>> team = ms.drive_team(scene, [
    ...     ms.Robot(name="rover1", waypoints=[[-8, -3], [8, -3]]),
    ...     ms.Robot(name="mer1", rover="mer", waypoints=[[-8, 3], [8, 3]])], seconds=5.0)
    >>> sorted(team.robots), team.robots["mer1"].summary["poses"]
    (['mer1', 'rover1'], 251)
    """
    config = config if config is not None else RunConfig()
    options = options if options is not None else DriveOptions()
    export = export if export is not None else ExportOptions()
    out = Path(out_dir) if out_dir is not None else None
    robots = list(robots)
    if not robots:
        raise ConfigError("a team needs at least one robot")
    names = [r.name for r in robots] + [s.name for s in scouts]
    if len(set(names)) != len(names):
        raise ConfigError(f"team: robot and scout names must differ: {names}")
    runs = [r.config if r.config is not None else config for r in robots]
    for r, run in zip(robots, runs, strict=True):
        check_exports(export, run, out / r.name if out is not None else None)
    with scene_dir(scene, out) as scene_path:
        routes = _routes(Path(scene_path), robots, options)
        team = _team(Path(scene_path), robots, runs, routes, options)
        plans = [_plan(team, r, rt, options, out, seed, seconds)
                 for r, rt in zip(robots, routes, strict=True)]
        t0 = time.perf_counter()
        session = SessionOptions(keep_sensors=keep_sensors, lidar_files=export.lidar_files)
        try:
            results = drive_team_sim(team, plans, session=session, progress=progress)
        except DriveInterrupted as stop:  # Ctrl-C: each folder is whole up to there
            if not options.stop_on_interrupt:
                raise
            results = stop.team
        wall_s = time.perf_counter() - t0
        flights = {s.name: _fly(Path(scene_path), s, out, seed) for s in scouts}
    drives = {r.name: _exported(out, r.name, results[r.name], rt, export, wall_s, team)
              for r, rt in zip(robots, routes, strict=True)}
    pairs = 0
    if out is not None:
        write_json(out / "team.json", _team_json(robots, drives, seed, wall_s, flights))
        if flights:
            from marsscene.runtime.crossview import write_crossview

            pairs = write_crossview(out, list(flights), [r.name for r in robots])
    return TeamRun(out, drives, wall_s, flights, pairs)


def _fly(scene_path: Path, scout: Scout, out: Path | None, seed: int) -> Any:
    """One scout's flight over the team's terrain, its noise keyed by its name."""
    from marsscene.scout import FlightPlan, fly

    plan = FlightPlan(altitude_m=scout.altitude_m, speed_m_s=scout.speed_m_s,
                      camera_hz=scout.camera_hz)
    return fly(scene_path, scout.waypoints, plan=plan, start_xy_m=scout.start_xy_m,
               out_dir=out / scout.name if out is not None else None,
               rng=robot_rng(seed, "sensors", scout.name))


def _team(scene_path: Path, robots: Sequence[Robot], runs: Sequence[RunConfig],
          routes: Sequence[Route | None], options: DriveOptions) -> TeamSim:
    """The team's one model, each robot at its start."""
    starts = [_start(r, rt, len(robots)) for r, rt in zip(robots, routes, strict=True)]
    placements = [Placement(r.name, r.rover_config, run, xy, yaw)
                  for r, run, (xy, yaw) in zip(robots, runs, starts, strict=True)]
    corridor = (None if any(rt is None for rt in routes)
                else np.concatenate([rt.xy_m for rt in routes if rt is not None]))
    return TeamSim(scene_path, placements, contact_corridor_xy_m=corridor,
                   contact_corridor_m=max(_corridor_m(options, run) for run in runs),
                   settle_s=options.settle_s)


def _plan(team: TeamSim, robot: Robot, route: Route | None, options: DriveOptions,
          out: Path | None, seed: int, seconds: float | None) -> MemberDrive:
    """What ``robot`` does; its controller made now if it is an ``OnStart``."""
    member = team.member(robot.name)
    if route is not None:
        _check_inside(route, team.heightfield)
    folder = out / robot.name if out is not None else None
    write_route(folder, member, route, options)
    ctrl, heard = started(robot.controller, member, route)
    return MemberDrive(robot.name, robot_rng(seed, "sensors", robot.name), route, ctrl,
                       robot.command, robot.seconds or seconds, folder, options.pursuit,
                       listeners=heard,
                       meta={"ros": RosNames.for_robot(robot.name).to_dict()})


def _exported(out: Path | None, name: str, result: DriveResult, route: Route | None,
              export: ExportOptions, wall_s: float, team: TeamSim) -> DriveRun:
    """One robot's :class:`DriveRun`, its bag and datasets written from its run folder."""
    folder = out / name if out is not None else None
    t1 = time.perf_counter()
    bag, datasets = export_run(folder, export, None, None)
    return DriveRun(folder, result, route, bag, datasets, wall_s=wall_s,
                    export_s=time.perf_counter() - t1, rocks_kept=team.rocks_kept)


def _team_json(robots: Sequence[Robot], drives: Mapping[str, DriveRun], seed: int,
               wall_s: float, flights: Mapping[str, Any]) -> dict[str, Any]:
    return {
        "seed": seed,
        "robots": [{"name": r.name, "folder": r.name, "rover": r.rover_type,
                    "status": drives[r.name].summary["status"],
                    "sim_time_s": drives[r.name].sim_s} for r in robots],
        **({"scouts": [{"name": n, "folder": n, "images": f.summary["images"],
                        "reached": all(f.reached), "sim_time_s": f.summary["sim_time_s"]}
                       for n, f in flights.items()]} if flights else {}),
        "wall_s": round(wall_s, 3),
    }
