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
import re
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from marsscene._validate import check_range, plain
from marsscene.errors import ConfigError
from marsscene.rover.config import RoverConfig, RunConfig
from marsscene.runs.logs import write_json
from marsscene.runtime._steps import scene_dir, write_route
from marsscene.runtime.api import DriveRun, _route
from marsscene.seeding import robot_rng
from marsscene.sim.mission import DriveOptions, _check_inside, _corridor_m
from marsscene.sim.route import Route, author_route, check_waypoints
from marsscene.sim.session import SessionOptions
from marsscene.sim.team import Placement, TeamSim
from marsscene.sim.team_drive import MemberDrive, TeamProgress, drive_team_sim

if TYPE_CHECKING:
    from marsscene.scene import Scene

__all__ = ["Robot", "TeamRun", "drive_team", "read_team_file"]

_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,62}")  # a ROS 2 namespace token


@dataclass(frozen=True, kw_only=True)
class Robot:
    """One robot of a team.

    Parameters
    ----------
    name : str
        Its name: the prefix of its bodies, its run folder, its ROS 2 namespace (letters,
        digits, ``_``; a letter first).
    rover : str or RoverConfig
        Its rover type (:meth:`RoverConfig.load`: ``"perseverance"``, ``"mer"``, a file).
    config : RunConfig, optional
        Its sensors and noise (default: the team's ``config``).
    waypoints, route, command, controller
        What it does, as :func:`marsscene.drive` takes them (at most one of ``waypoints`` and
        ``route``; ``command`` or ``controller`` instead of the route follower).
    start_xy_m, start_yaw_rad
        Start of a robot without a route (a route starts at its first point, facing along it).
    seconds : float, optional
        Its time limit (default: the team's ``seconds``, else until its goal).
    """

    name: str
    rover: str | RoverConfig = "perseverance"
    config: RunConfig | None = None
    waypoints: ArrayLike | None = None
    route: Route | str | os.PathLike[str] | None = None
    command: tuple[float, float] | Callable[[float], tuple[float, float]] | None = None
    controller: Callable[[Any], tuple[float, float]] | None = None
    start_xy_m: tuple[float, float] | None = None
    start_yaw_rad: float = 0.0
    seconds: float | None = None
    rover_type: str = field(init=False, default="perseverance")

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not _NAME.fullmatch(self.name):
            raise ConfigError(f"robot name {plain(self.name)!r}: letters, digits and _, a "
                              "letter first (it names the robot's folder and ROS namespace)")
        if not isinstance(self.rover, RoverConfig):
            object.__setattr__(self, "rover_type", str(self.rover))
            object.__setattr__(self, "rover", RoverConfig.load(str(self.rover)))
        elif self.rover != RoverConfig():
            object.__setattr__(self, "rover_type", "custom")
        if self.waypoints is not None and self.route is not None:
            raise ConfigError(f"robot {self.name!r}: give waypoints or a route, not both")
        if self.waypoints is not None:
            object.__setattr__(self, "waypoints",
                               check_waypoints(self.waypoints, f"robot {self.name!r} waypoints"))
        check_range(f"robot {self.name!r} start_yaw_rad", self.start_yaw_rad)

    @property
    def rover_config(self) -> RoverConfig:
        """Its rover type's configuration."""
        assert isinstance(self.rover, RoverConfig)
        return self.rover

    @classmethod
    def from_dict(cls, mapping: Mapping[str, Any], *, base: Path | None = None) -> Robot:
        """From a ``[[robots]]`` table: ``name``, ``rover``, ``waypoints`` (``[[x, y], ...]``)
        or ``route`` (a TUM file, relative to ``base``), ``command`` (``[v, omega]``),
        ``start_xy_m``, ``start_yaw_rad``, ``seconds``, and ``run`` (a run config's tables:
        ``[robots.run.lidar]``...)."""
        doc = dict(mapping)
        known = {"name", "rover", "waypoints", "route", "command", "start_xy_m",
                 "start_yaw_rad", "seconds", "run"}
        extra = sorted(set(doc) - known)
        if extra:
            raise ConfigError(f"[[robots]] {doc.get('name', '?')!r}: unknown keys {extra}; "
                              f"known: {sorted(known)}")
        if "name" not in doc:
            raise ConfigError("[[robots]]: every robot needs a name")
        run = doc.pop("run", None)
        if run is not None:
            doc["config"] = RunConfig.from_dict(run, source=f"robot {doc['name']!r} run")
        if "route" in doc and base is not None:
            doc["route"] = base / str(doc["route"])
        if "command" in doc:
            v = doc["command"]
            if not (isinstance(v, list) and len(v) == 2):
                raise ConfigError(f"robot {doc['name']!r}: command = {v!r} must be [v, omega]")
            doc["command"] = (float(v[0]), float(v[1]))
        if "start_xy_m" in doc:
            doc["start_xy_m"] = tuple(doc["start_xy_m"])
        return cls(**doc)


@dataclass(frozen=True)
class TeamRun:
    """A finished team drive: each robot's :class:`~marsscene.runtime.api.DriveRun` by name.

    ``wall_s`` is the whole team's drive; :attr:`realtime_factor` is the longest robot's sim
    seconds per wall second.
    """

    out_dir: Path | None
    robots: dict[str, DriveRun] = field(default_factory=dict)
    wall_s: float = float("nan")

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
    out = Path(out_dir) if out_dir is not None else None
    robots = list(robots)
    if not robots:
        raise ConfigError("a team needs at least one robot")
    with scene_dir(scene, out) as scene_path:
        routes = _routes(Path(scene_path), robots, options)
        runs = [r.config if r.config is not None else config for r in robots]
        starts = [_start(r, rt, len(robots)) for r, rt in zip(robots, routes, strict=True)]
        placements = [Placement(r.name, r.rover_config, run, xy, yaw)
                      for r, run, (xy, yaw) in zip(robots, runs, starts, strict=True)]
        corridor = (None if any(rt is None for rt in routes)
                    else np.concatenate([rt.xy_m for rt in routes if rt is not None]))
        team = TeamSim(scene_path, placements, contact_corridor_xy_m=corridor,
                       contact_corridor_m=max(_corridor_m(options, run) for run in runs),
                       settle_s=options.settle_s)
        plans = []
        for r, rt in zip(robots, routes, strict=True):
            if rt is not None:
                _check_inside(rt, team.heightfield)
            folder = out / r.name if out is not None else None
            write_route(folder, team.member(r.name), rt, options)
            plans.append(MemberDrive(r.name, robot_rng(seed, "sensors", r.name), rt,
                                     r.controller, r.command, r.seconds or seconds, folder,
                                     options.pursuit))
        t0 = time.perf_counter()
        results = drive_team_sim(team, plans, session=SessionOptions(keep_sensors=keep_sensors),
                                 progress=progress)
        wall_s = time.perf_counter() - t0
    drives = {r.name: DriveRun(out / r.name if out is not None else None, results[r.name], rt,
                               wall_s=wall_s, rocks_kept=team.rocks_kept)
              for r, rt in zip(robots, routes, strict=True)}
    if out is not None:
        write_json(out / "team.json", _team_json(robots, drives, seed, wall_s))
    return TeamRun(out, drives, wall_s)


def _team_json(robots: Sequence[Robot], drives: Mapping[str, DriveRun], seed: int,
               wall_s: float) -> dict[str, Any]:
    return {
        "seed": seed,
        "robots": [{"name": r.name, "folder": r.name, "rover": r.rover_type,
                    "status": drives[r.name].summary["status"],
                    "sim_time_s": drives[r.name].sim_s} for r in robots],
        "wall_s": round(wall_s, 3),
    }



def read_team_file(path: str | os.PathLike[str]) -> tuple[list[Robot], dict[str, Any]]:
    """The robots of a team file: TOML with ``[[robots]]`` tables (:meth:`Robot.from_dict`;
    routes relative to the file) and optional top-level ``seconds`` and ``seed``.

    Returns the robots and the top-level settings (``{"seconds": ..., "seed": ...}``, those
    given)."""
    import tomllib

    p = Path(path)
    try:
        doc = tomllib.loads(p.read_text(encoding="utf-8"))
    except (OSError, ValueError) as err:
        raise ConfigError(f"cannot read team file {p}: {err}") from None
    extra = sorted(set(doc) - {"robots", "seconds", "seed"})
    if extra:
        raise ConfigError(f"{p}: unknown keys {extra}; known: robots, seconds, seed")
    tables = doc.get("robots")
    if not isinstance(tables, list) or not tables:
        raise ConfigError(f"{p}: no [[robots]] tables")
    robots = [Robot.from_dict(t, base=p.parent) for t in tables]
    return robots, {k: doc[k] for k in ("seconds", "seed") if k in doc}
