"""``marsscene sun`` and the lighting options of ``marsscene build`` (CliRunner)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from marsscene.cli import main
from marsscene.lighting import mars_sun_position


def test_sun_text_and_json(runner: CliRunner) -> None:
    args = ["sun", "--site-lat-deg", "18.44", "--site-lon-east-deg", "77.45",
            "--utc", "2021-02-18T20:55Z"]
    res = runner.invoke(main, args)
    assert res.exit_code == 0, res.output
    assert "azimuth 258.72" in res.output and "elevation 37.02" in res.output
    res = runner.invoke(main, [*args, "--tau", "2", "--json"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.output)
    ref = mars_sun_position("2021-02-18T20:55Z", lat_deg=18.44, lon_east_deg=77.45)
    assert doc["elevation_deg"] == pytest.approx(ref.elevation_deg)
    assert doc["ls_deg"] == pytest.approx(ref.ls_deg)
    assert doc["tau"] == 2.0
    total = doc["direct_horizontal_w_m2"] + doc["diffuse_horizontal_w_m2"]
    assert doc["global_horizontal_w_m2"] == pytest.approx(total)


def test_sun_mars_local_time(runner: CliRunner) -> None:
    res = runner.invoke(main, ["sun", "--site-lat-deg", "0", "--site-lon-east-deg", "0",
                               "--mars-year", "36", "--ls-deg", "90", "--ltst-h", "12", "--json"])
    assert res.exit_code == 0, res.output
    assert json.loads(res.output)["ltst_h"] == pytest.approx(12.0, abs=1e-6)


@pytest.mark.parametrize("args, code, text", [
    (["--utc", "2021-02-18T20:55"], 1, "no time zone"),
    (["--utc", "2021-02-18T20:55Z", "--tau", "-1"], 2, "tau"),
    ([], 2, "--utc"),
])
def test_sun_errors(runner: CliRunner, args: list[str], code: int, text: str) -> None:
    res = runner.invoke(main, ["sun", "--site-lat-deg", "18.44", "--site-lon-east-deg", "77.45",
                               *args])
    assert res.exit_code == code
    assert text in res.output


def test_sun_bad_latitude(runner: CliRunner) -> None:
    res = runner.invoke(main, ["sun", "--site-lat-deg", "95", "--site-lon-east-deg", "0",
                               "--utc", "2021-02-18T20:55Z"])
    assert res.exit_code == 2 and "--site-lat-deg" in res.output


def test_build_with_explicit_sun_and_tau(runner: CliRunner, tmp_path: Path) -> None:
    cfg = tmp_path / "tiny.toml"
    cfg.write_text('[terrain]\nsource = "procedural"\nsize_m = [8.0, 8.0]\npost_m = 1.0\n'
                   "[craters]\nenabled = false\n[rocks]\nenabled = false\n"
                   '[lighting]\nutc = "2021-02-18T20:55:00Z"\n', encoding="utf-8")
    out = tmp_path / "out"
    res = runner.invoke(main, ["build", "--config", str(cfg), "--out", str(out),
                               "--sun-azimuth-deg", "360", "--sun-elevation-deg", "13",
                               "--tau", "2.5"])
    assert res.exit_code == 0, res.output
    summary = json.loads((out / "manifest.json").read_text())["summary"]
    assert summary["lighting_sun_azimuth_deg"] == 0.0  # the CLI sun replaces the config's utc
    assert summary["lighting_sun_elevation_deg"] == 13.0
    assert summary["lighting_tau"] == 2.5
    res = runner.invoke(main, ["build", "--config", str(cfg), "--out", str(out),
                               "--sun-azimuth-deg", "10"])
    assert res.exit_code == 2 and "go together" in res.output
