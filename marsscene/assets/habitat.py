"""A small procedural habitat (the Mars Base stand-in when no asset file is given), pure.

Five convex parts, sized like surface-habitat concepts (NASA's ~8 m diameter inflatable
modules): a 8 m wide, 3 m tall main module with a flattened dome roof, a 5 m airlock/lab
module joined by a 1.2 m radius tunnel, a solar array and an antenna mast. Each primitive is
its own collision part (each is convex).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from marsscene.assets.model import AssetModel, normalise_parts

if TYPE_CHECKING:
    import trimesh

__all__ = ["habitat_model"]


def _at(mesh: trimesh.Trimesh, xyz: tuple[float, float, float]) -> trimesh.Trimesh:
    mesh.apply_translation(xyz)
    return mesh


def habitat_model(name: str = "habitat") -> AssetModel:
    """The procedural habitat (deterministic; about 20 m x 10 m x 6 m).

    Examples
    --------
    >>> h = habitat_model()
    >>> len(h.parts), round(h.height_m, 2), round(h.radius_m, 1)
    (5, 6.0, 11.0)
    """
    import trimesh  # imported on use: keeps ``import marsscene`` light

    main = _at(trimesh.creation.cylinder(radius=4.0, height=3.0, sections=32), (0, 0, 1.5))
    dome = trimesh.creation.icosphere(subdivisions=2, radius=4.0)
    dome.apply_scale((1.0, 1.0, 0.5))
    dome = _at(dome, (0, 0, 3.0))
    tunnel = trimesh.creation.cylinder(radius=1.2, height=4.0, sections=24)
    tunnel.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, (0, 1, 0)))
    tunnel = _at(tunnel, (5.5, 0, 1.2))
    lab = _at(trimesh.creation.cylinder(radius=2.5, height=2.5, sections=32), (9.0, 0, 1.25))
    panel = _at(trimesh.creation.box(extents=(6.0, 2.0, 0.1)), (-5.0, 5.0, 0.05))
    mast = _at(trimesh.creation.cylinder(radius=0.1, height=6.0, sections=12), (-2.5, -3.2, 3.0))
    parts = [main, dome, tunnel, lab, panel, mast]
    # dome and main module are one part (their union is convex enough: hull of both)
    body = trimesh.convex.convex_hull(np.concatenate([main.vertices, dome.vertices]))
    return AssetModel(name=name, parts=normalise_parts([body, *parts[2:]]))
