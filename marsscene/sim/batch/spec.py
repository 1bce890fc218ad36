"""One drive of a batch (:class:`BatchDrive`) and a batch file of them (TOML ``[[drive]]``).

A batch file lists the drives; the sensors, their rates and the noise are the batch's, one
:class:`~marsscene.rover.config.RunConfig` for all (one MuJoCo Warp model carries one rover):

.. code-block:: toml

    [[drive]]
    scene = "scenes/a"            # a built scene folder
    waypoints = [[-5, 0], [5, 0]]  # or route = "route.tum"
    out = "runs/a"                 # the run folder
    seed = 1                       # the sensor-noise seed (default 0)
    seconds = 60                   # optional sim-time limit
    tau = 2.0                      # optional: the camera's dust optical depth (default: the
                                   # camera config's, else the scene's)
    sun_elevation_deg = 15.0       # optional: this drive's sun (default: as tau)
    sun_azimuth_deg = 270.0        # optional
    irradiance_scale = 0.1         # optional: its sun and sky dimmed (a dusk's light)
    exposure = "fixed"             # optional: its camera's exposure ("auto" or "fixed")
    lookahead_m = 2.5              # optional: its pure-pursuit lookahead
    lidar = false                  # optional: no LiDAR scans in this drive's folder

Relative paths are read from the batch file's folder.
"""

from __future__ import annotations

import os
import tomllib
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from marsscene.errors import ConfigError
from marsscene.rover.config import CameraConfig
from marsscene.sim.pursuit import PursuitConfig
from marsscene.sim.route import Route

__all__ = ["BatchDrive", "read_batch_file"]

#: A camera config whose checks the drive's dust and sun pass through.
_CAMERA = CameraConfig()
_KEYS = {"scene", "route", "waypoints", "out", "seed", "seconds", "tau", "sun_elevation_deg",
         "sun_azimuth_deg", "irradiance_scale", "exposure", "lookahead_m", "lidar"}


@dataclass(frozen=True, eq=False)
class BatchDrive:
    """One drive of a batch.

    Parameters
    ----------
    scene : path
        A built scene folder (``marsscene build``).
    route : Route or path, optional
        A route to follow (a TUM file: x and y are used).
    waypoints : array_like (N, 2), optional
        Instead of a route: waypoints through which a route avoiding slopes and rocks is
        authored (as :func:`marsscene.drive` does).
    out_dir : path, optional
        The run folder; nothing is written without one.
    seed : int
        Seed of the sensor-noise stream (``stage_rng(seed, "sensors")``, the CPU drive's).
    seconds : float, optional
        Sim-time limit (default: the CPU drive's, twice the route at 0.1 m/s plus a minute).
    tau : float, optional
        The camera's dust optical depth for this drive (its sky, sun, colour and visibility;
        default: the batch's camera config's ``tau``, else the scene's lighting).
    sun_elevation_deg, sun_azimuth_deg : float, optional
        The camera's sun for this drive (degrees above the horizon; clockwise from north), its
        direction, shadows and irradiance through the dust as the CPU camera's
        :class:`~marsscene.rover.config.CameraConfig` takes them (default: as ``tau``).
    irradiance_scale : float, optional
        The camera's sun and sky irradiance times this (``CameraConfig.irradiance_scale``).
    exposure : {"auto", "fixed"}, optional
        This drive's camera exposure (default: the batch camera config's).
    lookahead_m : float, optional
        This drive's pure-pursuit lookahead (default: the batch's ``DriveOptions.pursuit``).
    lidar : bool
        Log the batch's LiDAR in this drive (default True; False: its folder has no scans, as
        a CPU drive without a LiDAR).
    """

    scene: str | os.PathLike[str]
    route: Route | str | os.PathLike[str] | None = None
    waypoints: Any = None
    out_dir: str | os.PathLike[str] | None = None
    seed: int = 0
    seconds: float | None = None
    tau: float | None = None
    sun_elevation_deg: float | None = None
    sun_azimuth_deg: float | None = None
    irradiance_scale: float | None = None
    exposure: str | None = None
    lookahead_m: float | None = None
    lidar: bool = True

    def __post_init__(self) -> None:
        if (self.route is None) == (self.waypoints is None):
            raise ConfigError(f"drive on {self.scene}: give a route or waypoints (one of them)")
        if int(self.seed) < 0:
            raise ConfigError(f"drive on {self.scene}: seed = {self.seed} must be >= 0")
        if self.seconds is not None and not float(self.seconds) > 0:
            raise ConfigError(f"drive on {self.scene}: seconds = {self.seconds} must be > 0")
        try:  # the camera's and the follower's own ranges
            self.lighting_of(_CAMERA)
            if self.lookahead_m is not None:
                PursuitConfig(lookahead_m=float(self.lookahead_m))
        except ConfigError as err:
            raise ConfigError(f"drive on {self.scene}: {err}") from None

    def lighting_of(self, camera: Any) -> Any:
        """``camera`` (the batch's :class:`~marsscene.rover.config.CameraConfig`) with this
        drive's dust, sun, irradiance scale and exposure where it sets them."""
        given = {"tau": self.tau, "sun_elevation_deg": self.sun_elevation_deg,
                 "sun_azimuth_deg": self.sun_azimuth_deg,
                 "irradiance_scale": self.irradiance_scale}
        out = replace(camera, **{k: float(v) for k, v in given.items() if v is not None})
        return out if self.exposure is None else replace(out, exposure=str(self.exposure))


def read_batch_file(path: str | os.PathLike[str]) -> list[BatchDrive]:
    """The drives of a batch file (``[[drive]]`` tables; module docstring)."""
    p = Path(path)
    try:
        doc = tomllib.loads(p.read_text(encoding="utf-8"))
    except (OSError, tomllib.TOMLDecodeError) as err:
        raise ConfigError(f"{p}: cannot read the batch file: {err}") from None
    tables = doc.get("drive")
    if not isinstance(tables, list) or not tables:
        raise ConfigError(f"{p}: no [[drive]] tables")
    return [_drive(p.parent, i, t, p) for i, t in enumerate(tables)]


def _drive(base: Path, i: int, table: dict[str, Any], path: Path) -> BatchDrive:
    unknown = sorted(set(table) - _KEYS)
    if unknown:
        raise ConfigError(f"{path}: drive {i}: unknown key {unknown[0]!r} "
                          f"(known: {', '.join(sorted(_KEYS))})")
    if "scene" not in table:
        raise ConfigError(f"{path}: drive {i} has no scene")

    def rel(key: str) -> Path | None:
        return None if key not in table else base / str(table[key])

    wp = table.get("waypoints")
    if wp is not None:
        wp = np.asarray(wp, dtype=np.float64)
        if wp.ndim != 2 or wp.shape[1] != 2 or len(wp) < 2:
            raise ConfigError(f"{path}: drive {i}: waypoints must be [[x, y], ...], two or more")
    return BatchDrive(scene=base / str(table["scene"]), route=rel("route"), waypoints=wp,
                      out_dir=rel("out"), seed=int(table.get("seed", 0)),
                      seconds=table.get("seconds"), tau=table.get("tau"),
                      sun_elevation_deg=table.get("sun_elevation_deg"),
                      sun_azimuth_deg=table.get("sun_azimuth_deg"),
                      irradiance_scale=table.get("irradiance_scale"),
                      exposure=table.get("exposure"), lookahead_m=table.get("lookahead_m"),
                      lidar=bool(table.get("lidar", True)))
