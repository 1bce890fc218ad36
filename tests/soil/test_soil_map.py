"""The soil map: its rules over terrain and craters, seeded patches, its files, and the scene's
USD and MJCF carrying it to the simulators."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

import marsscene as ms
from marsscene.craters.table import CraterTable
from marsscene.errors import ConfigError
from marsscene.soil import SoilConfig, author_soil_map, read_soil_map, write_soil_map
from marsscene.terrain.heightfield import Heightfield

FLAT = Heightfield.centered(np.zeros((241, 241), np.float32), 0.25)  # 60 m x 60 m


def _craters(xy: list[tuple[float, float]], d_m: float) -> CraterTable:
    n = len(xy)
    return CraterTable(center_xy_m=np.array(xy, float), diameter_m=np.full(n, d_m),
                       depth_m=np.full(n, 0.1 * d_m), rim_height_m=np.full(n, 0.02 * d_m),
                       age_ga=np.ones(n), profile=np.zeros(n, int))


@pytest.mark.parametrize("fraction", [0.05, 0.3])
def test_drift_patches_cover_their_share_and_follow_the_seed(fraction: float) -> None:
    cfg = SoilConfig(enabled=True, patch_fraction=fraction, crater_floor_fraction=0.0)
    a = author_soil_map(cfg, FLAT, None, np.random.default_rng(1))
    assert a.shares()["drift_sand"] == pytest.approx(fraction, abs=0.005)
    again = author_soil_map(cfg, FLAT, None, np.random.default_rng(1))
    other = author_soil_map(cfg, FLAT, None, np.random.default_rng(2))
    assert np.array_equal(a.index, again.index) and not np.array_equal(a.index, other.index)
    # patches, not speckle: most drift posts have drift on all four sides
    d = a.index == 1
    inner = d[1:-1, 1:-1] & d[:-2, 1:-1] & d[2:, 1:-1] & d[1:-1, :-2] & d[1:-1, 2:]
    assert inner.sum() > 0.8 * d[1:-1, 1:-1].sum()


def test_crater_floors_and_steep_slopes_take_their_soils() -> None:
    cfg = SoilConfig(enabled=True, patch_fraction=0.0, ground="dry_sand",
                     crater_floor="megaripple_sand", crater_floor_fraction=0.5,
                     steep="firm_regolith", steep_deg=20.0)
    m = author_soil_map(cfg, FLAT, _craters([(10.0, -5.0)], 8.0), np.random.default_rng(0))
    at = lambda x, y: m.soils[int(m.at(np.array([[x, y]]))[0])].name  # noqa: E731
    assert at(10.0, -5.0) == at(11.9, -5.0) == "megaripple_sand"  # inside half the radius
    assert at(12.5, -5.0) == at(0.0, 0.0) == "dry_sand"
    assert m.shares()["megaripple_sand"] == pytest.approx(math.pi * 2.0**2 / 60**2, rel=0.05)
    x = (np.arange(241) - 120) * 0.25
    ramp = Heightfield.centered(np.tile(np.tan(np.radians(30.0)) * x, (241, 1))
                                .astype(np.float32), 0.25)
    # a 30 deg ramp is too steep for sand (all but the smoothing's edge posts)
    assert author_soil_map(cfg, ramp, None, np.random.default_rng(0)).shares()[
        "firm_regolith"] > 0.95


def test_files_round_trip_north_row_first(tmp_path: Path) -> None:
    cfg = SoilConfig(enabled=True, patch_fraction=0.2)
    m = author_soil_map(cfg, FLAT, _craters([(0.0, 20.0)], 10.0), np.random.default_rng(5))
    write_soil_map(m, tmp_path)
    back = read_soil_map(tmp_path)
    assert back is not None and np.array_equal(back.index, m.index)
    assert back.soils == m.soils and back.bounds_xy_m == m.bounds_xy_m
    from PIL import Image

    with Image.open(tmp_path / "soil" / "soil_map.png") as im:  # image order: north first
        assert np.array_equal(np.asarray(im)[0], m.index[-1])
    assert read_soil_map(tmp_path / "elsewhere") is None
    (tmp_path / "soil" / "soils.json").write_text("{", encoding="utf-8")
    with pytest.raises(ConfigError, match="not a readable soil map"):
        read_soil_map(tmp_path)


@pytest.mark.parametrize(("table", "message"), [
    ({"ground": "quicksand"}, "soil 'quicksand' is unknown"),
    ({"patch_fraction": 1.5}, "soil.patch_fraction"),
    ({"colour": "red"}, "colour"),
])
def test_bad_soil_tables_are_one_line_errors(table: dict, message: str) -> None:
    with pytest.raises(ConfigError, match=message) as err:
        ms.SceneConfig.from_dict({"soil": {"enabled": True, **table}})
    assert "\n" not in str(err.value)


def test_a_built_scene_carries_its_soils_to_usd_mjcf_and_the_rover(tmp_path: Path) -> None:
    pytest.importorskip("mujoco")
    from pxr import Usd, UsdPhysics

    from marsscene.sim.rover_sim import RoverSim

    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "procedural", "size_m": [30, 30], "rms_height_m": 0.05},
        "rocks": {"enabled": False}, "soil": {"enabled": True, "ground": "dry_sand"}})
    scene = ms.build_scene(cfg, seed=4)
    out = tmp_path / "scene"
    ms.write_scene(scene, out, formats=("usd", "mjcf"))
    doc = json.loads((out / "soil" / "soils.json").read_text(encoding="utf-8"))
    assert [s["name"] for s in doc["soils"]] == ["dry_sand", "drift_sand", "firm_regolith"]
    stage = Usd.Stage.Open(str(out / "scene.usda"))
    mat = stage.GetPrimAtPath("/World/Soil/drift_sand")
    assert mat.HasAPI(UsdPhysics.MaterialAPI)
    assert UsdPhysics.MaterialAPI(mat).GetStaticFrictionAttr().Get() == pytest.approx(
        math.tan(math.radians(27.0)))
    assert mat.GetAttribute("marsscene:soil:cohesionPa").Get() == 240.0
    terrain = stage.GetPrimAtPath("/World/Terrain")
    names = list(terrain.GetAttribute("marsscene:soil:names").Get())
    assert names == ["dry_sand", "drift_sand", "firm_regolith"]
    assert (out / "soil" / "soil_map.png").is_file()
    assert "marsscene_soil_map" in (out / "mjcf" / "scene.xml").read_text(encoding="utf-8")
    sim = RoverSim(out)
    assert sim.wheel_soil is not None and sim.soil_map.shares() == scene.soil.shares()
    assert RoverSim(out, soil="rigid").wheel_soil is None
