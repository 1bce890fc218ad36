"""Stamp craters into a :class:`Heightfield` (oldest first; never in place).

Each crater touches only the posts of its footprint (``reach * R`` of its degraded profile,
along the major axis). The new surface is

    z = z_old + h(rho) + w(rho) * (plane - lowpass(z_old))

where ``h`` is the (degraded) profile, ``plane`` the least-squares plane of ``z_old`` over the
box ``|dx|, |dy| <= 1.25 a`` and ``w`` = 1 inside the rim, falling smoothly to 0 at
``rho = 1.25`` (scaled by the crater's remaining relief fraction); ``lowpass`` is a box filter
~0.2 R wide, so roughness finer than that survives inside the crater. Inside its rim a young crater
therefore *replaces* the older topography (it cuts older rims) while its ejecta drapes over it:
the result depends on order, young over old.

Speed: craters are grouped into *waves* (a crater joins the wave after the latest earlier
crater whose footprint may overlap it), so footprints within a wave are disjoint and stamping
wave by wave equals stamping one crater at a time in age order. Within a wave, small craters
are stamped together as ``(m, S, S)`` arrays of equal padded box size ``S``; large ones as one
2-D slice each. The cost is proportional to the summed footprints.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np
from scipy.ndimage import uniform_filter

from marsscene._threads import worth_a_thread
from marsscene.craters.morphology import PROFILE_MODELS, ProfileFamily, profile_family
from marsscene.craters.table import CraterTable
from marsscene.terrain.heightfield import Heightfield

__all__ = ["BLEND_OUTER_RHO", "stamp_craters"]

#: Radius (in crater radii) where the interior replacement weight reaches 0.
BLEND_OUTER_RHO = 1.25
_SIZES = np.array([4, 6, 8, 12, 16, 24, 32, 48, 64])  # padded box sides of batched craters
_PAD = int(_SIZES[-1])
_WAVE_CELL = 16  # posts per cell of the coarse occupancy grid used to find overlaps
_BATCH_POSTS = 1_000_000
_STAMP_THREADS = 2  # threads for a wave's batches of small craters
#: Width of the box low-pass (in crater radii, >= 3 posts): inside the rim only the old surface's
#: low-pass is replaced by the plane, so roughness finer than ~0.2 R survives in young craters.
_LOWPASS_RADII = 0.2


def _families(profile_kwargs: dict[str, float | str] | None,
              used: np.ndarray) -> dict[int, ProfileFamily]:
    """The profile families of the profile ids in ``used`` only (tabulating one costs ~0.15 s);
    called with keywords in :meth:`CraterConfig.profile_kwargs` order, so the family the
    population sampler already made comes from ``profile_family``'s cache."""
    kw = dict(profile_kwargs or {})
    kw.pop("model", None)
    return {int(i): profile_family(model=PROFILE_MODELS[int(i)], **kw)
            for i in np.unique(used)}


def _edge_padded(z: np.ndarray, pad: int) -> np.ndarray:
    """``np.pad(z.astype(float64), pad, mode="edge")`` without the intermediate float64 copy
    (one 16 M-post float64 array less on a 1 km scene)."""
    rows, cols = z.shape
    out = np.zeros((rows + 2 * pad, cols + 2 * pad), dtype=np.float64)
    out[pad:pad + rows, pad:pad + cols] = z
    out[:pad, pad:pad + cols] = z[0]
    out[pad + rows:, pad:pad + cols] = z[-1]
    out[:, :pad] = out[:, pad:pad + 1]
    out[:, pad + cols:] = out[:, pad + cols - 1:pad + cols]
    return out


def _waves(r0: np.ndarray, r1: np.ndarray, c0: np.ndarray, c1: np.ndarray,
           shape: tuple[int, int]) -> np.ndarray:
    """Wave index of each crater (inputs in stamping order)."""
    last = np.full((shape[0] // _WAVE_CELL + 2, shape[1] // _WAVE_CELL + 2), -1, dtype=np.int64)
    a0, a1 = (r0 // _WAVE_CELL).tolist(), (r1 // _WAVE_CELL + 1).tolist()
    b0, b1 = (c0 // _WAVE_CELL).tolist(), (c1 // _WAVE_CELL + 1).tolist()
    out = np.zeros(r0.size, dtype=np.int64)
    for j in range(r0.size):  # scalar bookkeeping only; the stamping itself is batched
        cell = last[a0[j]:a1[j], b0[j]:b1[j]]
        out[j] = w = int(cell.max()) + 1
        cell[...] = w
    return out


def stamp_craters(
    heightfield: Heightfield,
    craters: CraterTable,
    *,
    profile_kwargs: dict[str, float | str] | None = None,
) -> Heightfield:
    """Apply craters to a heightfield, oldest first.

    Parameters
    ----------
    heightfield : Heightfield
        Input terrain (not modified).
    craters : CraterTable
        Craters; each one's degradation state is recovered from ``depth_m / diameter_m`` within
        its profile family, so the stamped relief matches the table.
    profile_kwargs : dict, optional
        Profile parameters (``CraterConfig.profile_kwargs()``; ``model`` is ignored: each row's
        ``profile`` id selects the model). Default: the documented defaults.

    Returns
    -------
    Heightfield
        A new heightfield on the same grid.

    Examples
    --------
    >>> import numpy as np
    >>> hf = Heightfield.centered(np.zeros((41, 41), np.float32), 0.5)
    >>> t = CraterTable(np.zeros((1, 2)), [8.0], [1.223], [0.288], [0.0], [0])
    >>> out = stamp_craters(hf, t)
    >>> round(float(out.z_m[20, 20]), 3)  # fresh floor = rim - depth = (0.036 - 0.1889) * 8
    -1.223
    """
    if len(craters) == 0:
        return heightfield
    fams = _families(profile_kwargs, craters.profile)
    p = _Params(craters, fams)
    rows, cols = heightfield.shape
    ox, oy = heightfield.origin_xy_m
    cs = heightfield.cell_size_m
    half = p.reach * p.semi_major
    # the whole footprint in post indices (it may extend past the grid) ...
    fr0 = np.ceil((p.cy - half - oy) / cs).astype(np.int64)
    fr1 = np.floor((p.cy + half - oy) / cs).astype(np.int64)
    fc0 = np.ceil((p.cx - half - ox) / cs).astype(np.int64)
    fc1 = np.floor((p.cx + half - ox) / cs).astype(np.int64)
    # ... and its part on the grid
    r0, r1 = np.maximum(fr0, 0), np.minimum(fr1, rows - 1)
    c0, c1 = np.maximum(fc0, 0), np.minimum(fc1, cols - 1)
    order = np.argsort(-craters.age_ga, kind="stable")
    order = order[(r0[order] <= r1[order]) & (c0[order] <= c1[order])]
    # batched craters use a square padded box of side S centred on the crater's nearest post,
    # sized from the whole footprint (not its clipped part): the box [rc - S/2, rc + S/2 - 1]
    # then holds the footprint, and a box of side <= _PAD that meets the grid lies in the pad
    rc = np.rint((p.cy - oy) / cs).astype(np.int64)
    cc = np.rint((p.cx - ox) / cs).astype(np.int64)
    reach_posts = np.maximum.reduce([rc - fr0, fr1 - rc, cc - fc0, fc1 - cc])
    size_class = np.searchsorted(_SIZES, 2 * reach_posts + 2)
    small = size_class < _SIZES.size
    s_of = _SIZES[np.minimum(size_class, _SIZES.size - 1)]
    br0 = np.where(small, rc - s_of // 2, r0)
    bc0 = np.where(small, cc - s_of // 2, c0)
    br1 = np.where(small, br0 + s_of - 1, r1)
    bc1 = np.where(small, bc0 + s_of - 1, c1)
    wave = _waves(br0[order] + _PAD, br1[order] + _PAD, bc0[order] + _PAD, bc1[order] + _PAD,
                  (rows + 2 * _PAD, cols + 2 * _PAD))
    # edge-replicated padding: the interior low-pass never sees artificial values
    zpad = _edge_padded(heightfield.z_m, _PAD)
    xs, ys = heightfield.grid_xy()
    xpad = ox + (np.arange(cols + 2 * _PAD) - _PAD) * cs
    ypad = oy + (np.arange(rows + 2 * _PAD) - _PAD) * cs
    valid_c = np.zeros(cols + 2 * _PAD, dtype=bool)
    valid_c[_PAD:-_PAD] = True
    valid_r = np.zeros(rows + 2 * _PAD, dtype=bool)
    valid_r[_PAD:-_PAD] = True
    z = zpad[_PAD:-_PAD, _PAD:-_PAD]  # view: slice stamping writes through to zpad
    by_wave = np.argsort(wave, kind="stable")
    wave_order = order[by_wave]
    bounds = np.searchsorted(wave[by_wave], np.arange(int(wave.max(initial=-1)) + 2))
    def boxes(chunk: np.ndarray, k: int) -> None:
        rr = br0[chunk, None] + _PAD + np.arange(_SIZES[k])[None, :]
        cc2 = bc0[chunk, None] + _PAD + np.arange(_SIZES[k])[None, :]
        _stamp_boxes(zpad, xpad, ypad, valid_r, valid_c, p, chunk, rr, cc2)

    # A wave's batches of small craters read and write only their own disjoint boxes, so two
    # threads stamp them (numpy releases the GIL in these (m, S, S) array operations) with the
    # same result as one; large craters read a low-pass halo around their box and stay serial.
    threaded = worth_a_thread(rows * cols)
    # two batches in flight hold the temporaries of one batch of the single-threaded path
    batch_posts = _BATCH_POSTS // _STAMP_THREADS if threaded else _BATCH_POSTS
    with ThreadPoolExecutor(max_workers=_STAMP_THREADS,
                            thread_name_prefix="marsscene-craters") as pool:
        for w in range(bounds.size - 1):
            members = wave_order[bounds[w]:bounds[w + 1]]
            for i in members[~small[members]]:
                _stamp_slice(z, xs, ys, p, int(i), (r0[i], r1[i], c0[i], c1[i]))
            sm = members[small[members]]
            batches = []
            for k in np.unique(size_class[sm]).tolist():
                ids = sm[size_class[sm] == k]
                step = min(4096, max(1, batch_posts // int(_SIZES[k]) ** 2))
                batches += [(ids[a:a + step], k) for a in range(0, ids.size, step)]
            if len(batches) > 1 and threaded:
                for done in [pool.submit(boxes, *b) for b in batches]:
                    done.result()
            else:
                for b in batches:
                    boxes(*b)
    return heightfield._with_owned_z(z.astype(np.float32))


class _Params:
    """Per-crater stamping parameters and the stacked profile tables of every model."""

    def __init__(self, craters: CraterTable, fams: dict[int, ProfileFamily]) -> None:
        n = len(craters)
        d = craters.diameter_m
        first = next(iter(fams.values()))  # all families share the rho step and s grid
        self.step = first.rho[1] - first.rho[0]
        n_s = first.s.size
        n_rho = max(f.rho.size for f in fams.values()) + 2
        self.table = np.zeros((len(PROFILE_MODELS), n_s, n_rho))
        self.i0 = np.zeros(n, dtype=np.int64)
        self.f = np.zeros(n)
        self.reach = np.zeros(n)
        self.strength = np.zeros(n)
        for pid, fam in fams.items():
            self.table[pid, :, : fam.rho.size] = fam.h_over_d
            sel = np.nonzero(craters.profile == pid)[0]
            if not sel.size:
                continue
            state = fam.state_of_depth(craters.depth_m[sel] / d[sel])
            i0 = np.minimum(state.astype(np.int64), n_s - 2)
            f = state - i0
            self.i0[sel], self.f[sel] = i0, f
            self.reach[sel] = np.where(f > 0, np.maximum(fam.reach[i0], fam.reach[i0 + 1]),
                                       fam.reach[i0])
            relief = (fam.depth_over_d + fam.rim_over_d) / (fam.depth_over_d[0] + fam.rim_over_d[0])
            self.strength[sel] = np.interp(state, np.arange(n_s), relief)
        self.pid = craters.profile
        self.diameter = d
        q = np.asarray(craters.axis_ratio, dtype=np.float64)
        self.radius = d / 2.0
        self.semi_major = self.radius / np.sqrt(q)
        self.sqrt_q = np.sqrt(q)
        az = np.radians(np.asarray(craters.azimuth_deg, dtype=np.float64))
        self.cos_az, self.sin_az = np.cos(az), np.sin(az)
        self.cx = craters.center_xy_m[:, 0]
        self.cy = craters.center_xy_m[:, 1]

    def rows(self, ids: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Profile rows (in m) of craters ``ids`` and their slopes, shape (m, n_rho)."""
        pid, i0, f = self.pid[ids], self.i0[ids], self.f[ids, None]
        rows = self.diameter[ids, None] * (
            (1 - f) * self.table[pid, i0] + f * self.table[pid, i0 + 1])
        return rows, np.diff(rows, axis=1, append=0.0)


def _lookup(p: _Params, ids: np.ndarray, k: np.ndarray, fr: np.ndarray) -> np.ndarray:
    rows, slope = p.rows(ids)
    flat = k + (np.arange(ids.size) * rows.shape[1])[:, None, None]
    return np.asarray(rows.ravel()[flat] + fr * slope.ravel()[flat])


def _rho(p: _Params, ids: np.ndarray | int, dx: np.ndarray, dy: np.ndarray) -> np.ndarray:
    """Normalised radius; ``dx`` broadcasts along columns, ``dy`` along rows."""
    ca, sa, sq, r = p.cos_az[ids], p.sin_az[ids], p.sqrt_q[ids], p.radius[ids]
    if np.all(sq == 1.0):
        return np.asarray(np.sqrt(dx * dx + dy * dy) / r)
    u = (dx * ca + dy * sa) * sq
    v = (dy * ca - dx * sa) / sq
    return np.asarray(np.sqrt(u * u + v * v) / r)


def _blend(p: _Params, ids: np.ndarray | int, rho: np.ndarray) -> np.ndarray:
    w = np.clip((BLEND_OUTER_RHO - rho) * (1.0 / (BLEND_OUTER_RHO - 1.0)), 0.0, 1.0)
    return np.asarray(w * w * (3.0 - 2.0 * w) * p.strength[ids])


def _stamp_slice(z: np.ndarray, xs: np.ndarray, ys: np.ndarray, p: _Params, i: int,
                 box: tuple[int, int, int, int]) -> None:
    """One large crater as a 2-D slice (float32 work arrays, nearest lookup in a profile row
    resampled to a quarter of the post spacing)."""
    r0, r1, c0, c1 = (int(v) for v in box)
    dx = (xs[c0:c1 + 1] - p.cx[i])[None, :]
    dy = (ys[r0:r1 + 1] - p.cy[i])[:, None]
    lim = BLEND_OUTER_RHO * p.semi_major[i]
    bx = np.nonzero(np.abs(dx[0]) <= lim)[0]
    by = np.nonzero(np.abs(dy[:, 0]) <= lim)[0]
    patch = z[r0:r1 + 1, c0:c1 + 1]
    if bx.size and by.size:  # plane fit on the inner box, before the crater is added
        a0, a1, b0, b1 = by[0], by[-1] + 1, bx[0], bx[-1] + 1
        sub = patch[a0:a1, b0:b1]
        xm = dx[0, b0:b1] - dx[0, b0:b1].mean()
        ym = dy[a0:a1, 0] - dy[a0:a1, 0].mean()
        sxx, syy = float(xm @ xm) * ym.size, float(ym @ ym) * xm.size
        gx = float(sub.sum(axis=0) @ xm) / sxx if sxx > 0 else 0.0
        gy = float(sub.sum(axis=1) @ ym) / syy if syy > 0 else 0.0
        plane = float(sub.mean()) + gx * xm[None, :] + gy * ym[:, None]
        rho_in = _rho(p, i, dx[:, b0:b1], dy[a0:a1])
        k = max(3, 2 * round(0.5 * _LOWPASS_RADII * p.radius[i] / (xs[1] - xs[0])) + 1)
        h = k // 2
        lo_r, lo_c = max(r0 + a0 - h, 0), max(c0 + b0 - h, 0)
        region = z[lo_r:r0 + a1 + h, lo_c:c0 + b1 + h]
        smooth = uniform_filter(region, size=k, mode="nearest")
        smooth = smooth[r0 + a0 - lo_r:r0 + a1 - lo_r, c0 + b0 - lo_c:c0 + b1 - lo_c]
        sub += _blend(p, i, rho_in) * (plane - smooth)
    rows, _ = p.rows(np.array([i]))
    fine = min(p.step, 0.25 * (xs[1] - xs[0]) / p.radius[i])  # in crater radii
    grid = np.arange(0.0, rows.shape[1] * p.step, fine)
    row = np.interp(grid, np.arange(rows.shape[1]) * p.step, rows[0]).astype(np.float32)
    row[-1] = 0.0
    if p.sqrt_q[i] == 1.0:
        scale = np.float32(1.0 / (p.radius[i] * fine))
        fx = (dx * scale).astype(np.float32)
        fy = (dy * scale).astype(np.float32)
        idx = np.sqrt(fx * fx + fy * fy)
    else:
        idx = (_rho(p, i, dx, dy) / fine).astype(np.float32)
    np.minimum(idx, np.float32(row.size - 1), out=idx)
    idx += np.float32(0.5)
    patch += row[idx.astype(np.int32)]


def _stamp_boxes(zpad: np.ndarray, xpad: np.ndarray, ypad: np.ndarray, valid_r: np.ndarray,
                 valid_c: np.ndarray, p: _Params, ids: np.ndarray, rr: np.ndarray,
                 cc: np.ndarray) -> None:
    """Many small craters with disjoint padded boxes, as ``(m, S, S)`` arrays."""
    dx = (xpad[cc] - p.cx[ids, None])[:, None, :]
    dy = (ypad[rr] - p.cy[ids, None])[:, :, None]
    rho = _rho(p, ids[:, None, None], dx, dy)
    old = zpad[rr[:, :, None], cc[:, None, :]]
    lim = (BLEND_OUTER_RHO * p.semi_major[ids])[:, None]
    ix = ((np.abs(dx[:, 0, :]) <= lim) & valid_c[cc]).astype(np.float64)  # (m, S)
    iy = ((np.abs(dy[:, :, 0]) <= lim) & valid_r[rr]).astype(np.float64)
    nx, ny = ix.sum(1), iy.sum(1)
    cnt = np.maximum(nx * ny, 1.0)
    xm = dx[:, 0, :] - ((ix * dx[:, 0, :]).sum(1) / np.maximum(nx, 1.0))[:, None]
    ym = dy[:, :, 0] - ((iy * dy[:, :, 0]).sum(1) / np.maximum(ny, 1.0))[:, None]
    sxx = (ix * xm * xm).sum(1) * ny
    syy = (iy * ym * ym).sum(1) * nx
    col_sum = np.einsum("mr,mrc->mc", iy, old)
    row_sum = np.einsum("mc,mrc->mr", ix, old)
    gx = np.divide((col_sum * ix * xm).sum(1), sxx, out=np.zeros(ids.size), where=sxx > 0)
    gy = np.divide((row_sum * iy * ym).sum(1), syy, out=np.zeros(ids.size), where=syy > 0)
    mean = (col_sum * ix).sum(1) / cnt
    plane = (mean[:, None, None] + gx[:, None, None] * xm[:, None, :]
             + gy[:, None, None] * ym[:, :, None])
    smooth = uniform_filter(old, size=(1, 3, 3), mode="nearest")
    new = old + _blend(p, ids[:, None, None], rho) * (plane - smooth)
    new += _lookup(p, ids, *_index(p, rho))
    zpad[rr[:, :, None], cc[:, None, :]] = new


def _index(p: _Params, rho: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    idx = rho / p.step
    k = np.minimum(idx.astype(np.int64), p.table.shape[2] - 2)
    return k, np.minimum(idx - k, 1.0)
