"""Many rocks' collision hulls merged into one static triangle mesh per square tile.

Physics clients pay per collider *prim* far more than per triangle: a USD prim per rock costs
about 80 us to author and save, OpenUSD's physics parser and the Asset Validator visit each
one, and Newton's importer builds a mesh per prim (about 1 ms). Merging the hulls of the many
small rocks of a tile into one mesh makes the cost a few vectorised array operations, at the
price of the rocks' identity as prims (kept as a face range per rock, :class:`MergedTile`) and
of convexity (a static triangle mesh: every loader collides with its faces).

Each rock's hull is a small inscribed hull of its prototype's collision parts
(:func:`marsscene.rocks.hull.greedy_hull`, :data:`HULL_VERTICES` vertices: 83-92 % of the
prototype hull's volume, its bounding box and so the rock's height kept), scaled, rotated and
placed as the rock table says. Pure numpy: no I/O, inputs untouched.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.rocks.table import RockTable
from marsscene.transforms import quat_to_matrix

__all__ = ["HULL_VERTICES", "TILE_M", "MergedTile", "merge_tiles", "small_hulls"]

#: Side of a merge tile (m): the merged rocks of a 64 m square share one mesh (a median of 739
#: in the default scene's 36 tiles; about 890 a tile for 10^6 rocks on 1 km^2), a region a
#: physics engine's broad phase still tells apart from the rest.
TILE_M = 64.0
#: Vertices of each merged rock's hull (at most 2 * HULL_VERTICES - 4 triangles).
HULL_VERTICES = 16


@dataclass(frozen=True, slots=True)
class MergedTile:
    """One tile's merged collision mesh (world frame, metres).

    ``rows[k]`` is the rock-table row of the k-th rock in the mesh; its triangles are
    ``faces[first_face[k]:first_face[k + 1]]`` (the last runs to the end).
    """

    name: str
    points_m: NDArray[np.float32]
    normals: NDArray[np.float32]
    faces: NDArray[np.int32]
    rows: NDArray[np.int64]
    first_face: NDArray[np.int64]


def small_hulls(prototypes: tuple[Any, ...], max_vertices: int = HULL_VERTICES) -> list[Any]:
    """One small convex hull (trimesh, unit frame) of each prototype's collision parts."""
    from marsscene.rocks.hull import greedy_hull

    return [greedy_hull(np.concatenate([np.asarray(p.vertices) for p in proto.collision]),
                        max_vertices=max_vertices) for proto in prototypes]


def _cell_name(row: int, col: int) -> str:
    """``rocks_<row>_<col>`` of a tile (``m`` for minus: ``rocks_m1_0`` lies south of the
    origin's tile)."""
    def part(i: int) -> str:
        return f"m{-i}" if i < 0 else str(i)

    return f"rocks_{part(row)}_{part(col)}"


def _tile_ids(xy: NDArray[np.float64], tile_m: float) -> tuple[NDArray[np.int64], int,
                                                              NDArray[np.int64]]:
    """Each rock's tile as one index, the index's row stride, and the south-west tile's cell
    (tiles are anchored at the world origin: the same square has the same name in any
    payload part)."""
    cell = np.floor(xy / tile_m).astype(np.int64)
    lo = cell.min(axis=0) if len(cell) else np.zeros(2, np.int64)
    cell -= lo
    ncol = int(cell[:, 0].max()) + 1 if len(cell) else 1
    return cell[:, 1] * ncol + cell[:, 0], ncol, lo


def _apply(linear: NDArray[np.float32], vectors: NDArray[np.float32]) -> NDArray[np.float32]:
    """``linear[k] @ vectors[v]`` for every v and k, shape (V, k, 3): one matrix product."""
    k = len(linear)
    return (vectors @ linear.reshape(3 * k, 3).T).reshape(len(vectors), k, 3)


@dataclass(frozen=True, slots=True)
class _Poses:
    """Every rock's linear maps (float32): unit-frame points to world offsets (rotation times
    scale) and unit normals to world normals (rotation over scale, the inverse transpose)."""

    points: NDArray[np.float32]
    normals: NDArray[np.float32]
    position_m: NDArray[np.float32]

    @classmethod
    def of(cls, rocks: RockTable) -> _Poses:
        rot = quat_to_matrix(np.asarray(rocks.orientation_wxyz, dtype=np.float64))
        scale = np.asarray(rocks.scale_xyz_m, dtype=np.float64)[:, None, :]
        return cls((rot * scale).astype(np.float32), (rot / scale).astype(np.float32),
                   np.asarray(rocks.position_xyz_m, dtype=np.float32))


def _placed(poses: _Poses, sel: NDArray[np.int64],
            hull: tuple[Any, Any, Any]) -> tuple[Any, Any]:
    """World vertices and unit normals (V, k, 3), vertex-major, of ``hull`` (vertices,
    normals, faces) at rocks ``sel`` (float32: a rock's offsets are metres, its position
    rounds to 0.1 mm at 1 km)."""
    points = _apply(poses.points[sel], hull[0])
    points += poses.position_m[sel][None]
    normals = _apply(poses.normals[sel], hull[1])
    normals /= np.sqrt((normals * normals).sum(axis=2, keepdims=True))
    return points, normals


def merge_tiles(rocks: RockTable, index: NDArray[np.int64], hulls: list[Any], *,
                tile_m: float = TILE_M) -> Iterator[MergedTile]:
    """The rocks' hulls merged per ``tile_m`` square, tiles in row-major order (a generator:
    one tile's arrays at a time).

    Parameters
    ----------
    rocks : RockTable
    index : array_like of int, shape (N,)
        Each rock's row in the scene's rock table (reported in :attr:`MergedTile.rows`).
    hulls : list of trimesh.Trimesh
        One hull per prototype in the unit frame (:func:`small_hulls`).
    tile_m : float
        Tile side (m); the tile holding world point (x, y) is ``rocks_<row>_<col>`` with
        ``row = floor(y / tile_m)``, ``col = floor(x / tile_m)`` (``m`` for a minus sign).
    """
    index = np.asarray(index, dtype=np.int64)
    proto = np.asarray(rocks.prototype, dtype=np.int64)
    arrays = [(np.asarray(h.vertices, dtype=np.float32),
               np.asarray(h.vertex_normals, dtype=np.float32),
               np.asarray(h.faces, dtype=np.int64)) for h in hulls]
    poses = _Poses.of(rocks)
    tile, ncol, lo = _tile_ids(np.asarray(rocks.position_xyz_m, dtype=np.float64)[:, :2], tile_m)
    order = np.lexsort((proto, tile))  # tile-major, then prototype, then table order
    key = tile[order] * len(hulls) + proto[order]
    tiles = np.unique(tile)
    wanted = (tiles[:, None] * len(hulls) + np.arange(len(hulls))[None, :]).ravel()
    start = np.searchsorted(key, wanted, side="left").reshape(len(tiles), len(hulls))
    stop = np.searchsorted(key, wanted, side="right").reshape(len(tiles), len(hulls))
    for j, t in enumerate(tiles.tolist()):  # one mesh per tile (hundreds at most)
        segments = [(order[a:b], hull) for a, b, hull in zip(start[j], stop[j], arrays,
                                                             strict=True)]
        name = _cell_name(t // ncol + int(lo[1]), t % ncol + int(lo[0]))
        yield _tile_mesh(name, poses, index, segments)


def _tile_mesh(name: str, poses: _Poses, index: NDArray[np.int64],
               segments: list[tuple[NDArray[np.int64], Any]]) -> MergedTile:
    """One tile: per prototype segment, vertex-major (vertex v of the segment's rock j at
    ``v * k + j``), faces rock by rock."""
    pts, nrm, faces, rows, first = [], [], [], [], []
    nv = nf = 0
    for sel, hull in segments:
        k = len(sel)
        if k == 0:
            continue
        p, n = _placed(poses, sel, hull)
        f = hull[2]
        pts.append(p.reshape(-1, 3))
        nrm.append(n.reshape(-1, 3))
        faces.append((nv + f[None] * k + np.arange(k)[:, None, None]).reshape(-1, 3))
        rows.append(index[sel])
        first.append(nf + len(f) * np.arange(k))
        nv += k * p.shape[0]
        nf += k * len(f)
    return MergedTile(name, np.concatenate(pts), np.concatenate(nrm),
                      np.concatenate(faces).astype(np.int32), np.concatenate(rows),
                      np.concatenate(first))
