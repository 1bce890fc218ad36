"""Sweeps on a LocalCluster, on a scheduler started here, and serially: same bytes everywhere."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import pytest
from sweep_util import assert_same_scene, write_sweep

from marsscene.cli import main
from marsscene.sweep import SweepSpec, run_sweep

GRID = 'seed = [1, 2]\n"lighting.tau" = [0.3, 3.0]\n'
IDS = ["seed=1__lighting.tau=0.3", "seed=1__lighting.tau=3.0",
       "seed=2__lighting.tau=0.3", "seed=2__lighting.tau=3.0"]


def _csv(path: Path) -> list[dict[str, str]]:
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


@pytest.fixture(scope="module")
def local_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Any, list[Any]]:
    """The 2 x 2 sweep on a LocalCluster of 2 worker processes."""
    tmp = tmp_path_factory.mktemp("local")
    spec = SweepSpec.from_toml(write_sweep(tmp / "sweep.toml", GRID))
    seen: list[Any] = []
    res = run_sweep(spec, tmp / "out", workers=2, progress=seen.append)
    return tmp / "out", res, seen


def test_local_cluster_cells_equal_serial_builds(local_run, runner, tmp_path: Path) -> None:
    out, res, seen = local_run
    assert [r["cell_id"] for r in res.rows] == IDS
    assert [r["status"] for r in res.rows] == ["ok"] * 4
    assert [p.done for p in seen] == [1, 2, 3, 4] and seen[-1].failed == 0
    table = _csv(out / "results.csv")
    assert [r["cell_id"] for r in table] == IDS
    assert [(r["seed"], r["lighting.tau"], r["tau"]) for r in table] == [
        ("1", "0.3", "0.3"), ("1", "3.0", "3.0"), ("2", "0.3", "0.3"), ("2", "3.0", "3.0")]
    assert all(int(r["n_rocks"]) > 0 and float(r["t_build_s"]) > 0 for r in table)
    # more dust: less direct sun; same seed: same rocks whatever tau
    assert float(table[1]["direct_normal_w_m2"]) < float(table[0]["direct_normal_w_m2"])
    assert table[0]["n_rocks"] == table[1]["n_rocks"] != table[2]["n_rocks"]
    for i, cid in enumerate(IDS):
        cell = out / cid
        assert sorted(p.name for p in cell.iterdir()) == ["config.toml", "result.json", "scene"]
        res_cli = runner.invoke(main, ["-q", "build", "--config", str(cell / "config.toml"),
                                       "--out", str(tmp_path / f"b{i}")])
        assert res_cli.exit_code == 0, res_cli.output
        assert_same_scene(cell / "scene", tmp_path / f"b{i}")


def test_rerun_skips_finished_cells_and_force_rebuilds_same_bytes(local_run,
                                                                  tmp_path: Path) -> None:
    out, _, _ = local_run
    spec = SweepSpec.from_toml(out.parent / "sweep.toml")
    stamps = {c: (out / c / "result.json").stat().st_mtime_ns for c in IDS}
    again = run_sweep(spec, out, serial=True)
    assert [r["status"] for r in again.rows] == ["skipped"] * 4
    assert {c: (out / c / "result.json").stat().st_mtime_ns for c in IDS} == stamps
    assert [r["status"] for r in _csv(out / "results.csv")] == ["skipped"] * 4
    assert str(again.rows[0]["n_rocks"]) == _csv(out / "results.csv")[0]["n_rocks"] != ""
    import shutil

    shutil.copytree(out / IDS[3] / "scene", tmp_path / "before")
    forced = run_sweep(spec, out, serial=True, force=True)
    assert [r["status"] for r in forced.rows] == ["ok"] * 4
    assert_same_scene(tmp_path / "before", out / IDS[3] / "scene")


def test_remote_scheduler_gives_the_same_bytes(local_run, scheduler_address: str,
                                               tmp_path: Path) -> None:
    out, _, _ = local_run
    spec = SweepSpec.from_toml(out.parent / "sweep.toml")
    res = run_sweep(spec, tmp_path / "remote", scheduler=scheduler_address)
    assert [r["status"] for r in res.rows] == ["ok"] * 4
    for cid in IDS:
        assert (tmp_path / "remote" / cid / "config.toml").read_bytes() == (
            out / cid / "config.toml").read_bytes()
        assert_same_scene(out / cid / "scene", tmp_path / "remote" / cid / "scene")
    again = run_sweep(spec, tmp_path / "remote", scheduler=scheduler_address)
    assert [r["status"] for r in again.rows] == ["skipped"] * 4


def test_one_invalid_cell_fails_and_the_others_finish(scheduler_address: str,
                                                      tmp_path: Path) -> None:
    spec = SweepSpec.from_toml(write_sweep(tmp_path / "s.toml", '"rocks.k" = [0.05, 1.5, 0.1]\n'))
    res = run_sweep(spec, tmp_path / "out", scheduler=scheduler_address)
    assert [r["status"] for r in res.rows] == ["ok", "failed", "ok"]
    bad = res.rows[1]
    assert bad["cell_id"] == "rocks.k=1.5"
    assert "rocks.k = 1.5 is out of range" in bad["error"] and "\n" not in bad["error"]
    assert [p.name for p in (tmp_path / "out" / "rocks.k=1.5").iterdir()] == ["result.json"]
    table = _csv(tmp_path / "out" / "results.csv")
    assert [r["status"] for r in table] == ["ok", "failed", "ok"]
    assert "out of range" in table[1]["error"] and table[1]["n_rocks"] == ""
    assert int(table[2]["n_rocks"]) > int(table[0]["n_rocks"])  # k 0.1 > 0.05
    again = run_sweep(spec, tmp_path / "out", serial=True)  # failed cells are retried
    assert [r["status"] for r in again.rows] == ["skipped", "failed", "skipped"]


def test_cli_sweep_reports_progress_and_failure(runner, tmp_path: Path) -> None:
    path = write_sweep(tmp_path / "s.toml", '"rocks.k" = [0.05, 2.0]\n')
    res = runner.invoke(main, ["-q", "sweep", str(path), "--out", str(tmp_path / "o"),
                               "--serial"])
    assert res.exit_code == 1
    assert "[2/2] FAILED rocks.k=2.0: ConfigError: rocks.k = 2.0 is out of range" in res.output
    assert "(done 2, running 0, failed 1)" in res.output
    assert "cells: 1 ok, 0 skipped, 1 failed" in res.output
    assert (tmp_path / "o" / "results.csv").is_file()


def test_driven_cell_metrics_match_the_logs(tmp_path: Path) -> None:
    from marsscene.runtime import ate, read_tum, rpe

    drive = "[drive]\nwaypoints = [[-5.0, 0.0], [5.0, 0.0]]\nnoise_seed = 4\nbag = true\n"
    spec = SweepSpec.from_toml(write_sweep(tmp_path / "s.toml", "seed = [0]\n", drive))
    (row,) = run_sweep(spec, tmp_path / "out", serial=True).rows
    assert row["status"] == "ok", row["error"]
    run = tmp_path / "out" / "seed=0" / "drive"
    gt, odom = read_tum(run / "gt.tum"), read_tum(run / "odom.tum")
    assert row["goal_reached"] is True and 8.0 < row["distance_m"] < 12.0
    assert row["ate_rmse_m"] == pytest.approx(ate(odom, gt).stats.rmse, abs=1e-6)
    assert row["rpe_trans_rmse_m"] == pytest.approx(rpe(odom, gt).translation.rmse, abs=1e-6)
    assert 0 < row["ate_rmse_m"] < 0.5 and row["sim_wall_ratio"] > 0
    from rosbags.highlevel import AnyReader

    with AnyReader([run / "bag"]) as reader:  # bag = true: the drive as a ROS 2 bag
        counts = {c.topic: c.msgcount for c in reader.connections}
    assert counts["/rover/odom"] == len(odom.timestamps_s) and row["bag_s"] > 0
    table = _csv(tmp_path / "out" / "results.csv")
    assert float(table[0]["ate_rmse_m"]) == pytest.approx(row["ate_rmse_m"])
