"""``[craters]`` configuration: defaults, TOML round trip, clear errors."""

from __future__ import annotations

from pathlib import Path

import pytest

import marsscene as ms
from marsscene.craters import CraterConfig, ResurfacingEvent
from marsscene.errors import ConfigError


def test_defaults() -> None:
    c = CraterConfig()
    assert (c.system, c.age_ga, c.d_min_m, c.d_max_m) == ("hartmann-daubar-2016", 3.5, 2.0, 20.0)
    assert c.equilibrium == "hartmann-1984" and c.profile == "watters-2015"
    assert c.resurfacing == ()


def test_toml_with_resurfacing_round_trips(tmp_path: Path) -> None:
    path = tmp_path / "scene.toml"
    path.write_text(
        """
[craters]
system = "hartmann-daubar-2016"
age_ga = 3.2
d_min_m = 1.0
d_max_m = 50.0
profile = "ftmod"
depth_to_diameter = 0.15
degradation = "none"

[[craters.resurfacing]]
age_ga = 1.0
d_max_m = 8.0
polygon_xy_m = [[-50, -50], [50, -50], [50, 50]]

[[craters.resurfacing]]
age_ga = 0.3
rule = "burial"
thickness_m = 0.5
""",
        encoding="utf-8",
    )
    cfg = ms.SceneConfig.from_toml(path)
    ev = cfg.craters.resurfacing
    assert isinstance(ev[0], ResurfacingEvent) and ev[0].polygon_xy_m == (
        (-50.0, -50.0), (50.0, -50.0), (50.0, 50.0))
    assert ev[1].rule == "burial" and ev[1].thickness_m == 0.5
    again = ms.SceneConfig.from_dict(cfg.to_dict())
    assert again.config_hash() == cfg.config_hash()


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"d_min_m": 10.0, "d_max_m": 10.0}, r"d_min_m = 10.0 must be < craters.d_max_m = 10.0"),
        ({"d_min_m": 30.0, "d_max_m": 10.0}, "d_min_m"),
        ({"age_ga": -1.0}, r"craters.age_ga = -1.0 is out of range; allowed \(0.0, 4.5\]"),
        ({"age_ga": 4.6}, r"craters.age_ga = 4.6 is out of range"),
        ({"system": "neukum-1983"}, r"craters.system = 'neukum-1983' is not allowed; choose"),
        ({"profile": "cone"}, "craters.profile"),
        ({"equilibrium": "trask"}, "craters.equilibrium"),
        ({"d_min_m": 0.0}, "craters.d_min_m"),
        ({"depth_to_diameter": 0.9}, "craters.depth_to_diameter"),
        ({"resurfacing": ({"age_ga": 4.0, "d_max_m": 5.0},)}, "younger than craters.age_ga"),
        ({"resurfacing": ({"age_ga": 1.0},)}, "needs d_max_m"),
        ({"resurfacing": ({"age_ga": 1.0, "rule": "ramp", "d_min_m": 9, "d_max_m": 5},)},
         "d_min_m = 9 must be < d_max_m"),
        ({"resurfacing": ({"age_ga": 1.0, "d_max_m": 5, "polygon_xy_m": [[0, 0], [1, 1]]},)},
         "at least 3"),
        ({"resurfacing": ({"age_ga": 1.0, "d_max_m": 5, "colour": "red"},)},
         r"unknown key craters.resurfacing\[0\].colour"),
    ],
)
def test_bad_configs_raise_clear_errors(kw: dict, match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        CraterConfig(**kw)


def test_unknown_key_in_toml_table() -> None:
    with pytest.raises(ConfigError, match=r"unknown key craters\.d_min"):
        ms.SceneConfig.from_dict({"craters": {"d_min": 1.0}})
