"""The rock colliders of a written USD scene, read back for a physics engine that does not
instance (Newton) and by the tests: the obstacle rocks' native instances and the merged tile
meshes of the smaller rocks (layout: :mod:`marsscene.export.usd.rock_colliders`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.export.usd.physics import ROCK_PHYSICS
from marsscene.export.usd.rock_colliders import COLLIDERS_PATH, FIRST_FACE_ATTR, ROWS_ATTR

__all__ = ["MergedRocks", "merged_rocks", "rock_instances"]



@dataclass(frozen=True, slots=True)
class MergedRocks:
    """One merged tile: world points (V, 3), triangles (F, 3), and per rock its row in the
    rock table and its first triangle (its triangles run to the next rock's first)."""

    path: str
    points_m: NDArray[np.float32]
    faces: NDArray[np.int32]
    rows: NDArray[np.int64]
    first_face: NDArray[np.int64]
    friction: float = ROCK_PHYSICS.dynamic_friction

    def rock_of_face(self) -> NDArray[np.int64]:
        """Index (into :attr:`rows`) of the rock each triangle belongs to."""
        counts = np.diff(np.append(self.first_face, len(self.faces)))
        return np.repeat(np.arange(len(self.rows)), counts)

    def centres_xy_m(self) -> NDArray[np.float64]:
        """Each rock's horizontal centre (mean of its triangles' first corners), (N, 2)."""
        corner = self.points_m[self.faces[:, 0], :2].astype(np.float64)
        counts = np.diff(np.append(self.first_face, len(self.faces)))
        return np.add.reduceat(corner, self.first_face, axis=0) / counts[:, None]

    def select(self, keep: NDArray[np.bool_]) -> tuple[NDArray[np.float32],
                                                       NDArray[np.int32], int]:
        """Points, triangles (re-indexed) and count of the rocks where ``keep`` is true."""
        faces = self.faces[keep[self.rock_of_face()]]
        used, inverse = np.unique(faces, return_inverse=True)
        return (self.points_m[used], inverse.reshape(-1, 3).astype(np.int32),
                int(np.count_nonzero(keep)))


def _friction(prim: Any) -> float:
    """Dynamic friction of the physics material bound to ``prim`` (the rock material's if
    none is)."""
    from pxr import UsdPhysics, UsdShade

    mat, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial("physics")
    if mat and mat.GetPrim().HasAPI(UsdPhysics.MaterialAPI):
        return float(UsdPhysics.MaterialAPI(mat.GetPrim()).GetDynamicFrictionAttr().Get())
    return float(ROCK_PHYSICS.dynamic_friction)


def merged_rocks(stage: Any) -> list[MergedRocks]:
    """The merged tile meshes under ``/World/RockColliders`` (every payload part)."""
    from pxr import Usd, UsdGeom

    root = stage.GetPrimAtPath(COLLIDERS_PATH)
    out = []
    for prim in Usd.PrimRange(root) if root else ():
        rows = prim.GetAttribute(ROWS_ATTR)
        if not (prim.IsA(UsdGeom.Mesh) and rows):
            continue
        mesh = UsdGeom.Mesh(prim)
        out.append(MergedRocks(
            str(prim.GetPath()), np.asarray(mesh.GetPointsAttr().Get(), dtype=np.float32),
            np.asarray(mesh.GetFaceVertexIndicesAttr().Get(), dtype=np.int32).reshape(-1, 3),
            np.asarray(rows.Get(), dtype=np.int64),
            np.asarray(prim.GetAttribute(FIRST_FACE_ATTR).Get(), dtype=np.int64),
            _friction(prim)))
    return out


def rock_instances(stage: Any) -> tuple[dict[str, list[Any]], NDArray[np.float64], list[str],
                                         NDArray[np.int64], float]:
    """The obstacle rocks' colliders of a scene stage (native instances under
    ``/World/RockColliders``).

    Returns
    -------
    parts : dict of str to list of (vertices (V, 3), triangle indices (F * 3,))
        Collision meshes of each prototype (unit frame), by prototype prim path.
    transforms : ndarray of shape (N, 4, 4)
        World transform of each rock (USD row-vector convention: rows 0-2 are the scaled
        axes, row 3 the position).
    prototypes : list of str
        Each rock's prototype path (a key of ``parts``).
    rows : ndarray of int, shape (N,)
        Each rock's row in the scene's rock table (its prim name ``rock_<row>``).
    friction : float
        Dynamic friction of the rocks' physics material (the rock material's if none is
        bound).
    """
    from pxr import Usd, UsdGeom

    root = stage.GetPrimAtPath(COLLIDERS_PATH)
    cache = UsdGeom.XformCache()
    parts: dict[str, list[Any]] = {}
    mats, keys, rows = [], [], []
    friction = float(ROCK_PHYSICS.dynamic_friction)
    for prim in Usd.PrimRange(root) if root else ():
        if not prim.IsInstance():
            continue  # the Merged scope and the merged meshes: merged_rocks

        key = str(prim.GetPrototype().GetPath())
        if key not in parts:  # a handful of prototypes
            parts[key] = []
            for child in Usd.PrimRange(prim, Usd.TraverseInstanceProxies()):
                if child.IsA(UsdGeom.Mesh):
                    mesh = UsdGeom.Mesh(child)
                    parts[key].append((np.asarray(mesh.GetPointsAttr().Get(), np.float32),
                                       np.asarray(mesh.GetFaceVertexIndicesAttr().Get(),
                                                  np.int32)))
                    friction = _friction(child)
        keys.append(key)
        rows.append(int(prim.GetName().rsplit("_", 1)[1]))
        mats.append(np.asarray(cache.GetLocalToWorldTransform(prim)))
    return (parts, np.asarray(mats, dtype=np.float64).reshape(-1, 4, 4), keys,
            np.asarray(rows, dtype=np.int64), friction)


