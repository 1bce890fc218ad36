"""The command line through click's CliRunner: happy path and user mistakes."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from marsscene.cli import main

pytest.importorskip("pxr")


def test_version(runner: CliRunner) -> None:
    from marsscene import __version__

    result = runner.invoke(main, ["--version"])
    assert result.exit_code == 0 and __version__ in result.output


def test_default_build_writes_the_scene(runner: CliRunner, tmp_path: Path) -> None:
    out = tmp_path / "demo"
    result = runner.invoke(main, ["build", "--seed", "7", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert (out / "scene.usda").is_file()
    assert (out / "mjcf" / "scene.xml").is_file()
    doc = json.loads((out / "manifest.json").read_text())
    assert doc["seed"] == 7
    assert doc["inputs"]["dem"]["sha256"] == (
        "d4bdfb6c2de2fb9e5eaf9595d2645daf9051408a3c56300282768fcbcdb889dd"
    )
    assert doc["terrain"]["post_m"] == 0.25
    assert abs(doc["frame"]["origin_lonlat_deg"][1] - (-4.667)) < 0.01
    assert "scene.usda" in doc["outputs"] and "mjcf/scene.xml" in doc["outputs"]
    assert "[terrain]" in result.output  # progress line per stage
    info = runner.invoke(main, ["info", str(out)])
    assert info.exit_code == 0 and "seed 7" in info.output


def test_procedural_build_with_formats(runner: CliRunner, tmp_path: Path) -> None:
    cfg = tmp_path / "s.toml"
    cfg.write_text('[terrain]\nsize_m = [10.0, 10.0]\npost_m = 0.5\n')
    out = tmp_path / "p"
    result = runner.invoke(main, ["-q", "build", "--procedural", "--config", str(cfg),
                                  "--format", "usdc", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert (out / "scene.usdc").is_file() and not (out / "mjcf").exists()


def _assert_clean_failure(result, out: Path, pattern: str) -> None:  # type: ignore[no-untyped-def]
    assert result.exit_code != 0
    assert pattern in result.output
    assert "Traceback" not in result.output
    assert not out.exists()
    assert not [p for p in out.parent.iterdir() if p.name.startswith(f".{out.name}.")]


def test_missing_dem_file(runner: CliRunner, tmp_path: Path) -> None:
    out = tmp_path / "o"
    result = runner.invoke(main, ["build", "--dem", str(tmp_path / "nope.img"), "--out", str(out)])
    _assert_clean_failure(result, out, "does not exist")


def test_unreadable_dem(runner: CliRunner, tmp_path: Path) -> None:
    bad = tmp_path / "fake.tif"
    bad.write_text("this is not a raster\n")
    out = tmp_path / "o"
    result = runner.invoke(main, ["build", "--dem", str(bad), "--out", str(out)])
    _assert_clean_failure(result, out, "fake.tif")


def test_bad_config_key(runner: CliRunner, tmp_path: Path) -> None:
    cfg = tmp_path / "bad.toml"
    cfg.write_text("[terrain]\nhurstt = 0.5\n")
    out = tmp_path / "o"
    result = runner.invoke(main, ["build", "--config", str(cfg), "--out", str(out)])
    _assert_clean_failure(result, out, "unknown key terrain.hurstt")


def test_negative_size(runner: CliRunner, tmp_path: Path) -> None:
    cfg = tmp_path / "neg.toml"
    cfg.write_text('[terrain]\nsource = "procedural"\nsize_m = [-10.0, 10.0]\n')
    out = tmp_path / "o"
    result = runner.invoke(main, ["build", "--config", str(cfg), "--out", str(out)])
    _assert_clean_failure(result, out, "terrain.size_m = -10.0")


def test_failed_export_leaves_previous_scene_intact(
    runner: CliRunner, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import marsscene.export as export

    out = tmp_path / "keep"
    out.mkdir()
    (out / "marker.txt").write_text("old")

    def boom(scene, out_dir):  # type: ignore[no-untyped-def]
        (out_dir / "partial.xml").write_text("<half")
        raise OSError("disk full")

    monkeypatch.setitem(export.WRITERS, "mjcf", boom)
    result = runner.invoke(main, ["build", "--procedural", "--out", str(out)])
    assert result.exit_code == 1 and "disk full" in result.output
    assert (out / "marker.txt").read_text() == "old" and not (out / "partial.xml").exists()


def test_info_on_a_dem(runner: CliRunner, synthetic_dem_path: Path) -> None:
    result = runner.invoke(main, ["info", str(synthetic_dem_path)])
    assert result.exit_code == 0, result.output
    assert "48 rows x 64 cols, post 1 m" in result.output
    assert "lon 77.5" in result.output


def test_info_on_a_folder_that_is_not_a_scene(runner: CliRunner, tmp_path: Path) -> None:
    result = runner.invoke(main, ["info", str(tmp_path)])
    assert result.exit_code == 1 and "not a marsscene scene folder" in result.output


def test_warnings_are_one_line_messages(
    runner: CliRunner, synthetic_dem_path: Path, tmp_path: Path
) -> None:
    out = tmp_path / "o"
    result = runner.invoke(main, ["build", "--dem", str(synthetic_dem_path), "--format", "mjcf",
                                  "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "marsscene: warning: bowl: filled 9 missing posts" in result.output
    assert "fill_nodata(" not in result.output  # no source-line excerpt
    info = runner.invoke(main, ["info", "--band", "1", str(synthetic_dem_path)])
    assert info.exit_code == 0 and "48 rows x 64 cols" in info.output
