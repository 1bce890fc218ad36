"""marsscene: author seeded, reproducible Mars worlds for rover autonomy research.

The build side, in pipeline order (wired only by ``pipeline/``)::

    dem/ -> terrain/ -> craters/ -> rocks/ -> lighting/ -> scene.py -> export/ (USD, MJCF)

and the run side: ``sim/`` (MuJoCo rover) with ``sensors/`` -> ``runs/`` (run folder, ATE/RPE)
-> ``runs/export/`` (ROS 2 bags, SLAM datasets); ``marsscene.runtime`` re-exports it. The
layers and which way imports run: ``docs/architecture.md``.

Examples
--------
>>> import marsscene as ms
>>> cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [10, 10]}})
>>> ms.build_scene(cfg, seed=7).heightfield.shape
(41, 41)
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any

from marsscene._show_versions import show_versions as show_versions
from marsscene._version import __version__ as __version__
from marsscene.config import SceneConfig as SceneConfig
from marsscene.errors import MarsSceneError as MarsSceneError
from marsscene.export import write_scene as write_scene
from marsscene.pipeline import build_scene as build_scene
from marsscene.scene import Scene as Scene

if TYPE_CHECKING:
    from marsscene.dem.io import read_dem as read_dem

logging.getLogger("marsscene").addHandler(logging.NullHandler())

__all__ = [
    "MarsSceneError",
    "Scene",
    "SceneConfig",
    "__version__",
    "build_scene",
    "read_dem",
    "show_versions",
    "write_scene",
]


def __getattr__(name: str) -> Any:  # rasterio is imported only when a DEM is read
    if name == "read_dem":
        from marsscene.dem.io import read_dem

        return read_dem
    raise AttributeError(f"module 'marsscene' has no attribute {name!r}")
