"""marsscene: author seeded, reproducible Mars worlds for rover autonomy research.

The build side, in pipeline order (wired only by ``pipeline/``)::

    dem/ -> terrain/ -> craters/ -> rocks/ -> lighting/ -> scene.py -> export/ (USD, MJCF)

and the run side: ``sim/`` (MuJoCo rover) with ``sensors/`` -> ``runs/`` (run folder, ATE/RPE)
-> ``runs/export/`` (ROS 2 bags, SLAM datasets), driven by one call, :func:`drive`
(:mod:`marsscene.runtime`). The layers and which way imports run: :doc:`/architecture`.

Examples
--------
>>> import marsscene as ms
>>> cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [10, 10]}})
>>> ms.build_scene(cfg, seed=7).heightfield.shape
(41, 41)
>>> ms.RunConfig(lidar=ms.LidarConfig(model="vlp16")).lidar.spec.channels
16
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING

import marsscene._gl  # noqa: F401  (first: MUJOCO_GL before anything imports mujoco)
from marsscene._lazy import lazy_attributes
from marsscene._show_versions import show_versions as show_versions
from marsscene._version import __version__ as __version__
from marsscene.config import SceneConfig as SceneConfig
from marsscene.errors import MarsSceneError as MarsSceneError
from marsscene.export import write_scene as write_scene
from marsscene.pipeline import build_scene as build_scene
from marsscene.scene import Scene as Scene

if TYPE_CHECKING:
    from marsscene.dem.io import read_dem as read_dem
    from marsscene.rover.config import CameraConfig as CameraConfig
    from marsscene.rover.config import LidarConfig as LidarConfig
    from marsscene.rover.config import NoiseConfig as NoiseConfig
    from marsscene.rover.config import RunConfig as RunConfig
    from marsscene.runs.export.options import BagOptions as BagOptions
    from marsscene.runs.export.options import ExportOptions as ExportOptions
    from marsscene.runtime.api import DriveRun as DriveRun
    from marsscene.runtime.api import drive as drive
    from marsscene.runtime.team import Robot as Robot
    from marsscene.runtime.team import Scout as Scout
    from marsscene.runtime.team import TeamRun as TeamRun
    from marsscene.runtime.team import drive_team as drive_team
    from marsscene.sim.control import Observation as Observation
    from marsscene.sim.mission import DriveOptions as DriveOptions

logging.getLogger("marsscene").addHandler(logging.NullHandler())

__all__ = [
    "BagOptions",
    "BatchDrive",
    "CameraConfig",
    "DriveOptions",
    "DriveRun",
    "ExportOptions",
    "LidarConfig",
    "MarsSceneError",
    "NoiseConfig",
    "Observation",
    "Robot",
    "RunConfig",
    "Scene",
    "SceneConfig",
    "Scout",
    "TeamRun",
    "__version__",
    "build_scene",
    "drive",
    "drive_batch",
    "drive_team",
    "read_dem",
    "show_versions",
    "write_scene",
]

#: Loaded on first use: rasterio with ``read_dem``, the run side (mujoco) with ``drive``.
_LAZY = {
    "read_dem": "marsscene.dem.io",
    **dict.fromkeys(("CameraConfig", "LidarConfig", "NoiseConfig", "RunConfig"),
                    "marsscene.rover.config"),
    **dict.fromkeys(("BagOptions", "ExportOptions"), "marsscene.runs.export.options"),
    **dict.fromkeys(("DriveRun", "drive"), "marsscene.runtime.api"),
    "Observation": "marsscene.sim.control",
    "DriveOptions": "marsscene.sim.mission",
    "drive_batch": "marsscene.sim.batch.api",
    "BatchDrive": "marsscene.sim.batch.spec",
    **dict.fromkeys(("Robot", "Scout", "TeamRun", "drive_team"), "marsscene.runtime.team"),
}

__getattr__ = lazy_attributes(__name__, _LAZY)
