"""Procedural rock prototypes: faceted, slightly noisy ellipsoids made watertight with manifold3d.

Each prototype lives in a unit frame: ``x, y`` in ``[-0.5, 0.5]``, ``z`` in ``[0, 1]`` with
the (flat) base at ``z = 0``; a placed rock scales it by ``RockTable.scale_xyz_m`` and rotates it
by ``orientation_wxyz``. Shape recipe: an icosphere's directions are pushed to the boundary of
an ellipsoid cut by random planes (an angular, convex body), roughened by low-frequency noise,
then trimmed flat at the base with manifold3d (which guarantees a watertight 2-manifold).
Collision geometry is the convex hull by default (milliseconds); coacd convex decomposition is
optional (:mod:`marsscene.rocks.collision`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from marsscene.errors import ExportError, missing_dependency
from marsscene.rocks.config import RockConfig
from marsscene.rocks.hull import convex_hull

if TYPE_CHECKING:
    import trimesh

__all__ = ["RockPrototype", "make_prototypes", "rock_mesh"]


@dataclass(frozen=True, eq=False)
class RockPrototype:
    """One rock prototype in the unit frame.

    Attributes
    ----------
    name : str
        ``rock_<index>``.
    size_class : int
        Size class (0 = smallest) this prototype represents.
    visual : trimesh.Trimesh
        Watertight render mesh.
    collision : tuple of trimesh.Trimesh
        Convex collision parts (one hull by default).
    """

    name: str
    size_class: int
    visual: trimesh.Trimesh
    collision: tuple[trimesh.Trimesh, ...]


def _to_manifold_trim(vertices: NDArray[np.float64], faces: NDArray[np.int64],
                      base_z: float) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    try:
        import manifold3d
    except ImportError as err:  # pragma: no cover - installed with the collision extra
        raise missing_dependency("manifold3d", None) from err
    mesh = manifold3d.Mesh(
        vert_properties=np.ascontiguousarray(vertices, dtype=np.float32),
        tri_verts=np.ascontiguousarray(faces, dtype=np.uint32),
    )
    solid = manifold3d.Manifold(mesh)
    if solid.status() != manifold3d.Error.NoError:
        raise ExportError(f"rock prototype is not a manifold: {solid.status()}")
    trimmed = solid.trim_by_plane((0.0, 0.0, 1.0), base_z).to_mesh()
    return (np.asarray(trimmed.vert_properties[:, :3], dtype=np.float64),
            np.asarray(trimmed.tri_verts, dtype=np.int64))


def rock_mesh(
    *, rng: np.random.Generator, subdivisions: int = 3, facets: int = 10, roughness: float = 0.04
) -> trimesh.Trimesh:
    """One watertight procedural rock in the unit frame (see module docstring).

    Parameters
    ----------
    rng : numpy.random.Generator
    subdivisions : int
        Icosphere subdivisions (2: 162 vertices, 3: 642 vertices).
    facets : int
        Number of random cutting planes (more = more angular).
    roughness : float
        Relative amplitude of the low-frequency radial noise.

    Returns
    -------
    trimesh.Trimesh
        Watertight mesh with ``x, y`` in ``[-0.5, 0.5]`` and ``z`` in ``[0, 1]``.
    """
    import trimesh  # imported on use: keeps ``import marsscene`` light

    sphere = trimesh.creation.icosphere(subdivisions=subdivisions)
    dirs = np.asarray(sphere.vertices, dtype=np.float64)
    axes = np.array([1.0, rng.uniform(0.7, 1.0), rng.uniform(0.5, 0.9)])
    # distance to the ellipsoid boundary along each direction
    r = 1.0 / np.sqrt(((dirs / axes) ** 2).sum(axis=1))
    normals = rng.normal(size=(facets, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    offsets = rng.uniform(0.45, 0.85, size=facets)
    cos = dirs @ normals.T  # (V, facets)
    with np.errstate(divide="ignore"):
        plane_r = np.where(cos > 1e-6, offsets / np.maximum(cos, 1e-6), np.inf)
    r = np.minimum(r, plane_r.min(axis=1))
    waves = rng.normal(size=(4, 3))
    phase = rng.uniform(0, 2 * np.pi, size=4)
    noise = np.sin(2.5 * dirs @ waves.T + phase).mean(axis=1)
    r *= 1.0 + roughness * noise
    verts = dirs * r[:, None]
    z_lo = verts[:, 2].min()
    base = z_lo + rng.uniform(0.12, 0.25) * (verts[:, 2].max() - z_lo)
    v, f = _to_manifold_trim(verts, np.asarray(sphere.faces, dtype=np.int64), base)
    lo, hi = v.min(axis=0), v.max(axis=0)
    v = (v - np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]])) / (hi - lo)
    mesh = trimesh.Trimesh(vertices=v, faces=f, process=True)
    mesh.fix_normals()
    return mesh


def make_prototypes(cfg: RockConfig, *, rng: np.random.Generator) -> tuple[RockPrototype, ...]:
    """The scene's rock prototypes: ``cfg.prototypes`` rocks dealt round-robin to the size
    classes; larger classes get finer, more angular meshes.

    Parameters
    ----------
    cfg : RockConfig
    rng : numpy.random.Generator
        Use ``stage_rng(seed, "rock_shapes")`` so shapes do not depend on the population.
    """
    n_classes = len(cfg.size_classes_m) + 1
    out = []
    for p in range(cfg.prototypes):  # a few prototypes, not rocks
        size_class = p % n_classes
        visual = rock_mesh(
            rng=rng,
            subdivisions=2 if size_class == 0 else 3,
            facets=8 + 4 * size_class,
            roughness=0.03 + 0.015 * size_class,
        )
        if cfg.collision == "coacd":
            from marsscene.rocks.collision import convex_decompose

            parts = convex_decompose(visual, threshold=cfg.coacd_threshold)
        else:
            parts = (convex_hull(visual),)
        out.append(RockPrototype(f"rock_{p:02d}", size_class, visual, parts))
    return tuple(out)
