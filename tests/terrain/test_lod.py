"""Two-level terrain (terrain.lod): focus independence, seams, stitching, craters, errors."""

from __future__ import annotations

import numpy as np
import pytest

import marsscene as ms
from marsscene.errors import ConfigError
from marsscene.terrain.heightfield import Heightfield
from marsscene.terrain.lod import TAPER_POSTS, plan_focus, reaches_box, stitch, taper_detail


def _cfg(size_m: float, **terrain: object) -> ms.SceneConfig:
    t = {"source": "procedural", "size_m": [size_m, size_m], "post_m": 1.0, "lod": True,
         "focus_size_m": 60.0, "focus_xy_m": [10.0, -6.0], "lod_blend_m": 30.0,
         "rms_height_m": 1.5, **terrain}
    return ms.SceneConfig.from_dict({
        "terrain": t, "craters": {"d_min_m": 2.0, "d_max_m": 40.0},
        "rocks": {"d_min_m": 0.3, "outer_d_min_m": 1.0}, "lighting": {"enabled": False}})


@pytest.fixture(scope="module")
def lod_pair() -> tuple[ms.Scene, ms.Scene]:
    return ms.build_scene(_cfg(200.0), seed=5), ms.build_scene(_cfg(320.0), seed=5)


def test_a_tile_built_alone_equals_the_same_tile_of_the_full_build() -> None:
    from marsscene.pipeline.tile import build_tile

    cfg = _cfg(200.0, tile_m=20.0)  # a 60 m focus in 3 x 3 tiles of 80 x 80 cells
    full = ms.build_scene(cfg, seed=5)
    hf = full.heightfield
    assert full.rocks is not None and full.craters is not None
    # craters straddle tile borders (the halo case)
    edges = np.array([-20.0, 0.0, 20.0, 40.0])
    cx = full.craters.center_xy_m[:, 0]
    r = full.craters.diameter_m / 2
    assert np.any((np.abs(cx[:, None] - edges[None, 1:3]) < r[:, None]).any(axis=1))
    for row, col in [(0, 0), (1, 1), (1, 2), (2, 2)]:
        tile, rocks = build_tile(cfg, seed=5, row=row, col=col)
        rs, cs = slice(row * 80, row * 80 + 81), slice(col * 80, col * 80 + 81)
        assert tile.origin_xy_m == (hf.origin_xy_m[0] + col * 20, hf.origin_xy_m[1] + row * 20)
        np.testing.assert_array_equal(tile.z_m, hf.z_m[rs, cs])  # border posts included
        assert rocks is not None and len(rocks) > 10
        p = full.rocks.position_xyz_m
        inside = tile.contains(p[:, 0], p[:, 1])
        np.testing.assert_array_equal(rocks.position_xyz_m, p[inside])
        np.testing.assert_array_equal(rocks.diameter_m, full.rocks.diameter_m[inside])
    with pytest.raises(ConfigError, match="outside the 3 x 3 focus tiles"):
        build_tile(cfg, seed=5, row=3, col=0)


def test_focus_rocks_have_the_full_sfd_and_outer_rocks_only_large(
        lod_pair: tuple[ms.Scene, ms.Scene]) -> None:
    small = lod_pair[0]
    r = small.rocks
    assert r is not None
    outside = ~small.heightfield.contains(r.position_xyz_m[:, 0], r.position_xyz_m[:, 1])
    assert r.diameter_m[~outside].min() < 0.35
    assert outside.sum() > 5 and r.diameter_m[outside].min() >= 1.0


def test_stitching_barely_bends_the_outer_terrain(lod_pair: tuple[ms.Scene, ms.Scene]) -> None:
    """The coarse grid carries the long wavelengths and the focus is built on it, so the focus
    border differs from the unstitched coarse terrain only by the sub-post detail and the fine
    crater shapes (the first design drew the focus independently: ~2 m RMS, bent away over the
    blend band, which steepened its slopes)."""
    from marsscene.pipeline.lod import lod_craters, lod_world

    for scene in lod_pair:
        assert scene.outer is not None
        cfg = scene.config
        world = lod_world(cfg.terrain, scene.seed)
        before, _, _ = lod_craters(world, cfg.craters, scene.seed)
        bend = scene.outer.heightfield.z_m - before.z_m
        relief = float(before.z_m.std())
        assert relief > 0.5
        assert float(np.sqrt(np.mean(bend[bend != 0] ** 2))) < 0.05 * relief
        slope_before, slope_after = before.slope_deg(), scene.outer.heightfield.slope_deg()
        assert abs(np.percentile(slope_after, 99) - np.percentile(slope_before, 99)) < 0.5


def test_seam_has_no_height_jump(lod_pair: tuple[ms.Scene, ms.Scene]) -> None:
    for scene in lod_pair:
        fine, outer = scene.heightfield, scene.outer
        assert outer is not None
        coarse = outer.heightfield
        # every coarse post on or inside the focus square is a fine post
        xs, ys = coarse.grid_xy()
        x0, y0, x1, y1 = fine.bounds_xy_m
        cols = np.flatnonzero((xs >= x0) & (xs <= x1))
        rows = np.flatnonzero((ys >= y0) & (ys <= y1))
        np.testing.assert_array_equal(coarse.z_m[np.ix_(rows, cols)], fine.z_m[::4, ::4])
        # along the whole border (every 5 cm) both surfaces agree within 1 mm
        t = np.linspace(0.0, 1.0, 1201)
        bx = np.concatenate([x0 + t * (x1 - x0), np.full_like(t, x1), x1 - t * (x1 - x0),
                             np.full_like(t, x0)])
        by = np.concatenate([np.full_like(t, y0), y0 + t * (y1 - y0), np.full_like(t, y1),
                             y1 - t * (y1 - y0)])
        jump = np.abs(fine.sample(bx, by) - coarse.sample(bx, by))
        assert float(jump.max()) < 1e-3
        # and the fine surface keeps its sub-metre detail away from the border
        resid = fine.z_m - coarse.sample(*np.meshgrid(*fine.grid_xy()))
        band = 4 * TAPER_POSTS
        assert float(np.abs(resid[band:-band, band:-band]).max()) > 0.01
        assert float(np.abs(resid[:, 0]).max()) < 1e-3


def test_taper_keeps_coarse_posts_and_straightens_the_border() -> None:
    rng = np.random.default_rng(0)
    coarse = Heightfield.centered(np.zeros((41, 41), np.float32), 1.0)
    plan = plan_focus(coarse, center_xy_m=(0.0, 0.0), size_m=20.0, fine_post_m=0.5)
    fine = Heightfield(rng.normal(size=(41, 41)).astype(np.float32), 0.5, plan.bounds_xy_m[:2])
    out = taper_detail(fine, plan)
    np.testing.assert_array_equal(out.z_m[::2, ::2], fine.z_m[::2, ::2])
    mid = (fine.z_m[0, :-2:2] + fine.z_m[0, 2::2]) / 2  # border: midpoints on the segments
    np.testing.assert_allclose(out.z_m[0, 1::2], mid, atol=1e-6)
    np.testing.assert_array_equal(out.z_m[20, 20], fine.z_m[20, 20])  # centre untouched


def test_stitch_blends_the_mismatch_out_over_blend_m() -> None:
    coarse = Heightfield.centered(np.zeros((101, 101), np.float32), 1.0)
    plan = plan_focus(coarse, center_xy_m=(0.0, 0.0), size_m=20.0, fine_post_m=0.5)
    fine = Heightfield(np.ones((41, 41), np.float32), 0.5, plan.bounds_xy_m[:2])
    z = stitch(coarse, fine, plan, blend_m=20.0).z_m
    row = z[50]  # the x axis: focus is x in [-10, 10] -> cols 40..60
    assert np.all(row[40:61] == 1.0)
    assert np.all(row[:20] == 0.0) and np.all(row[81:] == 0.0)  # >= 20 m away: untouched
    assert np.all(np.diff(row[20:41]) >= 0) and row[30] == pytest.approx(0.5)


def test_craters_reaching_the_focus_come_from_the_focus_sample(
        lod_pair: tuple[ms.Scene, ms.Scene]) -> None:
    small, large = lod_pair
    cfg = small.config.craters

    def reaching(scene: ms.Scene) -> np.ndarray:
        c = scene.craters
        assert c is not None
        reach = cfg.ejecta_reach * c.diameter_m / 2 / np.sqrt(cfg.axis_ratio_min)
        m = reaches_box(c.center_xy_m, reach, scene.heightfield.bounds_xy_m)
        return np.column_stack([c.center_xy_m[m], c.diameter_m[m], c.age_ga[m]])

    a, b = reaching(small), reaching(large)
    assert len(a) > 20
    np.testing.assert_array_equal(a, b)
    assert small.craters is not None and np.all(np.diff(small.craters.age_ga) <= 0)
    assert len(large.craters or ()) > len(small.craters or ())


@pytest.mark.parametrize(("terrain", "match"), [
    ({"focus_xy_m": [90.0, 0.0]}, "must lie inside the footprint"),
    ({"focus_post_m": 0.3}, "whole multiple"),
])
def test_impossible_plans_are_one_line_errors(terrain: dict[str, object], match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        ms.build_scene(_cfg(200.0, **terrain), seed=1)


def test_cli_focus_options(runner, tmp_path) -> None:  # type: ignore[no-untyped-def]
    from marsscene.cli import main

    base = ["build", "--procedural", "--size-m", "200", "200", "--post-m", "1", "--format",
            "mjcf", "--seed", "1"]
    res = runner.invoke(main, [*base, "--focus-xy", "95", "0", "--focus-size-m", "40",
                               "--out", str(tmp_path / "bad")])
    assert res.exit_code != 0
    assert "must lie inside the footprint" in res.output and "Traceback" not in res.output
    assert not (tmp_path / "bad" / "manifest.json").exists()
    res = runner.invoke(main, [*base, "--focus-xy", "30", "-20", "--focus-size-m", "40",
                               "--tile-m", "20", "--out", str(tmp_path / "ok")])
    assert res.exit_code == 0, res.output
    import json

    lod = json.loads((tmp_path / "ok" / "manifest.json").read_text())["summary"]["lod"]
    assert lod["focus_bounds_xy_m"] == [10.0, -40.0, 50.0, 0.0]
    assert (lod["focus_post_m"], lod["outer_post_m"]) == (0.25, 1.0)
    assert lod["focus_tiles"] == [2, 2] and lod["focus_tile_m"] == 20.0


def test_lod_with_a_dem_keeps_the_dem_posts_outside_and_details_the_focus(
        synthetic_dem_path, tmp_path) -> None:  # type: ignore[no-untyped-def]
    import mujoco

    from marsscene.pipeline.terrain import lod_inputs

    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "dem", "dem_path": str(synthetic_dem_path), "lod": True,
                    "lod_blend_m": 5.0},
        "craters": {"enabled": False}, "rocks": {"enabled": False},
        "export": {"formats": ["mjcf"]}})
    scene = ms.build_scene(cfg, seed=1)
    assert scene.outer is not None
    coarse, fine = scene.outer.heightfield, scene.heightfield
    assert coarse.cell_size_m == 1.0 and coarse.shape == (48, 64)  # the DEM's own posts
    assert fine.cell_size_m == 0.25
    assert any("focus square does not fit" in n for n in scene.provenance.notes)
    # the focus is the DEM (cubic between its posts) plus sub-metre detail of the continued
    # spectrum: at the DEM posts it differs from the DEM by the detail alone
    world, _ = lod_inputs(cfg, 1)
    x0, y0, x1, y1 = fine.bounds_xy_m
    xs, ys = coarse.grid_xy()
    cols = np.flatnonzero((xs >= x0) & (xs <= x1))
    rows = np.flatnonzero((ys >= y0) & (ys <= y1))
    dem_posts = world.coarse.z_m[np.ix_(rows, cols)]
    diff = fine.z_m[::4, ::4] - dem_posts
    assert 0 < world.detail.rms_m < 0.05
    assert float(np.sqrt(np.mean(diff**2))) < 3 * world.detail.rms_m
    assert float(np.abs(fine.z_m - fine.z_m.mean()).max()) > 0.5  # the bowl is there
    ms.write_scene(scene, tmp_path / "dem_lod")
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "dem_lod" / "mjcf" / "scene.xml"))
    assert model.nhfield == 2  # focus + outer


def test_a_focus_square_too_large_to_hold_is_a_one_line_error(runner, tmp_path) -> None:  # type: ignore[no-untyped-def]
    from marsscene.cli import main

    res = runner.invoke(main, ["build", "--procedural", "--size-m", "3600", "3600", "--post-m",
                               "1", "--focus-size-m", "3000", "--format", "mjcf", "--seed", "1",
                               "--out", str(tmp_path / "big")])
    assert res.exit_code != 0 and "Traceback" not in res.output
    assert "3000 m focus square at 0.25 m posts has 144,024,001 posts" in res.output
    assert not (tmp_path / "big").exists()


def test_dem_focus_keeps_the_dem_posts_under_a_coarser_outer_level(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """--dem X --lod --post-m 4: the outer level averages the DTM to 4 m, but the focus is
    interpolated from the DTM's own 1 m posts, so relief finer than 4 m survives there."""
    import rasterio
    from affine import Affine

    from marsscene.pipeline.terrain import lod_inputs

    rows = cols = 200
    yy, xx = np.mgrid[0:rows, 0:cols].astype(np.float64)
    ripple = 0.5 * np.sin(2 * np.pi * xx / 3.0) * np.cos(2 * np.pi * yy / 5.0)  # < 4 m
    z = -2000.0 + 0.02 * xx + ripple
    path = tmp_path / "ripple.tif"
    with rasterio.open(path, "w", driver="GTiff", height=rows, width=cols, count=1,
                       dtype="float32", crs="+proj=eqc +R=3396190 +units=m +no_defs",
                       transform=Affine(1.0, 0.0, 0.0, 0.0, -1.0, 0.0)) as ds:
        ds.write(z.astype(np.float32), 1)
    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "dem", "dem_path": str(path), "lod": True, "post_m": 4.0,
                    "focus_size_m": 120.0, "lod_blend_m": 8.0},
        "craters": {"enabled": False}, "rocks": {"enabled": False}})
    scene = ms.build_scene(cfg, seed=2)
    assert scene.outer is not None
    assert scene.outer.heightfield.cell_size_m == 4.0
    assert any("averaged to 4 m" in n for n in scene.provenance.notes)
    world, _ = lod_inputs(cfg, 2)
    assert world.base.cell_size_m == 1.0 and world.coarse.cell_size_m == 4.0
    fine = scene.heightfield
    xs, ys = fine.grid_xy()
    inner = slice(34, -34)  # past the taper (8 outer posts = 32 m) at the focus border
    at_posts = fine.z_m[::4, ::4][inner, inner]
    dem = world.base.sample(*np.meshgrid(xs[::4], ys[::4]))[inner, inner]
    assert float(np.sqrt(np.mean((at_posts - dem) ** 2))) < 3 * world.detail.rms_m + 1e-3
    # the 3 m ripple is there (the 4 m outer level cannot hold it)
    detrended = at_posts - at_posts.mean(axis=1, keepdims=True)
    assert float(detrended.std()) > 0.2
