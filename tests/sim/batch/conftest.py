"""Two small scenes and a batch of three drives on them, driven once a session on Warp's CPU
device (no GPU): 0.6 sim s at 100 Hz physics with a VLP-16, a 32 x 24 RGB-D camera and the
LN-200S noise, twice (the second in other folders, for the same-seed test). Drives ``c`` and
``d`` repeat drive ``a``'s scene and route, ``c`` under heavy dust (tau = 6), ``d`` under a sun
8 deg above the horizon; the camera's exposure is fixed, so light shows as light, and it has
sensor noise."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from tests.support.session_cache import shared_folder

pytest.importorskip("mujoco_warp")

_BASE = {"terrain": {"source": "procedural", "size_m": [20.0, 20.0], "post_m": 0.25,
                     "rms_height_m": 0.05},
         "craters": {"enabled": False}, "rocks": {"k": 0.05, "mjcf_min_diameter_m": 0.3}}
SECONDS = 0.6
WAYPOINTS = ([[-4.0, 0.0], [4.0, 0.0]], [[0.0, -4.0], [0.0, 4.0]])
DUST_TAU = 6.0
LOW_SUN_DEG = 8.0


@pytest.fixture(scope="session")
def batch_scenes(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    from marsscene.env import WorldSampler

    def sampler(folder: Path) -> WorldSampler:
        return WorldSampler(base=_BASE, count=2, seed=3, cache_dir=str(folder))

    folder = shared_folder(tmp_path_factory, "batchdrives", [_BASE, 3],
                           lambda f: [sampler(f).path(i) for i in range(2)])
    return [sampler(folder).path(i) for i in range(2)]


def run_config() -> Any:
    import marsscene as ms

    return ms.RunConfig(physics_hz=100.0, lidar=ms.LidarConfig(model="vlp16"),
                        camera=ms.CameraConfig(width_px=32, height_px=24, rate_hz=5.0,
                                               exposure="fixed", sensor_noise=True),
                        noise=ms.NoiseConfig(profile="ln200s"))


def drive_pair(scenes: list[Path], out: Path) -> Any:
    import marsscene as ms
    from marsscene.sim.batch import BatchDrive, drive_batch

    drives = [BatchDrive(scene=s, waypoints=w, out_dir=out / name, seed=seed, seconds=SECONDS,
                         tau=tau, sun_elevation_deg=sun)
              for s, w, name, seed, tau, sun in zip(
                  (*scenes, scenes[0], scenes[0]), (*WAYPOINTS, WAYPOINTS[0], WAYPOINTS[0]),
                  "abcd", (1, 2, 3, 4), (None, None, DUST_TAU, None),
                  (None, None, None, LOW_SUN_DEG), strict=True)]
    return drive_batch(drives, config=run_config(), device="cpu", seed=5,
                       options=ms.DriveOptions(settle_s=0.2), workers=2)


@pytest.fixture(scope="session")
def batch_seconds() -> float:
    return SECONDS


@pytest.fixture(scope="session")
def batch_runs(batch_scenes: list[Path], tmp_path_factory: pytest.TempPathFactory) -> Any:
    """The batch driven twice: (first, second)."""
    root = tmp_path_factory.mktemp("batch_runs")
    return drive_pair(batch_scenes, root / "one"), drive_pair(batch_scenes, root / "two")
