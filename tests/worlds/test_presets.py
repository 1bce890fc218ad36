"""Reference-scene presets: the paper's sizes, override order, the memory plan (one grid, or
two levels of detail), and a (shrunken) build of every preset through the CLI."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import marsscene as ms
from marsscene.cli import main
from marsscene.errors import ConfigError
from marsscene.presets import PRESET_NAMES, preset_info
from marsscene.rocks.sfd import cumulative_number_density_per_m2
from marsscene.terrain.synth import MAX_POSTS

#: MarsLab paper, Table "MarsLab reference scenes" (km).
PAPER_SIZES_KM = {"jezero-plain": 0.5, "main-crater": 3.6, "mars-base": 1.0,
                  "grand-canyon": 3.0}
LANDFORMS = {"jezero-plain": "plain", "main-crater": "crater", "mars-base": "plain",
             "grand-canyon": "canyon"}


def test_presets_have_the_papers_sizes_and_shapes() -> None:
    assert set(PRESET_NAMES) == set(PAPER_SIZES_KM)
    for name, km in PAPER_SIZES_KM.items():
        cfg = ms.SceneConfig.from_dict({"preset": name})
        assert cfg.preset == name
        assert cfg.terrain.size_m == (km * 1000.0, km * 1000.0)
        assert cfg.terrain.landform == LANDFORMS[name]
        assert cfg.lighting.sun_mode == "explicit"
    assert ms.SceneConfig.from_dict({"preset": "mars-base"}).assets.habitat
    assert not ms.SceneConfig.from_dict({"preset": "main-crater"}).assets.active


@pytest.mark.parametrize("name", sorted(PAPER_SIZES_KM))
def test_full_size_presets_fit_the_memory_plan(name: str) -> None:
    """Each grid within terrain.synth.MAX_POSTS (with headroom for the 2-core/24 GB machine),
    the expected rock count of each placement, even at the full ejecta boost, within
    rocks.max_rocks; the 3-3.6 km scenes at 0.25 m over their 1 km focus square."""
    cfg = ms.SceneConfig.from_dict({"preset": name})
    t, r = cfg.terrain, cfg.rocks
    assert t.size_m is not None and t.post_m is not None
    posts = (t.size_m[0] / t.post_m + 1) * (t.size_m[1] / t.post_m + 1)
    assert posts <= 0.15 * MAX_POSTS

    def expected_rocks(d_min: float, area_m2: float) -> float:
        n = cumulative_number_density_per_m2([r.d_max_m, d_min], k=r.k)
        return float(n[1] - n[0]) * area_m2 * r.ejecta_boost

    area = t.size_m[0] * t.size_m[1]
    from marsscene.pipeline.terrain import resolve_lod

    assert (t.lod is True) == (PAPER_SIZES_KM[name] >= 3.0)
    assert resolve_lod(cfg)[0].terrain.lod == (PAPER_SIZES_KM[name] >= 3.0)  # auto: one grid
    if t.lod is True:
        assert (t.focus_post_m, t.focus_size_m, t.post_m) == (0.25, 1000.0, 1.0)
        assert (t.focus_size_m / t.focus_post_m + 1) ** 2 <= 0.15 * MAX_POSTS
        assert expected_rocks(r.d_min_m, t.focus_size_m**2) <= r.max_rocks
        assert expected_rocks(r.outer_d_min_m, area) <= r.max_rocks
        assert r.d_min_m <= 0.2
    else:
        assert expected_rocks(r.d_min_m, area) <= r.max_rocks


def test_user_values_override_the_preset(tmp_path: Path) -> None:
    toml = tmp_path / "s.toml"
    toml.write_text('preset = "jezero-plain"\n[terrain]\npost_m = 0.5\n[lighting]\ntau = 1.5\n')
    cfg = ms.SceneConfig.from_toml(toml)
    assert (cfg.terrain.post_m, cfg.lighting.tau, cfg.terrain.size_m) == (0.5, 1.5,
                                                                          (500.0, 500.0))
    # the CLI's --preset replaces the file's preset; the file's own keys still win
    cfg = ms.SceneConfig.from_toml(toml, preset="grand-canyon")
    assert (cfg.preset, cfg.terrain.landform, cfg.terrain.post_m) == ("grand-canyon",
                                                                      "canyon", 0.5)
    with pytest.raises(ConfigError, match="preset = 'olympus' is not known"):
        ms.SceneConfig.from_dict({"preset": "olympus"})


def test_preset_with_a_dem_uses_the_dtm(synthetic_dem_path: Path) -> None:
    cfg = ms.SceneConfig.from_dict({
        "preset": "main-crater",
        "terrain": {"source": "dem", "dem_path": str(synthetic_dem_path), "size_m": [40, 30],
                    "post_m": 1.0},
        "craters": {"enabled": False}, "rocks": {"enabled": False}})
    scene = ms.build_scene(cfg, seed=1)
    # the preset's level-of-detail terrain on the DTM: the DTM crop at its own 1 m posts
    # outside, a 0.25 m focus square (shrunk to fit the small crop) inside
    assert scene.outer is not None and scene.outer.heightfield.shape == (31, 41)
    assert scene.heightfield.cell_size_m == 0.25
    assert any("focus square does not fit" in n for n in scene.provenance.notes)
    assert scene.provenance.frame.crs_wkt  # geo-referenced: it came from the DTM
    for hf in (scene.heightfield, scene.outer.heightfield):
        assert float(hf.z_m.min()) > -5.0  # no 200 m deep procedural crater
    assert "dem" in scene.provenance.inputs


@pytest.mark.parametrize("name", sorted(PAPER_SIZES_KM))
def test_every_preset_builds_shrunk(name: str, tmp_path: Path, runner) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / name
    size = "60" if name != "mars-base" else "80"
    lod = ["--focus-size-m", "20"] if PAPER_SIZES_KM[name] >= 3.0 else []  # LOD presets
    res = runner.invoke(main, ["build", "--preset", name, "--size-m", size, size,
                               "--post-m", "0.5", "--out", str(out), "--seed", "2",
                               "--format", "usdc", "--format", "mjcf", *lod])
    assert res.exit_code == 0, res.output
    man = json.loads((out / "manifest.json").read_text())
    assert man["config"]["preset"] == name
    assert man["config"]["terrain"]["size_m"] == [float(size)] * 2
    assert man["config"]["terrain"]["landform"] == LANDFORMS[name]
    assert man["config"]["lighting"]["tau"] == preset_info(name)["config"]["lighting"]["tau"]
    assert ("assets" in man["summary"]) == (name == "mars-base")
    if lod:  # 20 m at 0.25 m inside 60 m at 0.5 m
        assert man["summary"]["lod"]["focus_posts"] == 81 * 81
        assert man["summary"]["lod"]["outer_posts"] == 121 * 121
    from pxr import Usd

    stage = Usd.Stage.Open(str(out / "scene.usdc"))
    assert stage.GetPrimAtPath("/World/Terrain").IsValid()
    assert stage.GetPrimAtPath("/World/TerrainLod1").IsValid() == bool(lod)
    assert stage.GetPrimAtPath("/World/Assets/habitat").IsValid() == (name == "mars-base")
    from marsscene.export.mjcf import validate_mjcf

    validate_mjcf(out / "mjcf" / "scene.xml", seconds=0.2)


def test_preset_with_habitat_is_byte_reproducible(tmp_path: Path) -> None:
    cfg = ms.SceneConfig.from_dict({"preset": "mars-base", "terrain": {
        "size_m": [80.0, 80.0], "post_m": 0.5}, "rocks": {"d_min_m": 0.4}})
    outs = []
    for name in ("a", "b"):
        out = tmp_path / name
        ms.write_scene(ms.build_scene(cfg, seed=9), out)
        outs.append(out)
    files = sorted(p.relative_to(outs[0]) for p in outs[0].rglob("*") if p.is_file()
                   and p.name != "manifest.json")
    assert any("asset_habitat" in str(f) for f in files)
    for rel in files:
        assert (outs[0] / rel).read_bytes() == (outs[1] / rel).read_bytes(), rel
    docs = [json.loads((o / "manifest.json").read_text()) for o in outs]
    for d in docs:
        d.pop("timings_s")
    assert docs[0] == docs[1]


def test_example_config_expands_the_preset_and_builds() -> None:
    example = Path(__file__).resolve().parents[2] / "docs" / "examples" / "mars_base.toml"
    cfg = ms.SceneConfig.from_toml(example)
    assert cfg.preset == "mars-base" and cfg.seed == 7
    assert cfg.terrain.size_m == (1000.0, 1000.0) and cfg.lighting.tau == 0.8
    assert cfg.assets.habitat and cfg.assets.max_slope_deg == 6.0
    import dataclasses

    small = cfg.replace(terrain=dataclasses.replace(cfg.terrain, size_m=(90.0, 90.0)))
    scene = ms.build_scene(small, seed=7)
    assert scene.assets is not None and len(scene.assets) == 1


def test_lod_example_config_puts_the_focus_on_the_rim() -> None:
    example = Path(__file__).resolve().parents[2] / "docs" / "examples" / "crater_rim_lod.toml"
    cfg = ms.SceneConfig.from_toml(example)
    t = cfg.terrain
    assert cfg.preset == "main-crater" and t.lod and t.focus_xy_m == (700.0, 0.0)
    assert (t.size_m, t.post_m, t.focus_post_m) == ((3600.0, 3600.0), 1.0, 0.25)
    assert (cfg.rocks.d_min_m, cfg.rocks.outer_d_min_m) == (0.15, 1.5)
    import dataclasses

    # the same keys on a 2.4 km footprint at coarser posts: the focus sits on the rim
    small = cfg.replace(
        terrain=dataclasses.replace(t, size_m=(2400.0, 2400.0), post_m=4.0, focus_post_m=2.0),
        craters=dataclasses.replace(cfg.craters, d_min_m=30.0),
        rocks=dataclasses.replace(cfg.rocks, d_min_m=1.0, outer_d_min_m=2.5))
    scene = ms.build_scene(small, seed=7)
    assert scene.outer is not None
    assert scene.heightfield.bounds_xy_m == (300.0, -400.0, 1100.0, 400.0)
    z = scene.heightfield.z_m
    assert float(z.max() - z.min()) > 50.0  # rim crest above the wall and the plain
