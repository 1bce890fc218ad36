"""`marsscene benchmark slam` end to end on a tiny scene and a short route (serial, ~1 min)."""

from __future__ import annotations

import csv
import json
import os
import shutil
import socket
import subprocess
from pathlib import Path

import pytest

os.environ.setdefault("MUJOCO_GL", "egl")
pytest.importorskip("mujoco")

from bench_util import FLAT_SCENE
from click.testing import CliRunner

from marsscene.cli import main
from tests.support.extras import needs

SCENE = FLAT_SCENE

SPEC = """
[benchmark]
name = "tiny"
seeds = [3]
tau = [0.5, 6.0]
[sensors.camera]
width_px = 64
height_px = 48
rate_hz = 5.0
[sensors.lidar]
model = "vlp16"
channels = 3
horizontal_samples = 90
vertical_fov_deg = [-30.0, -10.0]
[[scenes]]
name = "tiny"
config = "scene.toml"
route = { waypoints = [[-3.0, 0.0], [3.0, 0.0]] }
seconds = 5.0
[[methods]]
name = "wheel"
kind = "wheel-odometry"
[[methods]]
name = "rgbd"
kind = "open3d-rgbd"
[[methods]]
name = "mono"
kind = "opencv-mono"
[[methods]]
name = "truth"
kind = "command"
command = "cp {tum_rgbd_dir}/groundtruth.txt {out_tum}"
[[methods]]
name = "broken"
kind = "command"
command = "false {out_tum}"
[[methods]]
name = "ghost"
kind = "command"
command = "no-such-slam-binary-here {tum_rgbd_dir} {out_tum}"
[[methods]]
name = "mine"
kind = "tum-file"
"""


def _rows(out: Path) -> dict[tuple[str, float], dict[str, str]]:
    with (out / "results.csv").open(encoding="utf-8") as f:
        return {(r["method"], float(r["tau"])): r for r in csv.DictReader(f)}


@pytest.fixture(scope="module")
def bench(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, str]:
    """The tiny benchmark run once: (spec file, output folder, command output)."""
    root = tmp_path_factory.mktemp("slambench")
    (root / "scene.toml").write_text(SCENE, encoding="utf-8")
    spec = root / "bench.toml"
    spec.write_text(SPEC, encoding="utf-8")
    out = root / "out"
    res = CliRunner().invoke(main, ["benchmark", "slam", str(spec), "--out", str(out),
                                    "--serial"])
    assert res.exit_code == 0, res.output
    return spec, out, res.output


def test_every_method_gets_a_row_with_a_status(bench: tuple[Path, Path, str]) -> None:
    _, out, output = bench
    rows = _rows(out)
    # tau-free methods (wheel odometry) only in the lidar_tau cell (the first tau)
    assert ("wheel", 0.5) in rows and ("wheel", 6.0) not in rows
    assert len(rows) == 7 + 6
    truth = rows[("truth", 0.5)]
    assert truth["status"] == "ok" and float(truth["ate_rmse_m"]) < 1e-4
    assert float(truth["tracked_fraction"]) == 1.0 and truth["align"] == "se3"
    assert rows[("broken", 6.0)]["status"] == "failed"
    assert "exit code 1" in rows[("broken", 6.0)]["note"]
    assert rows[("ghost", 0.5)]["status"] == "missing"
    assert rows[("mine", 0.5)]["status"] == "missing"
    wheel = rows[("wheel", 0.5)]
    assert wheel["status"] == "ok" and 0.0 < float(wheel["ate_rmse_m"]) < 0.5
    assert 2.0 < float(wheel["path_m"]) < 4.0  # 5 s at <= 0.5 m/s (slower at the start)
    assert rows[("mono", 0.5)]["align"] == "sim3"
    for r in rows.values():
        assert r["status"] in ("ok", "lost", "failed", "missing")
    assert "methods:" in output and "failed" in output


def test_table_plot_and_report_are_written(bench: tuple[Path, Path, str]) -> None:
    _, out, _ = bench
    table = (out / "table.md").read_text(encoding="utf-8")
    assert "| tiny |" in table and "truth τ=0.5" in table and "✗" in table  # broken
    assert "**0.00**" in table  # truth is the best of the row
    png = out / "traj_tiny.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000
    report = (out / "report.md").read_text(encoding="utf-8")
    assert "![tiny trajectories](traj_tiny.png)" in report and "ate_summary.png" in report
    n_ok = sum(r["status"] == "ok" for r in _rows(out).values())
    assert f"Scenes tiny × τ 0.5, 6 × seeds 3: 2 cells, 7 methods; {n_ok} of 13 runs tracked." \
        in report
    # the cost section shows each cell's stored stage times
    for c in sorted((out / "cells").glob("scene=*")):
        p = json.loads((c / "result.json").read_text(encoding="utf-8"))["params"]
        drive = json.loads((c / "drive" / "benchmark_drive.json").read_text(encoding="utf-8"))
        t_methods = sum(json.loads(m.read_text(encoding="utf-8"))["row"].get("t_method_s") or 0.0
                        for m in (c / "methods").glob("*.json"))
        line = next(ln for ln in report.splitlines()
                    if ln.startswith(f"| tiny τ {p['tau']:g} seed {p['seed']} |"))
        cols = [v.strip().replace(",", "") for v in line.strip("|").split("|")]
        assert float(cols[2]) == pytest.approx(drive["summary"]["t_drive_s"], abs=0.5)
        assert float(cols[4]) == pytest.approx(t_methods, abs=0.5)
    cells = (out / "cells" / "results.csv").read_text(encoding="utf-8").splitlines()
    assert len(cells) == 3 and cells[0].startswith("cell_id,scene,tau,seed,status")
    cell = out / "cells" / "scene=tiny__tau=0.5__seed=3"
    for rel in ("scene/mjcf/scene.xml", "drive/gt.tum", "drive/route.tum",
                "drive/tum_rgbd/groundtruth.txt", "drive/euroc/mav0/cam0/data.csv",
                "estimates/wheel.tum", "methods/wheel.json"):
        assert (cell / rel).is_file(), rel


def test_the_cost_section_adds_each_stage_once() -> None:
    """A cell's stage time is its build, drive and methods; the live LiDAR's time, part of the
    drive's, is shown, not added again."""
    from marsscene.benchmark.slam.report import cost_lines

    cells = [{"cell_id": "a", "params": {"scene": "s", "tau": 0.5, "seed": 1},
              "t_total_s": 3600.0, "t_drive_s": 7200.0, "drive": {"t_live_s": {"k": 1800.0}}},
             {"cell_id": "b", "params": {"scene": "s", "tau": 6.0, "seed": 1},
              "t_total_s": None, "status": "failed"}]
    rows = [{"cell_id": "a", "t_method_s": 1000.0}, {"cell_id": "a", "t_method_s": 800.0},
            {"cell_id": "b", "t_method_s": None}]
    text = "\n".join(cost_lines(rows, cells))
    assert "| s τ 0.5 seed 1 | 3,600 | 7,200 | 1,800 | 1,800 | 3.50 |" in text
    assert "| s τ 6 seed 1 | 0 | 0 | 0 | 0 | 0.00 |" in text
    assert "2 cells: 3.50 h of stage time" in text


def test_resume_reuses_finished_work_and_scores_a_dropped_file(
        bench: tuple[Path, Path, str]) -> None:
    spec, out, _ = bench
    runner = CliRunner()
    again = runner.invoke(main, ["benchmark", "slam", str(spec), "--out", str(out), "--serial"])
    assert again.exit_code == 1 and "already holds a benchmark; pass --resume" in again.output
    cells = sorted((out / "cells").glob("scene=*"))
    stamps = {p: p.stat().st_mtime_ns for c in cells
              for p in (c / "result.json", c / "drive" / "benchmark_drive.json",
                        c / "methods" / "rgbd.json")}
    for c in cells:  # "your method": a TUM file dropped into the cell
        shutil.copy(c / "drive" / "tum_rgbd" / "groundtruth.txt", c / "estimates" / "mine.tum")
    res = runner.invoke(main, ["benchmark", "slam", str(spec), "--out", str(out), "--serial",
                               "--resume"])
    assert res.exit_code == 0, res.output
    assert {p: p.stat().st_mtime_ns for p in stamps} == stamps  # build, drive, methods reused
    rows = _rows(out)
    assert rows[("mine", 6.0)]["status"] == "ok" and float(rows[("mine", 6.0)]["ate_rmse_m"]) < 1e-4


def test_a_failing_drive_is_a_failed_cell_with_failed_rows(tmp_path: Path) -> None:
    from marsscene.benchmark.slam.run import run_slam_benchmark
    from marsscene.benchmark.slam.spec import SlamSpec

    (tmp_path / "scene.toml").write_text(SCENE, encoding="utf-8")
    spec = SlamSpec.from_dict({
        "benchmark": {"tau": [0.5], "seeds": [1]},
        "scenes": [{"name": "off", "config": "scene.toml",
                    "route": {"waypoints": [[-3.0, 0.0], [90.0, 0.0]]}}],
        "methods": [{"name": "wheel", "kind": "wheel-odometry"}],
    }, base_dir=tmp_path)
    res = run_slam_benchmark(spec, tmp_path / "out", serial=True, report=False)
    assert res.cells[0]["status"] == "failed" and "outside the terrain" in res.cells[0]["error"]
    assert [(r["method"], r["status"]) for r in res.rows] == [("wheel", "failed")]
    assert "outside the terrain" in res.rows[0]["note"]


_MEET = ("bash -c 'touch {{cell_dir}}/{me}.flag; for i in $(seq 300); do "
         "if [ -e {{cell_dir}}/{other}.flag ]; then cp {{tum_rgbd_dir}}/groundtruth.txt "
         "{{out_tum}}; exit 0; fi; sleep 0.1; done; exit 1'")


def test_methods_of_a_cell_run_side_by_side(bench: tuple[Path, Path, str]) -> None:
    """Two command methods that each wait (up to 30 s) for the other to start: both finish
    only if the cell runs them at the same time (one after the other, the first times out).
    The cell's build and drive are the benchmark's, reused."""
    from marsscene.benchmark.slam.cell import run_slam_cell
    from marsscene.benchmark.slam.run import slam_cells
    from marsscene.benchmark.slam.spec import SlamSpec

    spec_path, out, _ = bench
    meet = spec_path.with_name("meet.toml")
    meet.write_text(SPEC + "".join(
        f'[[methods]]\nname = "{me}"\nkind = "command"\n'
        f'command = "{_MEET.format(me=me, other=other)}"\n'
        for me, other in (("left", "right"), ("right", "left"))), encoding="utf-8")
    spec = SlamSpec.from_toml(meet)
    cell = slam_cells(spec)[0]
    drive = out / "cells" / cell.cell_id / "drive" / "benchmark_drive.json"
    stamp = drive.stat().st_mtime_ns
    row = run_slam_cell(cell, out_dir=str(out / "cells"), spec=spec, method_workers=2)
    assert drive.stat().st_mtime_ns == stamp  # the drive was reused, not redone
    by_name = {m["method"]: m for m in row["methods"]}
    assert [m["method"] for m in row["methods"]] == [m.name for m in spec.methods]  # spec order
    assert by_name["left"]["status"] == by_name["right"]["status"] == "ok", by_name["left"]
    assert by_name["truth"]["status"] == "ok" and by_name["broken"]["status"] == "failed"


def test_a_drive_killed_in_its_exports_keeps_the_drive(bench: tuple[Path, Path, str]) -> None:
    """A worker killed while writing the drive's dataset folders (the drive itself finished and
    marked): the resumed cell writes the missing folders, reuses the drive, and scores the
    camera methods on them to the same rows."""
    needs("open3d", "bench")  # the camera-only cell's RGB-D row
    from marsscene.benchmark.slam.cell import run_slam_cell
    from marsscene.benchmark.slam.run import slam_cells
    from marsscene.benchmark.slam.spec import SlamSpec

    spec_path, out, _ = bench
    spec = SlamSpec.from_toml(spec_path)
    cell = next(c for c in slam_cells(spec) if c.params["tau"] == 6.0)  # a camera-only cell
    drive = out / "cells" / cell.cell_id / "drive"
    stamp = (drive / "benchmark_drive.json").stat().st_mtime_ns
    before = json.loads((drive.parent / "methods" / "rgbd.json").read_text(encoding="utf-8"))
    truth = (drive / "tum_rgbd" / "groundtruth.txt").read_bytes()
    shutil.rmtree(drive / "tum_rgbd")  # killed in the TUM RGB-D export: nothing of it kept,
    stale = drive / ".tum_rgbd.dead0001.tmp"  # ... but its killed writer's part
    (stale / "new" / "tum_rgbd").mkdir(parents=True)
    gone = subprocess.Popen(["true"])
    gone.wait()
    (stale / "owner.json").write_text(json.dumps(
        {"pid": gone.pid, "host": socket.gethostname(), "start": None}), encoding="utf-8")
    shutil.rmtree(drive / "euroc")  # and EuRoC never started
    (drive.parent / "methods" / "rgbd.json").unlink()  # its camera methods not yet scored
    row = run_slam_cell(cell, out_dir=str(out / "cells"), spec=spec)
    assert (drive / "benchmark_drive.json").stat().st_mtime_ns == stamp  # not driven again
    assert (drive / "tum_rgbd" / "groundtruth.txt").read_bytes() == truth
    assert (drive / "euroc" / "mav0" / "cam0" / "data.csv").is_file()
    assert not list(drive.glob(".tum_rgbd.*.tmp"))  # its owner gone: swept
    rgbd = next(m for m in row["methods"] if m["method"] == "rgbd")
    assert rgbd["ate_rmse_m"] == before["row"]["ate_rmse_m"]


def test_a_long_thin_route_gets_stacked_wide_panels() -> None:
    pytest.importorskip("matplotlib")
    import numpy as np

    from marsscene.benchmark.slam.report import _panel_grid, _plt

    plt = _plt()
    out_and_back = np.array([[-150.0, -10.0], [150.0, -10.0], [150.0, 10.0], [-150.0, 10.0]])
    fig, axes, stacked = _panel_grid(plt, 2, [out_and_back])
    w, h = fig.get_size_inches()
    assert stacked and len(axes) == 2 and w > 2.0 * h / 2  # each panel wider than 2:1
    plt.close(fig)
    angle = np.linspace(0.0, 2.0 * np.pi, 50)
    loop = np.column_stack([70.0 * np.cos(angle), 70.0 * np.sin(angle)])
    fig, axes, stacked = _panel_grid(plt, 2, [loop])
    w, h = fig.get_size_inches()
    assert not stacked and len(axes) == 2 and w > 1.5 * h  # side by side
    plt.close(fig)


def test_a_methods_extra_seeds_are_sensorless_cells_with_a_spread(tmp_path: Path) -> None:
    """``seeds`` on a method: its extra seeds get cells of their own (only the tau cell it
    runs in, driving without the sensors it does not need); the table gives mean ± sd."""
    from marsscene.benchmark.slam.run import run_slam_benchmark, slam_cells
    from marsscene.benchmark.slam.spec import SlamSpec

    (tmp_path / "scene.toml").write_text(SCENE, encoding="utf-8")
    doc = {"benchmark": {"tau": [0.5, 6.0], "seeds": [1]},
           "sensors": {"camera": {"width_px": 64, "height_px": 48}},
           "scenes": [{"name": "s", "config": "scene.toml", "seconds": 3.0,
                       "route": {"waypoints": [[-3.0, 0.0], [3.0, 0.0]]}}],
           "methods": [{"name": "wheel", "kind": "wheel-odometry", "seeds": [1, 2, 3]},
                       {"name": "mono", "kind": "opencv-mono"}]}
    spec = SlamSpec.from_dict(doc, base_dir=tmp_path)
    assert spec.all_seeds == (1, 2, 3)
    assert [(c.params["tau"], c.params["seed"]) for c in slam_cells(spec)] == [
        (0.5, 1), (0.5, 2), (0.5, 3), (6.0, 1)]  # no tau-6 cells for the wheel's extra seeds
    assert [m.name for m in spec.methods_for(0.5, 2)] == ["wheel"]
    sensorless = SlamSpec.from_dict({**doc, "sensors": {},
                                     "methods": doc["methods"][:1]}, base_dir=tmp_path)
    res = run_slam_benchmark(sensorless, tmp_path / "out", serial=True, report=False)
    assert [(r["seed"], r["status"]) for r in res.rows] == [(1, "ok"), (2, "ok"), (3, "ok")]
    assert not (tmp_path / "out" / "cells" / "scene=s__tau=0.5__seed=2" / "drive"
                / "camera").exists()
    from marsscene.benchmark.slam.table import ate_table_markdown

    table = ate_table_markdown(res.rows, sensorless)
    assert " ± " in table and "wheel over seeds 1, 2, 3 (mean ± sd)" in table
