"""SLAM benchmark scoring, routes and spec checks (pure, fast)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from marsscene.benchmark.routes import auto_route
from marsscene.benchmark.slam.metrics import failed_score, score_estimate
from marsscene.benchmark.slam.spec import RouteSpec, SlamSpec
from marsscene.errors import ConfigError
from marsscene.runs.tum import Trajectory
from marsscene.terrain.heightfield import Heightfield

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"


def _loop_gt(n: int = 600, radius_m: float = 15.0) -> Trajectory:
    """A closed circle of ~94 m with a gentle height wave, yaw along the path, 10 Hz."""
    a = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    xyz = np.column_stack([radius_m * np.cos(a), radius_m * np.sin(a), 0.5 * np.sin(3 * a)])
    q = Rotation.from_euler("z", (a + np.pi / 2)[:, None]).as_quat()
    return Trajectory(np.arange(n) * 0.1, xyz, q)


def _moved(gt: Trajectory, *, scale: float = 1.0, noise_m: float = 0.0,
           seed: int = 0) -> Trajectory:
    """``gt`` in another world frame (rotated 40 deg about z and tilted, shifted, scaled)."""
    rot = Rotation.from_euler("zyx", [40.0, 5.0, -3.0], degrees=True)
    rng = np.random.default_rng(seed)
    xyz = scale * rot.apply(gt.xyz_m) + [100.0, -20.0, 3.0]
    xyz += rng.normal(0.0, noise_m, xyz.shape)
    quat = (rot * Rotation.from_quat(gt.quat_xyzw)).as_quat()
    return Trajectory(gt.timestamps_s, xyz, quat)


def test_se3_ate_of_a_moved_trajectory_is_its_noise() -> None:
    gt = _loop_gt()
    score = score_estimate(_moved(gt, noise_m=0.05), gt, align="se3")
    assert score.status == "ok"
    # 3-D isotropic noise of 0.05 m per axis: RMSE of the norm is 0.05 * sqrt(3)
    assert score.ate_rmse_m == pytest.approx(0.05 * math.sqrt(3), rel=0.08)
    assert score.ate_pct_of_path == pytest.approx(100 * score.ate_rmse_m / gt.path_length_m())
    assert score.tracked_fraction == 1.0 and score.poses == len(gt)
    exact = score_estimate(_moved(gt), gt, align="se3")
    assert exact.ate_rmse_m < 1e-9 and exact.rpe_trans_m < 1e-9 and exact.rpe_rot_deg < 1e-4


def test_sim3_recovers_scale_and_se3_does_not() -> None:
    gt = _loop_gt()
    est = _moved(gt, scale=0.37)
    sim3 = score_estimate(est, gt, align="sim3")
    se3 = score_estimate(est, gt, align="se3")
    assert sim3.scale == pytest.approx(1 / 0.37, rel=1e-9)
    assert sim3.ate_rmse_m < 1e-9
    assert se3.ate_rmse_m > 5.0  # a 0.37-scale circle cannot be rigidly fitted to r = 15 m
    assert se3.scale == 1.0


def test_rpe_per_distance_measures_scale_drift() -> None:
    gt = _loop_gt()
    # aligned with SE(3) a 2 % scale error leaves 2 % of every 10 m relative motion
    est = Trajectory(gt.timestamps_s, gt.xyz_m * 1.02, gt.quat_xyzw)
    score = score_estimate(est, gt, align="se3", rpe_distance_m=10.0)
    assert score.rpe_trans_m == pytest.approx(0.02 * 10.0, rel=0.1)
    assert score.rpe_rot_deg < 1e-4


def test_partial_or_tiny_estimates_are_lost_not_errors() -> None:
    gt = _loop_gt()
    half = Trajectory(gt.timestamps_s[:200], gt.xyz_m[:200], gt.quat_xyzw[:200])
    score = score_estimate(half, gt, frames_total=len(gt), min_tracked_fraction=0.5)
    assert score.status == "lost" and score.tracked_fraction == pytest.approx(200 / 600)
    assert score.ate_rmse_m < 1e-9  # still reported for the tracked part
    two = Trajectory(gt.timestamps_s[:2], gt.xyz_m[:2], gt.quat_xyzw[:2])
    assert score_estimate(two, gt).status == "lost"
    late = Trajectory(gt.timestamps_s + 1000.0, gt.xyz_m, gt.quat_xyzw)
    assert score_estimate(late, gt).status == "failed"  # no stamp matches
    row = failed_score("missing", "no\nfile", path_m=3.0).as_row()
    assert row["status"] == "missing" and row["note"] == "no file" and math.isnan(
        row["ate_rmse_m"])


@pytest.mark.parametrize("shape", ["loop", "out-and-back"])
def test_auto_route_is_closed_and_about_the_asked_length(shape: str) -> None:
    hf = Heightfield.centered(np.zeros((241, 241), np.float32), 0.25)  # 60 m x 60 m, flat
    route = auto_route(RouteSpec(shape=shape, length_m=80.0, center_xy_m=(2.0, -1.0),
                                 heading_deg=30.0), hf, None)
    assert route.length_m == pytest.approx(80.0, rel=0.03)
    assert np.linalg.norm(route.xy_m[0] - route.xy_m[-1]) < 1e-9
    assert hf.contains(route.xy_m[:, 0], route.xy_m[:, 1]).all()
    with pytest.raises(Exception, match="does not fit inside the terrain"):
        auto_route(RouteSpec(shape=shape, length_m=400.0), hf, None)


def test_route_centred_on_a_placed_asset(tmp_path: Path) -> None:
    import json

    from marsscene.benchmark.routes import asset_xy_m, centred_on_asset
    from marsscene.errors import RuntimeSimError

    (tmp_path / "manifest.json").write_text(json.dumps({"summary": {"assets": [
        {"name": "lander", "xy_m": [-3.0, 4.0]}, {"name": "habitat", "xy_m": [376.0, -194.5]}]}}))
    assert asset_xy_m(tmp_path, "habitat") == (376.0, -194.5)
    # the SLAM cell and the VPR dataset both centre their routes through this
    loop = RouteSpec(shape="loop", length_m=100.0, center_asset="lander")
    assert centred_on_asset(loop, tmp_path).center_xy_m == (-3.0, 4.0)
    plain = RouteSpec(shape="loop", length_m=100.0, center_xy_m=(7.0, 8.0))
    assert centred_on_asset(plain, tmp_path / "nowhere") == plain
    with pytest.raises(RuntimeSimError, match=r"no such asset \(placed assets: 'lander', "
                                              r"'habitat'"):
        asset_xy_m(tmp_path, "rover")
    with pytest.raises(RuntimeSimError, match=r"no readable manifest\.json"):
        asset_xy_m(tmp_path / "nowhere", "habitat")


def test_example_specs_parse() -> None:
    quick = SlamSpec.from_toml(EXAMPLES / "benchmark_slam_quick.toml")
    paper = SlamSpec.from_toml(EXAMPLES / "benchmark_slam_paper.toml")
    assert quick.tau == (0.5, 6.0) and quick.lidar_tau == 0.5
    assert [s.name for s in paper.scenes] == ["mars-base", "main-crater", "grand-canyon"]
    assert paper.scenes[0].route.center_asset == "habitat"  # the paper's route is at the base
    assert {m.align for m in paper.methods} == {"se3", "sim3"}
    assert next(m for m in quick.methods if m.kind == "opencv-mono").align == "sim3"
    # the paper spec: one row per method of the paper, the wheel prior where the paper's
    # stacks had odometry; the extended spec adds the prior-free rows over the same cells
    assert [(m.kind, m.options.get("wheel_prior", False)) for m in paper.methods] == [
        ("wheel-odometry", False), ("kiss-icp", True), ("open3d-rgbd", True),
        ("opencv-mono", False)]
    extended = SlamSpec.from_toml(EXAMPLES / "benchmark_slam_paper_extended.toml")
    assert extended.methods[:4] == paper.methods and extended.scenes == paper.scenes
    assert extended.sensors == paper.sensors and extended.tau == paper.tau
    assert [(m.kind, m.options) for m in extended.methods[4:]] == [("kiss-icp", {}),
                                                                  ("open3d-rgbd", {})]


def test_extends_overrides_keys_and_methods_by_name(tmp_path: Path) -> None:
    (tmp_path / "sub").mkdir()
    (tmp_path / "route.tum").write_text("0 0 0 0 0 0 0 1\n1 5 0 0 0 0 0 1\n")
    (tmp_path / "base.toml").write_text(
        '[benchmark]\nseeds = [3]\ntau = [0.5]\n[sensors.lidar]\n'
        '[[scenes]]\nname = "a"\nroute = { file = "route.tum" }\n'
        '[[methods]]\nname = "w"\nkind = "wheel-odometry"\n'
        '[[methods]]\nname = "k"\nkind = "kiss-icp"\n')
    (tmp_path / "sub" / "child.toml").write_text(
        '[benchmark]\nextends = "../base.toml"\ntau = [6.0]\n'
        '[[methods]]\nname = "k"\nkind = "kiss-icp"\noptions = { wheel_prior = true }\n'
        '[[methods]]\nname = "k2"\nkind = "kiss-icp"\n')
    spec = SlamSpec.from_toml(tmp_path / "sub" / "child.toml")
    assert spec.seeds == (3,) and spec.tau == (6.0,)
    assert [(m.name, m.options) for m in spec.methods] == [
        ("w", {}), ("k", {"wheel_prior": True}), ("k2", {})]
    assert spec.scenes[0].route.file == str((tmp_path / "route.tum").resolve())
    (tmp_path / "loop.toml").write_text('[benchmark]\nextends = "loop.toml"\n')
    with pytest.raises(ConfigError, match="at most 8 levels"):
        SlamSpec.from_toml(tmp_path / "loop.toml")


_OK = {"sensors": {"camera": {}}, "scenes": [{"name": "a", "route": {"shape": "loop",
                                                                      "length_m": 20.0}}],
       "methods": [{"name": "w", "kind": "wheel-odometry"}]}


@pytest.mark.parametrize(("patch", "message"), [
    ({"methods": [{"name": "x", "kind": "orb"}]}, "kind = 'orb' is not allowed"),
    ({"methods": [{"name": "k", "kind": "kiss-icp"}]}, r"needs the lidar; add a \[sensors.lidar"),
    ({"methods": [{"name": "c", "kind": "command"}]}, "needs command"),
    ({"methods": [{"name": "m", "kind": "opencv-mono", "frame": "base"}]}, "estimates the camera"),
    ({"methods": [{"name": "o", "kind": "open3d-rgbd", "options": {"wheel": True}}]},
     "unknown option 'wheel' for open3d-rgbd; allowed: depth_trunc_m, wheel_prior"),
    ({"scenes": [{"name": "a", "route": {"shape": "loop", "length_m": 20.0,
                                         "waypoints": [[0, 0], [1, 1]]}}]}, "exactly one of"),
    ({"scenes": [{"name": "a", "route": {"shape": "loop"}}]}, "needs route.length_m"),
    ({"scenes": [{"name": "a", "preset": "olympus", "route": {"waypoints": [[0, 0], [5, 0]]}}]},
     "scene 'a': preset = 'olympus' is not known"),
    ({"scenes": [{"name": "a", "route": {"file": "r.tum"}}] * 2}, "scene name 'a' is used twice"),
    ({"scenes": [{"name": "a", "route": {"waypoints": [[0, 0], [5, 0]],
                                         "center_asset": "habitat"}}]}, "for automatic routes"),
    ({"benchmark": {"tau": [0.5], "lidar_tau": 6.0}}, "lidar_tau = 6.0 is not one of"),
    ({"benchmark": {"seeds": [1, 1]}}, "need distinct ints"),
    ({"routes": {}}, r"unknown table\(s\) \['routes'\]"),
    ({"sensors": {"camera": {"width_px": -3}}}, "camera size -3x480 is out of range"),
])
def test_spec_errors_are_one_line_config_errors(patch: dict, message: str) -> None:
    with pytest.raises(ConfigError, match=message) as err:
        SlamSpec.from_dict({**_OK, **patch})
    assert "\n" not in str(err.value)
