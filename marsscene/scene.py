"""The :class:`Scene`: what the pipeline produces and the exporters consume."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.config import SceneConfig
from marsscene.craters.table import CraterTable
from marsscene.lighting.model import Lighting
from marsscene.rocks.table import RockTable
from marsscene.terrain.from_dem import GeoFrame
from marsscene.terrain.heightfield import Heightfield
from marsscene.terrain.lod import OuterTerrain

__all__ = ["ModelRef", "Provenance", "Scene"]


@dataclass(frozen=True, slots=True)
class ModelRef:
    """A scientific model or dataset used in a build, with its citation."""

    stage: str
    name: str
    citation: str


@dataclass(frozen=True)
class Provenance:
    """Where a scene came from (written to ``manifest.json`` and USD ``customLayerData``)."""

    frame: GeoFrame
    inputs: dict[str, str] = field(default_factory=dict)
    """Input role -> path, e.g. ``{"dem": "/data/jezero.img"}``."""
    models: tuple[ModelRef, ...] = ()
    timings_s: dict[str, float] = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    """Warnings and rules applied (extrapolations, filled posts, dropped rocks, ...)."""
    extra: dict[str, Any] = field(default_factory=dict)
    """Stage-specific summary values (counts, τ, ...)."""


@dataclass(frozen=True, eq=False)
class Scene:
    """A built Mars scene.

    Attributes
    ----------
    heightfield : Heightfield
        Final terrain (with craters stamped).
    texture_rgb : ndarray of shape (rows, cols, 3), uint8, optional
        Image draped over the whole footprint, row 0 = north (image order).
    craters, rocks : tables, optional
        ``None`` when the stage is disabled.
    rock_prototypes : tuple, optional
        Rock prototypes (``marsscene.rocks.RockPrototype``: visual mesh, convex collision parts)
        referenced by ``rocks.prototype``.
    lighting : Lighting, optional
    assets : tuple of marsscene.assets.PlacedAsset, optional
        Habitats / landers on levelled pads (``None`` when none are configured).
    soil : marsscene.soil.SoilMap, optional
        Which soil lies where (``[soil] enabled``; ``None`` otherwise).
    outer : OuterTerrain, optional
        Level-of-detail scenes only: the coarse terrain over the whole footprint; then
        ``heightfield`` is the full-resolution focus square (:mod:`marsscene.terrain.lod`).
    config : SceneConfig
    seed : int
    provenance : Provenance
    """

    heightfield: Heightfield
    config: SceneConfig
    seed: int
    provenance: Provenance
    texture_rgb: NDArray[np.uint8] | None = None
    craters: CraterTable | None = None
    rocks: RockTable | None = None
    rock_prototypes: tuple[Any, ...] | None = None
    lighting: Lighting | None = None
    assets: tuple[Any, ...] | None = None
    outer: OuterTerrain | None = None
    soil: Any = None
