"""Scenes for the runtime tests: gentle procedural terrain, a flat plane and a 15 deg slope."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest

os.environ.setdefault("MUJOCO_GL", "egl")  # before mujoco is imported (headless rendering)

pytest.importorskip("mujoco")

import marsscene as ms
from marsscene.scene import Provenance, Scene
from marsscene.terrain.from_dem import GeoFrame
from marsscene.terrain.heightfield import Heightfield

_PROC = {
    "terrain": {"source": "procedural", "size_m": [40, 40], "post_m": 0.25, "rms_height_m": 0.05},
    "craters": {"enabled": False},
    "rocks": {"enabled": False},
}


def _write(z: np.ndarray, out: Path, cell_m: float = 0.25) -> Path:
    cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [10, 10]}})
    scene = Scene(
        heightfield=Heightfield.centered(z, cell_m),
        config=cfg,
        seed=0,
        provenance=Provenance(frame=GeoFrame(0.0, None, None, "", 1.0)),
    )
    ms.write_scene(scene, out, formats=("mjcf",))
    return out


@pytest.fixture(scope="session")
def gentle_scene(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """40 m x 40 m procedural terrain, 0.05 m RMS height."""
    scene = ms.build_scene(ms.SceneConfig.from_dict(_PROC), seed=3)
    out = tmp_path_factory.mktemp("gentle") / "scene"
    ms.write_scene(scene, out, formats=("mjcf",))
    return out


@pytest.fixture(scope="session")
def flat_scene(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """30 m x 30 m perfectly flat terrain at z = 0."""
    return _write(np.zeros((121, 121), np.float32), tmp_path_factory.mktemp("flat") / "scene")


@pytest.fixture(scope="session")
def slope_scene(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """40 m (x) x 16 m (y) plane rising at 15 deg towards +x."""
    x = (np.arange(161) - 80) * 0.25
    z = np.tile(math.tan(math.radians(15.0)) * x, (65, 1)).astype(np.float32)
    return _write(z, tmp_path_factory.mktemp("slope") / "scene")
