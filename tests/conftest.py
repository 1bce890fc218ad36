"""Shared fixtures: tiny synthetic inputs built in code (cf. rasterio tests/conftest.py), and the
scenes and runs the run-side tests drive on (a gentle procedural terrain, a flat plane, a 15 deg
slope, a short run with every sensor); those skip without mujoco."""

from __future__ import annotations

import os
import sys
from collections.abc import Callable
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
from tests.support.session_cache import shared_folder

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


#: The slow tier: drives, renders, DDS, the Asset Validator and the documentation site. A bare
#: ``python -m pytest`` (or one naming folders) leaves these out; ``python -m pytest -m slow``
#: runs them alone, ``-m "slow or not slow"`` runs both tiers, and a file or test named on the
#: command line runs whole. Keys are folders, files, ``file::test`` (every parameter of the
#: test) or one parametrised case, ``file::test[id]``; ``@pytest.mark.slow`` in a test file
#: marks one the same way. Durations of both tiers: the changelog.
SLOW_TESTS = {
    "tests/docs": "the built site: links, notebooks, browser",
    "tests/env/test_batch_sensing.py::test_same_seed_same_bytes_and_bad_input":
        "BatchCamera twice, 16 s",
    "tests/sim/batch/test_batch_drive.py": "batch drives on Warp's CPU device",
    "tests/benchmark/nav/test_nav_run.py::test_run_scores_and_writes": "navigation episodes",
    "tests/benchmark/nav/test_nav_run.py::test_resume_skips_done_episodes": "navigation episodes",
    "tests/benchmark/loc/test_run.py::test_a_tiny_cli_run_end_to_end_and_resume":
        "loc queries and CLI",
    "tests/scout/test_scout.py::"
    "test_the_controller_reaches_each_waypoint_and_lands_on_the_terrain": "a scout flight",
    "tests/scout/test_scout.py::"
    "test_run_folder_has_poses_images_and_altimeter_and_repeats_byte_for_byte": "two scout flights",
    "tests/test_notebooks.py": "executes the gallery notebooks",
    "tests/ros2": "loopback DDS at wall-clock rates",
    "tests/usd_clients": "Newton loads and steps the stages",
    "tests/benchmark/test_vpr.py::test_generate_and_evaluate_end_to_end": "VPR drives, 210 s",
    "tests/benchmark/test_vpr.py::test_distance_triggered_capture_spacing": "a camera drive",
    "tests/benchmark/test_kiss_icp.py": "KISS-ICP on an 8 m LiDAR drive",
    "tests/benchmark/test_baselines.py": "a 10 s RGB-D + LiDAR drive and Open3D",
    "tests/benchmark/test_slam_run.py": "benchmark cells: builds, drives, methods",
    "tests/benchmark/test_slam_storage.py::test_cell_storage_and_resume": "a benchmark cell",
    "tests/benchmark/test_route_lengths.py::test_any_length_is_authored_or_refused":
        "routes authored on many scenes",
    "tests/benchmark/test_route_lengths.py::test_the_short_routes_that_crashed_are_refused_in_one_line":
        "scenes built for each length",
    "tests/sim/test_long_drive.py::test_killed_drive_leaves_a_usable_prefix": "drives killed",
    "tests/sim/test_long_drive.py::test_ctrl_c_finishes_the_run_folder": "a drive interrupted",
    "tests/sim/test_wheel_soil.py::test_slip_on_a_slope_matches_the_single_wheel_theory":
        "slope drives per soil",
    "tests/sim/test_wheel_soil.py::test_odometry_overestimates_where_wheels_slip_and_the_log_says_why":
        "a slipping drive",
    "tests/sim/test_wheel_soil.py::test_a_parked_rover_holds_on_a_slope_as_on_rigid_ground":
        "a parked rover settling",
    "tests/runtime/test_bag_drive.py::test_drive_bag_equals_bag_of_the_run_and_reads_the_drives_jpegs":
        "a camera drive and its bag",
    "tests/runtime/test_bag_drive.py::test_interrupt_while_writing_the_bag_keeps_the_run_and_removes_the_cache":
        "a drive interrupted in its bag",
    "tests/runtime/test_drive_api.py::test_a_controller_drive_equals_the_route_drive_it_reproduces":
        "two drives",
    "tests/rover/test_noise_profiles.py::test_noise_free_export_floors_orbslam3_and_says_so":
        "a sensor drive",
    "tests/rover/test_noise_profiles.py::test_drive_with_a_profile_is_deterministic_and_recorded":
        "two sensor drives",
    "tests/assets/test_assets.py::test_rover_route_goes_around_the_habitat": "a drive",
    "tests/sensors/test_camera_rock_shadow.py": "renders against an exact shadow",
    "tests/sensors/test_camera_low_sun.py": "low-sun renders",
    "tests/sensors/test_offscreen_geoms.py": "renders",
    "tests/sensors/test_camera_rover_shadow.py": "renders of the rover's shadow",
    "tests/sensors/test_camera.py::test_image_statistics_tracking_and_rgbd_vo":
        "a camera drive and visual odometry",
    "tests/sensors/test_camera.py::test_sensor_noise_is_seeded": "camera drives",
    "tests/sensors/test_camera.py::test_camera_images_are_deterministic_and_dust_darkens":
        "camera drives",
    "tests/sensors/test_camera.py::test_one_pass_depth_equals_mujoco_renderer_depth": "renders",
    "tests/sensors/test_sensors.py::test_far_window_bounds_replays_the_cameras_window": "renders",
    "tests/sensors/test_sensors.py::test_camera_terrain_window_matches_full_render": "renders",
    "tests/export/test_lod_export.py::test_lod_stage_passes_the_omniverse_asset_validator":
        "the Asset Validator on a LoD stage",
    "tests/sensors/test_camera.py::test_stereo_pair_is_rectified_with_navcam_baseline":
        "the stereo camera drive",
    "tests/sensors/test_camera.py::test_stereo_drive_becomes_stereo_bag_topics":
        "the stereo camera drive",
    "tests/sensors/test_sensors.py::test_camera_rgbd": "RGB-D renders",
    "tests/runtime/test_drive_api.py::test_turning_the_camera_off_leaves_the_lidar_noise_as_it_was":
        "three sensor drives",
    "tests/runtime/test_drive_api.py::test_the_observation_holds_what_the_run_logs_before_its_time":
        "the sensor drives",
    "tests/sim/test_pursuit.py::test_pure_pursuit_20m_square": "an 80 m drive",
    "tests/rocks/test_rock_collision.py::test_multi_part_prototype_exports": "CoACD",
    "tests/rover/test_noise_profiles.py::test_exports_declare_the_simulated_noise":
        "a sensor drive",
    "tests/export/test_lod_export.py::test_camera_model_has_no_terrain_hfields": "a LoD build",
    "tests/export/test_usd_interop.py::test_asset_validator_reports_no_issues":
        "the Asset Validator",
    "tests/env/test_nav_env.py::test_every_registered_id_passes_gymnasiums_checker"
    "[marsscene/RoverNavCamera-v0]": "camera renders",
    "tests/sweep/test_sweep_dask.py::test_local_cluster_cells_equal_serial_builds":
        "a local Dask cluster's builds",
    "tests/sweep/test_sweep_dask.py::test_remote_scheduler_gives_the_same_bytes":
        "builds on a remote scheduler",
    "tests/env/test_batch_env.py::test_same_seed_same_bytes": "two batches on Warp's CPU device",
}


def _slow_entry(nodeid: str) -> bool:
    path, _, name = nodeid.partition("::")
    name = name.split("[", 1)[0]
    parts = path.split("/")
    return any(prefix in SLOW_TESTS for prefix in
               ("/".join(parts[:k]) for k in range(1, len(parts) + 1))) or \
        f"{path}::{name}" in SLOW_TESTS or nodeid in SLOW_TESTS


def _names_files(config: pytest.Config) -> bool:
    """Whether the command line names a test file or a test (not only folders)."""
    for arg in config.args:
        path = Path(arg.split("::", 1)[0])
        if "::" in arg or path.suffix == ".py":
            return True
    return False


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Mark the tests of :data:`SLOW_TESTS`; leave the slow tier out of a plain run."""
    for item in items:
        if _slow_entry(item.nodeid):
            item.add_marker(pytest.mark.slow)
    if config.getoption("markexpr") or _names_files(config):
        return
    slow = [item for item in items if item.get_closest_marker("slow")]
    if slow:
        config.hook.pytest_deselected(items=slow)
        items[:] = [item for item in items if not item.get_closest_marker("slow")]


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


# The session's scenes and runs are built once for all xdist workers (tests only read them).
@pytest.fixture(scope="session")
def gentle_scene(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """40 m x 40 m procedural terrain, 0.05 m RMS height."""
    pytest.importorskip("mujoco")

    def build(folder: Path) -> None:
        scene = ms.build_scene(ms.SceneConfig.from_dict(_PROC), seed=3)
        ms.write_scene(scene, folder / "scene", formats=("mjcf",))

    return shared_folder(tmp_path_factory, "gentle", [_PROC, 3], build) / "scene"


def _plane(tmp_path_factory: pytest.TempPathFactory, name: str,
           heights: Callable[[], np.ndarray]) -> Path:
    """The MJCF scene of the plane ``heights()`` (0.25 m posts), built once a session."""
    pytest.importorskip("mujoco")
    folder = shared_folder(tmp_path_factory, name, name,
                           lambda folder: _write(heights(), folder / "scene"))
    return folder / "scene"


@pytest.fixture(scope="session")
def flat_scene(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """30 m x 30 m perfectly flat terrain at z = 0."""
    return _plane(tmp_path_factory, "flat", lambda: np.zeros((121, 121), np.float32))


def _slope_15deg() -> np.ndarray:
    x = (np.arange(161) - 80) * 0.25
    return np.tile(math.tan(math.radians(15.0)) * x, (65, 1)).astype(np.float32)


@pytest.fixture(scope="session")
def slope_scene(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """40 m (x) x 16 m (y) plane rising at 15 deg towards +x."""
    return _plane(tmp_path_factory, "slope", _slope_15deg)


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

    def build(folder: Path) -> None:
        sim = RoverSim(gentle_scene, run=run)
        try:
            drive_sim(sim, command=(0.3, 0.05), seconds=3.0, out_dir=folder / "run",
                      rng=stage_rng(0, "sensors"))
        except RuntimeSimError as err:
            pytest.skip(f"no headless OpenGL (EGL/OSMesa) here: {err}")

    return shared_folder(tmp_path_factory, "bagrun", [str(gentle_scene), repr(run)],
                         build) / "run"


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

    def build(folder: Path) -> None:
        out = folder / "run"
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

    return shared_folder(tmp_path_factory, "stereorun", str(bag_run), build) / "run"
