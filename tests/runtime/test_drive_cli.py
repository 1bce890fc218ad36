"""``marsscene drive`` and ``marsscene eval`` end to end, and their error messages."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from marsscene.cli import main
from marsscene.runtime import Trajectory, ate, read_tum, write_tum


def test_drive_waypoints_then_eval(runner, gentle_scene: Path, tmp_path: Path) -> None:
    wp = tmp_path / "wp.txt"
    wp.write_text("# x y\n-8 -8\n-2 -8\n")
    noise = tmp_path / "noise.toml"
    noise.write_text("[noise]\nwheel_rate_sigma_rad_s = 0.05\n")
    out = tmp_path / "run"
    res = runner.invoke(
        main,
        [
            "drive",
            str(gentle_scene),
            "--waypoints",
            str(wp),
            "--seconds",
            "4",
            "--out",
            str(out),
            "--lidar",
            "--noise-config",
            str(noise),
            "--seed",
            "3",
        ],
    )
    assert res.exit_code == 0, res.output
    assert "x real time" in res.output
    for name in (
        "gt.tum",
        "odom.tum",
        "route.tum",
        "imu.csv",
        "wheels.csv",
        "run.json",
        "lidar/000000.ply",
    ):
        assert (out / name).is_file(), name
    gt = read_tum(out / "gt.tum")
    assert gt.timestamps_s[-1] == pytest.approx(4.0)
    assert gt.path_length_m() > 1.0  # moved towards the second waypoint
    run = json.loads((out / "run.json").read_text())
    assert run["noise"]["wheel_rate_sigma_rad_s"] == 0.05
    res = runner.invoke(main, ["eval", str(out / "odom.tum"), str(out / "gt.tum"), "--json"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.output)
    expected = ate(read_tum(out / "odom.tum"), gt).stats.rmse
    assert doc["ate_m"]["rmse"] == pytest.approx(expected)
    assert doc["ate_m"]["n"] == len(gt)


def test_drive_route_tum_outside_terrain(runner, gentle_scene: Path, tmp_path: Path) -> None:
    xy = np.c_[np.linspace(0, 60, 20), np.zeros(20)]
    route = Trajectory(np.arange(20.0), np.c_[xy, np.zeros(20)], np.tile([0, 0, 0, 1.0], (20, 1)))
    write_tum(tmp_path / "route.tum", route)
    res = runner.invoke(
        main,
        [
            "drive",
            str(gentle_scene),
            "--route",
            str(tmp_path / "route.tum"),
            "--out",
            str(tmp_path / "r"),
        ],
    )
    assert res.exit_code == 1
    assert "outside the terrain" in res.output


def test_drive_errors(runner, tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    wp = tmp_path / "wp.txt"
    wp.write_text("0 0\n1 0\n")
    res = runner.invoke(main, ["drive", str(tmp_path / "empty"), "--waypoints", str(wp)])
    assert res.exit_code == 1 and "scene.xml is missing" in res.output
    res = runner.invoke(main, ["drive", str(tmp_path / "empty")])
    assert res.exit_code == 2 and "give --route or --waypoints (or a --controller)" in res.output
    res = runner.invoke(main, ["drive", str(tmp_path / "empty"), "--waypoints", str(wp),
                               "--route", str(wp)])
    assert res.exit_code == 2 and "not both" in res.output


def test_eval_reports_bad_tum_line(runner, tmp_path: Path) -> None:
    good = tmp_path / "gt.tum"
    good.write_text("0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n2 2 0 0 0 0 0 1\n3 3 1 0 0 0 0 1\n")
    bad = tmp_path / "est.tum"
    bad.write_text("0 0 0 0 0 0 0 1\n1 1 0 0 0 0 1\n")
    res = runner.invoke(main, ["eval", str(bad), str(good)])
    assert res.exit_code == 1
    assert "est.tum:2: expected 8 numbers" in res.output
    res = runner.invoke(main, ["eval", str(good), str(good)])
    assert res.exit_code == 0 and "ATE (m):     rmse 0.000000" in res.output


_CONTROLLER = '''
class StopAfter:
    """Straight on the odometry, stop after 2 m (a class taking the route)."""

    def __init__(self, route=None):
        self.route, self.done = route, False

    def __call__(self, obs):
        if obs.step == 0:
            self.x0 = obs.odom_xyz_m[0]
        self.done = abs(obs.odom_xyz_m[0] - self.x0) >= 2.0
        return (0.0, 0.0) if self.done else (0.4, 0.0)


def spin(obs):
    return (0.0, 0.2)
'''


def test_drive_with_a_controller_from_a_module(runner, flat_scene, tmp_path, monkeypatch):
    (tmp_path / "my_nav.py").write_text(_CONTROLLER)
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "run"
    res = runner.invoke(main, ["drive", str(flat_scene), "--controller", "my_nav:StopAfter",
                               "--seconds", "30", "--out", str(out)])
    assert res.exit_code == 0, res.output
    run = json.loads((out / "run.json").read_text())
    assert run["controller"] == "my_nav:StopAfter" and run["summary"]["goal_reached"] is True
    assert 1.9 < run["summary"]["path_length_m"] < 2.3
    res = runner.invoke(main, ["drive", str(flat_scene), "--controller", "my_nav:spin",
                               "--seconds", "2", "--out", str(tmp_path / "spin")])
    assert res.exit_code == 0, res.output
    gt = read_tum(tmp_path / "spin" / "gt.tum")
    assert gt.path_length_m() < 0.2  # turning in place
    for ref, msg in (("my_nav", "MODULE:NAME"), ("my_nav:Nope", "AttributeError"),
                     ("no_such_module:f", "ModuleNotFoundError")):
        res = runner.invoke(main, ["drive", str(flat_scene), "--controller", ref,
                                   "--seconds", "1", "--out", str(tmp_path / "bad")])
        assert res.exit_code == 1 and msg in res.output and "Traceback" not in res.output
