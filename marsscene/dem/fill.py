"""Missing-post fill (harmonic inpainting) and detrending of a :class:`DEM` (pure).

Re-exported by :mod:`marsscene.dem.ops`.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.linalg import spsolve

from marsscene._warnings import warn_external
from marsscene.dem.model import DEM
from marsscene.errors import ConfigError, NodataFilledWarning

__all__ = ["detrend", "fill_nodata"]


def _laplace_fill(z: NDArray[np.float32], missing: NDArray[np.bool_]) -> NDArray[np.float32]:
    rows, cols = z.shape
    idx = -np.ones(z.shape, dtype=np.int64)
    rr, cc = np.nonzero(missing)
    n = rr.size
    idx[rr, cc] = np.arange(n)
    diag = np.zeros(n)
    rhs = np.zeros(n)
    off_i: list[NDArray[np.int64]] = []
    off_j: list[NDArray[np.int64]] = []
    for dr, dc in ((-1, 0), (1, 0), (0, -1), (0, 1)):
        nr, nc = rr + dr, cc + dc
        inside = (nr >= 0) & (nr < rows) & (nc >= 0) & (nc < cols)
        me = np.nonzero(inside)[0]
        nb_r, nb_c = nr[inside], nc[inside]
        diag[me] += 1.0
        nb_idx = idx[nb_r, nb_c]
        unknown = nb_idx >= 0
        off_i.append(me[unknown])
        off_j.append(nb_idx[unknown])
        np.add.at(rhs, me[~unknown], z[nb_r[~unknown], nb_c[~unknown]].astype(np.float64))
    i = np.concatenate([np.arange(n), *off_i])
    j = np.concatenate([np.arange(n), *off_j])
    v = np.concatenate([diag, -np.ones(sum(a.size for a in off_i))])
    mat = sp.csc_array((v, (i, j)), shape=(n, n))
    out = np.array(z, dtype=np.float32)
    out[rr, cc] = spsolve(mat, rhs)
    return out


def fill_nodata(dem: DEM, *, max_missing_fraction: float = 0.5) -> tuple[DEM, int]:
    """Fill missing posts by harmonic (Laplace) inpainting.

    The filled surface solves ``∇²z = 0`` with the valid neighbours as boundary values, so it is
    smooth and, by the maximum principle, never leaves the range of the bordering valid posts.
    Warns with :class:`~marsscene.errors.NodataFilledWarning` giving the count.

    Returns
    -------
    dem : DEM
    n_filled : int

    Raises
    ------
    ConfigError
        More than ``max_missing_fraction`` of the posts are missing.
    """
    z = dem.elevation_m
    missing = ~np.isfinite(z)
    n = int(missing.sum())
    if n == 0:
        return dem, 0
    frac = n / z.size
    if frac > max_missing_fraction:
        raise ConfigError(
            f"{dem.product_id or 'DEM'}: {frac * 100:.1f} % of the {z.size:,} posts are missing "
            f"(allowed at most {max_missing_fraction * 100:.0f} %, "
            "terrain.max_missing_fraction): choose a crop inside the DTM's valid area"
        )
    filled = _laplace_fill(z, missing)
    warn_external(
        f"{dem.product_id or 'DEM'}: filled {n:,} missing posts ({frac * 100:.2f} %) by "
        "Laplace inpainting", NodataFilledWarning,
    )
    return dem.replace(elevation_m=filled), n


def detrend(dem: DEM) -> DEM:
    """Remove the least-squares plane of the valid posts, keeping their mean elevation."""
    z = dem.elevation_m.astype(np.float64)
    rows, cols = z.shape
    rr, cc = np.mgrid[0:rows, 0:cols]
    ok = np.isfinite(z)
    design = np.stack([cc[ok], rr[ok], np.ones(int(ok.sum()))], axis=1).astype(np.float64)
    coef, *_ = np.linalg.lstsq(design, z[ok], rcond=None)
    plane = coef[0] * cc + coef[1] * rr
    plane -= plane[ok].mean()
    return dem.replace(elevation_m=(z - plane).astype(np.float32))
