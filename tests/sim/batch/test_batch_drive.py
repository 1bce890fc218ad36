"""Batched drives on Warp's CPU device: two drives in one batch write complete run folders that
the CPU drive's readers read (RunLog, TUM, PLY scans, depth PNGs, the summary); the same seed
gives the same bytes."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from marsscene.runs.runlog import RunLog, read_image, read_ply
from marsscene.runs.tum import read_tum
from marsscene.sim.goal import goal_reached

#: The summary keys of a CPU drive with a route (marsscene.sim.driver._result), no camera gain.
CPU_SUMMARY = {"status", "sim_time_s", "poses", "path_length_m", "lidar_scans", "camera_frames",
               "goal_reached", "imu_bias", "cross_track_rms_m", "cross_track_max_m"}


def test_run_folders_complete_and_read(batch_runs: Any, batch_seconds: float) -> None:
    SECONDS = batch_seconds
    run = batch_runs[0]
    assert len(run.out_dirs) == 4
    for out, summary in zip(run.out_dirs, run.summaries, strict=True):
        log = RunLog(out)  # raises on a missing file
        assert log.status == "complete"
        # 50 Hz control rows from 0 to the limit; IMU at 100 Hz
        assert len(log.gt) == round(SECONDS * 50) + 1 == summary["poses"]
        assert np.diff(log.gt.timestamps_s) == pytest.approx(0.02)
        assert np.diff(log.imu[:, 0]) == pytest.approx(0.01)
        assert len(log.imu) == round(SECONDS * 100) + 1
        assert log.gt.path_length_m() > 0.1  # it drove off along its route
        assert read_tum(out / "route.tum").xyz_m.shape[1] == 3
        meta = json.loads((out / "run.json").read_text())
        assert set(meta["summary"]) == CPU_SUMMARY
        assert meta["summary"]["sim_time_s"] == pytest.approx(SECONDS)
        assert meta["batch"]["engine"] == "mujoco_warp" and meta["pursuit"]["lookahead_m"] == 1.0
        assert meta["rates_hz"]["lidar"] == 10.0 and meta["rover"]["wheel_collision"] == "sphere"
        goal = read_tum(out / "route.tum").xyz_m[-1, :2]
        assert summary["goal_reached"] == bool(goal_reached(log.gt.xyz_m[-1, :2], goal))


def test_scans_and_depth_in_the_cpu_formats(batch_runs: Any, batch_seconds: float) -> None:
    SECONDS = batch_seconds
    out = batch_runs[0].out_dirs[0]
    _, files = RunLog(out).lidar  # type: ignore[misc]
    assert len(files) == round(SECONDS * 10) + 1 == batch_runs[0].summaries[0]["lidar_scans"]
    scan = read_ply(files[0])
    assert set(scan.dtype.names) >= {"x", "y", "z", "intensity", "t", "ring"}
    r = np.sqrt(scan["x"] ** 2 + scan["y"] ** 2 + scan["z"] ** 2)
    assert len(scan) > 1000 and 0.5 < float(np.median(r)) < 100.0  # VLP-16: ground hits
    assert set(np.unique(scan["ring"])) <= set(range(16))
    rows = (out / "camera" / "stamps.csv").read_text().splitlines()
    assert rows[0] == "t,rgb,depth" and len(rows) == round(SECONDS * 5) + 2
    depth = read_image(out / "camera" / rows[1].split(",")[2])
    assert depth.shape == (24, 32) and depth.dtype == np.uint16
    assert (depth > 0).mean() > 0.3  # the ground ahead, in mm


def test_rgbd_frames_each_under_its_lighting(batch_runs: Any) -> None:
    """RGB and depth of every frame; drives c (drive a's scene and route, tau = 6) and d (a low
    sun) see the same ground to the millimetre (one copy of the scene drawn for all three),
    c under a duller light, d under a far darker one."""
    a, _, c, d = batch_runs[0].out_dirs
    name = "000002.png"
    rgb_a, rgb_c, rgb_d = (read_image(x / "camera" / "rgb" / name) for x in (a, c, d))
    depth_a, depth_c = (read_image(x / "camera" / "depth" / name).astype(np.int64) for x in (a, c))
    assert rgb_a.shape == (24, 32, 3) and rgb_a.dtype == np.uint8
    ground = (depth_a > 0) & (depth_c > 0)
    assert ground.mean() > 0.3 and (np.abs(depth_a - depth_c)[ground] <= 2).mean() > 0.99
    r, g, b = rgb_a[ground].mean(axis=0)
    assert r > g > b  # regolith: red over green over blue
    assert rgb_c[ground].mean() < 0.97 * rgb_a[ground].mean()  # less direct sun through dust
    sky = depth_a == 0
    assert sky.any() and np.abs(rgb_c[sky].mean(axis=0) - rgb_a[sky].mean(axis=0)).max() > 5
    # a sun 8 deg up: its irradiance on level ground ~ sin(8 deg) through a long dusty path
    assert _linear(rgb_d[ground]).mean() < 0.6 * _linear(rgb_a[ground]).mean()


def _linear(srgb_u8: np.ndarray) -> np.ndarray:
    """sRGB codes as linear light (IEC 61966-2-1)."""
    c = srgb_u8.astype(np.float64) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def test_datasets_of_a_batch_drive(batch_runs: Any, tmp_path: Path) -> None:
    """The TUM RGB-D and EuRoC exports and the bag read a batch drive's folder as a CPU
    drive's (the bag read back by rosbags)."""
    from rosbags.highlevel import AnyReader

    from marsscene.runs.export.bag import write_bag
    from marsscene.runs.export.datasets import export_dataset

    out = batch_runs[0].out_dirs[0]
    frames = batch_runs[0].summaries[0]["camera_frames"]
    tum = export_dataset(out, "tum-rgbd", tmp_path / "tum")
    rgb_rows = [ln for ln in (tum / "rgb.txt").read_text().splitlines()
                if not ln.startswith("#")]
    assert len(rgb_rows) == frames and (tum / rgb_rows[0].split()[1]).is_file()
    assert len((tum / "groundtruth.txt").read_text().splitlines()) > 10
    euroc = export_dataset(out, "euroc", tmp_path / "euroc")
    assert len(list((euroc / "mav0" / "cam0" / "data").glob("*.png"))) == frames
    write_bag(out, tmp_path / "bag")
    with AnyReader([tmp_path / "bag"]) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
    scans = batch_runs[0].summaries[0]["lidar_scans"]
    assert counts["/rover/rgb/image_raw/compressed"] == frames
    assert counts["/rover/depth/image_raw/compressedDepth"] == frames
    assert counts["/rover/lidar/points"] == scans and counts["/rover/imu"] > 50


def _files(out: Path) -> dict[str, bytes]:
    return {str(p.relative_to(out)): p.read_bytes() for p in sorted(out.rglob("*"))
            if p.is_file() and p.name != "run.json"}


def test_same_seed_same_bytes(batch_runs: Any) -> None:
    one, two = batch_runs
    for a, b in zip(one.out_dirs, two.out_dirs, strict=True):
        fa, fb = _files(a), _files(b)
        assert fa.keys() == fb.keys() and "lidar/000000.ply" in fa
        assert [k for k in fa if fa[k] != fb[k]] == []
    # the two drives' noise differ (their own seeds): not one stream copied
    imu = [(d / "imu.csv").read_bytes() for d in one.out_dirs]
    assert imu[0] != imu[1]
