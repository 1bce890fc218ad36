"""Heightfield -> triangle mesh tiles (the single meshing adapter; vectorised, no per-post loop).

Tiles share their border posts so adjacent tiles meet without cracks. Each tile is at most
``max_tile_posts`` posts on a side, which bounds the vertex count per USD mesh prim.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from marsscene.terrain.heightfield import Heightfield

__all__ = [
    "TerrainTile",
    "grid_faces",
    "heightfield_tiles",
    "iter_heightfield_tiles",
    "tile_ranges",
]


@dataclass(frozen=True, eq=False)
class TerrainTile:
    """One mesh tile of the terrain.

    Attributes
    ----------
    name : str
        ``tile_<row>_<col>`` (tile indices, south-west first).
    points_m : ndarray of shape (V, 3), float32
    normals : ndarray of shape (V, 3), float32
        Per-vertex unit normals.
    st : ndarray of shape (V, 2), float32
        Texture coordinates over the whole terrain: s east, t north, in [0, 1].
    face_vertex_indices : ndarray of shape (F, 3), int32
        Counter-clockwise (seen from above) triangles.
    """

    name: str
    points_m: NDArray[np.float32]
    normals: NDArray[np.float32]
    st: NDArray[np.float32]
    face_vertex_indices: NDArray[np.int32]


def tile_ranges(n: int, max_posts: int) -> list[tuple[int, int]]:
    """Split ``n`` posts into overlapping ranges ``[start, stop)`` of at most ``max_posts``."""
    step = max_posts - 1
    starts = list(range(0, max(n - 1, 1), step))
    return [(s, min(s + max_posts, n)) for s in starts]


def grid_faces(rows: int, cols: int) -> NDArray[np.int32]:
    """Triangles of a ``rows x cols`` vertex grid (row-major), two per cell, CCW from +z."""
    r, c = np.meshgrid(np.arange(rows - 1), np.arange(cols - 1), indexing="ij")
    v00 = (r * cols + c).ravel()
    v01 = v00 + 1
    v10 = v00 + cols
    v11 = v10 + 1
    tri_a = np.stack([v00, v01, v11], axis=1)
    tri_b = np.stack([v00, v11, v10], axis=1)
    return np.stack([tri_a, tri_b], axis=1).reshape(-1, 3).astype(np.int32)


def iter_heightfield_tiles(hf: Heightfield, *,
                           max_tile_posts: int = 513) -> Iterator[TerrainTile]:
    """Mesh a heightfield as tiles of at most ``max_tile_posts**2`` vertices each, one tile at
    a time (south-west first), so a caller that converts and drops each tile holds one tile's
    arrays, not the whole mesh twice.

    Arrays are filled straight into float32 buffers (no float64 meshgrid temporaries, no
    whole-grid normal array: each tile's normals come from its window); tiles of the same shape
    share one read-only ``face_vertex_indices`` array.
    """
    rows, cols = hf.shape
    xs, ys = hf.grid_xy()
    x32, y32 = xs.astype(np.float32), ys.astype(np.float32)
    s_all = ((xs - xs[0]) / (xs[-1] - xs[0])).astype(np.float32)
    t_all = ((ys - ys[0]) / (ys[-1] - ys[0])).astype(np.float32)
    faces: dict[tuple[int, int], NDArray[np.int32]] = {}  # most tiles share one shape
    for ti, (r0, r1) in enumerate(tile_ranges(rows, max_tile_posts)):
        for tj, (c0, c1) in enumerate(tile_ranges(cols, max_tile_posts)):
            nr, nc = r1 - r0, c1 - c0
            if (nr, nc) not in faces:
                faces[nr, nc] = grid_faces(nr, nc)
                faces[nr, nc].flags.writeable = False
            pts = np.zeros((nr, nc, 3), np.float32)
            pts[..., 0] = x32[None, c0:c1]
            pts[..., 1] = y32[r0:r1, None]
            pts[..., 2] = hf.z_m[r0:r1, c0:c1]
            st = np.zeros((nr, nc, 2), np.float32)
            st[..., 0] = s_all[None, c0:c1]
            st[..., 1] = t_all[r0:r1, None]
            yield TerrainTile(
                name=f"tile_{ti}_{tj}",
                points_m=pts.reshape(-1, 3),
                normals=hf.window_normals((r0, r1), (c0, c1)).reshape(-1, 3),
                st=st.reshape(-1, 2),
                face_vertex_indices=faces[nr, nc],
            )


def heightfield_tiles(hf: Heightfield, *, max_tile_posts: int = 513) -> list[TerrainTile]:
    """Mesh a heightfield as tiles of at most ``max_tile_posts**2`` vertices each."""
    return list(iter_heightfield_tiles(hf, max_tile_posts=max_tile_posts))
