"""coacd convex decomposition: convex parts, volume kept, on-disk cache by parameter hash."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

coacd = pytest.importorskip("coacd")
trimesh = pytest.importorskip("trimesh")


def l_shape() -> trimesh.Trimesh:
    a = trimesh.creation.box((1.0, 0.3, 0.3))
    b = trimesh.creation.box((0.3, 1.0, 0.3))
    b.apply_translation((0.35, 0.35, 0.0))
    mesh = a.union(b)
    assert mesh.is_watertight
    return mesh


def test_coacd_parts_are_convex_and_cached(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from marsscene.rocks.collision import convex_decompose

    mesh = l_shape()
    parts = convex_decompose(mesh, threshold=0.05, cache=tmp_path)
    assert len(parts) >= 2  # a concave L needs at least two convex pieces
    assert all(p.is_convex and p.is_watertight for p in parts)
    np.testing.assert_allclose(sum(p.volume for p in parts), mesh.volume, rtol=0.05)
    assert len(list(tmp_path.glob("*.npz"))) == 1

    def boom(*args: object, **kwargs: object) -> None:
        raise AssertionError("coacd must not run on a cache hit")

    monkeypatch.setattr(coacd, "run_coacd", boom)
    again = convex_decompose(mesh, threshold=0.05, cache=tmp_path)
    for a, b in zip(parts, again, strict=True):
        np.testing.assert_array_equal(a.vertices, b.vertices)
    # another parameter value is another cache entry (and would run coacd)
    with pytest.raises(AssertionError, match="cache hit"):
        convex_decompose(mesh, threshold=0.1, cache=tmp_path)


def test_cache_dir_honours_environment(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    from marsscene.rocks.collision import cache_dir

    monkeypatch.setenv("MARSSCENE_CACHE_DIR", str(tmp_path))
    assert cache_dir() == tmp_path / "coacd"
    monkeypatch.delenv("MARSSCENE_CACHE_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert cache_dir() == tmp_path / "xdg" / "marsscene" / "coacd"


def test_multi_part_prototype_exports(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A coacd-decomposed prototype (~1.5 s) exported to MJCF (one geom per part) and USD."""
    import dataclasses

    pytest.importorskip("pxr")
    pytest.importorskip("mujoco")

    import marsscene as ms
    from marsscene.export.mjcf import validate_mjcf
    from marsscene.rocks import RockConfig, make_prototypes

    monkeypatch.setenv("MARSSCENE_CACHE_DIR", str(tmp_path / "cache"))
    rcfg = RockConfig(prototypes=1, collision="coacd", coacd_threshold=0.02)
    protos = make_prototypes(rcfg, rng=np.random.default_rng(2))
    n_parts = len(protos[0].collision)
    assert n_parts >= 2
    assert all(p.is_convex for p in protos[0].collision)
    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "procedural", "size_m": [16.0, 16.0]},
        "rocks": {"collision": "coacd", "prototypes": 1, "coacd_threshold": 0.02,
                  "mjcf_max_rocks": 10},
    })
    scene = ms.build_scene(cfg.replace(rocks=dataclasses.replace(rcfg, collision="convex_hull",
                                                                 mjcf_max_rocks=10)), seed=2)
    scene = dataclasses.replace(scene, config=cfg, rock_prototypes=protos)
    ms.write_scene(scene, tmp_path / "out")
    model, _ = validate_mjcf(tmp_path / "out" / "mjcf" / "scene.xml")
    assert sum(model.geom(i).name.startswith("rock_") for i in range(model.ngeom)) == 10 * n_parts
    from pxr import Usd, UsdPhysics

    stage = Usd.Stage.Open(str(tmp_path / "out" / "scene.usda"))
    widest = int(np.argmax(scene.rocks.diameter_m))  # an obstacle rock: an instance prim
    assert scene.rocks.diameter_m[widest] >= cfg.export.rock_instance_min_diameter_m
    rock = stage.GetPrimAtPath(f"/World/RockColliders/rock_{widest}")  # prototype rock_00
    parts = rock.GetPrototype().GetChildren()
    assert len(parts) == n_parts and all(p.HasAPI(UsdPhysics.CollisionAPI) for p in parts)
