"""TUM RGB-D and EuRoC exports re-read equal the run's data (PIL, numpy; no ROS)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from marsscene.cli import main
from marsscene.errors import ExportError, RuntimeSimError
from marsscene.runs.export.datasets import (
    TUM_DEPTH_PER_M,
    camera_trajectory,
    export_dataset,
    tum_depth_per_m,
)
from marsscene.runs.export.frames import frame_in_base, static_transforms
from marsscene.runs.runlog import RunLog, read_image
from marsscene.runtime import read_tum
from tests.support.extras import needs


def _table(path: Path) -> list[list[str]]:
    return [ln.split() for ln in path.read_text().splitlines() if not ln.startswith("#")]


def _yaml_matrix(text: str, key: str) -> np.ndarray:
    block = text[text.index(key):]
    data = block[block.index("data: [") + 7: block.index("]")]
    return np.array([float(v) for v in data.split(",")]).reshape(4, 4)


def test_tum_rgbd_depth_is_the_formats_unless_asked_and_named(bag_run, tmp_path) -> None:
    """By default TUM depth is at the format's 5000 per metre (colour hard-linked);
    ``images="run-depth"`` links the run's 1000-per-metre PNGs, declared, in a folder named so."""
    out = export_dataset(bag_run, "tum-rgbd", tmp_path / "tum")
    cam = RunLog(bag_run).camera_streams()[0]
    assert tum_depth_per_m(out) == TUM_DEPTH_PER_M == 5000.0
    assert "5000 per metre" in (out / "depth.txt").read_text()
    for (_, f), src in zip(_table(out / "depth.txt"), cam.depth_files, strict=True):
        tum, mm = read_image(out / f), read_image(src)
        assert tum.dtype == np.uint16
        want = mm.astype(np.int64) * 5
        np.testing.assert_array_equal(tum, np.where(want > 65535, 0, want))  # > 13.1 m: invalid
        assert (mm == 0).any() and (tum[mm == 0] == 0).all()  # the sky: no return stays 0
    assert export_dataset(bag_run, "tum-rgbd", tmp_path / "c", images="convert").is_dir()
    assert (tmp_path / "c" / "depth.txt").read_text() == (out / "depth.txt").read_text()
    mm_dir = export_dataset(bag_run, "tum-rgbd", images="run-depth")
    assert mm_dir == bag_run / "tum_rgbd_depth1000"  # a scale TUM readers do not expect: named
    try:
        for (_, f), src in zip(_table(mm_dir / "depth.txt"), cam.depth_files, strict=True):
            assert (mm_dir / f).samefile(src)  # no second copy on disk
        assert "1000 per metre" in (mm_dir / "depth.txt").read_text()
        assert "RGBD.DepthMapFactor: 1000.0" in (mm_dir / "orbslam3_rgbd.yaml").read_text()
        assert tum_depth_per_m(mm_dir) == 1000.0
        for name in ("rgb.txt", "associations.txt", "groundtruth.txt"):  # only depth differs
            assert (mm_dir / name).read_text() == (out / name).read_text()
    finally:
        shutil.rmtree(mm_dir)
    with pytest.raises(ExportError, match="images = 'copy'"):
        export_dataset(bag_run, "tum-rgbd", tmp_path / "bad", images="copy")


def test_open3ds_tum_reader_reads_the_run_depth_right(bag_run, tmp_path) -> None:
    """Open3D's ``create_from_tum_format`` (its TUM scale, 5000, hard-coded) gives the run's
    depth in metres, to the run's millimetre (up to the 4 m it truncates at: a Kinect's range;
    the folder holds depth to the format's 13.1 m)."""
    o3d = needs("open3d", "bench")
    out = export_dataset(bag_run, "tum-rgbd", tmp_path / "tum")
    cam = RunLog(bag_run).camera_streams()[0]
    for (_, c, _, d), src in list(zip(_table(out / "associations.txt"), cam.depth_files,
                                      strict=True))[:3]:
        rgbd = o3d.geometry.RGBDImage.create_from_tum_format(
            o3d.io.read_image(str(out / c)), o3d.io.read_image(str(out / d)), False)
        got = np.asarray(rgbd.depth, dtype=np.float64)
        run_m = read_image(src).astype(np.float64) / 1000.0
        near = (run_m > 0) & (run_m < 4.0)
        assert near.mean() > 0.2  # the ground near the rover in view
        np.testing.assert_allclose(got[near], run_m[near], atol=1e-6)
        assert (got[~near] == 0).all()


def test_tum_rgbd_export_equals_the_run(bag_run, tmp_path) -> None:
    out = export_dataset(bag_run, "tum-rgbd", tmp_path / "tum", images="convert")
    run = RunLog(bag_run)
    cam = run.camera_streams()[0]
    rgb, depth = _table(out / "rgb.txt"), _table(out / "depth.txt")
    np.testing.assert_allclose([float(r[0]) for r in rgb], cam.stamps_s, atol=1e-6)
    assert [r[0] for r in rgb] == [r[0] for r in depth]
    for (_, f), src in zip(rgb, cam.rgb_files, strict=True):
        assert (out / f).read_bytes() == src.read_bytes()
        assert (out / f).samefile(src)  # a hard link: no second copy on disk
    assoc = _table(out / "associations.txt")
    assert [a[1] for a in assoc] == [r[1] for r in rgb] and [a[3] for a in assoc] == [
        d[1] for d in depth]
    gt = read_tum(out / "groundtruth.txt")
    xyz, q = camera_trajectory(run, frame_in_base(static_transforms(run.rover),
                                                  "navcam_optical_frame"))
    np.testing.assert_allclose(gt.timestamps_s, run.gt.timestamps_s, atol=1e-6)
    np.testing.assert_allclose(gt.xyz_m, xyz, atol=2e-6)
    np.testing.assert_allclose(np.abs(np.sum(gt.quat_xyzw * q, axis=1)), 1.0, atol=1e-8)
    # the camera sits 0.75 m ahead of base_link and looks forward (optical z = rover x, level)
    fwd = Rotation.from_quat(gt.quat_xyzw[0]).apply([0, 0, 1])
    base_x = Rotation.from_quat(run.gt.quat_xyzw[0]).apply([1, 0, 0])
    assert np.degrees(np.arccos(fwd @ base_x)) == pytest.approx(20.0, abs=0.01)  # tilted down
    settings = (out / "orbslam3_rgbd.yaml").read_text()
    assert settings.startswith("%YAML:1.0") and "RGBD.DepthMapFactor: 5000.0" in settings
    assert f"Camera1.fx: {cam.k[0, 0]:.9g}" in settings


def test_euroc_export_equals_the_run(stereo_run, tmp_path) -> None:
    calls: list[tuple[int, int]] = []
    out = export_dataset(stereo_run, "euroc", tmp_path / "euroc",
                         progress=lambda d, n: calls.append((d, n)), images="convert")
    run = RunLog(stereo_run)
    cams = {c.name: c for c in run.camera_streams()}
    for k, side in enumerate(("left", "right")):
        d = out / "mav0" / f"cam{k}"
        rows = [ln.split(",") for ln in (d / "data.csv").read_text().splitlines()[1:]]
        np.testing.assert_array_equal([int(r[0]) for r in rows],
                                      np.round(cams[side].stamps_s * 1e9).astype(np.int64))
        for (_, f), src in zip(rows, cams[side].rgb_files, strict=True):
            np.testing.assert_array_equal(read_image(d / "data" / f), read_image(src))
    n = 2 * len(cams["left"].stamps_s)
    assert calls == [(i, n) for i in range(1, n + 1)]  # one call per image written
    # cam1 sits 0.3 m to the right of cam0: T_c1_c2 = +x 0.3 m, no rotation
    settings = (out / "orbslam3_stereo_inertial.yaml").read_text()
    np.testing.assert_allclose(_yaml_matrix(settings, "Stereo.T_c1_c2"),
                               [[1, 0, 0, 0.3], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]],
                               atol=1e-9)
    t_bs = _yaml_matrix((out / "mav0/cam0/sensor.yaml").read_text(), "T_BS")
    tfs = static_transforms(run.rover, {"left": {"baseline_m": 0.3}, "right": {"baseline_m": 0.3}})
    np.testing.assert_allclose(t_bs, frame_in_base(tfs, "stereo_left_optical_frame"), atol=1e-8)
    np.testing.assert_allclose(_yaml_matrix(settings, "IMU.T_b_c1"), t_bs, atol=1e-8)
    imu = np.loadtxt(out / "mav0/imu0/data.csv", delimiter=",", comments="#")
    np.testing.assert_array_equal(imu[:, 0], np.round(run.imu[:, 0] * 1e9))
    np.testing.assert_allclose(imu[:, 1:], run.imu[:, [4, 5, 6, 1, 2, 3]], rtol=1e-8, atol=1e-12)
    gyro_nd = float((out / "mav0/imu0/sensor.yaml").read_text().split(
        "gyroscope_noise_density: ")[1].split()[0])
    assert gyro_nd == pytest.approx(0.01 / np.sqrt(100.0))  # sigma / sqrt(rate)
    gt = np.loadtxt(out / "mav0/state_groundtruth_estimate0/data.csv", delimiter=",",
                    comments="#")
    np.testing.assert_allclose(gt[:, 1:4], run.gt.xyz_m, atol=1e-8)
    np.testing.assert_allclose(gt[:, 4:8], run.gt.quat_xyzw[:, [3, 0, 1, 2]], atol=1e-8)
    speed = np.linalg.norm(gt[5:-5, 8:11], axis=1)
    assert speed.mean() == pytest.approx(0.3, rel=0.1)  # commanded 0.3 m/s
    ts = [int(v) for v in (out / "timestamps.txt").read_text().split()]
    assert ts == [int(r.split(",")[0]) for r in
                  (out / "mav0/cam0/data.csv").read_text().splitlines()[1:]]


def test_euroc_without_stereo_is_mono_inertial(bag_run, tmp_path) -> None:
    out = export_dataset(bag_run, "euroc", tmp_path / "e", images="convert")
    assert not (out / "mav0" / "cam1").exists()
    assert (out / "orbslam3_mono_inertial.yaml").is_file()
    img = read_image(next((out / "mav0/cam0/data").iterdir()))
    assert img.ndim == 2 and img.dtype == np.uint8  # mono8, as in EuRoC
    linked = export_dataset(bag_run, "euroc", tmp_path / "l")  # the default: the run's RGB
    cam = RunLog(bag_run).camera_streams()[0]
    files = sorted((linked / "mav0/cam0/data").iterdir(), key=lambda p: int(p.stem))
    assert len(files) == len(cam.rgb_files)
    assert all(f.samefile(src) for f, src in zip(files, cam.rgb_files, strict=True))
    assert "rgb8" in (linked / "mav0/cam0/sensor.yaml").read_text()


def test_export_errors_and_cli(runner, bag_run, tmp_path) -> None:
    bare = tmp_path / "bare"
    shutil.copytree(bag_run, bare, ignore=shutil.ignore_patterns("camera"))
    with pytest.raises(RuntimeSimError, match="no camera logs"):
        export_dataset(bare, "tum-rgbd")
    export_dataset(bag_run, "tum-rgbd", tmp_path / "t")
    stamp = (tmp_path / "t" / "rgb.txt").stat().st_mtime_ns
    with pytest.raises(ExportError, match="exists"):
        export_dataset(bag_run, "tum-rgbd", tmp_path / "t")
    assert (tmp_path / "t" / "rgb.txt").stat().st_mtime_ns == stamp
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bare", "t"]  # no temp folders left
    res = runner.invoke(main, ["export", str(bare), "--format", "euroc"])
    assert res.exit_code == 1 and "no camera logs" in res.output and "Traceback" not in res.output
    res = runner.invoke(main, ["export", str(bag_run), "--format", "euroc", "--out",
                               str(tmp_path / "e")])
    assert res.exit_code == 0, res.output
    assert json.loads((bag_run / "run.json").read_text())["summary"]["camera_frames"] == len(
        (tmp_path / "e" / "timestamps.txt").read_text().split())
