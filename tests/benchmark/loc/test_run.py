"""dem-correlation through a query folder recovers a known offset; a tiny benchmark end to end
through the CLI, and ``--resume`` reusing every finished query and method row."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import marsscene as ms
from marsscene.benchmark.loc.cell import score
from marsscene.benchmark.loc.methods import read_answer, run_method
from marsscene.benchmark.loc.query import map_tile
from marsscene.benchmark.loc.spec import LocMethod
from marsscene.orbital import procedural_orbital_map, write_orbital_map


def test_dem_correlation_recovers_a_known_offset(tmp_path: Path) -> None:
    cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [200, 200]},
                                    "craters": {"enabled": False}, "rocks": {"enabled": False},
                                    "lighting": {"enabled": False}})
    hf = ms.build_scene(cfg, seed=3).heightfield
    omap = procedural_orbital_map(hf, None, 3, image=False)
    x, y, yaw = 8.0, -6.0, math.radians(40.0)
    gx, gy = hf.grid_xy()
    xx, yy = np.meshgrid(gx, gy)
    sel = np.hypot(xx - x, yy - y) < 30.0
    dx, dy = xx[sel] - x, yy[sel] - y
    c, s = math.cos(yaw), math.sin(yaw)
    pts = np.column_stack([c * dx + s * dy, -s * dx + c * dy, hf.z_m[sel] - 1.5])
    q = tmp_path / "query"
    (q / "local").mkdir(parents=True)
    np.save(q / "local" / "points.npy", pts.astype(np.float32))
    prior = (x + 24.0, y - 9.0, yaw + math.radians(2.5))  # 25.6 m and 2.5 deg off
    (q / "query.json").write_text(json.dumps({
        "stamp_s": 0.0, "local_radius_m": 30.0,
        "prior": {"x_m": prior[0], "y_m": prior[1], "yaw_rad": prior[2]},
        "search": {"position_error_max_m": 30.0, "heading_error_max_deg": 3.0}}))
    write_orbital_map(map_tile(omap, prior[0], prior[1], 70.0), q)
    run_method(LocMethod(name="dem", kind="dem-correlation"), q, tmp_path / "a.tum")
    row = score(read_answer(tmp_path / "a.tum"), {"x_m": x, "y_m": y, "yaw_rad": yaw})
    assert row["position_error_m"] < 1.5 and row["heading_error_deg"] < 2.5
    prior_row = score(prior, {"x_m": x, "y_m": y, "yaw_rad": yaw})
    assert prior_row["position_error_m"] == pytest.approx(math.hypot(24.0, 9.0), abs=1e-3)


SPEC = """
[benchmark]
queries = 1
[prior]
position_error_m = [10.0, 20.0]
[local]
scans = 2
camera = { width_px = 64, height_px = 48, texture_px = 256, terrain_window_m = 20.0 }
[[scenes]]
name = "small"
route = { waypoints = [[-20.0, 0.0], [20.0, 0.0]] }
[scenes.overrides]
terrain = { source = "procedural", size_m = [120.0, 120.0], post_m = 0.5 }
craters = { enabled = false }
rocks = { k = 0.01, d_min_m = 0.3 }
[[methods]]
name = "dem"
kind = "dem-correlation"
[[methods]]
name = "prior"
kind = "prior"
"""


def test_a_tiny_cli_run_end_to_end_and_resume(tmp_path: Path) -> None:
    from marsscene.cli import main

    spec, out = tmp_path / "loc.toml", tmp_path / "bench"
    spec.write_text(SPEC)
    res = CliRunner().invoke(main, ["benchmark", "loc", str(spec), str(out), "--serial"])
    assert res.exit_code == 0, res.output
    rows = list(csv.DictReader((out / "results.csv").open()))
    assert [r["method"] for r in rows] == ["dem", "prior"]
    assert 10.0 <= float(rows[1]["position_error_m"]) <= 20.0
    assert rows[0]["status"] == "ok"
    qdir = next((out / "cells").glob("*/queries/000"))
    assert sorted(p.name for p in (qdir / "query").iterdir()) == [
        "local", "orbital", "prior.tum", "query.json"]
    lidar = json.loads((qdir / "query" / "query.json").read_text())["lidar"]
    assert len(lidar["points_per_scan"]) == lidar["scans"] == 2  # local.scans
    assert sum(lidar["points_per_scan"]) == lidar["points"] == len(
        np.load(qdir / "query" / "local" / "points.npy"))
    assert not (qdir / "query" / "local" / "camera").exists()  # no method reads an image
    stamps = {p: p.stat().st_mtime_ns for p in [qdir / "truth.json",
                                                *(qdir / "methods").glob("*.json")]}
    again = CliRunner().invoke(main, ["benchmark", "loc", str(spec), str(out), "--serial"])
    assert again.exit_code == 1 and "--resume" in again.output
    res = CliRunner().invoke(main, ["benchmark", "loc", str(spec), str(out), "--serial",
                                    "--resume"])
    assert res.exit_code == 0, res.output
    assert {p: p.stat().st_mtime_ns for p in stamps} == stamps  # nothing redone
    assert list(csv.DictReader((out / "results.csv").open())) == rows
