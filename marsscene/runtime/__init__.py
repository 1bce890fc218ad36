"""MuJoCo rover runtime: a Perseverance-class rover on a built scene, pure-pursuit routes,
ground-truth and sensor logs (TUM, CSV, PLY, PNG) and ATE/RPE evaluation.

``mujoco`` is imported only when :class:`RoverSim` or :func:`drive` is used; the TUM, route and
evaluation helpers are pure numpy/scipy.

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

from typing import TYPE_CHECKING, Any

from marsscene.runtime.config import (
    CameraConfig,
    LidarConfig,
    NoiseConfig,
    RoverConfig,
    RunConfig,
)
from marsscene.runtime.evaluation import (
    ATEResult,
    ErrorStats,
    RPEResult,
    associate,
    ate,
    rpe,
    umeyama,
)
from marsscene.runtime.pursuit import PurePursuit, PursuitConfig
from marsscene.runtime.route import Obstacles, Route, RouteWarning, author_route, cross_track_m
from marsscene.runtime.rover import rover_mjcf, wheel_commands
from marsscene.runtime.tum import Trajectory, read_tum, write_tum

if TYPE_CHECKING:
    from marsscene.runtime.driver import DriveResult, drive
    from marsscene.runtime.sim import RoverSim, scene_obstacles

__all__ = [
    "ATEResult",
    "CameraConfig",
    "DriveResult",
    "ErrorStats",
    "LidarConfig",
    "NoiseConfig",
    "Obstacles",
    "PurePursuit",
    "PursuitConfig",
    "RPEResult",
    "Route",
    "RouteWarning",
    "RoverConfig",
    "RoverSim",
    "RunConfig",
    "Trajectory",
    "associate",
    "ate",
    "author_route",
    "cross_track_m",
    "drive",
    "read_tum",
    "rover_mjcf",
    "rpe",
    "scene_obstacles",
    "umeyama",
    "wheel_commands",
    "write_tum",
]

_LAZY = {"RoverSim": "sim", "scene_obstacles": "sim", "drive": "driver", "DriveResult": "driver"}


def __getattr__(name: str) -> Any:  # mujoco is imported on first use of the simulator
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(f"marsscene.runtime.{_LAZY[name]}"), name)
    raise AttributeError(f"module 'marsscene.runtime' has no attribute {name!r}")
