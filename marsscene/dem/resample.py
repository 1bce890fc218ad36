"""Separable grid resampling by sparse weight matrices (pure numpy/scipy, vectorised).

A 2-D resampling is ``out = W_rows @ z @ W_cols.T`` where each ``W`` maps source pixel centres to
target pixel centres along one axis. Target centres are given as *fractional source indices*
``u`` (``u = 0`` is the centre of source pixel 0), which callers compute from both grids'
transforms, so co-registration never relies on pixel counts.

Methods
-------
``"bilinear"``  two taps, linear weights (continuous, preserves planes exactly).
``"cubic"``     Keys (1981) cubic convolution, a = -0.5, four taps (preserves planes; sharper).
``"area"``      box average of the source pixels overlapped by each target pixel of width
                ``scale`` source pixels (for downsampling; preserves the mean).
Edges replicate the outermost source pixel.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from marsscene._validate import check_choice

__all__ = ["RESAMPLING", "axis_weights", "resample_separable"]

RESAMPLING = ("bilinear", "cubic", "area")


def _keys(t: NDArray[np.float64]) -> NDArray[np.float64]:
    a = -0.5
    at = np.abs(t)
    w1 = ((a + 2) * at - (a + 3)) * at * at + 1
    w2 = ((a * at - 5 * a) * at + 8 * a) * at - 4 * a
    return np.where(at <= 1, w1, np.where(at < 2, w2, 0.0))


def axis_weights(
    u: NDArray[np.float64], n_src: int, method: str, scale: float = 1.0
) -> sp.csr_array:
    """Sparse ``(len(u), n_src)`` weights; row ``j`` interpolates at fractional index ``u[j]``.

    Parameters
    ----------
    u : ndarray of shape (n_out,)
        Target pixel centres as fractional source indices.
    n_src : int
        Number of source pixels on this axis.
    method : {"bilinear", "cubic", "area"}
    scale : float
        Target pixel size in source pixels (only for ``"area"``).
    """
    check_choice("resampling", method, RESAMPLING)
    u = np.asarray(u, dtype=np.float64)
    n_out = u.size
    if method == "area" and scale > 1.0:
        lo = u - scale / 2.0  # target box [lo, hi] in source-index units (pixel k spans k±0.5)
        hi = u + scale / 2.0
        taps = int(np.ceil(scale)) + 2
        k = np.floor(lo + 0.5).astype(np.int64)[:, None] + np.arange(taps)[None, :]
        w = np.clip(np.minimum(hi[:, None], k + 0.5) - np.maximum(lo[:, None], k - 0.5), 0, None)
    elif method == "cubic":
        base = np.floor(u).astype(np.int64)
        k = base[:, None] + np.arange(-1, 3)[None, :]
        w = _keys(u[:, None] - k)
    else:  # bilinear (and "area" when not downsampling)
        base = np.floor(u).astype(np.int64)
        k = base[:, None] + np.arange(2)[None, :]
        w = np.clip(1.0 - np.abs(u[:, None] - k), 0.0, None)
    k = np.clip(k, 0, n_src - 1)
    w = w / w.sum(axis=1, keepdims=True)
    rows = np.repeat(np.arange(n_out), k.shape[1])
    mat = sp.csr_array((w.ravel(), (rows, k.ravel())), shape=(n_out, n_src))
    mat.sum_duplicates()
    mat.eliminate_zeros()
    return mat


def resample_separable(
    z: NDArray[np.floating],
    u_rows: NDArray[np.float64],
    u_cols: NDArray[np.float64],
    *,
    method: str = "bilinear",
    scale_rows: float = 1.0,
    scale_cols: float = 1.0,
) -> NDArray[np.float32]:
    """Resample a 2-D grid (or each band of ``(rows, cols, bands)``) at fractional indices.

    Returns float32 of shape ``(len(u_rows), len(u_cols)[, bands])``. NaNs spread to every
    target pixel that gives them weight: fill missing values first.
    """
    arr = np.asarray(z, dtype=np.float32)
    if arr.ndim == 3:
        bands = [resample_separable(arr[:, :, b], u_rows, u_cols, method=method,
                                    scale_rows=scale_rows, scale_cols=scale_cols)
                 for b in range(arr.shape[2])]
        return np.stack(bands, axis=-1)
    wr = axis_weights(u_rows, arr.shape[0], method, scale_rows).astype(np.float32)
    wc = axis_weights(u_cols, arr.shape[1], method, scale_cols).astype(np.float32)
    tmp = np.asarray(wc @ arr.T)  # (n_cols_out, rows)
    out = np.asarray(wr @ tmp.T)  # (n_rows_out, n_cols_out)
    return np.ascontiguousarray(out, dtype=np.float32)
