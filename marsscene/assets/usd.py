"""Reading a user's USD asset (extent, up axis, units) for placement: the input side's one
importer of ``pxr`` (writing USD is :mod:`marsscene.export.usd`)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from pxr import Usd, UsdGeom

from marsscene.errors import ConfigError

__all__ = ["UsdAssetInfo", "read_usd_asset"]


@dataclass(frozen=True)
class UsdAssetInfo:
    """What placement needs from a USD asset file."""

    extent_min: tuple[float, float, float]
    extent_max: tuple[float, float, float]
    up_axis: str
    meters_per_unit: float
    root_prim: str


def read_usd_asset(path: str | Path) -> UsdAssetInfo:
    """Open a USD file and return its root prim's world bounding box, up axis and units."""
    stage = Usd.Stage.Open(str(path))
    if stage is None:
        raise ConfigError(f"{path}: not a readable USD file")
    prim = stage.GetDefaultPrim()
    if not prim or not prim.IsValid():
        roots = list(stage.GetPseudoRoot().GetChildren())
        if not roots:
            raise ConfigError(f"{path}: the USD file has no root prim")
        prim = roots[0]
    cache = UsdGeom.BBoxCache(Usd.TimeCode.Default(), [UsdGeom.Tokens.default_,
                                                       UsdGeom.Tokens.render])
    box = cache.ComputeWorldBound(prim).ComputeAlignedRange()
    if box.IsEmpty():
        raise ConfigError(f"{path}: the USD asset has no geometry extent")
    lo, hi = box.GetMin(), box.GetMax()
    return UsdAssetInfo((lo[0], lo[1], lo[2]), (hi[0], hi[1], hi[2]),
                        str(UsdGeom.GetStageUpAxis(stage)),
                        float(UsdGeom.GetStageMetersPerUnit(stage)), str(prim.GetPath()))
