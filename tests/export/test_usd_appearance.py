"""USD regolith appearance: large-scale albedo + detail normal map textures that exist and
resolve, and follow the seeded model."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import marsscene as ms

pytest.importorskip("pxr")
from pxr import Sdf, Usd, UsdShade

from marsscene.export.usd.appearance import DETAIL_TILE_M, LARGE_TEXEL_MIN_M
from marsscene.seeding import stage_rng
from marsscene.terrain.albedo_field import albedo_field
from marsscene.terrain.appearance import regolith_tile

_CFG = {
    "terrain": {"source": "procedural", "size_m": [24.0, 16.0], "post_m": 0.25},
    "rocks": {"enabled": False},
    "craters": {"enabled": False},
}


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> tuple[ms.Scene, Path]:
    scene = ms.build_scene(ms.SceneConfig.from_dict(_CFG), seed=4)
    out = tmp_path_factory.mktemp("usd_app") / "scene"
    ms.write_scene(scene, out, formats=("usd",))
    return scene, out


def _shaders(stage: Usd.Stage) -> dict[str, UsdShade.Shader]:
    return {p.GetName(): UsdShade.Shader(p) for p in stage.Traverse()
            if p.IsA(UsdShade.Shader)}


def test_material_textures_exist_and_resolve_from_elsewhere(written, tmp_path, monkeypatch):
    scene, out = written
    monkeypatch.chdir(tmp_path)  # another working directory: paths must be layer-relative
    stage = Usd.Stage.Open(str(out / "scene.usda"))
    shaders = _shaders(stage)
    files = {}
    for name in ("LargeAlbedo", "DetailNormal"):
        attr = shaders[name].GetInput("file").GetAttr()
        resolved = attr.Get().resolvedPath
        assert resolved and Path(resolved).is_file(), name
        files[name] = Path(resolved)
    surface = shaders["PreviewSurface"]
    src = surface.GetInput("diffuseColor").GetConnectedSources()[0][0].source.GetPath()
    assert src.name == "LargeAlbedo"
    src = surface.GetInput("normal").GetConnectedSources()[0][0].source.GetPath()
    assert src.name == "DetailNormal"
    scale = shaders["DetailTransform"].GetInput("scale").Get()
    assert tuple(scale) == pytest.approx((24.0 / DETAIL_TILE_M, 16.0 / DETAIL_TILE_M))
    assert shaders["DetailNormal"].GetInput("sourceColorSpace").Get() == "raw"
    assert shaders["LargeAlbedo"].GetInput("wrapS").Get() == "clamp"
    # the albedo file is the detail tile's mean albedo times the seeded large-scale field at
    # texel centres (LARGE_TEXEL_MIN_M = 1 m on this 24 m x 16 m scene; sRGB, row 0 = north)
    from PIL import Image

    img = np.asarray(Image.open(files["LargeAlbedo"])).astype(np.float64) / 255
    lin = np.where(img <= 0.04045, img / 12.92, ((img + 0.055) / 1.055) ** 2.4)
    t = LARGE_TEXEL_MIN_M
    rows, cols = round(16 / t), round(24 / t)
    assert img.shape == (rows, cols, 3)
    tile = regolith_tile(size_px=1024, tile_m=DETAIL_TILE_M, rng=stage_rng(scene.seed, "texture"))
    field = albedo_field(rng=stage_rng(scene.seed, "albedo"))
    x0, y0 = scene.heightfield.xy_of(0, 0)
    xx, yy = np.meshgrid(x0 + t / 2 + t * np.arange(cols), y0 + t / 2 + t * np.arange(rows)[::-1])
    expect = np.exp(field.log_gain(xx, yy))[..., None] * tile.albedo_rgb.mean(axis=(0, 1))
    np.testing.assert_allclose(lin, expect, atol=0.006)
    assert lin[..., 0].std() / lin[..., 0].mean() > 0.05  # metre-scale variation is there
    assert Sdf.Layer.FindOrOpen(str(out / "scene.usda")) is not None
