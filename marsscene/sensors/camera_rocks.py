"""The camera's catalogue rocks: merged visual meshes of jittered icospheres, and the catalogue.

Every catalogue rock (``rocks.csv``, else ``rocks.parquet``, down to ``rocks.d_min_m``) in the
camera's window that is not an MJCF collision geom becomes part of a merged visual mesh
(:class:`RockLOD`): a jittered icosphere per rock (80 faces near the camera, 20 elsewhere),
scaled to its diameter and height, turned by a yaw from its id and coloured through a texture
atlas cell from its id. Each mesh has a fixed capacity; unused slots are tiny and buried.

At a low sun the terrain's shadows (:class:`marsscene.terrain.horizon.SunShadow`) reach the
rocks through their vertex normals (:func:`marsscene.sensors.camera_shadow.shadowed_normals`).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.sensors.camera_shadow import shadowed_normals
from marsscene.terrain.horizon import SunShadow

__all__ = ["ATLAS", "ATLAS_CELL_PX", "PEBBLE_MAX_M", "RockLOD", "RockLook", "read_rock_catalog",
           "read_rock_columns", "rock_arrays", "rock_look"]

ATLAS = 8  # rock texture atlas: 8 x 8 colour cells
#: Texels a side of one atlas cell.
ATLAS_CELL_PX = 32
#: The rock texture's speckle: exp(SPECKLE_SIGMA N(0, 1)) per texel.
SPECKLE_SIGMA = 0.25
_VARIANTS = 8
#: Rocks smaller than this are drawn with 20 faces instead of 80.
PEBBLE_MAX_M = 0.15


def read_rock_columns(scene_dir: Path) -> dict[str, NDArray[np.float64]] | None:
    """Every column of a scene folder's rock catalogue as float64 arrays, by name
    (``rocks.csv``, else ``rocks.parquet``); None where the scene has no catalogue."""
    path = scene_dir / "rocks.csv"
    if path.is_file():
        with open(path, encoding="utf-8") as fh:
            header = next(csv.reader(fh))
        raw = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2).reshape(-1, len(header))
        return {name: raw[:, i] for i, name in enumerate(header)}
    if (scene_dir / "rocks.parquet").is_file():
        from marsscene._optional import require_pyarrow

        require_pyarrow()
        import pyarrow.parquet as pq

        t = pq.read_table(str(scene_dir / "rocks.parquet"))
        return {name: t.column(name).to_numpy().astype(np.float64) for name in t.column_names}
    return None


def read_rock_catalog(scene_dir: Path, *, include_mjcf: bool = False) -> NDArray[np.float64]:
    """``rocks.csv`` (else ``rocks.parquet``) rows not already MJCF geoms (all rows with
    ``include_mjcf``): (N, 6) id, x, y, z, d, h+burial (m)."""
    col = read_rock_columns(scene_dir)
    if col is None or len(col["x_m"]) == 0:
        return np.zeros((0, 6))
    keep = (col["in_mjcf"] == 0 if "in_mjcf" in col and not include_mjcf
            else np.ones(len(col["x_m"]), bool))
    return np.column_stack([col[k][keep] for k in ("id", "x_m", "y_m", "z_m", "diameter_m")]
                           + [(col["height_m"] + col["burial_m"])[keep]])


def _icosphere(subdivide: bool) -> tuple[NDArray[np.float64], NDArray[np.int32]]:
    t = (1.0 + 5.0**0.5) / 2.0
    v = np.array([[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
                  [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]],
                 dtype=np.float64)
    f = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9],
                  [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2],
                  [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10],
                  [8, 6, 7], [9, 8, 1]])
    if not subdivide:
        return v / np.linalg.norm(v, axis=1, keepdims=True), f.astype(np.int32)
    edges = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    uniq, inv = np.unique(edges, axis=0, return_inverse=True)
    mid = len(v) + inv.reshape(3, -1).T  # midpoints of edges (01, 12, 20) per face
    v = np.vstack([v, (v[uniq[:, 0]] + v[uniq[:, 1]]) / 2])
    a, b, c = f.T
    ab, bc, ca = mid.T
    f2 = np.concatenate([np.c_[a, ab, ca], np.c_[b, bc, ab], np.c_[c, ca, bc], np.c_[ab, bc, ca]])
    return v / np.linalg.norm(v, axis=1, keepdims=True), f2.astype(np.int32)


def _normals_of(v: NDArray[np.float64], f: NDArray[np.int32]) -> NDArray[np.float64]:
    fn = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    n = np.zeros_like(v)
    for k in range(3):
        np.add.at(n, f[:, k], fn)
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)


class RockLOD:
    """One merged rock mesh: a jittered icosphere template (8 variants) and a capacity."""

    def __init__(self, name: str, subdivide: bool, rng: np.random.Generator) -> None:
        self.name = name
        base, self.faces = _icosphere(subdivide)
        self.v = base[None] * np.exp(0.22 * rng.standard_normal((_VARIANTS, len(base), 1)))
        self.n = np.stack([_normals_of(v, self.faces) for v in self.v])
        lon = np.arctan2(base[:, 1], base[:, 0])
        self.uv = np.c_[0.5 + 0.45 * np.cos(lon) * (1 - np.abs(base[:, 2])) ** 0.5,
                        0.5 + 0.45 * base[:, 2]]
        self.capacity = 0


@dataclass(frozen=True, eq=False)
class RockLook:
    """The camera's rocks' looks, drawn in this order from the camera's texture stream:
    ``colours`` (ATLAS**2, 3) the atlas cells' albedo, ``speckle`` (texels, texels) the
    texture's multiplicative speckle, ``lods`` the 80- and 20-face meshes' templates."""

    colours: NDArray[np.float64]
    speckle: NDArray[np.float64]
    lods: tuple[RockLOD, RockLOD]

    def face_albedo(self, rock_ids: NDArray[np.int64], uv: NDArray[np.float64]
                    ) -> NDArray[np.float64]:
        """Albedo (N, 3) of points ``uv`` (N, 2) of the atlas on rocks ``rock_ids`` (N,): their
        cell's colour times the speckle texel there (the texture a rock's mesh samples)."""
        size = self.speckle.shape[0]
        col = np.clip((uv[:, 0] * size).astype(np.int64), 0, size - 1)
        row = np.clip((uv[:, 1] * size).astype(np.int64), 0, size - 1)
        cell = (np.asarray(rock_ids, dtype=np.int64) * 2654435761) % (ATLAS * ATLAS)
        return self.colours[cell] * self.speckle[row, col][:, None]


def rock_look(rng: np.random.Generator) -> RockLook:
    """The rocks' :class:`RockLook` from the camera's texture stream (after its regolith
    tile)."""
    from marsscene.terrain.appearance import rock_albedo_rgb

    colours = np.asarray(rock_albedo_rgb(ATLAS * ATLAS, rng=rng), dtype=np.float64)
    speckle = np.exp(SPECKLE_SIGMA * rng.standard_normal((ATLAS * ATLAS_CELL_PX,) * 2))
    return RockLook(colours, speckle, (RockLOD("cam_rocks", True, rng),
                                       RockLOD("cam_pebbles", False, rng)))


def rock_arrays(lod: RockLOD, rocks: NDArray[np.float64], idx: NDArray[np.int64], *,
                hidden_z_m: float, shadow: SunShadow | None) -> tuple[Any, Any, Any, Any]:
    """Vertices, normals, texcoords and faces of the rocks ``rocks[idx]`` in ``lod``'s mesh.

    Beyond the capacity the largest rocks are kept (stable order); unused slots are 1 mm
    spheres at ``hidden_z_m``. With ``shadow`` the normals carry the terrain's shadows.
    """
    cap, nv = lod.capacity, lod.v.shape[1]
    rk = rocks
    if len(idx) > cap:  # keep the largest (stable order)
        idx = np.sort(idx[np.argsort(-rk[idx, 4], kind="stable")[:cap]])
    ids = np.zeros(cap, dtype=np.int64)
    centre = np.zeros((cap, 3))
    scale = np.full((cap, 3), 1e-3)
    k = len(idx)
    ids[:k] = rk[idx, 0].astype(np.int64)
    ids[k:] = np.arange(cap - k)
    centre[:k] = rk[idx, 1:4]
    centre[k:] = [0.0, 0.0, hidden_z_m]
    centre[k:, 0] = np.arange(cap - k) * 0.01  # distinct, hidden under the terrain
    d, hb = rk[idx, 4], rk[idx, 5]
    scale[:k] = np.c_[d / 2, d / 2, hb / 2]
    centre[:k, 2] += hb / 2
    var = ids % _VARIANTS
    yaw = (ids * 0.6180339887) % 1.0 * 2 * np.pi
    cy, sy = np.cos(yaw), np.sin(yaw)
    local = lod.v[var] * scale[:, None, :]
    v = np.zeros_like(local)
    v[..., 0] = cy[:, None] * local[..., 0] - sy[:, None] * local[..., 1]
    v[..., 1] = sy[:, None] * local[..., 0] + cy[:, None] * local[..., 1]
    v[..., 2] = local[..., 2]
    v += centre[:, None, :]
    ln = lod.n[var] / scale[:, None, :]
    n = np.zeros_like(ln)
    n[..., 0] = cy[:, None] * ln[..., 0] - sy[:, None] * ln[..., 1]
    n[..., 1] = sy[:, None] * ln[..., 0] + cy[:, None] * ln[..., 1]
    n[..., 2] = ln[..., 2]
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    if shadow is not None and k:  # rocks standing in a terrain shadow
        vis = np.ones((cap, nv), dtype=np.float32)
        vis[:k] = shadow.visibility_at(v[:k, :, 0], v[:k, :, 1], v[:k, :, 2])
        n = shadowed_normals(n, shadow.sun_direction_enu, vis)
    cell = (ids * 2654435761) % (ATLAS * ATLAS)
    cu, cv = (cell % ATLAS)[:, None], (cell // ATLAS)[:, None]
    uv = np.stack([(cu + lod.uv[None, :, 0]) / ATLAS,
                   (cv + lod.uv[None, :, 1]) / ATLAS], axis=-1)
    f = (lod.faces[None] + (np.arange(cap) * nv)[:, None, None]).reshape(-1, 3)
    return v.reshape(-1, 3), n.reshape(-1, 3), uv.reshape(-1, 2), f
