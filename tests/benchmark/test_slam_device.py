"""`marsscene benchmark slam --device cpu`: every cell of a tiny spec driven in one batch on
Warp's CPU device, then the methods as in any benchmark, reading the batch drives' folders
unchanged (the TUM RGB-D export, the LiDAR scans replayed into KISS-ICP)."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mujoco_warp")

from bench_util import FLAT_SCENE
from click.testing import CliRunner

from marsscene.benchmark.slam.methods import DRIVE_FILE
from marsscene.cli import main
from marsscene.runs.runlog import read_image
from tests.support.extras import needs

pytestmark = pytest.mark.slow

SPEC = """
[benchmark]
name = "tiny-gpu"
seeds = [3]
tau = [0.5, 6.0]
[sensors]
noise_profile = "none"
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
seconds = 4.0
[[methods]]
name = "wheel"
kind = "wheel-odometry"
[[methods]]
name = "kiss"
kind = "kiss-icp"
[[methods]]
name = "truth"
kind = "command"
command = "cp {tum_rgbd_dir}/groundtruth.txt {out_tum}"
"""


@pytest.fixture(scope="module")
def bench(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    needs("kiss_icp", "bench")
    root = tmp_path_factory.mktemp("slamdevice")
    (root / "scene.toml").write_text(FLAT_SCENE, encoding="utf-8")
    spec = root / "bench.toml"
    spec.write_text(SPEC, encoding="utf-8")
    out = root / "out"
    res = CliRunner().invoke(main, ["benchmark", "slam", str(spec), "--out", str(out),
                                    "--serial", "--device", "cpu"])
    assert res.exit_code == 0, res.output
    return spec, out


def _rows(out: Path) -> dict[tuple[str, float], dict[str, str]]:
    with (out / "results.csv").open(encoding="utf-8") as f:
        return {(r["method"], float(r["tau"])): r for r in csv.DictReader(f)}


def test_every_cell_driven_in_the_batch_and_scored(bench: tuple[Path, Path]) -> None:
    _, out = bench
    rows = _rows(out)
    assert set(rows) == {("wheel", 0.5), ("kiss", 0.5), ("truth", 0.5), ("truth", 6.0)}
    for tau in (0.5, 6.0):  # the batch's camera frames, exported as TUM RGB-D
        truth = rows[("truth", tau)]
        assert truth["status"] == "ok" and float(truth["ate_rmse_m"]) < 1e-4
    wheel = rows[("wheel", 0.5)]
    assert wheel["status"] == "ok" and float(wheel["ate_rmse_m"]) < 0.1  # noise-free wheels
    kiss = rows[("kiss", 0.5)]
    assert kiss["status"] == "ok" and float(kiss["path_m"]) > 1.0
    cells = sorted((out / "cells").glob("scene=*"))
    assert len(cells) == 2
    for cell in cells:
        meta = json.loads((cell / "drive" / "run.json").read_text())
        assert meta["batch"]["engine"] == "mujoco_warp" and meta["batch"]["drives"] == 2
        assert json.loads((cell / "drive" / DRIVE_FILE).read_text())["summary"][
            "engine"] == "mujoco_warp"
    lidar_cell = next(c for c in cells if "tau=0.5" in c.name)
    assert (lidar_cell / "drive" / "live" / "kiss.tum").is_file()


def test_each_cell_under_its_own_dust(bench: tuple[Path, Path]) -> None:
    """The two cells share the scene and route: the same ground, their own tau's light."""
    _, out = bench
    clear, dusty = (next((out / "cells").glob(f"scene=tiny__tau={t}__*")) / "drive" / "camera"
                    for t in ("0.5", "6.0"))
    name = "000005.png"
    gap_mm = np.abs(read_image(clear / "depth" / name).astype(int)
                    - read_image(dusty / "depth" / name).astype(int))
    assert (gap_mm <= 2).mean() > 0.99 and gap_mm.max() < 20  # two tiles' float32 physics
    a, b = (read_image(c / "rgb" / name).astype(float) for c in (clear, dusty))
    assert np.abs(a.mean(axis=(0, 1)) - b.mean(axis=(0, 1))).max() > 3


def test_a_resumed_run_drives_nothing_again(bench: tuple[Path, Path]) -> None:
    spec, out = bench
    stamps = {p: p.stat().st_mtime_ns for p in (out / "cells").glob(f"*/drive/{DRIVE_FILE}")}
    res = CliRunner().invoke(main, ["benchmark", "slam", str(spec), "--out", str(out),
                                    "--serial", "--device", "cpu", "--resume"])
    assert res.exit_code == 0, res.output
    assert {p: p.stat().st_mtime_ns for p in stamps} == stamps


def test_a_spec_the_batch_cannot_drive_is_one_line_before_any_work(tmp_path: Path) -> None:
    (tmp_path / "scene.toml").write_text(FLAT_SCENE, encoding="utf-8")
    spec = tmp_path / "bench.toml"
    spec.write_text(SPEC.replace("rate_hz = 5.0", "rate_hz = 5.0\nstereo = true"),
                    encoding="utf-8")
    res = CliRunner().invoke(main, ["benchmark", "slam", str(spec), "--out",
                                    str(tmp_path / "out"), "--device", "cpu"])
    assert res.exit_code == 1 and "no stereo camera" in res.output
    assert "Traceback" not in res.output and not (tmp_path / "out").exists()
