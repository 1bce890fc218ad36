"""The run side's public face: drive a Perseverance-class rover on a built scene.

:func:`drive` is the one call (a scene, a route or a controller, a :class:`RunConfig`, export
options) that the command line, sweeps and benchmarks use too; :func:`marsscene.drive` is the
same function. The pieces it wires are importable for finer control: the simulator
(:class:`RoverSim`), the steppable loop (:class:`DriveSession`), the controller seam
(:class:`Observation`, :class:`Controller`), routes, and trajectory evaluation (:func:`ate`,
:func:`rpe`). Code lives in :mod:`marsscene.rover`, :mod:`marsscene.sensors`,
:mod:`marsscene.sim`, :mod:`marsscene.runs` and :mod:`marsscene.runs.export`
(:doc:`/architecture`).

``mujoco`` is imported only when something that simulates is used; configs, routes, TUM files
and the evaluation are pure numpy/scipy.

Examples
--------
>>> from marsscene.runtime import Trajectory, ate
>>> import numpy as np
>>> t = np.arange(5.0)
>>> gt = Trajectory(t, np.c_[t, 0 * t, 0 * t], np.tile([0, 0, 0, 1.0], (5, 1)))
>>> round(ate(gt, gt).stats.rmse, 9)
0.0
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from marsscene._lazy import lazy_attributes
from marsscene.rover.config import CameraConfig, LidarConfig, NoiseConfig, RoverConfig, RunConfig
from marsscene.runs.evaluation import ate, rpe
from marsscene.runs.export.options import BagOptions, ExportOptions
from marsscene.runs.tum import Trajectory, read_tum, write_tum
from marsscene.sim.control import Controller, Observation, OnStart, OpenLoop
from marsscene.sim.mission import DriveOptions
from marsscene.sim.pursuit import PurePursuit, PursuitConfig
from marsscene.sim.route import Obstacles, Route, author_route

if TYPE_CHECKING:
    from marsscene.runtime.api import DriveRun, ExportProgress, drive
    from marsscene.runtime.team import Robot, Scout, TeamRun, drive_team
    from marsscene.sim.driver import DriveInterrupted, DriveProgress, DriveResult, drive_sim
    from marsscene.sim.rover_sim import RoverSim
    from marsscene.sim.session import DriveSession, SessionOptions
    from marsscene.sim.world import SceneWorld, load_world

__all__ = [
    "BagOptions",
    "CameraConfig",
    "Controller",
    "DriveInterrupted",
    "DriveOptions",
    "DriveProgress",
    "DriveResult",
    "DriveRun",
    "DriveSession",
    "ExportOptions",
    "ExportProgress",
    "LidarConfig",
    "NoiseConfig",
    "Observation",
    "Obstacles",
    "OnStart",
    "OpenLoop",
    "PurePursuit",
    "PursuitConfig",
    "Robot",
    "Route",
    "RoverConfig",
    "RoverSim",
    "RunConfig",
    "SceneWorld",
    "Scout",
    "SessionOptions",
    "TeamRun",
    "Trajectory",
    "ate",
    "author_route",
    "drive",
    "drive_sim",
    "drive_team",
    "load_world",
    "read_tum",
    "rpe",
    "write_tum",
]

#: Names whose modules import mujoco: loaded on first use.
_LAZY = {
    "drive": "marsscene.runtime.api",
    "DriveRun": "marsscene.runtime.api",
    "ExportProgress": "marsscene.runtime.api",
    **dict.fromkeys(("Robot", "Scout", "TeamRun", "drive_team"), "marsscene.runtime.team"),
    "drive_sim": "marsscene.sim.driver",
    "DriveInterrupted": "marsscene.sim.driver",
    "DriveProgress": "marsscene.sim.driver",
    "DriveResult": "marsscene.sim.driver",
    "RoverSim": "marsscene.sim.rover_sim",
    "DriveSession": "marsscene.sim.session",
    "SessionOptions": "marsscene.sim.session",
    "SceneWorld": "marsscene.sim.world",
    "load_world": "marsscene.sim.world",
}


__getattr__ = lazy_attributes(__name__, _LAZY)
