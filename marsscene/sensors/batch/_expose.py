# mypy: ignore-errors
# (Warp's kernel language: its annotations and indexing are not Python's typing)
"""Warp kernels of the batch camera's exposure and sRGB encoding, one gain a camera.

The CPU camera's auto exposure (:class:`marsscene.sensors.exposure.Exposure`) bisects, on every
fourth pixel of every fourth row, the gain whose mean sRGB intensity is the target, capped so
that at most ``max_saturated`` of the pixels clip, then smooths it in log gain. Here the
sampled pixels go into log2 histograms first (``BINS`` bins over ``[2^-LOG2_RANGE, 1]``, 1/16
of an octave each; integer atomics, so the bytes do not depend on thread order): the channel
values for the mean, each pixel's brightest channel for the quantile. The bisection runs on
the bins' centres (one thread a camera).
"""

from __future__ import annotations

import warp as wp

wp.set_module_options({"enable_backward": False})

#: Log2 bins of the auto exposure's histograms over [2^-LOG2_RANGE, 1].
BINS = 256
LOG2_RANGE = 16.0


@wp.func
def _bin(x: float) -> int:
    if x <= 0.0:
        return 0
    return wp.clamp(int((wp.log2(x) + LOG2_RANGE) * float(BINS) / LOG2_RANGE), 0, BINS - 1)


@wp.func
def _centre(b: int) -> float:
    return wp.pow(2.0, (float(b) + 0.5) * LOG2_RANGE / float(BINS) - LOG2_RANGE)


@wp.func
def srgb(x: float) -> float:
    """The IEC 61966-2-1 transfer function of a linear value (clipped to [0, 1])."""
    v = wp.clamp(x, 0.0, 1.0)
    if v <= 0.0031308:
        return 12.92 * v
    return 1.055 * wp.pow(v, 1.0 / 2.4) - 0.055


@wp.kernel
def histogram(linear: wp.array2d[wp.vec3], width: int, sub_cols: int,
              hist: wp.array2d[int], peak: wp.array2d[int]):
    """Bin pixel (4 a, 4 b) of camera ``i``: its three channels, its brightest channel."""
    i, j = wp.tid()
    a = j // sub_cols
    b = j - a * sub_cols
    x = linear[i, 4 * a * width + 4 * b]
    for ch in range(3):
        wp.atomic_add(hist, i, _bin(x[ch]), 1)
    wp.atomic_add(peak, i, _bin(wp.max(x[0], wp.max(x[1], x[2]))), 1)


@wp.kernel
def auto_gain(hist: wp.array2d[int], peak: wp.array2d[int], target_mean: float,
              max_saturated: float, max_gain: wp.array[float], smoothing: float,
              gain: wp.array[float]):
    """Camera ``i``'s gain from its histograms, smoothed with its last (0: none yet)."""
    i = wp.tid()
    total = wp.int32(0)
    for b in range(BINS):
        total += peak[i, b]
    above = wp.int32(0)
    bright = _centre(BINS - 1)
    for k in range(BINS):
        b = BINS - 1 - k
        above += peak[i, b]
        if float(above) > max_saturated * float(total):
            bright = _centre(b)
            break
    hi = 0.98 / wp.max(bright, 1.0e-6)
    lo_g = wp.float32(1.0e-3)
    hi_g = wp.float32(1.0e4)
    for _ in range(24):
        mid = wp.sqrt(lo_g * hi_g)
        acc = wp.float32(0.0)
        for b in range(BINS):
            acc += float(hist[i, b]) * srgb(_centre(b) * mid)
        if acc < target_mean * float(3 * total):
            lo_g = mid
        else:
            hi_g = mid
    g = wp.min(wp.min(wp.sqrt(lo_g * hi_g), hi), max_gain[i])
    last = gain[i]
    if last > 0.0:
        g = wp.exp((1.0 - smoothing) * wp.log(last) + smoothing * wp.log(g))
    gain[i] = g


@wp.kernel
def keep_fixed(fixed: wp.array[int], fixed_gain: wp.array[float], gain: wp.array[float]):
    """The fixed-exposure cameras' gain, after the auto exposure's."""
    i = wp.tid()
    if fixed[i] != 0:
        gain[i] = fixed_gain[i]


@wp.kernel
def encode(linear: wp.array2d[wp.vec3], gain: wp.array[float], width: int,
           rgb: wp.array4d[wp.uint8]):
    """8-bit sRGB of the exposed linear value, channels first."""
    i, k = wp.tid()
    x = linear[i, k] * gain[i]
    r = k // width
    c = k - r * width
    for ch in range(3):
        rgb[i, ch, r, c] = wp.uint8(int(wp.rint(255.0 * srgb(x[ch]))))


@wp.kernel
def encode_noisy(linear: wp.array2d[wp.vec3], gain: wp.array[float], width: int,
                 seeds: wp.array[int], frame: int, full_well_e: float, read_noise_e: float,
                 rgb: wp.array4d[wp.uint8]):
    """:func:`encode` with the CPU camera's sensor noise: ``e = clip(x) full_well_e``, ``e +
    sqrt(e) N + read_noise_e N``; camera ``i``'s frame ``frame`` draws from a stream seeded by
    ``(seeds[i], frame)``, one counter a pixel."""
    i, k = wp.tid()
    x = linear[i, k] * gain[i]
    r = k // width
    c = k - r * width
    state = wp.rand_init(wp.randi(wp.rand_init(seeds[i], frame)), k)
    for ch in range(3):
        e = wp.clamp(x[ch], 0.0, 1.0) * full_well_e
        e = e + wp.sqrt(e) * wp.randn(state) + read_noise_e * wp.randn(state)
        rgb[i, ch, r, c] = wp.uint8(int(wp.rint(255.0 * srgb(e / full_well_e))))
