"""The batch camera's terrain march (marsscene.sensors.batch._trace.march) on Warp's CPU
device: its first hit equals the nearest of every triangle of the heightfield tried one by one
(numpy, Moller-Trumbore), for rays from above, grazing, from outside the grid and rising; and
each block's top is the highest post of its block.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("warp", reason="needs marsscene[gpu] (warp-lang)")

import warp as wp

from marsscene.sensors.batch import _trace
from marsscene.sensors.batch.rgbd import block_tops


@wp.kernel
def _march_kernel(posts: wp.array3d[float], tops: wp.array3d[float], o: wp.array[wp.vec3],
                  d: wp.array[wp.vec3], z_top: float, out: wp.array[wp.vec4]):
    k = wp.tid()
    out[k] = _trace.march(posts, tops, 0, o[k], d[k], 0.0, 1.0e6, z_top)


def _triangles(z: np.ndarray) -> np.ndarray:
    """(T, 3, 3) every triangle of the posts as march cuts them (post units in x, y)."""
    rows, cols = z.shape
    r, c = np.meshgrid(np.arange(rows - 1), np.arange(cols - 1), indexing="ij")
    r, c = r.ravel(), c.ravel()

    def p(rr: np.ndarray, cc: np.ndarray) -> np.ndarray:
        return np.stack([cc, rr, z[rr, cc]], axis=-1).astype(np.float64)

    a, b, e, f = p(r, c), p(r, c + 1), p(r + 1, c + 1), p(r + 1, c)
    return np.concatenate([np.stack([a, b, e], 1), np.stack([a, e, f], 1)])


def _nearest_hit(tri: np.ndarray, o: np.ndarray, d: np.ndarray) -> np.ndarray:
    """(R,) the nearest t of each ray over all triangles (-1: none)."""
    a = tri[None, :, 0]
    e1, e2 = tri[None, :, 1] - a, tri[None, :, 2] - a
    dd = d[:, None, :]
    q = np.cross(dd, e2)
    det = np.einsum("rtk,rtk->rt", e1, q)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        s = o[:, None, :] - a
        u = np.einsum("rtk,rtk->rt", s, q) * inv
        rr = np.cross(s, e1)
        v = np.einsum("rtk,rtk->rt", dd, rr) * inv
        t = np.einsum("rtk,rtk->rt", e2, rr) * inv
    ok = (np.abs(det) > 1e-12) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t >= 0)
    t = np.where(ok, t, np.inf).min(axis=1)
    return np.where(np.isfinite(t), t, -1.0)


def test_block_tops_are_each_blocks_highest_post() -> None:
    rng = np.random.default_rng(4)
    posts = rng.standard_normal((3, 27, 19)).astype(np.float32)
    tops = block_tops(posts, 8)
    assert tops.shape == (3, 4, 3)
    for w in range(3):
        for i in range(4):
            for j in range(3):
                block = posts[w, 8 * i:8 * i + 9, 8 * j:8 * j + 9]
                assert tops[w, i, j] == block.max()


def test_march_finds_the_nearest_triangle_hit() -> None:
    rng = np.random.default_rng(11)
    rows, cols = 41, 35  # blocks of 8 cells: 5 x 5, the last column of blocks partial
    z = np.cumsum(np.cumsum(rng.normal(0.0, 0.15, (rows, cols)), 0), 1) * 0.2
    z += 1.5 * np.exp(-((np.arange(cols) - 17) ** 2)[None, :] / 20.0
                      - ((np.arange(rows) - 20) ** 2)[:, None] / 30.0)  # a hill between rays
    z = z.astype(np.float32)
    n = 600
    o = np.c_[rng.uniform(-5, cols + 4, n), rng.uniform(-5, rows + 4, n),
              rng.uniform(z.min(), z.max() + 2.0, n)]
    aim = np.c_[rng.uniform(0, cols - 1, n), rng.uniform(0, rows - 1, n),
                rng.uniform(z.min() - 0.5, z.max() + 0.5, n)]
    d = aim - o
    d[: n // 6, 2] = np.abs(d[: n // 6, 2])  # some rise
    d[n // 6: n // 3, 2] *= 0.02  # some graze
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    ref = _nearest_hit(_triangles(z.astype(np.float64)), o, d)
    assert 0.3 < (ref >= 0).mean() < 0.95  # both hits and misses are tried

    dev = "cpu"
    out = wp.zeros(n, dtype=wp.vec4, device=dev)
    wp.launch(_march_kernel, dim=n, device=dev, inputs=[
        wp.array(z[None], dtype=float, device=dev),
        wp.array(block_tops(z[None], int(_trace.BLOCK)), dtype=float, device=dev),
        wp.array(o.astype(np.float32), dtype=wp.vec3, device=dev),
        wp.array(d.astype(np.float32), dtype=wp.vec3, device=dev), float(z.max()) + 0.01,
        out])
    got = out.numpy()[:, 0]
    assert np.array_equal(got >= 0, ref >= 0)
    hit = ref >= 0
    np.testing.assert_allclose(got[hit], ref[hit], atol=2e-4)
