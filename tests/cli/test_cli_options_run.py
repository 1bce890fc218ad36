"""``marsscene.cli.options_run``: the sensor and run-config options of ``drive`` and ``serve``,
declared once, and the RunConfig they make."""

from __future__ import annotations

import pytest

from marsscene.cli.drive import drive
from marsscene.cli.options_run import RUN_OPTION_NAMES, run_config
from marsscene.cli.serve import serve
from marsscene.errors import ConfigError
from marsscene.rover.config import RunConfig


def _params(command) -> dict:
    return {p.name: p for p in command.params}


def test_drive_and_serve_share_the_declarations():
    d, s = _params(drive), _params(serve)
    assert set(RUN_OPTION_NAMES) <= set(d)
    shared = set(RUN_OPTION_NAMES) & set(s)
    assert shared == {"camera", "camera_size", "camera_hz", "stereo", "lidar", "lidar_model",
                      "noise_profile", "run_config", "soil"}
    for name in shared:
        a, b = d[name], s[name]
        assert (a.opts, a.default, a.is_flag, type(a.type)) == (
            b.opts, b.default, b.is_flag, type(b.type)), name
    assert "ros2" not in s  # no switch that cannot be turned off


def test_run_config_defaults_and_values():
    assert run_config({}) == RunConfig()
    run = run_config({"camera": True, "camera_size": "64x48", "lidar_model": "vlp16"})
    assert (run.camera.width_px, run.camera.height_px) == (64, 48)
    assert run.lidar.model == "vlp16" and run.camera.exposure == "auto"
    with pytest.raises(ConfigError, match="WIDTHxHEIGHT"):
        run_config({"camera": True, "camera_size": "64"})


def test_soil_option_sets_the_run_soil_over_the_config_file(tmp_path):
    cfg = tmp_path / "run.toml"
    cfg.write_text('[run]\nsoil = "dry_sand"\n', encoding="utf-8")
    assert run_config({"run_config": cfg}).soil == "dry_sand"
    assert run_config({"run_config": cfg, "soil": "rigid"}).soil == "rigid"


def test_unknown_values_are_a_programming_error():
    with pytest.raises(TypeError, match="lookahead"):
        run_config({"camera": True, "lookahead": 1.0})
