"""Regolith and rock appearance for camera imagery: seeded, periodic albedo and bump textures.

Pure numpy: no I/O besides reading the packaged coefficients, no global random state. The
textures are *detail tiles*: periodic (they wrap seamlessly), world-anchored by their users
(texture coordinate = world xy / ``tile_m``), with variation from the tile size (metres) down
to two texels (millimetres). A renderer draws them over the terrain near the camera; an
orthoimage, where one is draped, supplies the larger scales.

Albedos (linear RGB reflectance at low phase angle; ``data/appearance.json``):

* soil ~ (0.35, 0.17, 0.11): Viking Lander 1 soils, Guinness (1981), JGR 86(B8), 7983-7992
  (0.30-0.39 red, 0.17 green, 0.11 blue at 5 deg phase); finer soil is brighter and redder, so
  brighter mottles are made redder (``redness_exponent_rgb``);
* rocks darker and greyer than soil unless dust-coated: Johnson et al. (1999), JGR 104(E4),
  8809-8830 (Pathfinder); Johnson et al. (2006), JGR 111, E02S14, doi:10.1029/2005JE002494
  (Spirit Pancam). Each rock mixes ``rock_gray_rgb`` with soil by a seeded dust fraction.

Surfaces are treated as Lambertian with these albedos. Real regolith is strongly
backscattering with an opposition surge (Guinness 1981), so this is an approximation.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "AppearanceModel",
    "RegolithTile",
    "bump_shading",
    "normal_map_rgb",
    "regolith_tile",
    "rock_albedo_rgb",
]


@dataclass(frozen=True, kw_only=True)
class AppearanceModel:
    """Albedo coefficients (defaults from ``data/appearance.json``; sources in the module doc)."""

    soil_rgb: tuple[float, float, float]
    rock_gray_rgb: tuple[float, float, float]
    rock_dust_fraction_range: tuple[float, float]
    mottle_sigma: float
    """Std of the log-albedo mottling (metres to centimetres)."""
    mottle_spectral_slope: float
    """Amplitude spectrum ``~ f^-slope`` of the mottling (1 = scale-invariant look)."""
    mottle_max_wavelength_m: float
    """Longest mottling wavelength in the detail tile (longer ones: the albedo field)."""
    redness_exponent_rgb: tuple[float, float, float]
    pebbles_per_m2: float
    pebble_diameter_range_m: tuple[float, float]
    pebble_albedo_sigma: float
    bump_rms_m: float
    bump_max_wavelength_m: float
    albedo_mid_sigma: float
    """Std of the log albedo in the metre band (:mod:`marsscene.terrain.albedo_field`)."""
    albedo_mid_band_m: tuple[float, float]
    albedo_large_sigma: float
    """Std of the log albedo in the decametre band (Guinness 1981 soil-unit spread)."""
    albedo_large_band_m: tuple[float, float]
    ortho_smoothing_m: float
    """Gaussian smoothing of an orthoimage before it modulates the albedo."""
    extra: dict[str, Any] = field(default_factory=dict)

    @classmethod
    def default(cls) -> AppearanceModel:
        return _default_model()


@lru_cache(maxsize=1)
def _default_model() -> AppearanceModel:
    text = resources.files("marsscene.terrain").joinpath("data/appearance.json").read_text(
        encoding="utf-8"
    )
    doc = {k: v for k, v in json.loads(text).items() if not k.startswith("_")}
    kwargs: dict[str, Any] = {k: tuple(v) if isinstance(v, list) else v for k, v in doc.items()}
    return AppearanceModel(**kwargs)


@dataclass(frozen=True)
class RegolithTile:
    """A periodic detail tile: row index grows with +y, column with +x (row 0 at y = 0)."""

    albedo_rgb: NDArray[np.float32]
    """(n, n, 3) linear reflectance."""
    height_m: NDArray[np.float32]
    """(n, n) micro-relief (pebbles and bumps) about zero."""
    tile_m: float

    @property
    def texel_m(self) -> float:
        return self.tile_m / self.albedo_rgb.shape[0]


def _spectral_noise(
    n: int, texel_m: float, slope: float, lo_m: float, hi_m: float, rng: np.random.Generator
) -> NDArray[np.float64]:
    """Periodic Gaussian noise with amplitude ``~ f^-slope`` between wavelengths lo..hi, std 1."""
    f = np.fft.fftfreq(n, d=texel_m)
    fr = np.hypot(f[:, None], f[None, : n // 2 + 1])
    band = (fr >= 1.0 / hi_m) & (fr <= 1.0 / lo_m)
    amp = np.where(band, np.power(np.maximum(fr, 1e-12), -slope), 0.0)
    spec = amp * (rng.standard_normal(amp.shape) + 1j * rng.standard_normal(amp.shape))
    g = np.fft.irfft2(spec, s=(n, n))
    return g / max(float(g.std()), 1e-12)


def regolith_tile(
    *,
    size_px: int = 2048,
    tile_m: float = 8.0,
    rng: np.random.Generator,
    model: AppearanceModel | None = None,
) -> RegolithTile:
    """A seeded, seamless regolith tile: mottled soil albedo, pebbles and micro-relief.

    Parameters
    ----------
    size_px : int
        Texels per side (a power of two is fastest).
    tile_m : float
        Ground size of the tile (in m); the texel is ``tile_m / size_px``.
    rng : numpy.random.Generator
    model : AppearanceModel, optional

    Returns
    -------
    RegolithTile
    """
    m = model if model is not None else AppearanceModel.default()
    n = int(size_px)
    texel = tile_m / n
    mottle = _spectral_noise(n, texel, m.mottle_spectral_slope, 2 * texel,
                             min(tile_m, m.mottle_max_wavelength_m), rng)
    bump = _spectral_noise(n, texel, 1.0, 2 * texel, m.bump_max_wavelength_m, rng)
    height = m.bump_rms_m * bump
    factor = np.exp(m.mottle_sigma * mottle)
    # Pebbles: discs with their own albedo factor, stamped in one vectorised scatter.
    count = int(rng.poisson(m.pebbles_per_m2 * tile_m * tile_m))
    d_lo, d_hi = m.pebble_diameter_range_m
    u = rng.random(count)
    diam = d_lo * (d_hi / d_lo) ** (u**2)  # log-uniform, skewed towards small ones
    centre = rng.random((count, 2)) * n
    pfac = np.exp(m.pebble_albedo_sigma * rng.standard_normal(count) - 0.1)
    k = math.ceil(d_hi / texel / 2) + 1
    off = np.arange(-k, k + 1)
    dr, dc = np.meshgrid(off, off, indexing="ij")
    rr = np.floor(centre[:, 0, None, None]).astype(np.int64) + dr[None]
    cc = np.floor(centre[:, 1, None, None]).astype(np.int64) + dc[None]
    dist2 = (rr + 0.5 - centre[:, 0, None, None]) ** 2 + (cc + 0.5 - centre[:, 1, None, None]) ** 2
    rad = (diam / texel / 2)[:, None, None]
    inside = dist2 <= rad**2
    flat = ((rr % n) * n + (cc % n))[inside]
    dome = (np.sqrt(np.maximum(rad**2 - dist2, 0.0)) * texel * 0.6)[inside]
    order = np.argsort(dome, kind="stable")  # the highest dome wins where pebbles overlap
    hgt = height.ravel()
    peb_h = np.full(n * n, -np.inf)
    peb_h[flat[order]] = dome[order]
    idx = np.broadcast_to(np.arange(count)[:, None, None], inside.shape)[inside]
    peb_id = np.full(n * n, -1, dtype=np.int64)
    peb_id[flat[order]] = idx[order]
    on = peb_id >= 0
    hgt[on] = hgt[on] + peb_h[on]
    fac = factor.ravel()
    fac[on] = pfac[peb_id[on]] * np.exp(0.3 * m.mottle_sigma * mottle.ravel()[on])
    soil = np.asarray(m.soil_rgb)
    gray = np.asarray(m.rock_gray_rgb)
    expo = np.asarray(m.redness_exponent_rgb)
    rgb = soil[None, :] * fac[:, None] ** expo[None, :]
    rgb[on] = 0.5 * rgb[on] + 0.5 * gray[None, :] * fac[on, None]  # pebbles: greyer
    albedo = np.clip(rgb, 0.02, 0.95).reshape(n, n, 3).astype(np.float32)
    return RegolithTile(albedo, hgt.reshape(n, n).astype(np.float32), float(tile_m))


def _normals(height_m: NDArray[Any], texel_m: float) -> NDArray[np.float64]:
    """Unit normals (n, n, 3) in (x, y, z) of a periodic height tile (rows along +y)."""
    h = height_m.astype(np.float64)
    dzdx = (np.roll(h, -1, axis=1) - np.roll(h, 1, axis=1)) / (2 * texel_m)
    dzdy = (np.roll(h, -1, axis=0) - np.roll(h, 1, axis=0)) / (2 * texel_m)
    nrm = np.stack([-dzdx, -dzdy, np.ones_like(h)], axis=-1)
    return nrm / np.linalg.norm(nrm, axis=-1, keepdims=True)


def normal_map_rgb(tile: RegolithTile) -> NDArray[np.uint8]:
    """Tangent-space normal map (uint8, OpenGL convention: +x right, +y up the image).

    Row 0 of the returned image is the *top* (largest y), as image files store it.
    """
    nrm = _normals(tile.height_m, tile.texel_m)
    img = np.clip(np.rint((nrm * 0.5 + 0.5) * 255.0), 0, 255).astype(np.uint8)
    return np.ascontiguousarray(img[::-1])


def bump_shading(
    tile: RegolithTile,
    sun_direction_enu: tuple[float, float, float],
    direct_share: float,
) -> NDArray[np.float32]:
    """Lambertian shading of the micro-relief relative to flat ground, shape (n, n).

    ``(s * max(n . sun, 0) + (1 - s) * (1 + n_z) / 2) / (s * max(sun_z, 0) + (1 - s))`` with
    ``s = direct_share`` (direct / global horizontal irradiance): 1 on flat ground, < 1 on
    relief facing away from the sun. A renderer without normal mapping multiplies it into the
    albedo (valid while the terrain's own slope is small against the sun elevation).
    """
    nrm = _normals(tile.height_m, tile.texel_m)
    s = np.asarray(sun_direction_enu, dtype=np.float64)
    share = float(np.clip(direct_share, 0.0, 1.0))
    lit = share * np.maximum(nrm @ s, 0.0) + (1.0 - share) * 0.5 * (1.0 + nrm[..., 2])
    flat = share * max(float(s[2]), 0.0) + (1.0 - share)
    return (lit / max(flat, 1e-6)).astype(np.float32)


def rock_albedo_rgb(
    count: int, *, rng: np.random.Generator, model: AppearanceModel | None = None
) -> NDArray[np.float32]:
    """Per-rock linear albedo (count, 3): grey rock mixed with soil by a random dust cover."""
    m = model if model is not None else AppearanceModel.default()
    lo, hi = m.rock_dust_fraction_range
    dust = rng.uniform(lo, hi, size=int(count))[:, None]
    bright = np.exp(0.15 * rng.standard_normal(int(count)))[:, None]
    rgb = (1.0 - dust) * np.asarray(m.rock_gray_rgb) + dust * np.asarray(m.soil_rgb)
    return np.clip(rgb * bright, 0.02, 0.95).astype(np.float32)
