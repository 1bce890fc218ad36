"""terrain.lod = "auto" with a DEM: a crop too large for one grid gets two levels, decided from
the DEM's header (the DEM's posts in the focus square, the DEM averaged to a whole multiple of
them outside), says so, and records it; --no-lod refuses naming the options that would work;
a small crop keeps one grid. The post budgets are patched small so a modest GeoTIFF is "large"."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import marsscene as ms
from marsscene.cli import main
from marsscene.errors import MemoryBudgetError
from marsscene.pipeline.terrain import resolve_lod
from tests.dem.lod_checks import assert_outer_matches

CRS = "+proj=eqc +lat_ts=0 +lat_0=0 +lon_0=150 +x_0=0 +y_0=0 +R=3396190 +units=m +no_defs"
ROWS, COLS = 241, 321  # 1 m posts: 320 x 240 m
X0, Y0 = 1000.0, 500.0  # upper-left corner (projected m)
#: --size-m 300 200: rows 20..220, cols 10..310 (201 x 301 posts = 60,501 > MAX_POSTS below)
WIN = (20, 10, 201, 301)


@pytest.fixture
def budget(monkeypatch: pytest.MonkeyPatch) -> None:
    """MAX_POSTS 20,000 (so the focus is at most 140 posts a side), outer level <= 9,000 posts."""
    monkeypatch.setattr("marsscene.terrain.synth.MAX_POSTS", 20_000)
    monkeypatch.setattr("marsscene.pipeline.terrain.AUTO_OUTER_POSTS", 9_000)


@pytest.fixture
def dtm(tmp_path: Path) -> Path:
    """A 1 m GeoTIFF DTM: a slope and a 3 m x 7 m ripple (finer than any outer level)."""
    import rasterio
    from affine import Affine

    yy, xx = np.mgrid[0:ROWS, 0:COLS].astype(np.float64)
    z = -2000.0 + 0.03 * xx + 0.4 * np.sin(2 * np.pi * xx / 3.0) * np.cos(2 * np.pi * yy / 7.0)
    path = tmp_path / "dtm.tif"
    with rasterio.open(path, "w", driver="GTiff", height=ROWS, width=COLS, count=1,
                       dtype="float32", crs=CRS, transform=Affine(1.0, 0, X0, 0, -1.0, Y0)) as ds:
        ds.write(z.astype(np.float32), 1)
    return path


def _read_back(path: Path) -> np.ndarray:
    import rasterio

    with rasterio.open(path) as ds:
        return ds.read(1).astype(np.float64)


def _cfg(path: Path, **terrain: object) -> ms.SceneConfig:
    return ms.SceneConfig.from_dict({
        "terrain": {"source": "dem", "dem_path": str(path), "size_m": [300.0, 200.0],
                    "lod_blend_m": 8.0, **terrain},
        "craters": {"enabled": False}, "rocks": {"enabled": False},
        "lighting": {"enabled": False}})


def _box_means(z: np.ndarray, f: int) -> np.ndarray:
    """Output post (i, j) = mean of the odd box centred on input post (i f, j f): a plain loop."""
    h = (f | 1) // 2
    rows, cols = (z.shape[0] - 1) // f + 1, (z.shape[1] - 1) // f + 1
    out = np.empty((rows, cols))
    for i in range(rows):
        for j in range(cols):
            out[i, j] = z[max(i * f - h, 0):i * f + h + 1, max(j * f - h, 0):j * f + h + 1].mean()
    return out


@pytest.mark.usefixtures("budget")
def test_auto_chooses_the_smallest_outer_multiple_from_the_header(
        dtm: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    def no_pixels(*args: object, **kwargs: object) -> None:
        raise AssertionError("resolve_lod read pixels")

    monkeypatch.setattr("marsscene.dem.io.read_window", no_pixels)
    cfg = _cfg(dtm)
    assert cfg.terrain.lod == "auto"
    big, note = resolve_lod(cfg)
    t = big.terrain
    # 2 m would leave 101 x 151 = 15,251 outer posts (> 9,000); 3 m leaves 67 x 101 = 6,767
    assert (t.lod, t.post_m, t.focus_post_m) == (True, 3.0, 1.0)
    assert t.focus_size_m == 138.0  # 140 posts at most (MAX_POSTS), whole 3 m cells
    assert note is not None
    for part in ("the 300 x 200 m crop of dtm.tif at 1 m posts would hold 60,501 posts "
                 "(limit 20,000)", 'terrain.lod = "auto"', "1 m posts (the DEM's posts) in the "
                 "central 138 m square", "--focus-xy X Y --focus-size-m 138 --focus-post-m 1",
                 "the DEM averaged to 3 m outside", "--no-lod"):
        assert part in note
    # a finer --post-m that divides the DEM's posts is the focus's; the outer level is the same
    fine, note = resolve_lod(_cfg(dtm, post_m=0.25))
    assert (fine.terrain.post_m, fine.terrain.focus_post_m) == (3.0, 0.25)
    assert fine.terrain.focus_size_m == 33.0  # 140 posts of 0.25 m, floored to 3 m cells
    assert note is not None and "with seeded detail" in note
    # ... but a crop that fits at the DEM's posts keeps one grid (and its refusal) however fine
    # the request: 81 x 101 posts at 1 m, 321 x 401 at 0.25 m
    upsampled, note = resolve_lod(_cfg(dtm, size_m=[100.0, 80.0], post_m=0.25))
    assert upsampled.terrain.lod is False and note is None
    # over the memory budget (not the post budget): two levels as well, and the note says GB
    # (81 x 101 posts: 8,181 x 184 B = 1.5 MB)
    mem, note = resolve_lod(_cfg(dtm, size_m=[100.0, 80.0], max_memory_gb=0.001))
    assert mem.terrain.lod is True and mem.terrain.post_m == 2.0 and note is not None
    assert "the 100 x 80 m crop of dtm.tif at 1 m posts would need about 0.0015 GB " \
        "(terrain.max_memory_gb = 0.001)" in note
    # an explicit lod without post_m keeps its focus and gets the averaged outer level
    explicit, note = resolve_lod(_cfg(dtm, lod=True, focus_size_m=60.0))
    assert (explicit.terrain.post_m, explicit.terrain.focus_post_m) == (3.0, 0.25)
    assert explicit.terrain.focus_size_m == 60.0
    assert note is not None and "the DEM averaged to 3 m posts" in note
    # explicit choices are kept as they are
    assert resolve_lod(_cfg(dtm, lod=True, post_m=2.0)) == (_cfg(dtm, lod=True, post_m=2.0),
                                                          None)


@pytest.mark.usefixtures("budget")
def test_large_dem_crop_builds_two_levels_with_the_dem_in_the_focus(
        dtm: Path, tmp_path: Path) -> None:
    import mujoco

    z = _read_back(dtm)
    r0, c0, nr, nc = WIN
    crop = z[r0:r0 + nr, c0:c0 + nc]
    scene = ms.build_scene(_cfg(dtm), seed=3)
    notes = scene.provenance.notes
    assert any('terrain.lod = "auto"' in n and "60,501 posts" in n for n in notes)
    assert any("read averaged to 3 m posts strip by strip" in n for n in notes)
    outer, fine = scene.outer, scene.heightfield
    assert outer is not None
    datum = scene.provenance.frame.datum_m
    ox, oy = scene.provenance.frame.origin_projected_xy_m
    # the outer level: 3 m posts, every 3rd DEM post of the crop, the box means of the DEM
    assert outer.heightfield.cell_size_m == 3.0 and outer.heightfield.shape == (67, 101)
    ref = (_box_means(crop, 3) - datum)[::-1]  # south-up rows
    assert_outer_matches(outer, ref, 3.0, 3000)
    fx0, fy0, fx1, fy1 = outer.focus_bounds_xy_m
    # the focus: the central 138 m at the DEM's own 1 m posts, equal to the DEM there (past the
    # 24 m taper at its border), ripple included
    assert fine.cell_size_m == 1.0 and fine.shape == (139, 139)
    assert (fx0, fy0, fx1, fy1) == (-69.0, -69.0, 69.0, 69.0)
    fxs, fys = fine.grid_xy()
    cols = np.rint(fxs + ox - (X0 + 0.5)).astype(int)  # DEM column of each focus post
    rows = np.rint((Y0 - 0.5) - (fys + oy)).astype(int)  # DEM row (north-up)
    np.testing.assert_allclose(fxs + ox, X0 + 0.5 + cols, atol=1e-9)  # on the DEM's posts
    dem_at = z[np.ix_(rows, cols)] - datum
    inner = slice(25, -25)
    np.testing.assert_allclose(fine.z_m[inner, inner], dem_at[inner, inner], atol=1e-3)
    assert float(np.ptp(fine.z_m[inner, inner] - 0.03 * fxs[inner])) > 0.6  # the ripple
    # written: the MJCF compiles with the two hfields at those sizes, the manifest has the note
    ms.write_scene(scene, tmp_path / "w", formats=("mjcf",))
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "w" / "mjcf" / "scene.xml"))
    assert model.nhfield == 2
    assert sorted(zip(model.hfield_nrow, model.hfield_ncol, strict=True)) == [(67, 101),
                                                                              (139, 139)]
    man = json.loads((tmp_path / "w" / "manifest.json").read_text())
    assert any('terrain.lod = "auto"' in n for n in man["notes"])
    assert man["config"]["terrain"]["lod"] is True
    assert (man["summary"]["lod"]["outer_post_m"], man["summary"]["lod"]["focus_post_m"]) == \
        (3.0, 1.0)
    # determinism: the same build again gives the same grids
    again = ms.build_scene(_cfg(dtm), seed=3)
    assert again.outer is not None
    np.testing.assert_array_equal(again.heightfield.z_m, fine.z_m)
    np.testing.assert_array_equal(again.outer.heightfield.z_m, outer.heightfield.z_m)


@pytest.mark.usefixtures("budget")
def test_cli_says_so_and_no_lod_refuses_naming_the_options(dtm: Path, tmp_path: Path) -> None:
    toml = tmp_path / "c.toml"
    toml.write_text("[craters]\nenabled = false\n[rocks]\nenabled = false\n"
                    "[lighting]\nenabled = false\n")
    base = ["build", "--dem", str(dtm), "--config", str(toml), "--size-m", "300", "200",
            "--format", "mjcf", "--seed", "1"]
    runner = CliRunner()
    res = runner.invoke(main, [*base, "--out", str(tmp_path / "auto")])
    assert res.exit_code == 0, res.output
    assert 'so the terrain has two levels (terrain.lod = "auto")' in res.output
    man = json.loads((tmp_path / "auto" / "manifest.json").read_text())
    assert man["summary"]["lod"]["outer_post_m"] == 3.0
    assert man["summary"]["lod"]["focus_posts"] == 139 * 139
    res = runner.invoke(main, [*base, "--no-lod", "--out", str(tmp_path / "one")])
    assert res.exit_code == 1 and "Traceback" not in res.output
    assert "60,501 posts as one grid (limit 20,000" in res.output
    for hint in ("--no-lod", "--lod", "--focus-size-m", "--post-m", "--size-m", "--crop-px",
                 "--crop-lonlat"):
        assert hint in res.output
    assert not (tmp_path / "one").exists()
    # --focus-xy (which asks for --lod) moves the same focus: the note's options
    res = runner.invoke(main, [*base, "--focus-xy", "30", "0", "--focus-size-m", "138",
                               "--focus-post-m", "1", "--out", str(tmp_path / "moved")])
    assert res.exit_code == 0, res.output
    moved = json.loads((tmp_path / "moved" / "manifest.json").read_text())["summary"]["lod"]
    assert moved["focus_bounds_xy_m"] == [-39.0, -69.0, 99.0, 69.0]
    assert (moved["outer_post_m"], moved["focus_post_m"]) == (3.0, 1.0)


@pytest.mark.usefixtures("budget")
def test_small_dem_crop_keeps_one_grid(dtm: Path) -> None:
    cfg = _cfg(dtm, size_m=[100.0, 80.0])  # 81 x 101 posts: within the budget
    one, note = resolve_lod(cfg)
    assert one.terrain.lod is False and note is None
    scene = ms.build_scene(cfg, seed=3)
    assert scene.outer is None
    hf = scene.heightfield
    assert hf.cell_size_m == 1.0 and hf.shape == (81, 101)
    z = _read_back(dtm)
    r0, c0 = ROWS // 2 - 40, COLS // 2 - 50  # the centred crop
    ref = (z[r0:r0 + 81, c0:c0 + 101] - scene.provenance.frame.datum_m)[::-1]
    np.testing.assert_allclose(hf.z_m, ref, atol=1e-3)
    assert not any("terrain.lod" in n for n in scene.provenance.notes)


def test_no_lod_dem_object_over_the_budget_is_refused(dtm: Path,
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    from marsscene.dem.io import read_dem

    dem = read_dem(dtm)
    monkeypatch.setattr("marsscene.terrain.synth.MAX_POSTS", 20_000)
    cfg = ms.SceneConfig.from_dict({"terrain": {"source": "dem", "dem_path": str(dtm),
                                                "lod": False}})
    with pytest.raises(MemoryBudgetError, match=r"whole 320 x 240 m DEM dtm\.tif at 1 m posts "
                                                r"would hold 77,361 posts as one grid"):
        ms.build_scene(cfg, seed=0, dem=dem)
