"""MuJoCo rover runtime, the public face of the run side: a Perseverance-class rover on a built
scene, pure-pursuit routes, ground-truth and sensor logs (TUM, CSV, PLY, PNG) and ATE/RPE
evaluation. The code lives in :mod:`marsscene.rover` (configuration, geometry),
:mod:`marsscene.sensors`, :mod:`marsscene.sim`, :mod:`marsscene.runs` and
:mod:`marsscene.runs.export` (docs/architecture.md); this module re-exports the public names, and
``import marsscene.runtime.<old module>`` still works with a DeprecationWarning.

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

import importlib
import importlib.abc
import importlib.util
import sys
import types
import warnings
from typing import TYPE_CHECKING, Any

from marsscene.rover.config import (
    CameraConfig,
    LidarConfig,
    NoiseConfig,
    RoverConfig,
    RunConfig,
)
from marsscene.rover.geometry import wheel_commands
from marsscene.runs.evaluation import (
    ATEResult,
    ErrorStats,
    RPEResult,
    associate,
    ate,
    rpe,
    umeyama,
)
from marsscene.runs.tum import Trajectory, read_tum, write_tum
from marsscene.sim.pursuit import PurePursuit, PursuitConfig
from marsscene.sim.route import Obstacles, Route, RouteWarning, author_route, cross_track_m
from marsscene.sim.rover_model import rover_mjcf

if TYPE_CHECKING:
    from marsscene.sim.driver import DriveResult, drive
    from marsscene.sim.rover_sim import RoverSim, scene_obstacles

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

_LAZY = {
    "RoverSim": "marsscene.sim.rover_sim",
    "scene_obstacles": "marsscene.sim.rover_sim",
    "drive": "marsscene.sim.driver",
    "DriveResult": "marsscene.sim.driver",
}

#: Modules of the old flat ``runtime/`` folder and where they live now (docs/architecture.md).
MOVED_MODULES = {
    "config": "marsscene.rover.config",
    "transforms": "marsscene.transforms",
    "tum": "marsscene.runs.tum",
    "logs": "marsscene.runs.logs",
    "runlog": "marsscene.runs.runlog",
    "evaluation": "marsscene.runs.evaluation",
    "camera": "marsscene.sensors.camera",
    "camera_world": "marsscene.sensors.camera_world",
    "camera_ground": "marsscene.sensors.camera_ground",
    "camera_scene": "marsscene.sensors.camera_scene",
    "exposure": "marsscene.sensors.exposure",
    "offscreen": "marsscene.sensors.offscreen",
    "raycast": "marsscene.sensors.raycast",
    "sensors": "marsscene.sensors.lidar",
    "sim": "marsscene.sim.rover_sim",
    "rover": "marsscene.sim.rover_model",
    "driver": "marsscene.sim.driver",
    "pursuit": "marsscene.sim.pursuit",
    "route": "marsscene.sim.route",
    "corridor": "marsscene.sim.corridor",
    "mission": "marsscene.sim.mission",
    "bag": "marsscene.runs.export.bag",
    "bag_topics": "marsscene.runs.export.bag_topics",
    "bag_data": "marsscene.runs.export.bag_data",
    "frames": "marsscene.runs.export.frames",
    "datasets": "marsscene.runs.export.datasets",
}


def __getattr__(name: str) -> Any:  # mujoco is imported on first use of the simulator
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'marsscene.runtime' has no attribute {name!r}")


class _MovedModuleFinder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """``import marsscene.runtime.<old>`` still works, with a DeprecationWarning naming the
    module's new home."""

    def find_spec(self, fullname: str, path: Any, target: Any = None) -> Any:
        prefix, _, leaf = fullname.rpartition(".")
        if prefix != __name__ or leaf not in MOVED_MODULES:
            return None
        return importlib.util.spec_from_loader(fullname, self)

    def create_module(self, spec: Any) -> types.ModuleType:
        new = MOVED_MODULES[spec.name.rpartition(".")[2]]
        warnings.warn(f"{spec.name} moved to {new}; import it from there (or use the names "
                      "re-exported by marsscene.runtime)", DeprecationWarning, stacklevel=2)
        return importlib.import_module(new)

    def exec_module(self, module: types.ModuleType) -> None:
        pass


if not any(isinstance(f, _MovedModuleFinder) for f in sys.meta_path):
    sys.meta_path.append(_MovedModuleFinder())
