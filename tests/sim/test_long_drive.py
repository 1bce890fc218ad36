"""Long drives: logs stream to disk, Ctrl-C / SIGTERM / SIGKILL leave a usable prefix, and the
command line shows distance, sim time and an ETA (issue 23)."""

from __future__ import annotations

import io
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from marsscene.cli._progress import DriveMeter, format_eta
from marsscene.runs.runlog import IncompleteRunWarning, RunLog
from marsscene.runs.tum import read_tum
from marsscene.sim.driver import DriveInterrupted, DriveProgress

_SMALL = {
    "camera": {"width_px": 64, "height_px": 48},
    "lidar": {"channels": 4, "horizontal_samples": 64, "vertical_fov_deg": [-30.0, -5.0]},
}


def _sim(scene: Path, camera: bool = True, lidar: bool = True):
    from marsscene.runtime import CameraConfig, LidarConfig, RunConfig
    from marsscene.sim.rover_sim import RoverSim

    return RoverSim(scene, run=RunConfig(
        camera=CameraConfig(**_SMALL["camera"]) if camera else None,
        lidar=LidarConfig(channels=4, horizontal_samples=64, vertical_fov_deg=(-30.0, -5.0))
        if lidar else None))


def _drive(scene: Path, out: Path | None, seconds: float = 3.0, progress=None, **kw):
    from marsscene.seeding import stage_rng
    from marsscene.sim.driver import drive_sim

    return drive_sim(_sim(scene, **kw), command=(0.3, 0.05), seconds=seconds, out_dir=out,
                 rng=stage_rng(1, "sensors"), progress=progress)


def test_streamed_logs_equal_in_memory_drive(gentle_scene: Path, tmp_path: Path) -> None:
    """The trajectories streamed to gt.tum/odom.tum are those of a drive kept in memory."""
    a = _drive(gentle_scene, tmp_path / "r", camera=False, lidar=False)
    b = _drive(gentle_scene, None, camera=False, lidar=False)
    assert a.summary["status"] == "complete"
    assert len(a.gt) == len(b.gt) == 151  # 3 s at 50 Hz, t = 0 included
    np.testing.assert_allclose(a.gt.xyz_m, b.gt.xyz_m, atol=1e-6)
    np.testing.assert_allclose(a.odom.quat_xyzw, b.odom.quat_xyzw, atol=1e-9)
    np.testing.assert_allclose(a.cmd, b.cmd, atol=1e-8)
    assert json.loads((tmp_path / "r" / "run.json").read_text())["summary"]["status"] == \
        "complete"


def test_ctrl_c_finishes_the_run_folder(gentle_scene: Path, tmp_path: Path) -> None:
    """A KeyboardInterrupt at 2 sim s ends in DriveInterrupted with a complete prefix that the
    bag writer and the dataset export accept (with a warning, not silently)."""
    seen: list[DriveProgress] = []

    def stop(p: DriveProgress) -> None:
        seen.append(p)
        if p.sim_time_s >= 2.0:
            raise KeyboardInterrupt

    out = tmp_path / "r"
    with pytest.raises(DriveInterrupted) as info:
        _drive(gentle_scene, out, seconds=10.0, progress=stop)
    res = info.value.result
    assert res.summary["status"] == "interrupted"
    assert 1.9 < res.summary["sim_time_s"] <= 2.1
    assert [round(p.sim_time_s) for p in seen] == [1, 2]
    assert seen[-1].distance_m == pytest.approx(res.gt.path_length_m(), rel=0.05)
    with pytest.warns(IncompleteRunWarning, match="interrupted"):
        run = RunLog(out)
    assert len(run.gt) == len(run.odom) == len(res.gt)
    assert run.lidar is not None and len(run.lidar[1]) == res.summary["lidar_scans"]
    assert len(run.camera_streams()[0].rgb_files) == res.summary["camera_frames"] > 0
    from marsscene.runs.export.bag import write_bag

    with pytest.warns(IncompleteRunWarning):
        bag = write_bag(out)
    assert bag.counts["/rover/odom"] == len(run.odom)


def _wait_for_lines(path: Path, n: int, proc: subprocess.Popen, timeout_s: float = 120) -> None:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if path.is_file() and path.read_text().count("\n") > n:
            return
        if proc.poll() is not None:
            raise AssertionError(f"drive ended early: {proc.communicate()}")
        time.sleep(0.2)
    proc.kill()
    raise AssertionError("drive made no progress")


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL])
def test_killed_drive_leaves_a_usable_prefix(gentle_scene: Path, tmp_path: Path,
                                            sig: signal.Signals) -> None:
    """A real `marsscene drive` process stopped by SIGTERM (finished, exit 130) or SIGKILL
    (nothing to finish: the streamed logs are cut at their last whole line) still gives a run
    folder that `marsscene bag` writes."""
    wp = tmp_path / "wp.txt"
    wp.write_text("-12 -12\n12 -12\n12 12\n")
    out = tmp_path / "r"
    env = os.environ | {"PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen(
        [sys.executable, "-m", "marsscene", "drive", str(gentle_scene), "--waypoints", str(wp),
         "--camera", "--camera-size", "64x48", "--lidar", "--lidar-model", "simple",
         "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    _wait_for_lines(out / "camera" / "stamps.csv", 12, proc)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    status = json.loads((out / "run.json").read_text())["summary"]["status"]
    if sig == signal.SIGTERM:
        assert proc.returncode == 130, err
        assert "interrupted after" in err and "marsscene bag" in err
        assert status == "interrupted"
    else:
        assert proc.returncode == -signal.SIGKILL
        assert status == "running"
    assert not list(out.rglob(".*.part")) or sig == signal.SIGKILL
    with pytest.warns(IncompleteRunWarning):
        run = RunLog(out)
    assert len(run.gt) == len(run.odom) > 50
    cam = run.camera_streams()[0]
    assert len(cam.rgb_files) >= 12
    res = subprocess.run([sys.executable, "-m", "marsscene", "bag", str(out)],
                         capture_output=True, text=True, env=env)
    assert res.returncode == 0, res.stderr
    assert "warning" in res.stderr and "sim s it logged" in res.stderr
    from rosbags.highlevel import AnyReader

    with AnyReader([out / "bag"]) as reader:
        topics = {c.topic: c.msgcount for c in reader.connections}
    assert topics["/rover/GT_Trajectory"] == len(run.gt)
    assert max(v for k, v in topics.items() if k.startswith("/rover/rgb/")) == len(cam.rgb_files)


def test_truncated_last_line_is_ignored_only_for_unfinished_runs(tmp_path: Path) -> None:
    p = tmp_path / "t.tum"
    p.write_text("# x\n0.0 0 0 0 0 0 0 1\n0.1 1 0 0 0 0 0 1\n0.2 2 0")
    assert len(read_tum(p, complete_lines=True)) == 2
    from marsscene.errors import RuntimeSimError

    with pytest.raises(RuntimeSimError, match="expected 8 numbers"):
        read_tum(p)


class _Clock:
    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


def test_progress_line_and_eta() -> None:
    clock = _Clock()
    buf = io.StringIO()
    meter = DriveMeter(buf, clock=clock, log_every_s=60.0)
    clock.t = 30.0  # 30 s wall for 10 % of a 400 m route: 270 s to go
    p = DriveProgress(sim_time_s=45.0, limit_s=3000.0, distance_m=40.5, route_done_m=40.0,
                      route_length_m=400.0)
    assert meter.line(p) == ("driving: 40.0 of 400.0 m (10%) | sim 45 s | 1.50x real time | "
                             "ETA 4 min 30 s")
    meter(p)
    assert buf.getvalue() == ""  # not a terminal: one line per minute of wall time
    clock.t = 61.0
    meter(p)
    assert buf.getvalue().count("\n") == 1
    no_route = DriveProgress(sim_time_s=30.0, limit_s=120.0, distance_m=9.0)
    assert no_route.fraction == 0.25
    assert format_eta(3725) == "1 h 02 min" and format_eta(59.6) == "1 min 00 s"
