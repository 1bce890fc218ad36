"""Asset types: an asset's geometry in its own frame, and a placed asset (pure data)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import trimesh  # imported on use: keeps ``import marsscene`` light

__all__ = ["AssetModel", "PlacedAsset", "normalise_parts"]


@dataclass(frozen=True, eq=False)
class AssetModel:
    """An asset in its local frame: x east, y north, z up, metres, base centre at the origin
    (its lowest point at z = 0, its horizontal bounding-box centre at x = y = 0).

    Attributes
    ----------
    name : str
        Valid prim / MJCF name (letters, digits, underscores).
    parts : tuple of trimesh.Trimesh
        Visual meshes; each part's convex hull is its collision shape.
    source_path : str, optional
        The user's file (``None`` for the procedural habitat).
    usd_root : str, optional
        For a USD file: the prim to reference (its default prim or first root prim).
    usd_offset_m : (3,) tuple
        For a USD file: translation that moves its base centre to the origin (after
        ``usd_rotate_x_deg`` and ``usd_scale``).
    usd_rotate_x_deg, usd_scale : float
        Y-up to Z-up rotation (90 or 0) and unit scale of a referenced USD file.
    """

    name: str
    parts: tuple[trimesh.Trimesh, ...]
    source_path: str | None = None
    usd_root: str | None = None
    usd_offset_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    usd_rotate_x_deg: float = 0.0
    usd_scale: float = 1.0

    @property
    def radius_m(self) -> float:
        """Horizontal radius of the footprint (largest distance of a vertex from the z axis)."""
        v = np.concatenate([p.vertices for p in self.parts])
        return float(np.hypot(v[:, 0], v[:, 1]).max())

    @property
    def height_m(self) -> float:
        """Top of the asset above its base (in m)."""
        return float(max(p.vertices[:, 2].max() for p in self.parts))


@dataclass(frozen=True, eq=False)
class PlacedAsset:
    """An asset standing on levelled ground: its base centre at ``(x, y, base_z_m)``."""

    model: AssetModel
    xy_m: tuple[float, float]
    base_z_m: float
    pad_radius_m: float
    """Radius of the levelled pad (footprint radius + margin) (in m)."""


def normalise_parts(parts: list[trimesh.Trimesh]) -> tuple[trimesh.Trimesh, ...]:
    """Translate parts together so their base centre sits at the origin (new meshes)."""
    v = np.concatenate([p.vertices for p in parts])
    lo, hi = v.min(axis=0), v.max(axis=0)
    shift = -np.array([(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, lo[2]])
    out = []
    for p in parts:
        m = p.copy()
        m.apply_translation(shift)
        out.append(m)
    return tuple(out)
