"""Large-scale ground albedo: seeded metre-to-decametre variation and orthoimage modulation.

The regolith detail tile (:func:`marsscene.terrain.appearance.regolith_tile`) carries the
centimetre-to-metre mottling and repeats every ``tile_m``. On top of it the ground albedo is
multiplied by a world-anchored, effectively aperiodic gain ``exp(log_gain(x, y))``:

* **metre band** (``albedo_mid_band_m``, 1-8 m): continues the tile's mottling spectrum
  (amplitude ~ f^-1) beyond the tile with ``albedo_mid_sigma``; drawn on a 128 m periodic
  grid, so the 8 m tile no longer repeats visibly (a 128 m period is twice the camera window);
* **decametre band** (``albedo_large_band_m``, 8-1000 m) with ``albedo_large_sigma`` = 0.09 in
  log albedo: the spread of red reflectance between the soil units within tens of metres of
  Viking Lander 1 (0.30-0.39; Guinness 1981, JGR 86(B8), 7983-7992) read as +-1.5 sigma;
* **orthoimage** (where a scene drapes one): the log luminance of the image, smoothed over
  ``ortho_smoothing_m``, replaces the decametre band, so the ground follows the image at
  large scale and the regolith model up close. The draped image is contrast-stretched at
  build time (:func:`marsscene.dem.texture.texture_rgb`), so its brightness ratios are not
  albedo ratios: its log luminance is rescaled to the decametre band's std
  (``albedo_large_sigma``) and clipped at 3 std. Its colour is not used (HiRISE RED is
  panchromatic): the gain scales the soil albedo.

Pure numpy/scipy; randomness only through the ``rng`` passed in.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from marsscene.terrain.appearance import AppearanceModel

__all__ = ["AlbedoField", "albedo_field", "ortho_gain"]

_MID_PERIOD_M, _MID_PX = 128.0, 512  # 0.25 m cells
_LARGE_PERIOD_M, _LARGE_PX = 1024.0, 256  # 4 m cells


def _band_noise(n: int, period_m: float, lo_m: float, hi_m: float, slope: float,
                rng: np.random.Generator) -> NDArray[np.float32]:
    """Periodic Gaussian noise (n, n), std 1, amplitude ~ f^-slope for wavelengths lo..hi."""
    f = np.fft.fftfreq(n, d=period_m / n)
    fr = np.hypot(f[:, None], f[None, : n // 2 + 1])
    band = (fr >= 1.0 / hi_m) & (fr <= 1.0 / lo_m)
    amp = np.where(band, np.power(np.maximum(fr, 1e-12), -slope), 0.0)
    spec = amp * (rng.standard_normal(amp.shape) + 1j * rng.standard_normal(amp.shape))
    g = np.fft.irfft2(spec, s=(n, n))
    return (g / max(float(g.std()), 1e-12)).astype(np.float32)


def _bilinear_periodic(grid: NDArray[np.float32], cell_m: float, x: NDArray[np.float64],
                       y: NDArray[np.float64]) -> NDArray[np.float32]:
    """Sample a periodic grid (row along +y, column along +x, post (0, 0) at the origin)."""
    n_r, n_c = grid.shape
    u, v = x / cell_m, y / cell_m
    c0, r0 = np.floor(u), np.floor(v)
    fu, fv = (u - c0).astype(np.float32), (v - r0).astype(np.float32)
    c0i, r0i = c0.astype(np.int64) % n_c, r0.astype(np.int64) % n_r
    c1i, r1i = (c0i + 1) % n_c, (r0i + 1) % n_r
    top = grid[r0i, c0i] * (1 - fu) + grid[r0i, c1i] * fu
    bot = grid[r1i, c0i] * (1 - fu) + grid[r1i, c1i] * fu
    return (top * (1 - fv) + bot * fv).astype(np.float32)


@dataclass(frozen=True)
class OrthoGain:
    """Log gain of a smoothed orthoimage over a footprint (row 0 at ``y0_m``, along +y)."""

    log_gain: NDArray[np.float32]
    x0_m: float
    y0_m: float
    pixel_m: float

    def sample(self, x: NDArray[np.float64], y: NDArray[np.float64]) -> NDArray[np.float32]:
        """Log gain at world points; 0 (gain 1) outside the image."""
        rows, cols = self.log_gain.shape
        u = np.clip((x - self.x0_m) / self.pixel_m - 0.5, 0, cols - 1)
        v = np.clip((y - self.y0_m) / self.pixel_m - 0.5, 0, rows - 1)
        c0 = np.minimum(np.floor(u).astype(np.int64), cols - 2) if cols > 1 else 0 * u
        r0 = np.minimum(np.floor(v).astype(np.int64), rows - 2) if rows > 1 else 0 * v
        c0, r0 = np.asarray(c0, np.int64), np.asarray(r0, np.int64)
        fu = np.clip(u - c0, 0, 1).astype(np.float32)
        fv = np.clip(v - r0, 0, 1).astype(np.float32)
        c1, r1 = np.minimum(c0 + 1, cols - 1), np.minimum(r0 + 1, rows - 1)
        g = self.log_gain
        top = g[r0, c0] * (1 - fu) + g[r0, c1] * fu
        bot = g[r1, c0] * (1 - fu) + g[r1, c1] * fu
        out = top * (1 - fv) + bot * fv
        w, h = cols * self.pixel_m, rows * self.pixel_m
        inside = ((x >= self.x0_m) & (x <= self.x0_m + w) & (y >= self.y0_m)
                  & (y <= self.y0_m + h))
        return np.where(inside, out, 0.0).astype(np.float32)


def ortho_gain(image_rgb: NDArray[np.uint8], *, x0_m: float, y0_m: float, width_m: float,
               model: AppearanceModel | None = None) -> OrthoGain:
    """Log luminance gain of an orthoimage draped over ``width_m`` from ``(x0_m, y0_m)``.

    ``image_rgb`` is in image order (row 0 = north); ``(x0_m, y0_m)`` is its south-west
    corner. The luminance (Rec. 709 weights of the sRGB-decoded image) is smoothed with a
    Gaussian of ``ortho_smoothing_m``; its log, less the mean, is scaled to a std of
    ``albedo_large_sigma`` and clipped at +-3 std (see the module doc).
    """
    m = model if model is not None else AppearanceModel.default()
    smoothing_m, sigma = m.ortho_smoothing_m, m.albedo_large_sigma
    from scipy.ndimage import gaussian_filter

    img = np.asarray(image_rgb, dtype=np.float64) / 255.0
    if img.ndim == 2:
        img = img[..., None]
    lin = np.where(img <= 0.04045, img / 12.92, ((img + 0.055) / 1.055) ** 2.4)
    w = np.array([0.2126, 0.7152, 0.0722])[: lin.shape[-1]]
    luma = (lin @ (w / w.sum()))[::-1]  # row 0 = south
    pixel = float(width_m) / luma.shape[1]
    luma = gaussian_filter(luma, sigma=max(smoothing_m / pixel, 0.0), mode="nearest")
    log = np.log(np.maximum(luma, 1e-3 * max(float(luma.mean()), 1e-6)))
    log -= float(log.mean())
    log *= sigma / max(float(log.std()), 1e-9)
    log = np.clip(log, -3 * sigma, 3 * sigma)
    return OrthoGain(log.astype(np.float32), float(x0_m), float(y0_m), pixel)


@dataclass(frozen=True)
class AlbedoField:
    """World-anchored log-albedo gain: metre band + (decametre band or orthoimage)."""

    mid: NDArray[np.float32]
    """(512, 512) metre-band log gain on a 128 m periodic grid."""
    large: NDArray[np.float32]
    """(256, 256) decametre-band log gain on a 1024 m periodic grid."""
    ortho: OrthoGain | None = None

    def log_gain(self, x_m: NDArray[np.float64], y_m: NDArray[np.float64]
                 ) -> NDArray[np.float32]:
        """``log(albedo / detail albedo)`` at world points (any matching shapes)."""
        x, y = np.asarray(x_m, dtype=np.float64), np.asarray(y_m, dtype=np.float64)
        out = _bilinear_periodic(self.mid, _MID_PERIOD_M / _MID_PX, x, y)
        if self.ortho is not None:
            return out + self.ortho.sample(x, y)
        return out + _bilinear_periodic(self.large, _LARGE_PERIOD_M / _LARGE_PX, x, y)

    def with_ortho(self, ortho: OrthoGain | None) -> AlbedoField:
        return AlbedoField(self.mid, self.large, ortho)


def albedo_field(*, rng: np.random.Generator, model: AppearanceModel | None = None,
                 ortho: OrthoGain | None = None) -> AlbedoField:
    """The seeded large-scale albedo field (see the module doc for bands and amplitudes).

    >>> f = albedo_field(rng=np.random.default_rng(0))
    >>> g = f.log_gain(np.linspace(0, 500, 2001), np.zeros(2001))
    >>> 0.08 < float(g.std()) < 0.2
    True
    """
    m = model if model is not None else AppearanceModel.default()
    mid = _band_noise(_MID_PX, _MID_PERIOD_M, *m.albedo_mid_band_m, m.mottle_spectral_slope, rng)
    large = _band_noise(_LARGE_PX, _LARGE_PERIOD_M, *m.albedo_large_band_m,
                        m.mottle_spectral_slope, rng)
    return AlbedoField(mid * np.float32(m.albedo_mid_sigma),
                       large * np.float32(m.albedo_large_sigma), ortho)
