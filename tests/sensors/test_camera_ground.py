"""The camera's baked ground textures: follow the orthoimage, no 8 m repeat (pure numpy)."""

from __future__ import annotations

import numpy as np
import pytest

from marsscene.sensors.camera_ground import bake_ground
from marsscene.terrain.albedo_field import AlbedoField, albedo_field, ortho_gain
from marsscene.terrain.appearance import regolith_tile


@pytest.fixture(scope="module")
def tile_u8():
    tile = regolith_tile(size_px=512, tile_m=8.0, rng=np.random.default_rng(3))
    return np.clip(np.rint(tile.albedo_rgb / 0.5 * 255), 0, 255).astype(np.uint8), tile.texel_m


def _lag_correlations(img: np.ndarray, texel_m: float, block_m: float = 0.5
                      ) -> dict[int, float]:
    g = img[..., 0].astype(np.float64)
    b = round(block_m / texel_m)
    r, c = g.shape[0] // b, g.shape[1] // b
    bm = g[: r * b, : c * b].reshape(r, b, c, b).mean(axis=(1, 3))
    out = {}
    for lag_m in (6, 7, 8, 9, 10):
        k = round(lag_m / block_m)
        out[lag_m] = float(np.corrcoef(bm[:, :-k].ravel(), bm[:, k:].ravel())[0, 1])
    return out


def test_field_breaks_the_detail_tile_repeat(tile_u8) -> None:
    u8, texel = tile_u8
    field = albedo_field(rng=np.random.default_rng(4))
    flat = AlbedoField(np.zeros_like(field.mid), np.zeros_like(field.large))
    kw = {"x0_m": -100.0, "y0_m": 37.0, "size_px": (1024, 4096), "texel_m": texel}
    old = _lag_correlations(bake_ground(u8, texel, flat, **kw), texel)
    new = _lag_correlations(bake_ground(u8, texel, field, **kw), texel)
    assert old[8] > 0.99  # the tile alone repeats exactly every 8 m
    assert new[8] < 0.5
    assert new[8] - 0.5 * (new[7] + new[9]) < 0.15  # no peak at the tile period


def test_baked_texture_follows_the_ortho_at_large_scale(tile_u8) -> None:
    from scipy.ndimage import gaussian_filter

    u8, texel = tile_u8
    rng = np.random.default_rng(9)
    blob = gaussian_filter(rng.standard_normal((128, 128)), 8, mode="wrap")
    ortho = np.clip(128 * np.exp(0.3 * blob / blob.std()), 0, 255).astype(np.uint8)
    og = ortho_gain(np.repeat(ortho[..., None], 3, -1), x0_m=0.0, y0_m=0.0, width_m=64.0)
    field = albedo_field(rng=np.random.default_rng(4))
    far = u8.reshape(128, 4, 128, 4, 3).mean(axis=(1, 3)).astype(np.uint8)
    lum = ortho[::-1].astype(np.float64)  # 0.5 m pixels, row 0 = south
    ortho_blocks = lum[16:112, 16:112].reshape(12, 8, 12, 8).mean(axis=(1, 3))
    corr = {}
    for name, f in (("field", field), ("ortho", field.with_ortho(og))):
        img = bake_ground(far, 4 * texel, f, x0_m=8.0, y0_m=8.0, size_px=(768, 768),
                          texel_m=4 * texel)  # 48 m at 6.25 cm
        g = img.astype(np.float64).mean(axis=-1)
        blocks = g.reshape(12, 64, 12, 64).mean(axis=(1, 3))  # 4 m blocks
        corr[name] = np.corrcoef(blocks.ravel(), ortho_blocks.ravel())[0, 1]
    assert corr["ortho"] > 0.8
    assert abs(corr["field"]) < 0.5  # without the ortho, no relation (the test can fail)


def test_bake_is_world_anchored(tile_u8) -> None:
    """Two overlapping bakes agree texel for texel where they overlap (meshes can move)."""
    u8, texel = tile_u8
    field = albedo_field(rng=np.random.default_rng(4))
    a = bake_ground(u8, texel, field, x0_m=0.0, y0_m=0.0, size_px=(512, 512), texel_m=texel)
    b = bake_ground(u8, texel, field, x0_m=64 * texel, y0_m=128 * texel, size_px=(256, 256),
                    texel_m=texel)
    diff = np.abs(a[128:384, 64:320].astype(int) - b.astype(int))
    assert diff.max() <= 1  # float rounding of the interpolated gain only
