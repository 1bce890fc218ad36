"""Seeded self-affine (fractional Brownian) terrain: synthesis and sub-DEM detail.

A self-affine surface with Hurst exponent H has the isotropic power spectral density
``P(k) ∝ k^-(2H+2)`` (Turcotte, *Fractals and Chaos in Geology and Geophysics*, 2nd ed., 1997,
doi:10.1017/CBO9781139174695, ch. 7) and variogram ``V(h) ∝ h^(2H)``. Mars topography is
self-affine over metre to kilometre baselines with H ≈ 0.6–0.9 (Orosei et al. 2003, JGR 108(E4)
8023, doi:10.1029/2002JE001883). Synthesis filters white Gaussian noise in the Fourier domain
(spectral synthesis, Saupe 1988 in *The Science of Fractal Images*).

:func:`add_detail` upsamples a DEM with a cubic spline and adds detail **only above the DEM's
Nyquist frequency**, with an amplitude that continues the DEM's own spectrum: the variance of the
DEM in a reference octave (wavelengths of 8-16 posts, below the smoothing of stereo DEMs) fixes
the variance of the new band ``(k_c, k_f]`` through ``σ²_band ∝ k1^-2H − k2^-2H``.
Coarse scales are left untouched, so the detailed terrain still
matches the DEM when averaged back to its posts.
"""

from __future__ import annotations

import numpy as np
import scipy.fft as sfft
from numpy.typing import NDArray
from scipy.interpolate import make_interp_spline

from marsscene.errors import MemoryBudgetError
from marsscene.terrain.heightfield import Heightfield

__all__ = ["add_detail", "continued_detail_rms", "fbm_surface", "measure_hurst", "resample",
           "synthesize"]

#: Posts above which a grid is refused (about 2 GB of float32 work arrays per 10^8 posts).
MAX_POSTS = 120_000_000


def _check_posts(rows: int, cols: int) -> None:
    if rows * cols > MAX_POSTS:
        est_gb = rows * cols * 4 * 6 / 1e9
        raise MemoryBudgetError(
            f"a {rows} x {cols} grid ({rows * cols:,} posts) needs about {est_gb:.1f} GB; "
            f"the limit is {MAX_POSTS:,} posts: raise post_m (--post-m), crop the DEM, or "
            "build a level-of-detail terrain (terrain.lod = true, --lod, with --focus-size-m and "
            '--focus-xy; terrain.lod = "auto", the default, does it by itself; --preset '
            "main-crater is such a scene)"
        )


def _radial_k(shape: tuple[int, int], post_m: float) -> NDArray[np.float32]:
    """|k| (in cycles/m) of an ``rfft2`` spectrum, float32 (the spectrum's own precision)."""
    ky = sfft.fftfreq(shape[0], d=post_m).astype(np.float32)
    kx = sfft.rfftfreq(shape[1], d=post_m).astype(np.float32)
    return np.hypot(ky[:, None], kx[None, :])


def fbm_surface(
    shape: tuple[int, int],
    post_m: float,
    *,
    hurst: float,
    rng: np.random.Generator,
    k_min_cyc_m: float = 0.0,
) -> NDArray[np.float32]:
    """Zero-mean, unit-variance self-affine noise on a grid.

    Parameters
    ----------
    shape : (rows, cols)
    post_m : float
        Post spacing (in m).
    hurst : float
        Hurst exponent H in (0, 1].
    rng : numpy.random.Generator
    k_min_cyc_m : float
        Spatial frequencies at or below this (in cycles/m) are removed (high-pass).
    """
    rows, cols = shape
    _check_posts(rows, cols)
    fshape = (sfft.next_fast_len(rows, real=True), sfft.next_fast_len(cols, real=True))
    white = rng.standard_normal(fshape, dtype=np.float32)
    spec = sfft.rfft2(white, workers=-1)
    del white
    k = _radial_k(fshape, post_m)
    amp = np.zeros_like(k)  # |k|^-(H+1) above the high-pass, 0 at and below it and at k = 0
    np.power(k, np.float32(-(hurst + 1.0)), out=amp, where=k > k_min_cyc_m)
    amp[0, 0] = 0.0
    spec *= amp
    del k, amp
    z = np.ascontiguousarray(sfft.irfft2(spec, s=fshape, workers=-1)[:rows, :cols],
                             dtype=np.float32)
    del spec
    z -= z.mean(dtype=np.float64)
    std = float(np.sqrt(np.mean(np.square(z), dtype=np.float64)))
    if std > 0:
        z /= np.float32(std)
    return z


def synthesize(
    size_m: tuple[float, float],
    post_m: float,
    *,
    hurst: float,
    rms_height_m: float,
    rng: np.random.Generator,
    rms_slope_deg: float | None = None,
) -> Heightfield:
    """A procedural self-affine terrain centred on the origin.

    The RMS height is exactly ``rms_height_m`` unless ``rms_slope_deg`` is given, in which case
    the surface is scaled so that ``atan(sqrt(mean(|grad z|^2)))`` equals it.
    """
    cols = int(np.floor(size_m[0] / post_m + 1e-9)) + 1
    rows = int(np.floor(size_m[1] / post_m + 1e-9)) + 1
    z = fbm_surface((rows, cols), post_m, hurst=hurst, rng=rng)
    if rms_slope_deg is not None:
        gy, gx = np.gradient(z, post_m)
        rms_grad = float(np.sqrt(np.mean(gx * gx + gy * gy)))
        scale = np.tan(np.radians(rms_slope_deg)) / rms_grad
    else:
        scale = rms_height_m
    z *= np.float32(scale)
    return Heightfield._centered_owning(z, post_m)


def _band_variance(z: NDArray[np.float32], post_m: float, k_lo: float, k_hi: float) -> float:
    """Variance of ``z`` in the radial frequency band ``(k_lo, k_hi]`` (cycles/m).

    The plane trend is removed and the grid is mirrored into a 2x2 periodic tile first, so the
    DEM's edges do not leak spurious high-frequency power into the band.
    """
    rows, cols = z.shape
    yy, xx = np.mgrid[0:rows, 0:cols]
    a = np.column_stack([np.ones(z.size), xx.ravel(), yy.ravel()])
    coef = np.linalg.lstsq(a, z.astype(np.float64).ravel(), rcond=None)[0]
    zz = z - (a @ coef).reshape(rows, cols)
    zz = np.concatenate([zz, zz[::-1, :]], axis=0)
    zz = np.concatenate([zz, zz[:, ::-1]], axis=1)
    spec = sfft.rfft2(zz, workers=-1)
    k = _radial_k(zz.shape, post_m)
    band = sfft.irfft2(spec * ((k > k_lo) & (k <= k_hi)), s=zz.shape, workers=-1)
    return float(band.var())


#: The reference octave is [k_c / 2**REFERENCE_OCTAVE, k_c / 2**(REFERENCE_OCTAVE - 1)].
REFERENCE_OCTAVE = 3


def continued_detail_rms(hf: Heightfield, post_m: float, hurst: float) -> float:
    """RMS of the band ``(k_c, k_f]`` that continues the DEM's spectrum with exponent ``H``.

    Stereo DEMs are smoothed over their top octaves (HiRISE DTMs resolve features of ~3-5 posts,
    Kirk et al. 2008, doi:10.1029/2007JE003000), so the power law is anchored on the octave of
    wavelengths 8-16 posts and extrapolated: ``σ²(k1, k2) ∝ k1^-2H − k2^-2H``.
    """
    k_c = 0.5 / hf.cell_size_m
    k_f = 0.5 / post_m
    octave = REFERENCE_OCTAVE if min(hf.shape) >= 2 ** (REFERENCE_OCTAVE + 2) else 1
    k_lo, k_hi = k_c / 2.0**octave, k_c / 2.0 ** (octave - 1)
    ref_var = _band_variance(hf.z_m, hf.cell_size_m, k_lo, k_hi)
    e = -2.0 * hurst
    ratio = (k_c**e - k_f**e) / (k_lo**e - k_hi**e)
    return float(np.sqrt(max(ref_var, 0.0) * ratio))


def _spline_resample(hf: Heightfield, cols: int, rows: int, post_m: float) -> NDArray[np.float32]:
    r_old, c_old = hf.shape
    x_old = np.arange(c_old) * hf.cell_size_m
    y_old = np.arange(r_old) * hf.cell_size_m
    x_new = np.minimum(np.arange(cols) * post_m, x_old[-1])
    y_new = np.minimum(np.arange(rows) * post_m, y_old[-1])
    # cubic where there are enough posts (a not-a-knot cubic needs 4), else linear
    kx, ky = (3 if n >= 4 else 1 for n in (c_old, r_old))
    tmp = make_interp_spline(x_old, hf.z_m.astype(np.float64), k=kx, axis=1)(x_new)
    return make_interp_spline(y_old, tmp, k=ky, axis=0)(y_new).astype(np.float32)


def _target_shape(hf: Heightfield, post_m: float) -> tuple[int, int]:
    width, height = hf.size_m
    cols = int(np.floor(width / post_m + 1e-9)) + 1
    rows = int(np.floor(height / post_m + 1e-9)) + 1
    _check_posts(rows, cols)
    return rows, cols


def resample(hf: Heightfield, *, post_m: float) -> Heightfield:
    """Resample to ``post_m`` with a cubic spline (no added detail); same south-west origin.

    For downsampling by more than 2x prefer ``marsscene.dem.ops`` area averaging.
    """
    rows, cols = _target_shape(hf, post_m)
    return Heightfield(_spline_resample(hf, cols, rows, post_m), post_m, hf.origin_xy_m)


def add_detail(
    hf: Heightfield,
    *,
    post_m: float,
    hurst: float,
    rng: np.random.Generator,
    detail_rms_m: float | None = None,
) -> Heightfield:
    """Upsample a heightfield to ``post_m`` and add seeded fractal detail below its resolution.

    Parameters
    ----------
    hf : Heightfield
        Coarse terrain (e.g. a 1 m DEM).
    post_m : float
        Target post spacing (in m), at most ``hf.cell_size_m``.
    hurst : float
        Hurst exponent used to continue the spectrum below the DEM's resolution.
    rng : numpy.random.Generator
    detail_rms_m : float, optional
        RMS of the added detail (in m). By default it continues the DEM's top-octave spectrum.

    Returns
    -------
    Heightfield
        A new heightfield with the same south-west origin; the input is not modified.
    """
    rows, cols = _target_shape(hf, post_m)
    z = _spline_resample(hf, cols, rows, post_m)
    k_c = 0.5 / hf.cell_size_m  # coarse Nyquist (cycles/m)
    if detail_rms_m is None:
        detail_rms_m = continued_detail_rms(hf, post_m, hurst)
    if detail_rms_m > 0:
        noise = fbm_surface((rows, cols), post_m, hurst=hurst, rng=rng, k_min_cyc_m=k_c)
        z += noise * np.float32(detail_rms_m)
    return Heightfield(z, post_m, hf.origin_xy_m)


def measure_hurst(
    hf: Heightfield, *, lag_posts: tuple[int, ...] = (1, 2, 4, 8, 16)
) -> float:
    """Estimate H from the variogram slope, ``V(h) ∝ h^(2H)``, along both grid axes."""
    z = hf.z_m.astype(np.float64)
    v = []
    for lag in lag_posts:
        dx = z[:, lag:] - z[:, :-lag]
        dy = z[lag:, :] - z[:-lag, :]
        v.append(0.5 * (np.mean(dx * dx) + np.mean(dy * dy)))
    h = np.asarray(lag_posts, dtype=np.float64) * hf.cell_size_m
    slope = np.polyfit(np.log(h), np.log(np.asarray(v)), 1)[0]
    return float(slope / 2.0)
