"""Parquet rock catalogue: same rows, columns and units as ``rocks.csv``, reproducible bytes,
read back with pyarrow; the config key, the CLI flag and a missing pyarrow."""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import marsscene as ms
from marsscene.errors import ConfigError, MissingDependencyError
from marsscene.export.catalog_rocks import COLUMNS
from marsscene.sensors.camera_world import read_rock_catalog

pq = pytest.importorskip("pyarrow.parquet")
pytest.importorskip("pxr")

CFG = {
    "terrain": {"source": "procedural", "size_m": [30.0, 24.0], "post_m": 0.5},
    "rocks": {"k": 0.08, "d_min_m": 0.1, "mjcf_max_rocks": 25},
    "craters": {"enabled": False},
    "export": {"formats": ["mjcf"], "rock_catalogue": "both"},
}


@pytest.fixture(scope="module")
def scene() -> ms.Scene:
    return ms.build_scene(ms.SceneConfig.from_dict(CFG), seed=9)


def _with_catalogue(scene: ms.Scene, kind: str) -> ms.Scene:
    export = dataclasses.replace(scene.config.export, rock_catalogue=kind)
    return dataclasses.replace(scene, config=scene.config.replace(export=export))


def test_parquet_equals_the_csv_and_is_reproducible(scene: ms.Scene, tmp_path: Path) -> None:
    assert scene.rocks is not None and len(scene.rocks) > 1000
    ms.write_scene(scene, tmp_path / "a")
    ms.write_scene(ms.build_scene(ms.SceneConfig.from_dict(CFG), seed=9), tmp_path / "b")
    first = (tmp_path / "a" / "rocks.parquet").read_bytes()
    assert first == (tmp_path / "b" / "rocks.parquet").read_bytes()
    assert first[:4] == b"PAR1"

    table = pq.read_table(tmp_path / "a" / "rocks.parquet")
    assert tuple(table.column_names) == COLUMNS
    units = {f.name: f.metadata[b"unit"].decode() for f in table.schema}
    assert units["x_m"] == units["diameter_m"] == units["burial_m"] == "m"
    assert units["id"] == units["prototype"] == units["in_mjcf"] == "1"
    csv = np.loadtxt(tmp_path / "a" / "rocks.csv", delimiter=",", skiprows=1)
    assert table.num_rows == len(csv) == len(scene.rocks)
    for i, name in enumerate(COLUMNS):
        values = table.column(name).to_numpy().astype(np.float64)
        if name.endswith("_m"):  # csv: 0.1 mm fixed point; parquet: float32
            np.testing.assert_allclose(values, csv[:, i], rtol=0, atol=6e-5, err_msg=name)
        else:
            np.testing.assert_array_equal(values, csv[:, i], err_msg=name)
    assert table.column("in_mjcf").to_numpy().sum() == 25  # mjcf_max_rocks
    manifest = json.loads((tmp_path / "a" / "manifest.json").read_text())
    assert {"rocks.csv", "rocks.parquet"} <= set(manifest["outputs"])


def test_parquet_only_catalogue_serves_the_runtime_camera(scene: ms.Scene,
                                                          tmp_path: Path) -> None:
    ms.write_scene(_with_catalogue(scene, "parquet"), tmp_path / "p")
    ms.write_scene(_with_catalogue(scene, "csv"), tmp_path / "c")
    assert not (tmp_path / "p" / "rocks.csv").exists()
    assert not (tmp_path / "c" / "rocks.parquet").exists()
    from_parquet = read_rock_catalog(tmp_path / "p")
    from_csv = read_rock_catalog(tmp_path / "c")
    assert from_parquet.shape == from_csv.shape == (len(scene.rocks or ()) - 25, 6)
    np.testing.assert_allclose(from_parquet, from_csv, rtol=0, atol=1.2e-4)


def test_bad_choice_and_cli_flag(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"export\.rock_catalogue"):
        ms.SceneConfig.from_dict({"export": {"rock_catalogue": "xlsx"}})
    from marsscene.cli import main

    cfg = tmp_path / "s.toml"
    cfg.write_text('[terrain]\nsize_m = [10.0, 10.0]\npost_m = 0.5\n'
                   '[rocks]\nk = 0.08\nd_min_m = 0.2\n')
    out = tmp_path / "cli"
    result = CliRunner().invoke(main, ["-q", "build", "--procedural", "--config", str(cfg),
                                       "--format", "mjcf", "--rock-catalogue", "parquet",
                                       "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert not (out / "rocks.csv").exists()
    assert pq.read_table(out / "rocks.parquet").num_rows > 0


def test_missing_pyarrow_fails_before_writing(scene: ms.Scene, tmp_path: Path,
                                              monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "pyarrow", None)  # import pyarrow -> ImportError
    with pytest.raises(MissingDependencyError, match=r"marsscene\[parquet\]"):
        ms.write_scene(scene, tmp_path / "x")
    assert list(tmp_path.iterdir()) == []
    ms.write_scene(_with_catalogue(scene, "csv"), tmp_path / "y")  # csv needs no pyarrow
    assert (tmp_path / "y" / "rocks.csv").is_file()


def test_example_script_reads_the_catalogue(tmp_path: Path) -> None:
    import runpy

    example = Path(__file__).resolve().parents[2] / "examples" / "rock_catalogue_parquet.py"
    result = runpy.run_path(str(example))["main"](tmp_path / "demo")
    table = pq.read_table(tmp_path / "demo" / "rocks.parquet")
    assert result["rocks"] == table.num_rows > 10_000  # k = 0.05, D >= 0.1 m on 0.04 km^2
    assert result["mjcf_rocks"] == int(table.column("in_mjcf").to_numpy().sum()) > 0
    assert not (tmp_path / "demo" / "rocks.csv").exists()


def test_cli_without_pyarrow_is_a_one_line_error_before_building(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from marsscene.cli import main

    monkeypatch.setitem(sys.modules, "pyarrow", None)
    out = tmp_path / "nope"
    result = CliRunner().invoke(main, ["build", "--procedural", "--rock-catalogue", "both",
                                       "--out", str(out)])
    assert result.exit_code != 0
    assert "marsscene[parquet]" in result.output and "Traceback" not in result.output
    assert not out.exists()
