"""``kind = "policy"`` in ``marsscene benchmark nav``: a trained policy's file drives the
episodes, fed its height scan or its navcam depth; a retrained file reruns its episodes."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from marsscene.cli import main
from marsscene.env.observe import HeightScan
from tests.support.nav_policies import goal_seeking_mlp, ground_seeing_cnn

pytestmark = pytest.mark.slow

SPEC = """
[benchmark]
name = "policies"
seed = 2
pairs = 1
distance_m = [20.0, 22.0]
time_factor = 2.0
[[scenes]]
name = "small"
overrides.terrain = { source = "procedural", size_m = [40.0, 40.0], post_m = 0.25 }
overrides.rocks = { k = 0.02 }
[[methods]]
name = "mlp"
kind = "policy"
policy = "mlp.npz"
[[methods]]
name = "cnn"
kind = "policy"
policy = "cnn.npz"
"""


@pytest.fixture(scope="module")
def bench(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    pytest.importorskip("mujoco")
    root = tmp_path_factory.mktemp("navpolicy")
    goal_seeking_mlp(root / "mlp.npz", HeightScan(size_m=2.0, resolution_m=0.5))
    ground_seeing_cnn(root / "cnn.npz")
    spec = root / "spec.toml"
    spec.write_text(SPEC, encoding="utf-8")
    out = root / "out"
    res = CliRunner().invoke(main, ["benchmark", "nav", str(spec), str(out), "--serial"])
    assert res.exit_code == 0, res.output
    return spec, out


def _rows(out: Path) -> dict[str, dict[str, object]]:
    doc = json.loads((out / "results.json").read_text(encoding="utf-8"))
    return {str(r["method"]): r for r in doc["episodes"]}


def test_both_policies_reach_the_goal_at_the_environments_rate(bench: tuple[Path, Path]) -> None:
    _, out = bench
    rows = _rows(out)
    for name in ("mlp", "cnn"):  # the CNN moves only while its depth frames see ground
        row = rows[name]
        assert row["status"] == "ok" and row["kind"] == "policy", row
        assert row["success"], row
        # one call per 0.2 s (RoverNavEnv's 5 Hz) over the time it drove
        assert row["plan_calls"] == pytest.approx(5.0 * float(row["time_s"]), abs=3), row


def test_a_retrained_policy_runs_again(bench: tuple[Path, Path]) -> None:
    spec, out = bench
    cnn = spec.parent / "cnn.npz"
    before = {p.name: p.stat().st_mtime_ns for p in (out / "episodes").glob("*.json")}
    goal_seeking_mlp(spec.parent / "mlp.npz", HeightScan(size_m=3.0, resolution_m=0.5))
    res = CliRunner().invoke(main, ["benchmark", "nav", str(spec), str(out), "--serial",
                                    "--resume"])
    assert res.exit_code == 0, res.output
    rows = _rows(out)
    assert not rows["mlp"].get("skipped") and rows["cnn"].get("skipped")
    after = {p.name: p.stat().st_mtime_ns for p in (out / "episodes").glob("*.json")}
    changed = sorted(n for n in after if after[n] != before.get(n))
    assert len(changed) == 1 and "method=mlp" in changed[0] and cnn.is_file()


def test_a_policy_file_that_is_missing_is_one_line(tmp_path: Path) -> None:
    spec = tmp_path / "spec.toml"
    spec.write_text(SPEC, encoding="utf-8")
    res = CliRunner().invoke(main, ["benchmark", "nav", str(spec), str(tmp_path / "o")])
    assert res.exit_code == 1
    assert res.output.strip().splitlines()[-1].startswith("Error: method 'mlp': policy file")
