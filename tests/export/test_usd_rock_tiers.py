"""The rock colliders' two tiers in USD, read back through pxr and OpenUSD's physics parser:
obstacle rocks as instance prims, the other colliding rocks merged per tile (issue 42)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import marsscene as ms
from marsscene.export.config import ExportConfig
from marsscene.rover.config import RoverConfig

pytest.importorskip("pxr")
from pxr import Usd, UsdGeom, UsdPhysics

from marsscene.export.usd.rock_colliders_read import merged_rocks
from tests.support.usd import physics_parse, rock_collider_tiers

CFG = {
    "terrain": {"source": "procedural", "size_m": [60.0, 60.0], "post_m": 0.5},
    "rocks": {"k": 0.05, "d_min_m": 0.3},
    "craters": {"d_min_m": 2.0},
    "export": {"formats": ["usd"]},
}


@pytest.fixture(scope="module")
def scene() -> ms.Scene:
    return ms.build_scene(ms.SceneConfig.from_dict(CFG), seed=5)


@pytest.fixture(scope="module")
def written(scene: ms.Scene, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("tiers") / "scene"
    ms.write_scene(scene, out)
    return out


def test_rock_colliders_sit_where_the_rocks_are(scene: ms.Scene, written: Path) -> None:
    """Instances: their transforms put unit-frame points where the rock table does. Merged
    tiles: every vertex, taken back to its rock's unit frame, is a vertex of the rock's
    prototype collision hull, and each rock's triangles enclose the volume of its small hull
    scaled to the rock (a closed, outward surface)."""
    from marsscene.rocks.merged import small_hulls
    from marsscene.transforms import quat_to_matrix

    stage = Usd.Stage.Open(str(written / "scene.usda"))
    cache = UsdGeom.XformCache()
    rocks = scene.rocks
    rot = quat_to_matrix(rocks.orientation_wxyz)
    big = np.flatnonzero(rocks.diameter_m >= ExportConfig().rock_instance_min_diameter_m)
    probe = np.array([[0.4, -0.3, 0.9], [-0.5, 0.5, 0.0]])  # unit-frame points
    expect = np.einsum("nij,nkj->nki", rot[big], probe[None] * rocks.scale_xyz_m[big, None]) \
        + rocks.position_xyz_m[big, None]
    got = np.zeros_like(expect)
    for j, i in enumerate(big):
        prim = stage.GetPrimAtPath(f"/World/RockColliders/rock_{i}")
        assert prim.IsInstance()
        m = np.asarray(cache.GetLocalToWorldTransform(prim))
        got[j] = np.c_[probe, np.ones(2)] @ m[:, :3]
        part = prim.GetPrototype().GetChildren()[0]
        assert part.HasAPI(UsdPhysics.CollisionAPI)
        assert UsdPhysics.MeshCollisionAPI(part).GetApproximationAttr().Get() == "convexHull"
    np.testing.assert_allclose(got, expect, atol=1e-9)
    hull_volume = np.array([h.volume for h in small_hulls(tuple(scene.rock_prototypes))])
    for tile in merged_rocks(stage):
        prim = stage.GetPrimAtPath(tile.path)
        assert prim.HasAPI(UsdPhysics.CollisionAPI)
        assert UsdPhysics.MeshCollisionAPI(prim).GetApproximationAttr().Get() == "none"
        face_rock = tile.rows[tile.rock_of_face()]
        vert_rock = np.zeros(len(tile.points_m), dtype=np.int64)
        vert_rock[tile.faces] = face_rock[:, None]
        local = np.einsum("nji,nj->ni", rot[vert_rock],  # R^T (p - position) / scale
                          tile.points_m - rocks.position_xyz_m[vert_rock]) \
            / rocks.scale_xyz_m[vert_rock]
        for p, proto in enumerate(scene.rock_prototypes):
            on = rocks.prototype[vert_rock] == p
            hull = np.concatenate([part.vertices for part in proto.collision])
            gap = np.linalg.norm(local[on, None] - hull[None], axis=2).min(axis=1)
            assert gap.max(initial=0.0) < 1e-3
        a, b, c = (tile.points_m[tile.faces[:, k]].astype(np.float64) - tile.points_m[
            tile.faces[:, 0]].mean(axis=0) for k in range(3))
        volume = np.add.reduceat(np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0,
                                 tile.first_face)
        expect_v = hull_volume[rocks.prototype[tile.rows]] * rocks.scale_xyz_m[tile.rows].prod(1)
        np.testing.assert_allclose(volume, expect_v, rtol=1e-3)


def test_rock_collider_min_diameter_keeps_the_wide_rocks_only(
        scene: ms.Scene, tmp_path: Path) -> None:
    """``export.rock_collider_min_diameter_m``: the parser reports colliders for exactly the
    rocks at least that wide, each under its rock-table row (an instance or a merged row)."""
    d_min = float(np.median(scene.rocks.diameter_m))
    cfg = dict(CFG, export={**CFG["export"], "rock_collider_min_diameter_m": d_min})
    small = ms.build_scene(ms.SceneConfig.from_dict(cfg), seed=5)
    ms.write_scene(small, tmp_path / "s")
    stage = Usd.Stage.Open(str(tmp_path / "s" / "scene.usda"))
    instances, tiles = rock_collider_tiers(stage, physics_parse(stage)["MeshShape"][0])
    wide = np.flatnonzero(small.rocks.diameter_m >= d_min)
    assert 0 < len(wide) < len(small.rocks)
    rows = {int(p.split("/")[3].split("_")[1]) for p in instances}
    rows |= {int(r) for t in tiles for r in t.rows}
    assert rows == set(wide.tolist())
    count = stage.GetPrimAtPath("/World/RockColliders").GetAttribute("marsscene:rockCount")
    assert count.Get() == len(wide)


def test_every_collider_its_own_prim_on_request(scene: ms.Scene, tmp_path: Path) -> None:
    """``rock_instance_min_diameter_m = 0``: no merged tiles, one instance per rock (the
    layout for users who need each rock as a prim); ``rock_collider_min_diameter_m`` beyond
    every rock: no colliders at all, the render rocks unchanged."""
    for key, value in (("rock_instance_min_diameter_m", 0.0),
                       ("rock_collider_min_diameter_m", 100.0)):
        cfg = dict(CFG, export={**CFG["export"], key: value})
        ms.write_scene(ms.build_scene(ms.SceneConfig.from_dict(cfg), seed=5), tmp_path / key)
        stage = Usd.Stage.Open(str(tmp_path / key / "scene.usda"))
        instances, tiles = rock_collider_tiers(stage, physics_parse(stage)["MeshShape"][0])
        assert not tiles
        n = len(scene.rocks) if value == 0.0 else 0
        assert len({p.split("/")[3] for p in instances}) == n
        assert stage.GetPrimAtPath("/World/Rocks/Instancer")


def test_collider_sizes_follow_the_rovers_wheel() -> None:
    """The two rock sizes of the collider tiers are stated from the wheel: an obstacle rock
    (``OBSTACLE_MIN_DIAMETER_M``) stands about a wheel radius tall at the mean exposed height,
    a contact rock (``CONTACT_MIN_DIAMETER_M``) under half a wheel radius even at the tallest,
    and the MJCF's contact rocks start where the USD colliders do."""
    from marsscene.export.config import CONTACT_MIN_DIAMETER_M, OBSTACLE_MIN_DIAMETER_M
    from marsscene.rocks import RockConfig

    low, high = RockConfig().range_of("height_ratio")
    wheel = RoverConfig().wheel_radius_m
    assert OBSTACLE_MIN_DIAMETER_M * (low + high) / 2 == pytest.approx(wheel, rel=0.15)
    assert CONTACT_MIN_DIAMETER_M * high < 0.5 * wheel
    assert RockConfig().mjcf_min_diameter_m == ExportConfig().rock_collider_min_diameter_m
