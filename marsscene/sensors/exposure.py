"""Camera response: exposure (auto or fixed), optional shot + read noise, sRGB encoding.

The renderer's output is treated as *linear* scene radiance (lights and textures are set up
in linear units by :mod:`marsscene.sensors.camera`). A frame is made like a real camera:

1. gain ``g``: fixed, or auto-exposure that brings the mean sRGB intensity to
   ``target_mean`` (0.45 by default; mid-grey for an 8-bit image) while at most
   ``max_saturated`` of the pixels clip; the gain follows the target with first-order
   smoothing between frames (``smoothing`` = weight of the new target in log gain), as a
   camera's AE loop does, so consecutive frames differ little in brightness. The renderer's
   values times ``input_scale`` are in the fixed mode's reference units; there the gain is at
   most ``max_gain`` (the longest exposure), so a scene too dark for it stays dark;
2. optional sensor noise: ``e = g L full_well_e``; ``e + sqrt(e) N(0,1) + read_noise_e N(0,1)``
   (shot noise as its Gaussian limit), from a seeded generator;
3. the IEC 61966-2-1 sRGB transfer function and 8-bit rounding.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

__all__ = ["FULL_WELL_E", "READ_NOISE_E", "Exposure", "srgb_encode"]

#: The sensor noise's full well (electrons at a linear value of 1) and read noise (electrons).
FULL_WELL_E = 10000.0
READ_NOISE_E = 10.0


def srgb_encode(linear: NDArray[np.floating]) -> NDArray[np.float64]:
    """sRGB transfer function of linear values in [0, 1]."""
    x = np.clip(np.asarray(linear, dtype=np.float64), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


_LUT_N = 1 << 16
#: 8-bit sRGB code of linear value i / (_LUT_N - 1) (a 16-bit linear table: fast and exact
#: to within the 8-bit rounding of the output).
_SRGB_LUT = np.rint(srgb_encode(np.arange(_LUT_N) / (_LUT_N - 1)) * 255.0).astype(np.uint8)


def _srgb_u8(linear: NDArray[np.floating]) -> NDArray[np.uint8]:
    idx = np.rint(np.clip(linear, 0.0, 1.0) * (_LUT_N - 1)).astype(np.int64)
    return _SRGB_LUT[idx]


class Exposure:
    """Stateful exposure of successive frames (one instance per camera stream).

    Parameters
    ----------
    mode : {"auto", "fixed"}
    target_mean : float
        Auto-exposure target of the mean sRGB intensity in [0, 1].
    fixed_gain : float
        Gain of the fixed mode (linear units).
    max_saturated : float
        Auto-exposure never lets more than this fraction of pixels clip.
    smoothing : float
        Weight of a new frame's gain in the (log) gain filter; 1 = no smoothing.
    full_well_e, read_noise_e : float
        Noise model (used only when ``rng`` is passed to :meth:`apply`).
    input_scale : float
        Reference units per unit of the renderer's linear output (the fixed gain applies to
        reference units; :attr:`gain` of the auto mode stays in the renderer's units).
    max_gain : float
        Largest gain in reference units (auto mode).
    """

    def __init__(
        self,
        mode: str = "auto",
        *,
        target_mean: float = 0.45,
        fixed_gain: float = 1.0,
        max_saturated: float = 0.01,
        smoothing: float = 0.5,
        full_well_e: float = FULL_WELL_E,
        read_noise_e: float = READ_NOISE_E,
        input_scale: float = 1.0,
        max_gain: float = math.inf,
    ) -> None:
        self.mode = mode
        self.target_mean = float(target_mean)
        self.fixed_gain = float(fixed_gain)
        self.max_saturated = float(max_saturated)
        self.smoothing = float(smoothing)
        self.full_well_e = float(full_well_e)
        self.read_noise_e = float(read_noise_e)
        self.input_scale = float(input_scale)
        self.max_gain = float(max_gain)
        self.gain: float | None = None

    @property
    def render_gain(self) -> float | None:
        """The last frame's gain on the renderer's linear values (None before a frame)."""
        if self.gain is None:
            return None
        return self.gain * self.input_scale if self.mode == "fixed" else self.gain

    def _auto_gain(self, lin: NDArray[np.floating]) -> float:
        sample = lin[::4, ::4].reshape(-1, lin.shape[-1]) if lin.ndim == 3 else lin[::4, ::4]
        peak = sample.max(axis=-1) if sample.ndim == 2 else sample
        bright = float(np.quantile(peak, 1.0 - self.max_saturated))
        hi = 0.98 / max(bright, 1e-6)  # the brightest allowed fraction stays just below 1
        lo_g, hi_g = 1e-3, 1e4
        for _ in range(24):  # bisection in log gain on the mean sRGB intensity (~0.1 %)
            mid = math.sqrt(lo_g * hi_g)
            if float(srgb_encode(sample * mid).mean()) < self.target_mean:
                lo_g = mid
            else:
                hi_g = mid
        return min(math.sqrt(lo_g * hi_g), hi, self.max_gain * self.input_scale)

    def apply(
        self, linear: NDArray[np.floating], rng: np.random.Generator | None = None
    ) -> NDArray[np.uint8]:
        """Expose one frame: linear (H, W, 3) in [0, 1] -> sRGB uint8."""
        lin = np.asarray(linear, dtype=np.float32)
        if self.mode == "fixed":
            g = self.fixed_gain
        else:
            target = self._auto_gain(lin)
            if self.gain is None:
                g = target
            else:
                a = self.smoothing
                g = math.exp((1 - a) * math.log(self.gain) + a * math.log(target))
        self.gain = g
        x = lin * (g * self.input_scale if self.mode == "fixed" else g)
        if rng is not None:
            e = np.clip(x, 0.0, 1.0) * self.full_well_e
            e = e + np.sqrt(e) * rng.standard_normal(e.shape)
            e = e + self.read_noise_e * rng.standard_normal(e.shape)
            x = e / self.full_well_e
        return _srgb_u8(x)
