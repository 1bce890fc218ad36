"""``marsscene benchmark nav`` end to end on a small scene: two methods and a broken
controller (its rows fail, the others go on), the files, and ``--resume`` skipping done
episodes; one-line errors for bad specs."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from marsscene.cli import main

SPEC = """
[benchmark]
name = "tiny"
seed = 2
pairs = 1
distance_m = [20.0, 22.0]
time_factor = 2.0
[[scenes]]
name = "small"
overrides.terrain = {{ source = "procedural", size_m = [40.0, 40.0], post_m = 0.25 }}
overrides.rocks = {{ k = 0.05 }}
[[methods]]
name = "straight"
[[methods]]
name = "global-astar"
{extra}
"""
BROKEN = """[[methods]]
name = "broken"
kind = "controller"
controller = "no_such_module_66:Planner"
"""


@pytest.fixture(scope="module")
def bench(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, object]:
    root = tmp_path_factory.mktemp("nav")
    spec = root / "spec.toml"
    spec.write_text(SPEC.format(extra=BROKEN), encoding="utf-8")
    out = root / "out"
    res = CliRunner().invoke(main, ["benchmark", "nav", str(spec), str(out), "--serial"])
    return spec, out, res


def test_run_scores_and_writes(bench: tuple[Path, Path, object]) -> None:
    _, out, res = bench
    assert res.exit_code == 1, res.output  # the broken controller's row failed
    assert "episodes: 2 ok, 1 failed" in res.output
    doc = json.loads((out / "results.json").read_text())
    rows = {r["method"]: r for r in doc["episodes"]}
    assert rows["broken"]["status"] == "failed"
    assert "no_such_module_66" in rows["broken"]["error"]
    astar = rows["global-astar"]
    assert astar["status"] == "ok" and astar["success"]
    assert 0.8 < astar["spl"] <= 1.0 and astar["plan_calls"] == 1
    assert astar["shortest_m"] >= astar["distance_m"] - 1e-6
    pairs = json.loads((out / "pairs.json").read_text())["scenes"]["small"]
    assert len(pairs) == 1 and pairs[0]["distance_m"] == astar["distance_m"]
    for name in ("results.csv", "summary.csv", "table.md", "report.md", "paths_small.png",
                 "success_vs_distance.png"):
        assert (out / name).is_file(), name
    assert "| small | global-astar | 1 | 0 | 1.000 |" in (out / "table.md").read_text()


def test_resume_skips_done_episodes(bench: tuple[Path, Path, object]) -> None:
    spec, out, _ = bench
    done = sorted((out / "episodes").glob("*method=global-astar.json"))
    before = [p.stat().st_mtime_ns for p in done]
    again = CliRunner().invoke(main, ["benchmark", "nav", str(spec), str(out), "--serial",
                                      "--resume"])
    assert again.exit_code == 1  # the broken row runs again, and fails again
    assert [p.stat().st_mtime_ns for p in done] == before
    rows = json.loads((out / "results.json").read_text())["episodes"]
    assert {r["method"]: bool(r.get("skipped")) for r in rows} == {
        "straight": True, "global-astar": True, "broken": False}
    fresh = CliRunner().invoke(main, ["benchmark", "nav", str(spec), str(out), "--serial"])
    assert fresh.exit_code == 1 and "pass --resume" in fresh.output


@pytest.mark.parametrize(("edit", "message"), [
    ('distance_m = [20.0, 22.0]', 'distance_m = [5.0, 22.0]'),
    ('name = "straight"', 'name = "teleport"'),
])
def test_bad_spec_is_one_line(tmp_path: Path, edit: str, message: str) -> None:
    spec = tmp_path / "bad.toml"
    spec.write_text(SPEC.format(extra="").replace(edit, message), encoding="utf-8")
    res = CliRunner().invoke(main, ["benchmark", "nav", str(spec), str(tmp_path / "o")])
    assert res.exit_code == 1
    line = res.output.strip().splitlines()[-1]
    assert line.startswith("Error: ") and ("distance_m" in line or "teleport" in line)
