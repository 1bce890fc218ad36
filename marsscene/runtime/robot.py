"""A robot of a team (:class:`Robot`) and the team file that lists them (``[[robots]]``).

:func:`marsscene.runtime.team.drive_team` drives them; ``marsscene drive --team`` and
``marsscene serve --team`` read the file (:func:`read_team_file`).
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from numpy.typing import ArrayLike

from marsscene._validate import check_range, plain
from marsscene.errors import ConfigError
from marsscene.rover.config import RoverConfig, RunConfig
from marsscene.sim.control import OnStart
from marsscene.sim.route import Route, check_waypoints

__all__ = ["Robot", "Scout", "read_team_file"]

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
        ``route``; ``command`` or ``controller`` instead of the route follower; an
        :class:`~marsscene.sim.control.OnStart` is made from the robot's
        :class:`~marsscene.sim.team.TeamMember`, as the live team's ROS 2 bridges are).
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
    controller: Callable[[Any], tuple[float, float]] | OnStart | None = None
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


@dataclass(frozen=True, kw_only=True)
class Scout:
    """A helicopter scout of a team: it flies ``waypoints`` ((N, 2) map x, y in m) at
    ``altitude_m`` above the ground and lands at the last (:func:`marsscene.scout.fly`), in the
    rovers' world and map frame; its run folder is ``OUT/<name>/`` beside theirs.

    The scout flies the same terrain as the rovers drive, in a model of its own: the rovers'
    cameras and LiDARs do not see it, and it does not see them.
    """

    name: str
    waypoints: ArrayLike
    start_xy_m: tuple[float, float] | None = None
    altitude_m: float = 10.0
    speed_m_s: float = 3.0
    camera_hz: float = 2.0

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not _NAME.fullmatch(self.name):
            raise ConfigError(f"scout name {plain(self.name)!r}: letters, digits and _, a "
                              "letter first")
        object.__setattr__(self, "waypoints",
                           check_waypoints(self.waypoints, f"scout {self.name!r} waypoints"))
        check_range(f"scout {self.name!r} altitude_m", self.altitude_m, 1.0, 100.0)
        check_range(f"scout {self.name!r} speed_m_s", self.speed_m_s, 0.1, 10.0)
        check_range(f"scout {self.name!r} camera_hz", self.camera_hz, 0.0, 30.0, lo_open=True)

    @classmethod
    def from_dict(cls, mapping: Mapping[str, Any]) -> Scout:
        """From a ``[[scouts]]`` table: ``name``, ``waypoints``, ``start_xy_m``,
        ``altitude_m``, ``speed_m_s``, ``camera_hz``."""
        doc = dict(mapping)
        known = {"name", "waypoints", "start_xy_m", "altitude_m", "speed_m_s", "camera_hz"}
        extra = sorted(set(doc) - known)
        if extra:
            raise ConfigError(f"[[scouts]] {doc.get('name', '?')!r}: unknown keys {extra}; "
                              f"known: {sorted(known)}")
        if "name" not in doc or "waypoints" not in doc:
            raise ConfigError("[[scouts]]: every scout needs a name and waypoints")
        if "start_xy_m" in doc:
            doc["start_xy_m"] = tuple(doc["start_xy_m"])
        return cls(**doc)


def read_team_file(path: str | os.PathLike[str]) -> tuple[list[Robot], dict[str, Any]]:
    """The robots of a team file: TOML with ``[[robots]]`` tables (:meth:`Robot.from_dict`;
    routes relative to the file), optional ``[[scouts]]`` tables (:meth:`Scout.from_dict`) and
    optional top-level ``seconds`` and ``seed``.

    Returns the robots and the other settings (``{"seconds": ..., "seed": ..., "scouts":
    [Scout, ...]}``, those given)."""
    import tomllib

    p = Path(path)
    try:
        doc = tomllib.loads(p.read_text(encoding="utf-8"))
    except (OSError, ValueError) as err:
        raise ConfigError(f"cannot read team file {p}: {err}") from None
    extra = sorted(set(doc) - {"robots", "scouts", "seconds", "seed"})
    if extra:
        raise ConfigError(f"{p}: unknown keys {extra}; known: robots, scouts, seconds, seed")
    tables = doc.get("robots")
    if not isinstance(tables, list) or not tables:
        raise ConfigError(f"{p}: no [[robots]] tables")
    robots = [Robot.from_dict(t, base=p.parent) for t in tables]
    settings: dict[str, Any] = {k: doc[k] for k in ("seconds", "seed") if k in doc}
    if "scouts" in doc:
        if not isinstance(doc["scouts"], list):
            raise ConfigError(f"{p}: scouts must be [[scouts]] tables")
        settings["scouts"] = [Scout.from_dict(t) for t in doc["scouts"]]
    return robots, settings
