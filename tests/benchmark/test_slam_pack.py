"""A SLAM benchmark packed down to its results resumes elsewhere: the packed cells are reused
without their scenes or logs (same rows, table and plots), a cell missing a row runs again."""

from __future__ import annotations

import csv
import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest

os.environ.setdefault("MUJOCO_GL", "egl")
pytest.importorskip("mujoco")

from bench_util import FLAT_SCENE
from click.testing import CliRunner

from marsscene.cli import main


@pytest.fixture(scope="module")
def bench(tmp_path_factory: pytest.TempPathFactory) -> tuple[Any, Path]:
    """A two-cell benchmark (wheel odometry, seeds 1 and 2), run once: (spec, its folder)."""
    from marsscene.benchmark.slam.run import run_slam_benchmark
    from marsscene.benchmark.slam.spec import SlamSpec

    root = tmp_path_factory.mktemp("packbench")
    (root / "scene.toml").write_text(FLAT_SCENE, encoding="utf-8")
    spec = SlamSpec.from_dict({
        "benchmark": {"tau": [0.5], "seeds": [1]},
        "scenes": [{"name": "s", "config": "scene.toml", "seconds": 3.0,
                    "route": {"waypoints": [[-3.0, 0.0], [3.0, 0.0]]}}],
        "methods": [{"name": "wheel", "kind": "wheel-odometry", "seeds": [1, 2]}],
    }, base_dir=root)
    run_slam_benchmark(spec, root / "out", serial=True)
    return spec, root / "out"


def _scores(root: Path) -> list[dict[str, str]]:
    with (root / "results.csv").open(encoding="utf-8") as f:
        return [{k: v for k, v in r.items() if not k.startswith("t_")}
                for r in csv.DictReader(f)]


def _sizes(root: Path) -> int:
    return sum(p.stat().st_size for p in root.rglob("*") if p.is_file())


def test_a_packed_benchmark_resumes_without_scenes_or_logs(bench: tuple[Any, Path],
                                                            tmp_path: Path) -> None:
    from marsscene.benchmark.slam.run import run_slam_benchmark

    spec, out = bench
    packed = tmp_path / "packed"
    res = CliRunner().invoke(main, ["benchmark", "pack", str(out), str(packed)])
    assert res.exit_code == 0, res.output
    assert res.output.startswith("packed 2 cells: ")
    assert not list(packed.rglob("scene")) and not list(packed.rglob("imu.csv"))
    assert _sizes(packed) < _sizes(out) / 4  # a tiny scene, a 3 s drive: still 5x smaller
    cell = packed / "cells" / "scene=s__tau=0.5__seed=2"
    for rel in ("result.json", "drive/gt.tum", "drive/run.json", "estimates/wheel.tum",
                "methods/wheel.json"):
        assert (cell / rel).is_file(), rel

    again = run_slam_benchmark(spec, packed, serial=True, resume=True)
    assert not list(packed.rglob("scene"))  # reused as packed: nothing built, nothing driven
    assert [c["status"] for c in again.cells] == ["skipped", "skipped"]
    for name in ("results.csv", "table.md", "report.md"):
        assert (packed / name).read_bytes() == (out / name).read_bytes(), name
    assert (packed / "traj_s.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

    (cell / "methods" / "wheel.json").unlink()  # a row missing: that cell runs again
    run_slam_benchmark(spec, packed, serial=True, resume=True)
    assert (cell / "scene" / "mjcf" / "scene.xml").is_file()
    assert not (packed / "cells" / "scene=s__tau=0.5__seed=1" / "scene").exists()
    assert _scores(packed) == _scores(out)  # the same scores (its timing is new)


def test_a_thinned_pack_keeps_the_rows_and_plots_fewer_poses(bench: tuple[Any, Path],
                                                             tmp_path: Path) -> None:
    from marsscene.benchmark.slam.pack import pack_benchmark
    from marsscene.benchmark.slam.run import run_slam_benchmark
    from marsscene.runs.tum import read_tum

    spec, out = bench
    thin = tmp_path / "thin"
    pack_benchmark(out, thin, max_rate_hz=2.0)
    cell = "cells/scene=s__tau=0.5__seed=1"
    est, gt = (read_tum(thin / cell / rel) for rel in ("estimates/wheel.tum", "drive/gt.tum"))
    full = read_tum(out / cell / "drive" / "gt.tum")
    assert len(full) > 100 and len(est) == len(np.unique(np.floor(full.timestamps_s * 2.0)))
    assert np.all(np.isin(est.timestamps_s, gt.timestamps_s))  # every kept pose has its truth
    assert len(gt) < len(full) / 10
    assert "thinned by marsscene benchmark pack" in (thin / cell / "drive" / "gt.tum").read_text(
        encoding="utf-8")
    run_slam_benchmark(spec, thin, serial=True, resume=True)
    assert not list(thin.rglob("scene"))
    for name in ("results.csv", "table.md", "report.md"):
        assert (thin / name).read_bytes() == (out / name).read_bytes(), name
    assert (thin / "traj_s.png").stat().st_size > 10_000


def test_pack_refuses_what_is_not_its_benchmark_in_one_line(tmp_path: Path) -> None:
    runner = CliRunner()
    res = runner.invoke(main, ["benchmark", "pack", str(tmp_path), str(tmp_path / "p")])
    assert res.exit_code == 1 and "not a SLAM benchmark folder" in res.output
    assert "Traceback" not in res.output
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "benchmark.json").write_text('{"name": "a"}', encoding="utf-8")
    (tmp_path / "b").mkdir()
    (tmp_path / "b" / "benchmark.json").write_text('{"name": "b"}', encoding="utf-8")
    res = runner.invoke(main, ["benchmark", "pack", str(tmp_path / "a"), str(tmp_path / "b")])
    assert res.exit_code == 1 and "a pack of another benchmark spec" in res.output
    res = runner.invoke(main, ["benchmark", "pack", str(tmp_path / "a"), str(tmp_path / "a")])
    assert res.exit_code == 1 and "the benchmark folder itself" in res.output
