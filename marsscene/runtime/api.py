"""``drive``: one call from a scene to a finished run folder, bag and dataset exports.

The command line (``marsscene drive``), sweep cells, SLAM benchmark cells and VPR traversals
all drive through :func:`drive`; it wires the steps every drive takes: load the scene and set
the rover at its start (:func:`~marsscene.sim.mission.prepare_drive`), write ``route.tum``,
drive with the sensors on (:func:`~marsscene.sim.driver.drive_sim`, the noise from the
``"sensors"`` stream of ``seed``), then write the bag and the dataset folders
(:mod:`marsscene.runs.export`), JPEG-encoding the bag's colour frames while driving.
"""

from __future__ import annotations

import logging
import math
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from numpy.typing import ArrayLike

from marsscene.rover.config import RoverConfig, RunConfig
from marsscene.runs.export.options import ExportOptions
from marsscene.runs.tum import Trajectory, read_tum
from marsscene.runtime._steps import (
    ExportProgress,
    check_exports,
    export_run,
    jpeg_cache,
    scene_dir,
    started,
    write_route,
)
from marsscene.seeding import stage_rng
from marsscene.sim.control import Controller, OnStart
from marsscene.sim.driver import DriveInterrupted, DriveProgress, DriveResult, drive_sim
from marsscene.sim.mission import DriveOptions, prepare_drive
from marsscene.sim.route import Route
from marsscene.sim.session import SessionOptions

if TYPE_CHECKING:
    from marsscene.runs.export.bag import BagSummary
    from marsscene.scene import Scene

__all__ = ["DriveRun", "ExportProgress", "drive"]

log = logging.getLogger("marsscene")


@dataclass(frozen=True)
class DriveRun:
    """A finished drive: its run folder, the trajectories and summary, and the exports.

    Attributes
    ----------
    out_dir : Path or None
        The run folder (None for a drive kept in memory).
    result : DriveResult
        Ground truth, odometry, commands, summary (and sensor data with ``keep_sensors``).
    route : Route or None
        The route driven (authored from waypoints, or as given).
    bag : BagSummary or None
    datasets : dict
        Dataset format -> folder written.
    wall_s : float
        Wall-clock seconds of the drive itself.
    export_s : float
        Wall-clock seconds of the exports (bag and datasets).
    rocks_kept : (int, int)
        MJCF rocks simulated near the route, of those in the scene.
    stats : dict
        What the controller reports of itself (a live session: messages, bytes and write
        seconds per topic, commands, time-outs, resets, teleports, the goal's sim time).

    Examples
    --------
    >>> import marsscene as ms
    >>> from marsscene.runs import ate
    >>> cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [20, 20]}})
    >>> run = ms.drive(ms.build_scene(cfg, seed=1), command=(0.3, 0.0), seconds=3.0,
    ...                config=ms.RunConfig(noise=ms.NoiseConfig(profile="ln200s")))
    >>> run.out_dir is None, run.sim_s, run.summary["poses"]
    (True, 3.0, 151)

    The wheel odometry drifts from the ground truth; :func:`marsscene.runs.ate` measures it:

    >>> bool(ate(run.odom, run.gt, align="none").stats.max < 0.5)
    True
    """

    out_dir: Path | None
    result: DriveResult
    route: Route | None = None
    bag: BagSummary | None = None
    datasets: dict[str, Path] = field(default_factory=dict)
    wall_s: float = float("nan")
    export_s: float = 0.0
    rocks_kept: tuple[int, int] = (0, 0)
    stats: dict[str, Any] = field(default_factory=dict)

    @property
    def summary(self) -> dict[str, Any]:
        return self.result.summary

    @property
    def sim_s(self) -> float:
        """Simulated seconds driven."""
        return float(self.result.summary["sim_time_s"])

    @property
    def realtime_factor(self) -> float:
        """Sim seconds per wall second of the drive."""
        return self.sim_s / self.wall_s if self.wall_s > 0 else math.nan

    @property
    def gt(self) -> Trajectory:
        return self.result.gt

    @property
    def odom(self) -> Trajectory:
        return self.result.odom


def _route(route: Route | str | os.PathLike[str] | None) -> Route | None:
    if route is None or isinstance(route, Route):
        return route
    return Route.from_trajectory(read_tum(route))


def drive(
    scene: str | os.PathLike[str] | Scene,
    *,
    route: Route | str | os.PathLike[str] | None = None,
    waypoints: ArrayLike | None = None,
    controller: Controller | Callable[[Any], tuple[float, float]] | OnStart | None = None,
    command: tuple[float, float] | Callable[[float], tuple[float, float]] | None = None,
    seconds: float | None = None,
    config: RunConfig | None = None,
    options: DriveOptions | None = None,
    export: ExportOptions | None = None,
    out_dir: str | os.PathLike[str] | None = None,
    seed: int = 0,
    progress: Callable[[DriveProgress | ExportProgress], None] | None = None,
    keep_sensors: bool = False,
    listeners: Sequence[Any] = (),
    rover: RoverConfig | str | None = None,
) -> DriveRun:
    """Drive the rover on a scene with its sensors, then export the run.

    Parameters
    ----------
    scene : path or Scene
        A built scene folder (``marsscene build``), or a :class:`~marsscene.Scene` (written as
        MJCF into ``out_dir/scene`` first).
    route : Route or path, optional
        A route to follow (a :class:`~marsscene.sim.route.Route` or a TUM file, x and y used).
    waypoints : array_like of shape (N, 2), optional
        Instead of a route: waypoints in m through which a smooth route avoiding steep slopes
        and rocks is authored (``options.max_slope_deg``).
    controller : callable, optional
        ``controller(Observation) -> (v, omega)`` once per control period
        (:mod:`marsscene.sim.control`); with a route it steers instead of pure pursuit (the
        route then sets the start, the rock corridor and the cross-track summary). Its
        optional ``done`` attribute ends the drive. An :class:`~marsscene.sim.control.OnStart`
        makes it from the prepared simulator (the live ROS 2 bridge), and from the drive's
        route too when its ``make`` takes a ``route`` (``marsscene drive --controller``).
    command : (v, omega) or callable t -> (v, omega), optional
        An open-loop command instead.
    seconds : float, optional
        Sim-time limit; required without a route (default with one: until the goal).
    config : RunConfig, optional
        Sensors (camera, LiDAR), their rates and the noise profile (default: no camera, no
        LiDAR, noise-free).
    options : DriveOptions, optional
        Slope limit, rock corridor, settling, the follower, the start pose without a route.
    export : ExportOptions, optional
        A ROS 2 bag and dataset folders to write into the run folder (and whether the LiDAR
        scans are stored at all: ``lidar_files``).
    out_dir : path, optional
        The run folder (layout: :doc:`/runtime`); without it the drive is kept in memory.
    seed : int
        Seed of the sensor-noise stream (``stage_rng(seed, "sensors")``).
    progress : callable, optional
        Called with a :class:`~marsscene.sim.driver.DriveProgress` once per simulated second
        and an :class:`ExportProgress` per exported message or image.
    keep_sensors : bool
        Keep LiDAR scans, images and IMU samples in memory in ``result``.
    listeners : sequence, optional
        Objects receiving every sample as it is made (:mod:`marsscene.sim.session`).
    rover : RoverConfig or str, optional
        The rover type: a :class:`~marsscene.rover.config.RoverConfig` or a name for
        :meth:`RoverConfig.load <marsscene.rover.config.RoverConfig.load>` (``"mer"``); default
        the Perseverance-class rover.

    Returns
    -------
    DriveRun
        The run folder (``out_dir``), the ground-truth and odometry trajectories (``gt``,
        ``odom``), the ``summary`` (status, path length, frames, cross-track error), the
        route, and the bag and dataset folders written.

    Raises
    ------
    DriveInterrupted
        On Ctrl-C during the drive; the run folder is complete up to there (no exports),
        unless ``options.stop_on_interrupt``.
    MarsSceneError
        A missing scene, a route off the terrain, exports that cannot be written: before
        anything is driven.

    Examples
    --------
    Ten simulated seconds along a route through two waypoints, kept in memory:

    >>> import marsscene as ms
    >>> cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [20, 20]}})
    >>> scene = ms.build_scene(cfg, seed=1)
    >>> run = ms.drive(scene, waypoints=[[-4, 0], [4, 0]], seconds=10.0, seed=1)
    >>> run.summary["status"], run.sim_s
    ('complete', 10.0)
    >>> run.gt.xyz_m.shape  # ground-truth poses at 50 Hz
    (501, 3)

    A run folder with a small camera and a noisy IMU, then a TUM RGB-D dataset from it:

    >>> import tempfile
    >>> config = ms.RunConfig(camera=ms.CameraConfig(width_px=64, height_px=48, rate_hz=2.0),
    ...                       noise=ms.NoiseConfig(profile="ln200s"))
    >>> out = tempfile.mkdtemp()
    >>> run = ms.drive(scene, command=(0.3, 0.0), seconds=1.0, config=config, out_dir=out,
    ...                export=ms.ExportOptions(datasets=("tum-rgbd",)))
    >>> run.summary["camera_frames"], sorted(run.datasets)
    (3, ['tum-rgbd'])
    >>> (run.out_dir / "gt.tum").is_file()
    True
    """
    config = config if config is not None else RunConfig()
    options = options if options is not None else DriveOptions()
    export = export if export is not None else ExportOptions()
    out = Path(out_dir) if out_dir is not None else None
    check_exports(export, config, out)
    rover_cfg = RoverConfig.load(rover) if isinstance(rover, str) else rover
    with scene_dir(scene, out) as scene_path:
        sim, path = prepare_drive(scene_path, config, route=_route(route),
                                  waypoints_xy_m=waypoints, options=options, rover=rover_cfg)
        write_route(out, sim, path, options)
        ctrl, heard = started(controller, sim, path)
        with jpeg_cache(out, export, config) as cache:
            session = SessionOptions(keep_sensors=keep_sensors, lidar_files=export.lidar_files,
                                     listeners=(*listeners, *heard), jpeg_cache=cache)
            t0 = time.perf_counter()
            try:
                res = drive_sim(sim, route=path, controller=ctrl, command=command,
                                seconds=seconds, out_dir=out, rng=stage_rng(seed, "sensors"),
                                pursuit=options.pursuit, session=session, progress=progress)
            except DriveInterrupted as stop:  # Ctrl-C
                if not options.stop_on_interrupt:
                    raise
                res = stop.result
            t1 = time.perf_counter()
            bag, datasets = export_run(out, export, cache, progress)
    return DriveRun(out, res, path, bag, datasets, wall_s=t1 - t0,
                    export_s=time.perf_counter() - t1, rocks_kept=sim.rocks_kept)


