"""``dem-correlation``: a local elevation map matched against the orbital DTM over position and
heading.

For each heading of a sweep around the prior's, the local map is rotated into a north-up
template on the orbital posts (cubic spline, a cell kept where all its neighbours are observed);
template and map are high-passed (less their Gaussian mean over ``highpass_m``: the regional
slope, which any tilted patch shares, and the unknown vertical datum go); the masked normalised
cross-correlation (Padfield 2012, IEEE TIP 21(5), 2706-2718, doi:10.1109/TIP.2011.2181402) is
computed over every shift in the search window at once with FFTs (``scipy.signal.fftconvolve``).
The best (heading, shift) is refined to sub-cell and sub-step by parabolas through its
neighbours. Confidence compares the peak with the best correlation farther than
``exclusion_m`` from it (any heading): ``(peak - second) / (1 - second)``, 0 for an ambiguous
or featureless map, near 1 for a unique sharp match.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage, signal

from marsscene.errors import ConfigError
from marsscene.orbital.grid import OrbitalMap, sample_bilinear
from marsscene.orbital.local import LocalMap
from marsscene.orbital.model import FWHM_PER_SIGMA

__all__ = ["DemMatch", "match_dem"]

_EPS = 1e-9


@dataclass(frozen=True)
class DemMatch:
    """The pose of the local map's frame in the scene that best matches the orbital DTM."""

    x_m: float
    y_m: float
    yaw_rad: float
    peak_ncc: float
    """Normalised cross-correlation at the match (1 = identical up to offset and scale)."""
    second_ncc: float
    """The best correlation farther than ``exclusion_m`` from the match."""
    confidence: float
    """``(peak - second) / (1 - second)`` in [0, 1]."""
    observed_cells: int


def _masked_mean(z: NDArray[np.float64], mask: NDArray[np.bool_], sigma_px: float
                 ) -> NDArray[np.float64]:
    """The Gaussian mean of ``z`` over ``mask`` (normalised convolution)."""
    w = mask.astype(np.float64)
    num = ndimage.gaussian_filter(np.where(mask, z, 0.0), sigma_px, mode="nearest")
    return num / np.maximum(ndimage.gaussian_filter(w, sigma_px, mode="nearest"), _EPS)


def _bandpass(z: NDArray[np.float64], mask: NDArray[np.bool_], smooth_px: float,
              highpass_px: float) -> NDArray[np.float64]:
    """``z`` smoothed over ``smooth_px`` less its mean over ``highpass_px`` (masked Gaussian
    means; the plain mean for 0), 0 outside ``mask``."""
    low = _masked_mean(z, mask, smooth_px) if smooth_px > 0 else np.where(mask, z, 0.0)
    if highpass_px > 0:
        base = _masked_mean(z, mask, highpass_px)
    else:
        base = np.full(z.shape, float(z[mask].mean()) if mask.any() else 0.0)
    return np.where(mask, low - base, 0.0)


def _spline(local: LocalMap) -> NDArray[np.float64]:
    """Cubic B-spline coefficients of the local map, unobserved cells filled by the nearest
    observed one (they are masked out after; the fill only keeps the spline finite)."""
    idx = ndimage.distance_transform_edt(~local.mask, return_distances=False,
                                         return_indices=True)
    filled = np.where(local.mask, local.z_m, 0.0)[tuple(idx)]
    return np.asarray(ndimage.spline_filter(filled, order=3, mode="nearest"), dtype=np.float64)


def _template(local: LocalMap, coeffs: NDArray[np.float64], yaw: float, half: int,
              cell_m: float) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """The local map rotated by ``yaw`` onto a north-up (2 half + 1)^2 grid of ``cell_m``
    centred on the local origin: cubic spline (its smoothing hardly depends on the heading, a
    bilinear one's does), a cell kept where its four neighbours are observed."""
    off = cell_m * np.arange(-half, half + 1)
    gx, gy = np.meshgrid(off, off)
    c, s = math.cos(yaw), math.sin(yaw)
    lx, ly = c * gx + s * gy, -s * gx + c * gy  # R(-yaw) of the world-aligned offsets
    m = sample_bilinear(local.mask.astype(np.float64), local.origin_xy_m, local.cell_m, lx, ly)
    mask = np.nan_to_num(m, nan=0.0) > 1.0 - 1e-6
    rc = np.stack([(ly - local.origin_xy_m[1]) / local.cell_m,
                   (lx - local.origin_xy_m[0]) / local.cell_m])
    z = ndimage.map_coordinates(coeffs, rc, order=3, mode="nearest", prefilter=False)
    return np.where(mask, z, 0.0), mask


def _ncc(image: NDArray[np.float64], t: NDArray[np.float64], mask: NDArray[np.bool_]
         ) -> NDArray[np.float64]:
    """Masked NCC of template ``t`` (zero-mean over ``mask``) at every valid shift."""
    m = mask.astype(np.float64)
    n = m.sum()
    tz = np.where(mask, t - t[mask].mean(), 0.0)
    flip = (slice(None, None, -1), slice(None, None, -1))
    num = signal.fftconvolve(image, tz[flip], mode="valid")
    s1 = signal.fftconvolve(image, m[flip], mode="valid")
    s2 = signal.fftconvolve(image * image, m[flip], mode="valid")
    var_i = np.maximum(s2 - s1 * s1 / n, 0.0)
    var_t = float((tz * tz).sum())
    den = np.sqrt(var_i * var_t)
    ok = den > _EPS * max(n, 1.0) * max(float(np.abs(image).max()) ** 2, 1e-12)
    return np.where(ok, num / np.where(ok, den, 1.0), 0.0)


def _parabola(a: float, b: float, c: float) -> float:
    """Offset in (-0.5, 0.5) of the vertex of the parabola through (-1, a), (0, b), (1, c)."""
    d = a - 2.0 * b + c
    return 0.0 if d >= 0 else float(np.clip(0.5 * (a - c) / d, -0.5, 0.5))


def _refine(surface: NDArray[np.float64], r: int, c: int) -> tuple[float, float]:
    rows, cols = surface.shape
    dr = _parabola(*surface[r - 1:r + 2, c]) if 0 < r < rows - 1 else 0.0
    dc = _parabola(*surface[r, c - 1:c + 2]) if 0 < c < cols - 1 else 0.0
    return r + dr, c + dc


def _sweep(image: NDArray[np.float64], local: LocalMap, yaws: NDArray[np.float64], half: int,
           cell_m: float, smooth_px: float, highpass_px: float) -> NDArray[np.float64]:
    """NCC surfaces (yaws, shifts) of the rotated local map over ``image``."""
    out, coeffs = [], _spline(local)
    for yaw in yaws:
        t, mask = _template(local, coeffs, float(yaw), half, cell_m)
        out.append(_ncc(image, _bandpass(t, mask, smooth_px, highpass_px), mask))
    return np.stack(out)


def _window(orbital: OrbitalMap, prior: tuple[float, float], radius_m: float, half: int
            ) -> tuple[int, int, NDArray[np.float64], NDArray[np.bool_]]:
    """The map's posts a template of ``half`` centred within ``radius_m`` of ``prior`` covers:
    their first row and column, elevations (0 where missing) and validity."""
    cell, (ox, oy), (rows, cols) = orbital.cell_m, orbital.origin_xy_m, orbital.shape
    r_lo = max(math.floor((prior[1] - radius_m - oy) / cell) - half, 0)
    c_lo = max(math.floor((prior[0] - radius_m - ox) / cell) - half, 0)
    r_hi = min(math.ceil((prior[1] + radius_m - oy) / cell) + half, rows - 1)
    c_hi = min(math.ceil((prior[0] + radius_m - ox) / cell) + half, cols - 1)
    if r_hi - r_lo < 2 * half or c_hi - c_lo < 2 * half:
        raise ConfigError("the search window around the prior does not hold the local map "
                          "inside the orbital map")
    crop = np.asarray(orbital.dem_m[r_lo:r_hi + 1, c_lo:c_hi + 1], dtype=np.float64)
    valid = np.isfinite(crop)
    return r_lo, c_lo, np.where(valid, crop, 0.0), valid


def _yaw_fit(per_yaw: NDArray[np.float64], yaws: NDArray[np.float64]) -> float:
    k = int(np.argmax(per_yaw))
    dk = _parabola(*per_yaw[k - 1:k + 2]) if 0 < k < len(yaws) - 1 else 0.0
    step = float(yaws[1] - yaws[0]) if len(yaws) > 1 else 0.0
    return float(yaws[k] + dk * step)


def match_dem(local: LocalMap, orbital: OrbitalMap, prior_xy_yaw: tuple[float, float, float],
              *, search_radius_m: float = 30.0, yaw_window_deg: float = 10.0,
              yaw_step_deg: float = 1.0, smooth_m: float | None = None, highpass_m: float = 0.0,
              exclusion_m: float = 5.0) -> DemMatch:
    """Match ``local`` against ``orbital.dem_m`` around the prior pose of its frame.

    Parameters
    ----------
    local : LocalMap
        The rover's elevation map in its local frame (:func:`local_elevation_map`).
    orbital : OrbitalMap
        The scene's orbital map (:func:`marsscene.orbital.orbital_map`).
    prior_xy_yaw : (x_m, y_m, yaw_rad)
        The prior pose of the local frame in the scene (dead reckoning).
    search_radius_m : float
        Half side of the square of positions searched around the prior (in m).
    yaw_window_deg, yaw_step_deg : float
        Headings searched: the prior's +- the window, in steps (in degrees); then a sweep of
        quarter steps around the best, refined by a parabola.
    smooth_m : float, optional
        Sigma of the Gaussian both maps are smoothed with (in m; default the orbital PSF's:
        the rover's sharp map blurred as the orbiter's, the map's white noise halved).
    highpass_m : float
        Sigma of the Gaussian mean taken off both maps (in m; 0 takes off the mean only).
    exclusion_m : float
        Radius around the match outside which the second peak is sought (in m).

    Returns
    -------
    DemMatch
    """
    if local.observed < 3:
        raise ConfigError(f"the local map has {local.observed} observed cells; need >= 3")
    if yaw_step_deg <= 0 or search_radius_m < 0 or yaw_window_deg < 0:
        raise ConfigError("yaw_step_deg must be > 0, search_radius_m and yaw_window_deg >= 0")
    cell = orbital.cell_m
    sigma = orbital.model.dem_psf_fwhm_m / FWHM_PER_SIGMA if smooth_m is None else smooth_m
    smooth_px, high_px = sigma / cell, highpass_m / cell
    lx, ly = local.cell_xy()
    half = math.ceil((float(np.hypot(lx[local.mask], ly[local.mask]).max())
                          + local.cell_m) / cell)
    r_lo, c_lo, crop, valid = _window(orbital, prior_xy_yaw[:2], search_radius_m, half)
    image = _bandpass(crop, valid, smooth_px, high_px)
    n_steps = math.floor(yaw_window_deg / yaw_step_deg + 1e-9)
    yaws = prior_xy_yaw[2] + np.radians(yaw_step_deg * np.arange(-n_steps, n_steps + 1))
    stack = _sweep(image, local, yaws, half, cell, smooth_px, high_px)
    k, r, c = (int(v) for v in np.unravel_index(int(np.argmax(stack)), stack.shape))
    gr, gc = np.mgrid[0:stack.shape[1], 0:stack.shape[2]]
    far = np.hypot(gr - r, gc - c) * cell > exclusion_m
    second = float(stack[:, far].max()) if far.any() else 0.0
    # the fine sweep: quarter steps over +- one step, shifts within 2 cells of the peak
    r0, c0 = max(r - 2, 0), max(c - 2, 0)
    sub = image[r0:r + 3 + 2 * half, c0:c + 3 + 2 * half]
    fine_yaws = yaws[k] + np.radians(yaw_step_deg) * np.linspace(-1.0, 1.0, 9)
    fine = _sweep(sub, local, fine_yaws, half, cell, smooth_px, high_px)
    kf, rf, cf = (int(v) for v in np.unravel_index(int(np.argmax(fine)), fine.shape))
    peak = float(fine[kf, rf, cf])
    rr, cc = _refine(fine[kf], rf, cf)
    yaw = _yaw_fit(fine.reshape(len(fine_yaws), -1).max(axis=1), fine_yaws)
    confidence = float(np.clip((peak - second) / max(1.0 - second, _EPS), 0.0, 1.0))
    ox, oy = orbital.origin_xy_m
    return DemMatch(float(ox + (c_lo + c0 + cc + half) * cell),
                    float(oy + (r_lo + r0 + rr + half) * cell), yaw, peak, second, confidence,
                    local.observed)
