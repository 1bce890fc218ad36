"""The terrain terms over the rover's footprint: a least-squares plane over a disc (its tilt and
RMS residual), the step a wheel meets, and what rises under the belly above the plane the
wheels stand on.

The plane ``z = a + b u + c v`` (``u, v`` the offsets from the cell) is fitted to the posts of a
kernel (disc or ring) that lie on the terrain: its normal equations' sums are correlations of
the terrain, its square and the valid mask with the kernel times ``1, u, v, u^2, u v, v^2``
(FFT convolutions, one per sum), solved per cell in closed form. At the terrain's edges the
kernel is cut, and the fit stays exact on a plane.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage
from scipy.fft import irfft2, next_fast_len, rfft2

__all__ = ["PlaneFit", "belly_intrusion", "disc_offsets", "fit_plane", "plane_correlator",
           "ring_kernel", "step_height"]

F64 = NDArray[np.float64]


def disc_offsets(radius_m: float, cell_m: float, inner_m: float = -1.0) -> tuple[
        NDArray[np.intp], NDArray[np.intp]]:
    """Row and column offsets of the posts within ``(inner_m, radius_m]`` of a post (a disc, or
    a ring with ``inner_m >= 0``); a disc always holds the post itself, and a ring that falls
    between the posts becomes the disc it bounds."""
    k = int(np.floor(radius_m / cell_m + 1e-9))
    d = np.arange(-k, k + 1)
    dr, dc = np.meshgrid(d, d, indexing="ij")
    dist = np.hypot(dr, dc) * cell_m
    keep = (dist <= radius_m + 1e-9) & (dist > inner_m + 1e-9)
    if inner_m < 0 or not keep.any():  # a ring between posts: the disc it bounds
        keep |= dist <= radius_m + 1e-9
        keep[k, k] = True
    return dr[keep], dc[keep]


def ring_kernel(radius_m: float, cell_m: float, inner_m: float = -1.0) -> NDArray[np.bool_]:
    """The footprint of :func:`disc_offsets` as a square boolean kernel (centre at its middle)."""
    dr, dc = disc_offsets(radius_m, cell_m, inner_m)
    k = int(max(np.abs(dr).max(initial=0), np.abs(dc).max(initial=0),
                np.floor(radius_m / cell_m + 1e-9)))
    out = np.zeros((2 * k + 1, 2 * k + 1), bool)
    out[dr + k, dc + k] = True
    return out


class PlaneFit:
    """Per-cell plane fit over a kernel: height ``a`` at the cell, gradient ``(b, c)`` (x east,
    y north) and RMS residual."""

    def __init__(self, a: F64, b: F64, c: F64, rms_m: F64) -> None:
        self.a, self.b, self.c, self.rms_m = a, b, c, rms_m

    @property
    def slope_deg(self) -> F64:
        """The plane's tilt from level."""
        return np.degrees(np.arctan(np.hypot(self.b, self.c)))


class _Correlator:
    """Correlations of a few fields with many small kernels, sharing the fields' FFTs
    (zero outside the grid)."""

    def __init__(self, fields: dict[str, F64], reach: int) -> None:
        first = next(iter(fields.values()))
        self.grid = first.shape
        self.reach = reach
        self.shape = tuple(next_fast_len(n + 2 * reach, real=True) for n in self.grid)
        self.spectra = {key: rfft2(f, self.shape) for key, f in fields.items()}
        self.mean_m = 0.0  # what was taken off the fields' first (added back to the plane)

    def __call__(self, key: str, kernel: F64) -> F64:
        k = kernel.shape[0] // 2
        pad = np.zeros(self.shape)
        # The kernel flipped (convolution = correlation), its centre wrapped to index (0, 0).
        flipped = kernel[::-1, ::-1]
        rows = np.arange(-k, k + 1) % self.shape[0]
        cols = np.arange(-k, k + 1) % self.shape[1]
        pad[np.ix_(rows, cols)] = flipped
        full = irfft2(self.spectra[key] * rfft2(pad), self.shape)
        return full[:self.grid[0], :self.grid[1]].copy()  # not a view: frees the padding


#: Rows solved at a time (the per-cell algebra's temporaries stay small).
_CHUNK_ROWS = 128


def _edge_index(n: int, k: int) -> NDArray[np.intp]:
    """Each of ``n`` rows' (or columns') row in a small grid that keeps ``k + 1`` at each edge
    and one for the interior, where a kernel of reach ``k`` sees the same."""
    i = np.arange(n)
    if n <= 2 * k + 3:
        return i
    return np.where(i <= k, i, np.where(i >= n - k - 1, i - n + 2 * k + 3, k + 1))


def _mask_moments(shape: tuple[int, int], kernel: F64, weights: dict[str, F64],
                  ) -> tuple[dict[str, F64], NDArray[np.intp], NDArray[np.intp]]:
    """Correlations of the grid's all-ones mask with ``kernel * weight``: they differ from
    the interior's only within the kernel's reach of an edge, so they are taken on a small grid
    (:func:`_edge_index`); returns them with the rows' and columns' index into it."""
    k = kernel.shape[0] // 2
    rows, cols = _edge_index(shape[0], k), _edge_index(shape[1], k)
    corr = _Correlator({"1": np.ones((int(rows.max()) + 1, int(cols.max()) + 1))}, k)
    return {key: corr("1", kernel * w) for key, w in weights.items()}, rows, cols


def fit_plane(z_m: NDArray[np.floating], cell_m: float, kernel: NDArray[np.bool_], *,
              correlator: _Correlator | None = None, residual: bool = True) -> PlaneFit:
    """Least-squares plane over ``kernel`` around every post of ``z_m`` (rows south to north);
    ``residual=False`` skips the RMS residual (then zero)."""
    k = kernel.shape[0] // 2
    off = np.arange(-k, k + 1) * cell_m
    v, u = np.meshgrid(off, off, indexing="ij")  # v: north offset (rows), u: east (columns)
    w = kernel.astype(np.float64)
    corr = correlator if correlator is not None else plane_correlator(z_m, k)
    small, rows, cols = _mask_moments(corr.grid, w, {
        "1": np.ones_like(u), "u": u, "v": v, "uu": u * u, "uv": u * v, "vv": v * v})
    sums = [corr("z", w * f) for f in (np.ones_like(u), u, v)]
    if residual:
        sums.append(corr("zz", w))
    out = np.zeros((4, *corr.grid))
    for r0 in range(0, corr.grid[0], _CHUNK_ROWS):
        part = slice(r0, r0 + _CHUNK_ROWS)
        m = {key: g[np.ix_(rows[part], cols)] for key, g in small.items()}
        out[:, part] = _solve(m, [s[part] for s in sums])
    out[0] += corr.mean_m
    return PlaneFit(out[0], out[1], out[2], out[3])


def _solve(m: dict[str, F64], sums: list[F64]) -> F64:
    """Height, gradient and RMS residual from the normal equations' sums (rows of cells)."""
    n = np.maximum(m["1"], 1.0)
    # Centre the offsets on the fitted posts' mean (exact at cut kernels), then solve 2 x 2.
    mu, mv = m["u"] / n, m["v"] / n
    cuu, cuv, cvv = m["uu"] - n * mu * mu, m["uv"] - n * mu * mv, m["vv"] - n * mv * mv
    zm = sums[0] / n
    tu, tv = sums[1] - n * mu * zm, sums[2] - n * mv * zm
    det = cuu * cvv - cuv * cuv
    safe = np.where(np.abs(det) > 1e-12, det, np.inf)
    b, c = (cvv * tu - cuv * tv) / safe, (cuu * tv - cuv * tu) / safe
    rms = np.zeros_like(zm)
    if len(sums) > 3:
        ss = sums[3] - n * zm * zm - (b * tu + c * tv)
        rms = np.sqrt(np.maximum(ss, 0.0) / n)
    return np.stack([zm - b * mu - c * mv, b, c, rms])


def plane_correlator(z_m: NDArray[np.floating], reach: int) -> _Correlator:
    """The shared FFTs of the terrain (less its mean) and its square for :func:`fit_plane`
    with kernels up to ``reach`` posts from their centre."""
    mean = float(np.mean(z_m))
    z = np.asarray(z_m, dtype=np.float64) - mean  # smaller sums, less round-off
    corr = _Correlator({"z": z, "zz": z * z}, reach)
    corr.mean_m = mean
    return corr


def step_height(z_m: NDArray[np.floating], cell_m: float, wheel_radius_m: float,
                ring: NDArray[np.bool_]) -> F64:
    """The largest height range a wheel meets: max minus min of the terrain over a disc of the
    wheel's diameter, then the largest of that over the ``ring`` the wheels can stand on."""
    disc = ring_kernel(wheel_radius_m, cell_m)
    z = np.asarray(z_m, dtype=np.float64)
    rng = (ndimage.maximum_filter(z, footprint=disc, mode="nearest")
           - ndimage.minimum_filter(z, footprint=disc, mode="nearest"))
    return np.asarray(ndimage.maximum_filter(rng, footprint=ring, mode="nearest"))


def belly_intrusion(ground_m: F64, cell_m: float, plane: PlaneFit, radius_m: float) -> F64:
    """How far the ground (terrain plus rocks) rises above the wheels' plane within
    ``radius_m`` of each cell: ``max_j (g_j - a - b u_j - c v_j)`` (offsets in a loop, each
    over the whole grid; edges extend)."""
    dr, dc = disc_offsets(radius_m, cell_m)
    k = int(max(np.abs(dr).max(), np.abs(dc).max()))
    rows, cols = ground_m.shape
    padded = np.pad(ground_m, k, mode="edge")
    out = np.full(ground_m.shape, -np.inf)
    for i, j in zip(dr.tolist(), dc.tolist(), strict=True):
        shifted = padded[k + i:k + i + rows, k + j:k + j + cols]
        np.maximum(out, shifted - plane.b * (j * cell_m) - plane.c * (i * cell_m), out=out)
    return out - plane.a
