"""Shared fixtures: tiny synthetic inputs built in code (cf. rasterio tests/conftest.py), and the
scenes and runs the run-side tests drive on (a gentle procedural terrain, a flat plane, a 15 deg
slope, a short run with every sensor); those skip without mujoco."""

from __future__ import annotations

import os
import sys
from pathlib import Path

# Headless offscreen rendering: must be set before anything imports mujoco (any test module).
if not os.environ.get("DISPLAY"):
    os.environ.setdefault("MUJOCO_GL", "egl")

import math

import numpy as np
import pytest
from click.testing import CliRunner

import marsscene as ms
from marsscene.scene import Provenance, Scene
from marsscene.terrain.from_dem import GeoFrame
from marsscene.terrain.heightfield import Heightfield

# Bytecode caches on: an environment that sets PYTHONDONTWRITEBYTECODE (some CI images do) would
# recompile every marsscene and test module (and re-rewrite the tests' asserts) in each xdist
# worker and in each child process a test starts; they inherit this environment, and the modules
# imported from here on are cached. __pycache__/ is ignored by git.
sys.dont_write_bytecode = False
os.environ.pop("PYTHONDONTWRITEBYTECODE", None)

SHARED_REAL = Path(__file__).resolve().parents[2] / "shared" / "data" / "real"


# The parallel run (pytest-xdist, ``-n auto --dist loadfile``) hands each file to one worker, so a
# module's fixtures are built once; these folders go to one worker whole, since their files share
# a session fixture (the sweep's Dask scheduler) or loopback DDS and wall-clock pacing (ROS 2).
_FOLDER_GROUPS = ("ros2", "sweep")


def pytest_xdist_make_scheduler(config: pytest.Config, log: object) -> object | None:
    """``--dist loadfile``, with the folders of ``_FOLDER_GROUPS`` as one unit each."""
    if config.getvalue("dist") != "loadfile":
        return None
    from xdist.scheduler import LoadFileScheduling

    class _FilesAndFolders(LoadFileScheduling):
        def _split_scope(self, nodeid: str) -> str:
            path = nodeid.split("::", 1)[0]
            parts = path.split("/")
            if len(parts) > 2 and parts[0] == "tests" and parts[1] in _FOLDER_GROUPS:
                return "/".join(parts[:2])
            return path

    return _FilesAndFolders(config, log)


def pytest_xdist_auto_num_workers(config: pytest.Config) -> int:
    """``-n auto``: one worker a core this process may use, at most 8 (the longest file is
    already about a tenth of the serial run)."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return max(1, min(8, cores or 1))


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


@pytest.fixture
def runner() -> CliRunner:
    return CliRunner()


@pytest.fixture
def small_procedural_config() -> ms.SceneConfig:
    """A 20 m x 16 m procedural terrain at 0.25 m, all later stages at their defaults."""
    return ms.SceneConfig.from_dict(
        {"terrain": {"source": "procedural", "size_m": [20.0, 16.0], "post_m": 0.25}}
    )


@pytest.fixture
def synthetic_dem_path(tmp_path: Path) -> Path:
    """A 64 x 48 projected GeoTIFF DEM (a bowl plus a slope, 1 m posts, nodata corner)."""
    import rasterio
    from affine import Affine

    rows, cols = 48, 64
    yy, xx = np.mgrid[0:rows, 0:cols].astype(np.float64)
    z = -4400.0 + 0.05 * xx + 0.02 * ((xx - 32) ** 2 + (yy - 24) ** 2) ** 0.5
    z[:3, :3] = -32767.0
    crs = (
        "+proj=eqc +lat_ts=18.4 +lat_0=0 +lon_0=77.5 +x_0=0 +y_0=0 "
        "+R=3394839.8 +units=m +no_defs"
    )
    path = tmp_path / "bowl.tif"
    with rasterio.open(
        path, "w", driver="GTiff", height=rows, width=cols, count=1, dtype="float32",
        crs=crs, transform=Affine(1.0, 0.0, -32.0, 0.0, -1.0, 1_090_000.0), nodata=-32767.0,
    ) as ds:
        ds.write(z.astype(np.float32), 1)
    return path


_PROC = {
    "terrain": {"source": "procedural", "size_m": [40, 40], "post_m": 0.25, "rms_height_m": 0.05},
    "craters": {"enabled": False},
    "rocks": {"enabled": False},
}


def _write(z: np.ndarray, out: Path, cell_m: float = 0.25) -> Path:
    pytest.importorskip("mujoco")
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
    pytest.importorskip("mujoco")
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


@pytest.fixture(scope="session")
def bag_run(gentle_scene: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 3 s run folder with noisy IMU/odometry, an 80 x 60 RGB-D camera and a 3-ring LiDAR."""
    from marsscene.errors import RuntimeSimError
    from marsscene.runtime import CameraConfig, LidarConfig, NoiseConfig, RunConfig
    from marsscene.seeding import stage_rng
    from marsscene.sim.driver import drive_sim
    from marsscene.sim.rover_sim import RoverSim

    run = RunConfig(
        noise=NoiseConfig(wheel_rate_sigma_rad_s=0.05, accel_sigma_m_s2=0.05,
                          gyro_sigma_rad_s=0.01),
        camera=CameraConfig(width_px=80, height_px=60),
        lidar=LidarConfig(channels=3, horizontal_samples=90, vertical_fov_deg=(-30.0, -10.0)),
    )
    sim = RoverSim(gentle_scene, run=run)
    out = tmp_path_factory.mktemp("bagrun") / "run"
    try:
        drive_sim(sim, command=(0.3, 0.05), seconds=3.0, out_dir=out, rng=stage_rng(0, "sensors"))
    except RuntimeSimError as err:
        pytest.skip(f"no headless OpenGL (EGL/OSMesa) here: {err}")
    return out


@pytest.fixture(scope="session")
def stereo_run(bag_run: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``bag_run`` plus ``camera/left`` and ``camera/right`` folders made here (0.3 m baseline).

    The right images are the left ones shifted by 4 px, mono8; each folder has its own
    ``intrinsics.json`` with ``baseline_m``, as a stereo head would log it.
    """
    import json
    import shutil

    from marsscene.runs.logs import png_bytes
    from marsscene.runs.runlog import read_image

    out = tmp_path_factory.mktemp("stereorun") / "run"
    shutil.copytree(bag_run, out)
    cam = out / "camera"
    intr = json.loads((cam / "intrinsics.json").read_text()) | {"baseline_m": 0.3}
    lines = (cam / "stamps.csv").read_text().splitlines()[1:]
    for side in ("left", "right"):
        (cam / side / "rgb").mkdir(parents=True)
        rows = ["t,rgb"]
        for line in lines:
            t, rgb, _ = line.split(",")
            img = read_image(cam / rgb)
            mono = img.mean(axis=2).astype(np.uint8)
            if side == "right":
                mono = np.roll(mono, -4, axis=1)
            (cam / side / rgb).write_bytes(png_bytes(mono))
            rows.append(f"{t},{rgb}")
        (cam / side / "stamps.csv").write_text("\n".join(rows) + "\n")
        (cam / side / "intrinsics.json").write_text(json.dumps(intr))
    return out
