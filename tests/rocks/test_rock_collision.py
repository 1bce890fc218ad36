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


@pytest.mark.slow
def test_pipeline_with_coacd_parts(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """~15 s: three prototypes decomposed by coacd, exported to MJCF and USD."""
    import marsscene as ms
    from marsscene.export.mjcf import validate_mjcf

    monkeypatch.setenv("MARSSCENE_CACHE_DIR", str(tmp_path / "cache"))
    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "procedural", "size_m": [20.0, 20.0]},
        "rocks": {"collision": "coacd", "prototypes": 3, "coacd_threshold": 0.03,
                  "mjcf_max_rocks": 30},
    })
    scene = ms.build_scene(cfg, seed=2)
    assert scene.rock_prototypes is not None
    assert max(len(p.collision) for p in scene.rock_prototypes) > 1
    ms.write_scene(scene, tmp_path / "out")
    model, _ = validate_mjcf(tmp_path / "out" / "mjcf" / "scene.xml")
    assert model.ngeom > 31  # several convex parts per exported rock
