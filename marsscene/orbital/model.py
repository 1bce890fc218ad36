"""The orbital map model: HiRISE-like posts, a Gaussian point-spread function and seeded noise.

A HiRISE stereo DTM is posted at 1 m (about 4x the 0.25-0.3 m image pixels it is matched from)
but resolves only features of about 3 posts: stereo matching correlates patches of several
pixels, so relief shorter than ~3 m is smoothed away (the effective horizontal resolution is
about 3x the post spacing; Kirk et al. 2008, JGR 113, E00A24, doi:10.1029/2007JE003000). The
model states that as a **half-amplitude wavelength**
``dem_half_wavelength_m`` = 3 m: a sinusoid of that wavelength keeps half its amplitude. The
PSF is the Gaussian with exactly that transfer, whose full width at half maximum is
``FWHM = (2 ln 2 / pi) * lambda_half`` (1.32 m for 3 m): its transfer function is
``exp(-pi^2 FWHM^2 / (4 ln 2 lambda^2))``.

The DTM's noise is Gaussian with ``dem_noise_sigma_m`` = 0.25 m per post: Kirk et al. (2008)
give an expected vertical precision of tens of centimetres for HiRISE stereo pairs at typical
convergence (0.1-0.5 m; 0.2-0.3 m is common for 0.25-0.3 m/pixel pairs). It is **spatially
correlated**, as a stereo DTM's error is: each post is matched from a correlation patch of
several image pixels shared with its neighbours, so neighbouring posts err together over about
the patch, the same ~3 posts that set the effective resolution (Kirk et al. 2008). The model
draws white noise, convolves it with a Gaussian of sigma ``dem_noise_correlation_m / 2`` and
rescales it to ``dem_noise_sigma_m``: its autocorrelation is ``exp(-(r / L)^2)`` with
``L = dem_noise_correlation_m`` = 3 m (the lag where it falls to 1/e); 0 gives white noise.

The orthoimage (a procedural scene's, from its albedo field) is sampled at 0.5 m pixels (HiRISE
RED bin-2 products; 0.25 m at bin 1) with the same half-amplitude rule at 3 pixels (McEwen et
al. 2007, JGR 112, E05S02: objects of ~3 pixels are resolved) and 1 % noise (signal-to-noise
ratio of about 100 for typical HiRISE RED images, McEwen et al. 2007).

The image is shaded by the terrain under the orbiter's sun before the PSF
(:mod:`marsscene.orbital.shading`: Lambert's law, ``image_shading`` = "lambert", the sun at
``image_sun_incidence_deg`` = 48 deg and ``image_sun_azimuth_deg`` = 252 deg, Jezero's at 15:00
local solar time at the equinox; "none" leaves the albedo alone).

Rocks: the orbiter sees only boulders of ``rock_resolved_d_m`` = 1 m and more (HiRISE counts
start at ~1-1.5 m diameter, Golombek et al. 2008, JGR 113, E00A09); smaller rocks are absent
from the orbital map. Rocks at or above the cut-off are raised into the terrain as half-
ellipsoids before the PSF, so the PSF then softens them as it would.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene._validate import plain
from marsscene.errors import ConfigError
from marsscene.orbital.shading import SHADING_LAWS

__all__ = ["FWHM_PER_SIGMA", "OrbitalModel", "apply_psf", "correlated_noise",
           "fwhm_of_half_wavelength", "psf_gain"]

#: A Gaussian's full width at half maximum per standard deviation, 2 sqrt(2 ln 2).
FWHM_PER_SIGMA = 2.0 * math.sqrt(2.0 * math.log(2.0))


@dataclass(frozen=True, kw_only=True)
class OrbitalModel:
    """The parameters of an orbital map (defaults and their sources: the module doc)."""

    dem_post_m: float = 1.0
    """Post spacing of the orbital DTM of a procedural scene (in m)."""
    dem_half_wavelength_m: float = 3.0
    """Wavelength the DTM's PSF halves in amplitude (in m): ~3 posts."""
    dem_noise_sigma_m: float = 0.25
    """Std of the DTM's vertical noise per post (in m)."""
    dem_noise_correlation_m: float = 3.0
    """Lag at which the DTM noise's autocorrelation falls to 1/e (in m; 0 = white)."""
    image_pixel_m: float = 0.5
    """Pixel size of the orthoimage of a procedural scene (in m)."""
    image_half_wavelength_m: float = 1.5
    """Wavelength the image's PSF halves in amplitude (in m): ~3 pixels."""
    image_noise_fraction: float = 0.01
    """Std of the image's noise as a fraction of its mean (SNR ~100)."""
    rock_resolved_d_m: float = 1.0
    """Rocks of this diameter and larger appear in the orbital DTM (in m)."""
    image_shading: str = "lambert"
    """The image's shading law: ``"lambert"`` or ``"none"`` (the albedo alone)."""
    image_sun_incidence_deg: float = 48.0
    """The orbiter's sun: angle from the zenith (in deg, [0, 90))."""
    image_sun_azimuth_deg: float = 252.0
    """The orbiter's sun: azimuth clockwise from north (in deg, [0, 360))."""

    def __post_init__(self) -> None:
        if self.image_shading not in SHADING_LAWS:
            raise ConfigError(f"orbital image_shading = {plain(self.image_shading)!r}; use one "
                              f"of {', '.join(SHADING_LAWS)}")
        for name, hi in (("image_sun_incidence_deg", 90.0), ("image_sun_azimuth_deg", 360.0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not (isinstance(value, int | float | np.number)
                                               and 0.0 <= value < hi):
                raise ConfigError(f"orbital {name} must be in [0, {hi:g}); got "
                                  f"{plain(value)!r}")
        for name, value in asdict(self).items():
            if name.startswith(("image_shading", "image_sun_")):
                continue
            positive = name.endswith(("post_m", "pixel_m", "wavelength_m"))
            ok = np.isfinite(value) and (value > 0 if positive else value >= 0)
            if isinstance(value, bool) or not ok:
                raise ConfigError(f"orbital {name} must be {'> 0' if positive else '>= 0'}; "
                                  f"got {plain(value)!r}")

    @property
    def dem_psf_fwhm_m(self) -> float:
        """Full width at half maximum of the DTM's Gaussian PSF (in m)."""
        return fwhm_of_half_wavelength(self.dem_half_wavelength_m)

    @property
    def image_psf_fwhm_m(self) -> float:
        """Full width at half maximum of the image's Gaussian PSF (in m)."""
        return fwhm_of_half_wavelength(self.image_half_wavelength_m)

    def to_dict(self) -> dict[str, Any]:
        """The parameters and the derived PSF widths (for ``orbital/model.json``)."""
        return asdict(self) | {"dem_psf_fwhm_m": round(self.dem_psf_fwhm_m, 9),
                               "image_psf_fwhm_m": round(self.image_psf_fwhm_m, 9)}


def fwhm_of_half_wavelength(half_wavelength_m: float) -> float:
    """FWHM of the Gaussian PSF that halves a sinusoid of ``half_wavelength_m`` (in m).

    >>> round(fwhm_of_half_wavelength(3.0), 4)
    1.3238
    """
    return 2.0 * math.log(2.0) / math.pi * float(half_wavelength_m)


def psf_gain(fwhm_m: float, wavelength_m: float | NDArray[np.float64]) -> Any:
    """Amplitude transfer of the Gaussian PSF of ``fwhm_m`` at ``wavelength_m``.

    >>> round(float(psf_gain(fwhm_of_half_wavelength(3.0), 3.0)), 12)
    0.5
    """
    lam = np.asarray(wavelength_m, dtype=np.float64)
    return np.exp(-(math.pi * fwhm_m) ** 2 / (4.0 * math.log(2.0) * lam * lam))


def apply_psf(z: NDArray[np.floating[Any]], cell_m: float, fwhm_m: float
              ) -> NDArray[np.float64]:
    """Convolve a grid with the Gaussian PSF of ``fwhm_m`` (exact transfer, in Fourier space).

    The grid is padded by reflection over 4 sigma before the FFT, so its edges do not wrap.
    """
    a = np.asarray(z, dtype=np.float64)
    if fwhm_m <= 0:
        return a.copy()
    sigma_m = fwhm_m / FWHM_PER_SIGMA
    pad = math.ceil(4.0 * sigma_m / cell_m) + 1
    pad_r, pad_c = min(pad, a.shape[0] - 1), min(pad, a.shape[1] - 1)
    padded = np.pad(a, ((pad_r, pad_r), (pad_c, pad_c)), mode="reflect")
    fr = np.fft.fftfreq(padded.shape[0], d=cell_m)
    fc = np.fft.rfftfreq(padded.shape[1], d=cell_m)
    f2 = fr[:, None] ** 2 + fc[None, :] ** 2
    transfer = np.exp(-2.0 * (math.pi * sigma_m) ** 2 * f2)
    out = np.fft.irfft2(np.fft.rfft2(padded) * transfer, s=padded.shape)
    return out[pad_r:pad_r + a.shape[0], pad_c:pad_c + a.shape[1]]


def correlated_noise(shape: tuple[int, int], cell_m: float, sigma_m: float,
                     correlation_m: float, *, rng: np.random.Generator) -> NDArray[np.float64]:
    """Gaussian noise of std ``sigma_m`` per cell whose autocorrelation is
    ``exp(-(r / correlation_m)^2)``: white noise convolved with a Gaussian of sigma
    ``correlation_m / 2`` (wrapping at the edges, so every cell has the same statistics),
    divided by the kernel's root sum of squares. ``correlation_m = 0`` gives white noise."""
    white = rng.standard_normal(shape)
    s_px = 0.5 * correlation_m / cell_m
    if s_px <= 0:
        return sigma_m * white
    from scipy import ndimage

    k = math.ceil(4.0 * s_px)
    g = np.exp(-0.5 * (np.arange(-k, k + 1) / s_px) ** 2)
    g /= g.sum()
    gain = float((g * g).sum())  # the 2-D kernel g x g: its root sum of squares
    smooth = ndimage.convolve1d(ndimage.convolve1d(white, g, axis=0, mode="wrap"), g, axis=1,
                                mode="wrap")
    return sigma_m * smooth / gain
