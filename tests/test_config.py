"""SceneConfig: TOML round trip, hashing, and messages that name key, value and range."""

from __future__ import annotations

from pathlib import Path

import pytest

import marsscene as ms
from marsscene.errors import ConfigError


def test_from_toml_and_to_dict(tmp_path: Path) -> None:
    p = tmp_path / "scene.toml"
    p.write_text(
        'seed = 3\n[terrain]\nsource = "procedural"\nsize_m = [50.0, 40.0]\npost_m = 0.5\n'
        "[rocks]\nenabled = false\n[export]\nusd_format = \"usdc\"\n"
    )
    cfg = ms.SceneConfig.from_toml(p)
    assert cfg.seed == 3
    assert cfg.terrain.size_m == (50.0, 40.0)
    assert cfg.rocks.enabled is False
    assert cfg.export.usd_format == "usdc"
    again = ms.SceneConfig.from_dict(cfg.to_dict())
    assert again == cfg and again.config_hash() == cfg.config_hash()
    assert ms.SceneConfig().config_hash() != cfg.config_hash()


def test_relative_dem_path_resolves_against_the_config_file(tmp_path: Path) -> None:
    (tmp_path / "cfg").mkdir()
    p = tmp_path / "cfg" / "scene.toml"
    p.write_text('[terrain]\nsource = "dem"\ndem_path = "../dem.tif"\n')
    assert ms.SceneConfig.from_toml(p).terrain.dem_path == str((tmp_path / "dem.tif").resolve())


@pytest.mark.parametrize(
    ("mapping", "pattern"),
    [
        ({"terrain": {"sorce": "dem"}}, r"unknown key terrain\.sorce"),
        ({"terrian": {}}, r"unknown key terrian = "),
        ({"terrain": {"size_m": [-5.0, 10.0]}}, r"terrain\.size_m = -5\.0 .*\(0\.0, 100000\.0\]"),
        ({"terrain": {"hurst": 1.5}}, r"terrain\.hurst = 1\.5 .*\(0\.0, 1\.0\]"),
        ({"terrain": {"source": "moon"}}, r"terrain\.source = 'moon'"),
        ({"terrain": {"source": "dem"}}, r"needs terrain\.dem_path"),
        ({"export": {"usd_format": "obj"}}, r"export\.usd_format = 'obj'"),
        ({"seed": -1}, r"seed = -1"),
    ],
)
def test_bad_values_are_rejected_with_a_message(mapping: dict, pattern: str) -> None:
    with pytest.raises(ConfigError, match=pattern):
        ms.SceneConfig.from_dict(mapping)


def test_bad_toml_is_a_config_error(tmp_path: Path) -> None:
    p = tmp_path / "bad.toml"
    p.write_text("[terrain\n")
    with pytest.raises(ConfigError, match="not valid TOML"):
        ms.SceneConfig.from_toml(p)
    with pytest.raises(ConfigError, match="not found"):
        ms.SceneConfig.from_toml(tmp_path / "missing.toml")


def test_configs_are_frozen() -> None:
    cfg = ms.SceneConfig()
    with pytest.raises(AttributeError):
        cfg.terrain.hurst = 0.5  # type: ignore[misc]
