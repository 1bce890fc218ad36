"""Pointwise fractal detail: hashed gradient-noise octaves evaluated at world coordinates.

Level-of-detail tiles need terrain detail that is a function of position alone, so that a tile
built by itself equals the same tile in a full build and neighbouring tiles meet without a seam.
Spectral (FFT) synthesis cannot give that: every output post depends on the whole grid. Gradient
noise can (Perlin 1985, "An image synthesizer", SIGGRAPH, doi:10.1145/325165.325247; quintic
fade of Perlin 2002, doi:10.1145/566654.566636): pseudo-random unit gradients on a square lattice,
here drawn from an integer hash of the lattice point and a seed word, interpolated with the
quintic fade. A fractal surface is a sum of octaves whose amplitude scales as ``cell^H``
(Musgrave, Kolb & Mace 1989, "The synthesis and rendering of eroded fractal terrains",
doi:10.1145/74334.74337), the discrete counterpart of the power law ``P(k) ∝ k^-(2H+2)`` that
:mod:`marsscene.terrain.synth` synthesises spectrally.

Every octave's lattice is offset by a hashed fraction of a cell so lattice points (where gradient
noise is 0) never line up with the posts.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

__all__ = ["LATTICE_CITATION", "fractal_detail", "gradient_noise", "octave_cells_m"]

LATTICE_CITATION = ("gradient noise: Perlin 1985, doi:10.1145/325165.325247 and 2002, "
                    "doi:10.1145/566654.566636; fractal octave sum: Musgrave, Kolb & Mace 1989, "
                    "doi:10.1145/74334.74337")

_M1 = np.uint64(0x9E3779B97F4A7C15)
_M2 = np.uint64(0xC2B2AE3D27D4EB4F)
_M3 = np.uint64(0x165667B19E3779F9)


def _mix(h: NDArray[np.uint64]) -> NDArray[np.uint64]:
    """SplitMix64 finaliser (Steele, Lea & Flood 2014, doi:10.1145/2714064.2660195)."""
    h = h ^ (h >> np.uint64(30))
    h = h * np.uint64(0xBF58476D1CE4E5B9)
    h = h ^ (h >> np.uint64(27))
    h = h * np.uint64(0x94D049BB133111EB)
    return h ^ (h >> np.uint64(31))


def _unit(h: NDArray[np.uint64]) -> NDArray[np.float64]:
    """A hash as a float in [0, 1)."""
    return (h >> np.uint64(11)).astype(np.float64) * 2.0**-53


def _hash_word(key: int, *words: int) -> np.uint64:
    h = np.array([key & 0xFFFFFFFFFFFFFFFF], dtype=np.uint64)
    with np.errstate(over="ignore"):
        for w in words:
            h = _mix(h ^ (np.array([w & 0xFFFFFFFFFFFFFFFF], dtype=np.uint64) * _M3))
    return np.uint64(h[0])


def _fade(t: NDArray[np.float64]) -> NDArray[np.float64]:
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0)


def gradient_noise(x_m: NDArray[np.float64], y_m: NDArray[np.float64], *, cell_m: float,
                   key: int) -> NDArray[np.float32]:
    """2-D gradient noise on the grid ``y_m x x_m`` (rows x cols), lattice spacing ``cell_m``.

    A pure function of the coordinates, ``cell_m`` and the 64-bit ``key``.
    """
    with np.errstate(over="ignore"):  # uint64 hashing wraps by design
        off = _unit(np.array([_hash_word(key, 1), _hash_word(key, 2)], dtype=np.uint64))
        u = np.asarray(x_m, dtype=np.float64) / cell_m + off[0]
        v = np.asarray(y_m, dtype=np.float64) / cell_m + off[1]
        iu, iv = np.floor(u), np.floor(v)
        fu, fv = u - iu, v - iv
        iu0, iv0 = int(iu.min()), int(iv.min())
        # one gradient per lattice point of the window, then gathered per post
        lu = np.arange(iu0, int(iu.max()) + 2, dtype=np.int64).astype(np.uint64)
        lv = np.arange(iv0, int(iv.max()) + 2, dtype=np.int64).astype(np.uint64)
        h = _mix((lv[:, None] * _M1) ^ (lu[None, :] * _M2) ^ np.uint64(key))
        angle = _unit(h) * (2.0 * np.pi)
    gx, gy = np.cos(angle).astype(np.float32), np.sin(angle).astype(np.float32)
    cu = (iu - iu0).astype(np.intp)
    cv = (iv - iv0).astype(np.intp)
    fu32, fv32 = fu.astype(np.float32), fv.astype(np.float32)
    su, sv = _fade(fu).astype(np.float32), _fade(fv).astype(np.float32)
    out = np.zeros((len(cv), len(cu)), dtype=np.float32)
    for dv in (0, 1):
        wv = (sv if dv else 1.0 - sv)[:, None]
        # gradients of the posts' lattice rows: two 1-D gathers instead of one 2-D gather
        row_gx, row_gy = gx[cv + dv], gy[cv + dv]
        ev = (fv32 - dv)[:, None]
        for du in (0, 1):
            wu = (su if du else 1.0 - su)[None, :]
            dot = row_gx[:, cu + du] * (fu32 - du)[None, :]
            dot += row_gy[:, cu + du] * ev
            dot *= wu
            dot *= wv
            out += dot
    return out


@lru_cache(maxsize=1)
def _noise_std() -> float:
    """Standard deviation of :func:`gradient_noise` (a constant of the method; measured once on
    a dense 256 x 256-cell reference grid with a fixed key: 65 536 independent cells, < 1 %)."""
    t = np.arange(0, 256, 0.25)
    return float(gradient_noise(t, t, cell_m=1.0, key=0x5EED).std())


def octave_cells_m(coarse_post_m: float, fine_post_m: float) -> list[float]:
    """Lattice spacings of the octaves between two post spacings: ``coarse_post_m`` halved while
    at least two fine posts per cell (finer octaves would alias)."""
    cells = []
    c = coarse_post_m
    while c >= 2.0 * fine_post_m * (1 - 1e-9):
        cells.append(c)
        c /= 2.0
    return cells


def fractal_detail(x_m: NDArray[np.float64], y_m: NDArray[np.float64], *,
                   cells_m: list[float], hurst: float, rms_m: float,
                   key: int) -> NDArray[np.float32]:
    """Sum of gradient-noise octaves with amplitude ``∝ cell^H``, scaled to RMS ``rms_m``.

    The scaling uses the method's constant noise variance (not the window's sample variance), so
    any window of the plane gets the same values.
    """
    if not cells_m or rms_m <= 0:
        return np.zeros((len(y_m), len(x_m)), dtype=np.float32)
    amps = np.array([c**hurst for c in cells_m])
    scale = rms_m / (_noise_std() * float(np.sqrt(np.sum(amps**2))))
    z = np.zeros((len(y_m), len(x_m)), dtype=np.float32)
    for i, (c, a) in enumerate(zip(cells_m, amps, strict=True)):
        z += np.float32(a * scale) * gradient_noise(x_m, y_m, cell_m=c,
                                                     key=int(_hash_word(key, 100 + i)))
    return z
