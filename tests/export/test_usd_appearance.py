"""USD regolith appearance: detail albedo + normal map textures that exist and resolve."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import marsscene as ms

pytest.importorskip("pxr")
from pxr import Sdf, Usd, UsdShade

from marsscene.export.usd.appearance import DETAIL_TILE_M
from marsscene.seeding import stage_rng
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
    for name in ("DetailAlbedo", "DetailNormal"):
        attr = shaders[name].GetInput("file").GetAttr()
        resolved = attr.Get().resolvedPath
        assert resolved and Path(resolved).is_file(), name
        files[name] = Path(resolved)
    surface = shaders["PreviewSurface"]
    src = surface.GetInput("diffuseColor").GetConnectedSources()[0][0].source.GetPath()
    assert src.name == "DetailAlbedo"
    src = surface.GetInput("normal").GetConnectedSources()[0][0].source.GetPath()
    assert src.name == "DetailNormal"
    scale = shaders["DetailTransform"].GetInput("scale").Get()
    assert tuple(scale) == pytest.approx((24.0 / DETAIL_TILE_M, 16.0 / DETAIL_TILE_M))
    assert shaders["DetailNormal"].GetInput("sourceColorSpace").Get() == "raw"
    # the albedo file is the seeded tile (sRGB-encoded, bottom row first in st)
    from PIL import Image

    img = np.asarray(Image.open(files["DetailAlbedo"])).astype(np.float64) / 255
    lin = np.where(img <= 0.04045, img / 12.92, ((img + 0.055) / 1.055) ** 2.4)
    tile = regolith_tile(size_px=img.shape[0], tile_m=DETAIL_TILE_M,
                         rng=stage_rng(scene.seed, "texture"))
    np.testing.assert_allclose(lin[::-1], tile.albedo_rgb, atol=0.01)
    assert Sdf.Layer.FindOrOpen(str(out / "scene.usda")) is not None
