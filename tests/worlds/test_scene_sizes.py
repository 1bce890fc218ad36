"""Every scene size builds with its defaults (issue 63): property tests over footprints from
0.1 to 4 km, procedural and DEM crops, and the main terrain and rock options. Each valid
configuration builds, with its rocks within rocks.max_rocks (the full population over the focus
square and rocks above the stated cut-off outside it), or is refused in one line naming the
option to change.

Kept cheap: coarse posts and small rock budgets (the plan and the code paths are those of a
full-size build at 0.25 m; ``python perf/run.py scene_sizes`` measures the real sizes)."""

from __future__ import annotations

import dataclasses
import math
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import marsscene as ms
from marsscene.config import SceneConfig
from marsscene.errors import ConfigError, MemoryBudgetError
from marsscene.pipeline.record import BuildRecord
from marsscene.pipeline.rocks import rock_stage
from marsscene.terrain.heightfield import Heightfield
from marsscene.testing.pds3 import write_pds3_dtm

OPTION = re.compile(r"\b(rocks|terrain|craters)\.[a-z_]+\b|--[a-z-]+")
DTM_POST_M = 4.0
DTM_LINES, DTM_SAMPLES = 3000, 1100  # 4.4 x 12 km at 4 m: the 4 km crop fits the strip


def _rocks(**kw: object) -> dict[str, object]:
    return {"max_rocks": 20_000, **kw}


def _check(cfg: SceneConfig, seed: int = 3) -> None:
    """Build ``cfg``: it builds within its rock budget, or is refused in one line naming an
    option (a ConfigError or MemoryBudgetError; anything else fails the test)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # extrapolated k, filled DTM posts, ...
            scene = ms.build_scene(cfg, seed=seed)
    except (ConfigError, MemoryBudgetError) as err:
        msg = str(err)
        assert "\n" not in msg and OPTION.search(msg), msg
        return
    rc = scene.config.rocks
    rocks = scene.rocks
    assert rocks is not None
    assert len(rocks) <= rc.max_rocks + 6 * math.sqrt(rc.max_rocks)  # Poisson about <= budget
    d = rocks.diameter_m
    assert np.all(d >= rc.d_min_m - 1e-12)
    levels = scene.provenance.extra["rocks"].get("levels")
    if levels is None:
        assert scene.outer is None  # a level-of-detail terrain always has two rock levels
        return
    x0, y0, x1, y1 = levels["focus_bounds_xy_m"]
    p = rocks.position_xyz_m
    inside = (p[:, 0] >= x0) & (p[:, 0] <= x1) & (p[:, 1] >= y0) & (p[:, 1] <= y1)
    assert np.all(d[~inside] >= levels["outer_d_min_m"] - 1e-12)
    assert (levels["focus_count"], levels["outer_count"]) == (int(inside.sum()),
                                                              int((~inside).sum()))
    assert any("rocks: two levels" in n for n in scene.provenance.notes)


sizes = st.floats(100.0, 4000.0)
rock_options = st.fixed_dictionaries({
    "d_min_m": st.sampled_from([0.3, 0.6, 1.0]),
    "outer_d_min_m": st.sampled_from([0.1, 1.2, 1.5, 2.0, 2.5]),  # 0.1: every rock everywhere
    "k": st.floats(0.03, 0.2),
    "placement": st.sampled_from(["uniform", "ejecta", "clustered"]),
    "max_rocks": st.integers(5_000, 60_000),
})


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(w=sizes, h=sizes, rocks=rock_options, lod=st.sampled_from(["auto", True]),
       focus=st.floats(60.0, 600.0), offset=st.booleans())
def test_procedural_scenes_build_or_are_refused_in_one_line(
        w: float, h: float, rocks: dict[str, object], lod: object, focus: float,
        offset: bool) -> None:
    post = float(max(1, math.ceil(max(w, h) / 600.0)))  # at most ~0.4 M posts
    terrain: dict[str, object] = {"source": "procedural", "size_m": [w, h], "post_m": post,
                                  "lod": lod, "focus_size_m": focus, "tile_m": 250.0,
                                  "lod_blend_m": 20.0}
    if lod is True:
        terrain |= {"post_m": 2 * post, "focus_post_m": post}
    if offset:
        terrain["focus_xy_m"] = [w / 5, -h / 7]
    cfg = SceneConfig.from_dict({"terrain": terrain, "rocks": rocks,
                                 "craters": {"d_min_m": 10.0, "d_max_m": 200.0},
                                 "lighting": {"enabled": False}})
    _check(cfg)


@pytest.fixture(scope="module")
def strip_dtm(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A HiRISE-shaped DTM: valid posts in a slanted strip, MISSING_CONSTANT outside it."""
    x = np.arange(DTM_SAMPLES, dtype=np.float32)
    y = np.arange(DTM_LINES, dtype=np.float32)[:, None]
    z = -2500.0 + 20.0 * np.sin(x / 90.0) * np.cos(y / 120.0) + 0.01 * y + 0 * x
    centre = DTM_SAMPLES / 2 + 0.05 * (y - DTM_LINES / 2)
    z[np.abs(x - centre) > 520] = np.nan
    path = tmp_path_factory.mktemp("dtm") / "DTEEC_STRIP_U01.IMG"
    return write_pds3_dtm(path, z.astype(np.float32), map_scale_m=DTM_POST_M)


@settings(max_examples=6, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(w=sizes, h=sizes, rocks=rock_options, lod=st.sampled_from(["auto", True]),
       focus=st.floats(60.0, 600.0))
def test_dem_crops_build_or_are_refused_in_one_line(
        strip_dtm: Path, w: float, h: float, rocks: dict[str, object], lod: object,
        focus: float) -> None:
    terrain: dict[str, object] = {"source": "dem", "dem_path": str(strip_dtm), "size_m": [w, h],
                                  "lod": lod, "focus_size_m": focus, "focus_post_m": 2.0,
                                  "tile_m": 250.0, "lod_blend_m": 20.0}
    cfg = SceneConfig.from_dict({"terrain": terrain, "rocks": rocks,
                                 "craters": {"d_min_m": 10.0, "d_max_m": 200.0},
                                 "lighting": {"enabled": False}})
    _check(cfg)


def test_a_procedural_rock_plan_that_cannot_fit_is_refused_before_the_terrain(
        monkeypatch: pytest.MonkeyPatch) -> None:
    import marsscene.pipeline.build as build

    def no_terrain(*_: object) -> None:
        raise AssertionError("the terrain was built")

    monkeypatch.setattr(build, "terrain_stage", no_terrain)
    cfg = SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [1500.0, 1500.0]},
                                 "rocks": {"k": 0.3}})  # one grid: refused before its terrain
    with pytest.raises(ConfigError, match=r"^rocks: about 4.\d+e\+06 rocks .* focus square"):
        ms.build_scene(cfg, seed=1)


def test_a_level_of_detail_rock_plan_that_cannot_fit_is_refused_before_the_tiles(
        monkeypatch: pytest.MonkeyPatch) -> None:
    import marsscene.pipeline.lod as lod

    def no_tiles(*_: object) -> None:
        raise AssertionError("the focus tiles were built")

    monkeypatch.setattr(lod, "focus_heightfield", no_tiles)
    cfg = SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [3000.0, 3000.0]},
                                 "craters": {"enabled": False}, "rocks": {"k": 0.3}})
    with pytest.raises(ConfigError, match=r"focus square .* terrain.focus_size_m"):
        ms.build_scene(cfg, seed=1)


def _stage(hf: Heightfield, cfg: SceneConfig) -> ms.RockTable:
    rocks, _ = rock_stage(cfg, 11, hf, None, None, None, None, BuildRecord())
    return rocks


@pytest.mark.parametrize("placement", ["uniform", "clustered"])
def test_the_focus_rocks_are_the_same_whatever_the_outer_size(placement: str) -> None:
    """Two-level rocks on the same terrain in the focus square (a DEM crop's posts: here one
    surface sampled on each footprint) are the same rocks, draw for draw, for any footprint
    around it: the focus tiles' streams depend on the focus square alone."""
    def z(xx: np.ndarray, yy: np.ndarray) -> np.ndarray:
        return (3.0 * np.sin(xx / 9.0) * np.cos(yy / 7.0) + 0.02 * xx).astype(np.float32)

    base = SceneConfig.from_dict({
        "terrain": {"source": "procedural", "size_m": [300.0, 300.0], "focus_size_m": 100.0,
                    "tile_m": 50.0},
        "rocks": _rocks(d_min_m=0.2, k=0.1, placement=placement, max_rocks=7_000)})
    focus = []
    for side in (200.0, 300.0, 420.0):
        post = 0.5
        n = round(side / post) + 1
        g = -side / 2 + post * np.arange(n)
        hf = Heightfield(z(*np.meshgrid(g, g)), post, (-side / 2, -side / 2))
        cfg = base.replace(terrain=dataclasses.replace(base.terrain, size_m=(side, side)))
        rocks = _stage(hf, cfg)
        p = rocks.position_xyz_m
        inside = (np.abs(p[:, 0]) <= 50.0) & (np.abs(p[:, 1]) <= 50.0)
        assert np.all(rocks.diameter_m[~inside] >= 1.0)  # the cut-off outside
        focus.append(rocks.take(inside))
    for other in focus[1:]:
        assert len(other) == len(focus[0]) > 1000
        for name in ("position_xyz_m", "diameter_m", "height_m", "orientation_wxyz",
                     "prototype"):
            np.testing.assert_array_equal(getattr(other, name), getattr(focus[0], name))


def test_a_raised_budget_places_every_rock_and_the_log_states_its_memory(
        caplog: pytest.LogCaptureFixture) -> None:
    cfg = SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [160.0, 160.0],
                                             "post_m": 0.5, "focus_size_m": 60.0},
                                 "craters": {"enabled": False}, "lighting": {"enabled": False},
                                 "rocks": _rocks(d_min_m=0.2, max_rocks=3_000)})
    with caplog.at_level("INFO", logger="marsscene"):
        scene = ms.build_scene(cfg, seed=2)
    two = scene.provenance.extra["rocks"]["levels"]
    assert two["outer_d_min_m"] == 1.0 and two["outer_count"] < two["focus_count"]
    assert re.search(r"rocks: two levels, .* GiB while placing", caplog.text)
    assert re.search(r"\[rocks\] \d+ rocks in the focus square .* cut-off of 1 m", caplog.text)
    everything = cfg.replace(rocks=dataclasses.replace(cfg.rocks, max_rocks=10_000))
    caplog.clear()
    with caplog.at_level("INFO", logger="marsscene"):
        full = ms.build_scene(everything, seed=2)
    assert "levels" not in full.provenance.extra["rocks"]
    assert full.rocks is not None
    assert len(full.rocks) > 3_000 and full.rocks.diameter_m.min() < 1.0
    assert re.search(r"rocks: one level, about .* GiB while placing", caplog.text)


@pytest.mark.slow
def test_the_issues_1500m_scene_builds_with_its_defaults() -> None:
    """The issue's case: ``marsscene build --procedural --size-m 1500 1500 --seed 7``."""
    cfg = SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [1500, 1500]}})
    scene = ms.build_scene(cfg, seed=7)
    levels = scene.provenance.extra["rocks"]["levels"]
    assert levels["focus_bounds_xy_m"] == [-500.0, -500.0, 500.0, 500.0]
    assert levels["outer_d_min_m"] == 1.0 and not levels["outer_d_min_raised"]
    assert 0.9e6 < levels["focus_count"] < 1.1e6 and levels["outer_count"] > 100


@pytest.mark.slow
def test_a_2km_crop_of_a_1m_dtm_builds_with_its_defaults(tmp_path: Path) -> None:
    """A 2 km crop of a 1 m HiRISE-shaped DTM (slanted strip, MISSING_CONSTANT outside)."""
    n = 2600
    x = np.arange(n, dtype=np.float32)
    y = np.arange(n, dtype=np.float32)[:, None]
    z = -2500.0 + 15.0 * np.sin(x / 300.0) * np.cos(y / 400.0) + 0 * x
    z[np.abs(x - n / 2 - 0.1 * (y - n / 2)) > 1150] = np.nan
    path = write_pds3_dtm(tmp_path / "DTEEC_1M_U01.IMG", z.astype(np.float32), map_scale_m=1.0)
    cfg = SceneConfig.from_dict({"terrain": {"source": "dem", "dem_path": str(path),
                                             "size_m": [2000.0, 2000.0]}})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = ms.build_scene(cfg, seed=7)
    levels = scene.provenance.extra["rocks"]["levels"]
    assert levels["outer_d_min_m"] == 1.0 and 0.9e6 < levels["focus_count"] < 1.1e6


def test_mjcf_rocks_of_a_two_level_population_come_from_its_focus_square() -> None:
    """As in a level-of-detail scene: the rover drives in the focus, so its contact rocks (MJCF
    geoms, the catalogue's in_mjcf) are the focus square's largest, not the outer level's."""
    from marsscene.export.catalog_rocks import rock_catalog_columns
    from marsscene.export.mjcf.build import build_mjcf

    cfg = SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [400.0, 400.0],
                                             "post_m": 0.5, "focus_size_m": 100.0},
                                 "craters": {"enabled": False}, "lighting": {"enabled": False},
                                 "rocks": _rocks(d_min_m=0.2, outer_d_min_m=0.6, max_rocks=20_000,
                                                 mjcf_max_rocks=50)})
    scene = ms.build_scene(cfg, seed=4)
    assert scene.rocks is not None and scene.provenance.extra["rocks"]["levels"]
    p = scene.rocks.position_xyz_m
    far = (np.abs(p[:, 0]) > 50.0) | (np.abs(p[:, 1]) > 50.0)
    assert scene.rocks.diameter_m[far].max() > scene.rocks.diameter_m[~far].max()
    in_mjcf = rock_catalog_columns(scene)["in_mjcf"].astype(bool)
    assert in_mjcf.sum() == 50 and not (in_mjcf & far).any()
    root, _ = build_mjcf(scene)
    geoms = [g for g in root.iter("geom") if g.get("name", "").startswith("rock")]
    xy = np.array([[float(v) for v in g.get("pos", "0 0 0").split()[:2]] for g in geoms])
    assert len(xy) >= 50 and np.all(np.abs(xy) <= 50.0 + 1e-6)
