"""``marsscene.drive``: the one drive call, its controller seam, listeners, and the option types.

Every wiring site (the command line, sweep cells, SLAM benchmark cells, VPR traversals) drives
through it; a controller sees what the drive logs; exports that cannot be written are refused
before anything is driven.
"""

from __future__ import annotations

import ast
import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import marsscene as ms
from marsscene.errors import ConfigError, ExportError, MarsSceneError, RuntimeSimError
from marsscene.runs.runlog import RunLog, read_numeric_csv
from marsscene.runs.tum import read_tum
from marsscene.sim.pursuit import PurePursuit
from marsscene.sim.route import Route

ROOT = Path(__file__).resolve().parents[2]
WP = [[-8.0, -8.0], [-2.0, -8.0]]


class _Called(Exception):
    """Raised by the stand-in drive: the call site reached it."""


def _spy(calls: list[dict]):
    def drive(scene, **kw):
        calls.append({"scene": scene, **kw})
        raise _Called

    return drive


def test_the_four_call_sites_drive_through_ms_drive(gentle_scene, tmp_path, monkeypatch, runner):
    """The command line, a sweep cell, a SLAM benchmark cell and a VPR traversal each call
    :func:`marsscene.drive` (a stand-in records the call)."""
    from marsscene.benchmark.slam import cell as slam_cell
    from marsscene.benchmark.slam.spec import SlamSpec
    from marsscene.benchmark.vpr import dataset as vpr_dataset
    from marsscene.benchmark.vpr.spec import VprSpec
    from marsscene.cli import main
    from marsscene.sweep.drive import drive_cell
    from marsscene.sweep.spec import DriveSpec

    calls: list[dict] = []
    monkeypatch.setattr("marsscene.runtime.api.drive", _spy(calls))
    wp = tmp_path / "wp.txt"
    wp.write_text("-8 -8\n-2 -8\n")
    res = runner.invoke(main, ["drive", str(gentle_scene), "--waypoints", str(wp), "--lidar",
                               "--bag", "--seed", "5", "--out", str(tmp_path / "r")])
    assert isinstance(res.exception, _Called), res.output
    assert calls[-1]["seed"] == 5 and calls[-1]["export"].bag == ms.BagOptions()
    with pytest.raises(_Called):
        drive_cell(gentle_scene, DriveSpec(waypoints=((-8.0, -8.0), (-2.0, -8.0))),
                   tmp_path / "cell")
    spec = SlamSpec.from_dict({
        "sensors": {"lidar": {}}, "scenes": [{"name": "g", "route": {"waypoints": WP}}],
        "methods": [{"name": "w", "kind": "wheel-odometry"}, {"name": "k", "kind": "kiss-icp"}]})
    cell_dir = tmp_path / "slam"
    (cell_dir / "scene").mkdir(parents=True)
    with pytest.raises(_Called):
        slam_cell._drive(spec, spec.scenes[0], cell_dir, True, "hash", True,
                         live=tuple(m for m in spec.methods if m.kind == "kiss-icp"))
    # KISS-ICP runs during the drive: no bag, no stored scans, a live listener
    assert calls[-1]["export"].bag is None and not calls[-1]["export"].lidar_files
    assert [type(x).__name__ for x in calls[-1]["listeners"]] == ["LiveKissIcp"]
    vpr = VprSpec.from_toml("dust")
    with pytest.raises(_Called):
        vpr_dataset._traverse(vpr, "database", vpr.database, gentle_scene,
                              Route(np.array(WP)), 0.5, 2.0, tmp_path / "v", None)
    assert calls[-1]["config"].camera.trigger_distance_m == vpr.spacing_m
    assert len(calls) == 4


#: Pieces of a drive that only ``marsscene.runtime.api`` wires together.
_WIRING_NAMES = {"drive_sim", "prepare_drive", "DriveSession", "JpegCache", "write_bag",
                 "export_dataset", "stage_rng", "scene_dir", "jpeg_cache", "export_run"}
#: Where a piece may still be imported, and why: ``marsscene bag`` and ``marsscene export``
#: convert existing run folders, and so does a SLAM benchmark cell (its finished drive's
#: datasets, a stage of their own so that a killed export resumes without a new drive; and a
#: batch drive's bag, written from its finished folder: ``benchmark/slam/device.py``); a
#: Gymnasium environment steps a session itself (one control period per ``step``), its world
#: and start drawn by its task, not a drive.
_ALLOWED = {("cli", "bag.py", "write_bag"), ("cli", "export.py", "export_dataset"),
            ("benchmark", "cell.py", "export_dataset"), ("benchmark", "device.py", "write_bag"),
            ("env", "nav.py", "DriveSession"), ("env", "episode.py", "DriveSession")}
#: The packages that make the drive's pieces (and the run side's API that wires them).
_PIECES = {"runtime", "sim", "runs", "sensors", "rover", "testing"}


def _uses_the_run_side(package: Path) -> bool:
    """Whether a package imports the run side at all (the build side's packages do not: they
    sit below it, and ``stage_rng`` seeds their own stages)."""
    for path in package.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith(
                    ("marsscene.sim", "marsscene.runtime", "marsscene.runs")):
                return True
    return False


def _packages() -> list[str]:
    return sorted(p.name for p in (ROOT / "marsscene").iterdir()
                  if (p / "__init__.py").is_file() and p.name not in _PIECES
                  and _uses_the_run_side(p))


def test_every_package_is_checked():
    """Every package on the run side is checked below (the list is not hand-kept)."""
    assert {"cli", "sweep", "benchmark", "ros2", "env"} <= set(_packages())


@pytest.mark.parametrize("package", _packages())
def test_no_package_wires_a_drive_itself(package):
    """No package but ``marsscene.runtime`` imports the drive's pieces (see ``_ALLOWED``)."""
    found = []
    for path in sorted((ROOT / "marsscene" / package).rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom):
                found += [f"{path.name}: {a.name}" for a in node.names if a.name in _WIRING_NAMES
                          and (package, path.name, a.name) not in _ALLOWED]
    assert found == []


# ---- the controller seam -----------------------------------------------------------------------
class _Recorder:
    """Pure pursuit on the observation's ground truth, recording every observation."""

    def __init__(self, route: Route) -> None:
        self.follow = PurePursuit(route)
        self.seen: list = []

    @property
    def done(self) -> bool:
        return self.follow.done

    def __call__(self, obs):
        self.seen.append((obs.t_s, obs.odom_xyz_m.copy(), obs.gt_xyz_m.copy(), obs.imu_t_s,
                          obs.camera.t_s if obs.camera is not None else None,
                          obs.lidar["t"] if obs.lidar is not None else None))
        return self.follow(obs)


def _seam_config(camera: bool) -> ms.RunConfig:
    return ms.RunConfig(camera=ms.CameraConfig(width_px=64, height_px=48, rate_hz=5.0)
                        if camera else None,
                        lidar=ms.LidarConfig(channels=4, horizontal_samples=64,
                                             vertical_fov_deg=(-20.0, -5.0), rate_hz=5.0),
                        noise=ms.NoiseConfig(profile="ln200s"))


@pytest.fixture(scope="module")
def route_pair(gentle_scene, tmp_path_factory):
    """The same route driven by pure pursuit and by a controller wrapping it, with camera and
    LiDAR: (route run, controller run, the controller)."""
    root = tmp_path_factory.mktemp("seam")
    config = _seam_config(camera=True)
    try:
        by_route = ms.drive(gentle_scene, waypoints=WP, seconds=6.0, config=config,
                            out_dir=root / "route", seed=3)
    except RuntimeSimError as err:
        pytest.skip(f"no headless OpenGL here: {err}")
    ctrl = _Recorder(by_route.route)
    by_ctrl = ms.drive(gentle_scene, route=by_route.route, controller=ctrl, seconds=6.0,
                       config=config, out_dir=root / "ctrl", seed=3)
    return by_route, by_ctrl, ctrl


def test_a_controller_drive_equals_the_route_drive_it_reproduces(route_pair):
    by_route, by_ctrl, _ = route_pair
    for name in ("gt.tum", "odom.tum", "cmd.csv", "imu.csv", "wheels.csv", "lidar/stamps.csv",
                 "camera/stamps.csv", "lidar/000003.ply", "camera/rgb/000004.png"):
        assert (by_ctrl.out_dir / name).read_bytes() == \
            (by_route.out_dir / name).read_bytes(), name
    meta = json.loads((by_ctrl.out_dir / "run.json").read_text())
    assert meta["controller"].endswith("_Recorder") and meta["pursuit"] is None
    assert json.loads((by_route.out_dir / "run.json").read_text())["pursuit"]["lookahead_m"] == 1


def test_turning_the_camera_off_leaves_the_lidar_noise_as_it_was(route_pair, gentle_scene,
                                                                  tmp_path):
    # each sensor draws from its own fixed child stream: a LiDAR-only drive of the same seed
    # scans as the camera + LiDAR drive does, noise and all
    by_route, _, _ = route_pair
    lidar_only = ms.drive(gentle_scene, route=by_route.route, seconds=6.0,
                          config=_seam_config(camera=False), out_dir=tmp_path / "r", seed=3)
    for name in ("imu.csv", "lidar/stamps.csv", "lidar/000003.ply", "lidar/000020.ply"):
        assert (lidar_only.out_dir / name).read_bytes() == \
            (by_route.out_dir / name).read_bytes(), name


def test_the_observation_holds_what_the_run_logs_before_its_time(route_pair):
    _, by_ctrl, ctrl = route_pair
    t = np.array([s[0] for s in ctrl.seen])
    np.testing.assert_allclose(np.diff(t), 0.02, atol=1e-9)  # every 50 Hz control step
    gt, odom = read_tum(by_ctrl.out_dir / "gt.tum"), read_tum(by_ctrl.out_dir / "odom.tum")
    assert len(gt) == len(ctrl.seen)
    np.testing.assert_allclose(np.array([s[2] for s in ctrl.seen]), gt.xyz_m, atol=1e-6)
    np.testing.assert_allclose(np.array([s[1] for s in ctrl.seen]), odom.xyz_m, atol=1e-6)
    imu_t = read_numeric_csv(by_ctrl.out_dir / "imu.csv", 7)[:, 0]
    for ti, imu_ti, cam_ti, lidar_ti in ((s[0], s[3], s[4], s[5]) for s in ctrl.seen[1:]):
        assert imu_ti == pytest.approx(imu_t[imu_t < ti - 1e-9][-1], abs=1e-6)  # newest before t
        assert cam_ti is None or ti - 0.2 - 1e-9 <= cam_ti < ti  # 5 Hz camera
        assert lidar_ti is None or ti - 0.4 - 1e-9 <= lidar_ti < ti  # newest finished scan
    assert ctrl.seen[0][3] is None and ctrl.seen[0][4] is None  # nothing sampled before t = 0
    assert sum(s[4] is not None for s in ctrl.seen) > len(ctrl.seen) - 12


class _StopAfter:
    """Drives straight on the odometry alone and stops 2 m from where it started."""

    done = False

    def __call__(self, obs):
        if obs.step == 0:
            self.start = obs.odom_xyz_m[:2].copy()
        self.done = float(np.hypot(*(obs.odom_xyz_m[:2] - self.start))) >= 2.0
        return (0.0, 0.0) if self.done else (0.4, 0.0)


def test_a_closed_loop_controller_ends_the_drive(flat_scene, tmp_path):
    run = ms.drive(flat_scene, controller=_StopAfter(), seconds=30.0,
                   options=ms.DriveOptions(start_xy_m=(-5.0, 0.0)), out_dir=tmp_path / "r")
    s = run.summary
    assert s["goal_reached"] is True and s["sim_time_s"] < 10.0
    assert 1.9 < s["path_length_m"] < 2.2
    assert abs(run.gt.xyz_m[0, 0] + 5.0) < 0.05 and not (tmp_path / "r" / "route.tum").exists()


class _Counter:
    def __init__(self) -> None:
        self.n = {"control": 0, "imu": 0, "lidar": 0}

    def control(self, *a):
        self.n["control"] += 1

    def imu(self, *a):
        self.n["imu"] += 1

    def lidar(self, t, i, scan):
        self.n["lidar"] += 1
        assert {"xyz_m", "range_m", "intensity", "ring", "t_s"} <= set(scan)


def test_listeners_receive_every_sample_the_run_folder_holds(flat_scene, tmp_path):
    counter = _Counter()
    config = ms.RunConfig(lidar=ms.LidarConfig(channels=2, horizontal_samples=32))
    run = ms.drive(flat_scene, command=(0.3, 0.0), seconds=1.0, config=config,
                   out_dir=tmp_path / "r", listeners=[counter])
    log = RunLog(run.out_dir)
    assert counter.n == {"control": len(log.gt), "imu": len(log.imu),
                         "lidar": len(log.lidar[0])}


def test_a_drive_kept_in_memory_equals_the_streamed_one(flat_scene, tmp_path):
    a = ms.drive(flat_scene, command=lambda t: (0.3, 0.05 * math.sin(t)), seconds=2.0,
                 out_dir=tmp_path / "r", seed=2,
                 config=ms.RunConfig(noise=ms.NoiseConfig(profile="ln200s")))
    b = ms.drive(flat_scene, command=lambda t: (0.3, 0.05 * math.sin(t)), seconds=2.0, seed=2,
                 config=ms.RunConfig(noise=ms.NoiseConfig(profile="ln200s")))
    assert b.out_dir is None
    np.testing.assert_allclose(a.odom.xyz_m, b.odom.xyz_m, atol=1e-6)
    np.testing.assert_allclose(a.gt.xyz_m, b.gt.xyz_m, atol=1e-6)


def test_a_built_scene_is_written_beside_the_run(tmp_path):
    cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [20, 20]},
                                    "rocks": {"enabled": False}})
    run = ms.drive(ms.build_scene(cfg, seed=2), command=(0.2, 0.0), seconds=0.5,
                   out_dir=tmp_path / "r")
    assert (tmp_path / "r" / "scene" / "mjcf" / "scene.xml").is_file()
    assert run.summary["poses"] == 26


@pytest.mark.parametrize(("kw", "message"), [
    ({"controller": 3, "seconds": 1.0}, "is not callable"),
    ({"controller": lambda o: (0, 0), "command": (0.1, 0.0), "seconds": 1.0}, "not both"),
    ({"command": (0.1, 0.0)}, "seconds"),
    ({"seconds": 1.0}, "route, a command or a controller"),
    ({"controller": lambda o: (float("nan"), 0.0), "seconds": 1.0}, "controller returned"),
    ({"controller": lambda o: "go", "seconds": 1.0}, "controller returned"),
])
def test_bad_drives_are_one_line_errors(flat_scene, kw, message):
    with pytest.raises(RuntimeSimError, match=message) as err:
        ms.drive(flat_scene, **kw)
    assert "\n" not in str(err.value)


def test_exports_that_cannot_be_written_are_refused_before_driving(flat_scene, tmp_path,
                                                                     monkeypatch):
    monkeypatch.setattr("marsscene.runtime.api.drive_sim", _spy([]))  # never reached
    with pytest.raises(RuntimeSimError, match="need the camera"):
        ms.drive(flat_scene, command=(0.1, 0.0), seconds=1.0, out_dir=tmp_path / "a",
                 export=ms.ExportOptions(datasets=("euroc",)))
    with pytest.raises(RuntimeSimError, match="need a run folder"):
        ms.drive(flat_scene, command=(0.1, 0.0), seconds=1.0,
                 export=ms.ExportOptions(bag=ms.BagOptions()))
    (tmp_path / "b" / "bag").mkdir(parents=True)
    with pytest.raises(ExportError, match="overwrite"):
        ms.drive(flat_scene, command=(0.1, 0.0), seconds=1.0, out_dir=tmp_path / "b",
                 export=ms.ExportOptions(bag=ms.BagOptions()))


# ---- option types ------------------------------------------------------------------------------
_BAG_CHOICES = {"storage": ["mcap", "sqlite3"], "depth_encoding": ["16UC1", "32FC1"],
                "images": ["compressed", "raw", "both"], "image_codec": ["jpeg", "png"],
                "compression": ["zstd", "zstd_fast", "zstd_small", "lz4", "none"],
                "ros_distro": ["jazzy", "humble"]}


@settings(max_examples=60, deadline=None)
@given(st.fixed_dictionaries({}, optional={
    **{k: st.sampled_from(v) for k, v in _BAG_CHOICES.items()},
    "cloud_stride_px": st.integers(-2, 20), "jpeg_quality": st.integers(-5, 110),
    "sensors": st.lists(st.sampled_from(["camera", "stereo", "lidar", "radar"]), max_size=3),
    "depth_cloud": st.sampled_from([True, False, None])}))
def test_bag_options_accept_exactly_what_rosbag2_can_write(doc):
    bad = (doc.get("cloud_stride_px", 4) < 1 or not 1 <= doc.get("jpeg_quality", 95) <= 100
           or "radar" in doc.get("sensors", ())
           or (doc.get("storage") == "sqlite3" and doc.get("compression") == "lz4"))
    if bad:
        with pytest.raises(MarsSceneError) as err:
            ms.BagOptions.from_dict(doc)
        assert "\n" not in str(err.value)
        return
    opts = ms.BagOptions.from_dict(doc)
    assert ms.BagOptions.from_dict(opts.to_dict()) == opts
    assert opts.depth_cloud_on == (opts.images != "compressed" if opts.depth_cloud is None
                                   else opts.depth_cloud)


def test_export_and_drive_options_from_dict():
    e = ms.ExportOptions.from_dict({"bag": True, "datasets": ["tum-rgbd", "euroc"]})
    assert e.bag == ms.BagOptions() and e.folders == ("bag", "tum_rgbd", "euroc")
    assert ms.ExportOptions.from_dict({"bag": False}).bag is None
    with pytest.raises(ExportError, match="twice"):
        ms.ExportOptions(datasets=("euroc", "euroc"))
    with pytest.raises(ConfigError, match="unknown"):
        ms.ExportOptions.from_dict({"bags": True})
    d = ms.DriveOptions.from_dict({"corridor_m": 30.0, "pursuit": {"lookahead_m": 2.0},
                                   "start_xy_m": [1, 2]})
    assert d.pursuit.lookahead_m == 2.0 and d.start_xy_m == (1.0, 2.0)
    with pytest.raises(ConfigError, match="corridor_m"):
        ms.DriveOptions(corridor_m=0.0)


def test_every_spec_type_loads_the_same_way():
    from marsscene.benchmark import SlamSpec, VprSpec
    from marsscene.sweep import SweepSpec

    for cls in (ms.SceneConfig, ms.RunConfig, ms.NoiseConfig, SweepSpec, SlamSpec, VprSpec):
        assert callable(cls.from_dict) and callable(cls.from_toml), cls
    assert ms.RunConfig.from_dict({"lidar": {"model": "vlp16"}}).lidar.spec.channels == 16
