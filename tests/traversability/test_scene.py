"""``marsscene build --traversability`` and ``marsscene traversability`` on small built scenes:
the files, their georeferencing, the summary, one-line errors and reproducible bytes."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from marsscene.cli import main
from marsscene.traversability import LAYERS

pytest.importorskip("mujoco")
rasterio = pytest.importorskip("rasterio")

_TOML = """
[terrain]
source = "procedural"
size_m = [32.0, 32.0]
post_m = 0.25

[soil]
enabled = true
patch_fraction = 0.3
"""
FILES = ("traversability.tif", "preview.png", "summary.json")


@pytest.fixture(scope="module")
def rocky_scene(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 32 m procedural scene with rocks and drift-sand patches, built with its map."""
    root = tmp_path_factory.mktemp("trav")
    (root / "scene.toml").write_text(_TOML, encoding="utf-8")
    out = root / "scene"
    result = CliRunner().invoke(main, ["build", "--config", str(root / "scene.toml"), "--seed",
                                       "5", "--format", "mjcf", "--out", str(out),
                                       "--traversability"])
    assert result.exit_code == 0, result.output
    assert "traversability.tif" in result.output
    return out


def _digest(folder: Path) -> dict[str, bytes]:
    return {name: (folder / name).read_bytes() for name in FILES}


def test_build_writes_the_map_and_the_command_rewrites_the_same_bytes(rocky_scene: Path) -> None:
    folder = rocky_scene / "traversability"
    first = _digest(folder)
    result = CliRunner().invoke(main, ["traversability", str(rocky_scene)])
    assert result.exit_code == 0, result.output
    assert _digest(folder) == first  # same inputs, same bytes
    doc = json.loads(first["summary.json"])
    assert doc["grid"]["cell_m"] == 0.25 and doc["grid"]["shape_rows_cols"] == [129, 129]
    assert doc["grid"]["georeferenced"] is False  # a procedural scene: scene metres
    assert set(doc["soil_shares"]) == {"firm_regolith", "drift_sand"}
    assert 0.0 < doc["hazard_fraction"] < 1.0 and doc["limits"]["belly"] == 0.6
    with rasterio.open(folder / "traversability.tif") as ds:
        assert ds.descriptions == LAYERS and ds.shape == (129, 129) and ds.crs is None
        hazard = ds.read(LAYERS.index("hazard") + 1)
        cost = ds.read(LAYERS.index("cost") + 1)
        assert ds.res == (0.25, 0.25) and ds.bounds.left == pytest.approx(-16.125)
    assert float(hazard.mean()) == pytest.approx(doc["hazard_fraction"], abs=1e-6)
    assert np.all(cost[hazard > 0] == 1.0) and 0.0 <= float(cost.min())
    rocks = np.loadtxt(rocky_scene / "rocks.csv", delimiter=",", skiprows=1, ndmin=2)
    assert len(rocks) > 100 and doc["hazard_fraction_by_term"]["rock"] > 0.0


def test_a_coarser_cell_and_one_line_errors(rocky_scene: Path, tmp_path: Path) -> None:
    runner = CliRunner()
    result = runner.invoke(main, ["traversability", str(rocky_scene), "--cell-m", "1"])
    assert result.exit_code == 0, result.output
    doc = json.loads((rocky_scene / "traversability" / "summary.json").read_text("utf-8"))
    assert doc["grid"]["cell_m"] == 1.0 and doc["grid"]["shape_rows_cols"] == [33, 33]
    bad = runner.invoke(main, ["traversability", str(rocky_scene), "--cell-m", "0.1"])
    assert bad.exit_code == 1 and "finer than the terrain's 0.25 m posts" in bad.output
    assert len(bad.output.strip().splitlines()) == 1
    empty = runner.invoke(main, ["traversability", str(tmp_path)])
    assert empty.exit_code == 1 and "is not a built scene" in empty.output
    usd_only = runner.invoke(main, ["build", "--procedural", "--format", "usda", "--out",
                                    str(tmp_path / "u"), "--traversability"])
    assert usd_only.exit_code == 2 and "--format mjcf" in usd_only.output


def test_a_dem_scene_is_written_in_its_crs(synthetic_dem_path: Path, tmp_path: Path) -> None:
    out = tmp_path / "dem"
    result = CliRunner().invoke(main, ["build", "--dem", str(synthetic_dem_path), "--format",
                                       "mjcf", "--out", str(out), "--traversability",
                                       "--traversability-cell-m", "1"])
    assert result.exit_code == 0, result.output
    frame = json.loads((out / "manifest.json").read_text("utf-8"))["frame"]
    with rasterio.open(out / "traversability" / "traversability.tif") as ds:
        assert ds.crs is not None and "eqc" in ds.crs.to_proj4()
        x0, y0 = frame["origin_projected_xy_m"]
        cx, cy = ds.xy(ds.height // 2, ds.width // 2)  # the scene's centre is its origin
        assert abs(cx - x0) <= 1.0 and abs(cy - y0) <= 1.0


def test_the_scene_in_memory_gives_the_map_of_its_folder(tmp_path: Path) -> None:
    import marsscene as ms
    from marsscene.traversability.scene import (
        inputs_of_scene,
        read_scene_inputs,
        scene_traversability,
    )

    cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [24.0, 24.0],
                                                "post_m": 0.25}, "soil": {"enabled": True}})
    scene = ms.build_scene(cfg, seed=2)
    ms.write_scene(scene, tmp_path / "s", formats=("mjcf",))
    memory = scene_traversability(inputs_of_scene(scene))
    folder = scene_traversability(read_scene_inputs(tmp_path / "s"))
    assert memory.shape == folder.shape and memory.soils == folder.soils
    np.testing.assert_allclose(memory.slope_deg, folder.slope_deg, atol=0.01)
    np.testing.assert_allclose(memory.rock_m, folder.rock_m, atol=1e-3)  # 0.1 mm catalogue
    assert np.mean(memory.hazard == folder.hazard) > 0.999
