"""What a SLAM benchmark cell keeps on disk: MJCF-only scenes, KISS-ICP fed during the drive
(no LiDAR stream stored), camera images deleted after scoring with ``keep_images = false``,
and a resume that drives again only when a camera method must run on deleted images."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

os.environ.setdefault("MUJOCO_GL", "egl")
pytest.importorskip("mujoco")
pytest.importorskip("kiss_icp")

from click.testing import CliRunner

from marsscene.cli import main

SCENE = """
[terrain]
source = "procedural"
size_m = [40.0, 40.0]
post_m = 0.25
rms_height_m = 0.05
[craters]
enabled = false
[rocks]
k = 0.04
d_min_m = 0.15
"""

SPEC = """
[benchmark]
name = "storage"
seeds = [3]
tau = [0.5]
[sensors]
keep_images = false
[sensors.camera]
width_px = 64
height_px = 48
rate_hz = 5.0
[sensors.lidar]
model = "vlp16"
[[scenes]]
name = "tiny"
config = "scene.toml"
route = { waypoints = [[-3.0, 0.0], [3.0, 0.0]] }
seconds = 6.0
[[methods]]
name = "kiss"
kind = "kiss-icp"
[[methods]]
name = "kiss-wheel"
kind = "kiss-icp"
options = { wheel_prior = true }
[[methods]]
name = "truth"
kind = "command"
command = "cp {tum_rgbd_dir}/groundtruth.txt {out_tum}"
[[methods]]
name = "mono"
kind = "opencv-mono"
[[methods]]
name = "mine"
kind = "tum-file"
"""


def _run(spec: Path, out: Path, *extra: str) -> str:
    res = CliRunner().invoke(main, ["benchmark", "slam", str(spec), "--out", str(out),
                                    "--serial", *extra])
    assert res.exit_code == 0, res.output
    return res.output


def test_cell_storage_and_resume(tmp_path: Path) -> None:
    (tmp_path / "scene.toml").write_text(SCENE, encoding="utf-8")
    spec = tmp_path / "bench.toml"
    spec.write_text(SPEC, encoding="utf-8")
    out = tmp_path / "out"
    _run(spec, out)
    cell = out / "cells" / "scene=tiny__tau=0.5__seed=3"
    drive = cell / "drive"
    # the scene is MJCF only: the cells drive in MuJoCo
    assert (cell / "scene" / "mjcf" / "scene.xml").is_file()
    assert not list((cell / "scene").glob("*.usd*"))
    # KISS-ICP ran on the scans as they were made: no PLYs, no bag, the stamps kept
    assert not list((drive / "lidar").glob("*.ply")) and not (drive / "bag").exists()
    assert (drive / "lidar" / "scans_not_stored.txt").is_file()
    stamps = (drive / "lidar" / "stamps.csv").read_text(encoding="utf-8").splitlines()
    assert len(stamps) > 50  # 6 s at 10 Hz, header included
    live = (drive / "live" / "kiss.tum").read_text(encoding="utf-8").splitlines()
    assert len([ln for ln in live if not ln.startswith("#")]) == len(stamps) - 1
    row = (cell / "methods" / "kiss.json").read_text(encoding="utf-8")
    assert '"status": "ok"' in row
    # with the wheel prior, in the same drive: its row says how many ICP steps it kept
    primed = json.loads((cell / "methods" / "kiss-wheel.json").read_text(encoding="utf-8"))
    kept = json.loads((drive / "benchmark_drive.json").read_text(encoding="utf-8"))[
        "summary"]["icp_steps_kept"]["kiss-wheel"]
    assert kept[1] == len(stamps) - 1 and 0 < kept[0] < kept[1]
    assert f"{kept[0]} of {kept[1]} ICP steps kept" in primed["row"]["note"]
    assert primed["row"]["tracked_fraction"] == pytest.approx(kept[0] / kept[1], abs=0.02)
    assert "with the wheel odometry's prior" in (drive / "live" / "kiss-wheel.tum").read_text(
        encoding="utf-8").splitlines()[0]
    # scored, the camera images are gone; what the scores need stays
    assert (drive / "images_removed.txt").is_file()
    assert not list(drive.rglob("*.png"))
    for rel in ("gt.tum", "camera/stamps.csv", "tum_rgbd/associations.txt",
                "tum_rgbd/groundtruth.txt"):
        assert (drive / rel).is_file(), rel
    assert (cell / "estimates" / "mono.tum").is_file()
    # a resume with nothing new reuses the drive ...
    mtime = (drive / "benchmark_drive.json").stat().st_mtime_ns
    _run(spec, out, "--resume")
    assert (drive / "benchmark_drive.json").stat().st_mtime_ns == mtime
    # ... and a camera method to score again on the deleted images drives the cell again
    (cell / "methods" / "mono.json").unlink()
    _run(spec, out, "--resume")
    assert (drive / "benchmark_drive.json").stat().st_mtime_ns != mtime
    assert (cell / "methods" / "mono.json").is_file()
    assert not list(drive.rglob("*.png"))  # scored again, deleted again
