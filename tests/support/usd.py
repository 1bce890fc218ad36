"""USD read-back helpers shared by the export tests: OpenUSD's physics parser and the two tiers
of rock colliders."""

from __future__ import annotations

from typing import Any

from pxr import Usd, UsdPhysics

from marsscene.export.usd.rock_colliders_read import merged_rocks


def physics_parse(stage: Usd.Stage) -> dict[str, tuple[list[str], list[Any]]]:
    """OpenUSD's physics parser over ``/World``: per descriptor type, (prim paths, descs)."""
    load = getattr(UsdPhysics, "UsdPhysicsLoadStageFromPrimRange", None) or \
        UsdPhysics.LoadUsdPhysicsFromRange
    return {str(k).rsplit(".", 1)[-1]: ([str(p) for p in v[0]], list(v[1]))
            for k, v in load(stage, ["/World"]).items()}


def rock_collider_tiers(stage: Usd.Stage, meshes: list[str]) -> tuple[list[str], list[Any]]:
    """The parser's rock collider paths of the obstacle instances' parts, and the merged
    tiles (checked to be exactly the merged meshes the parser reported)."""
    rocks = [p for p in meshes if p.startswith("/World/RockColliders/")]
    tiles = merged_rocks(stage)
    assert sorted(p for p in rocks if "/Merged/" in p) == sorted(t.path for t in tiles)
    return [p for p in rocks if "/Merged/" not in p], tiles
