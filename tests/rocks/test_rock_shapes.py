"""Rock prototypes: watertight visual meshes, convex collision parts, unit frame, seeding."""

from __future__ import annotations

import numpy as np

import marsscene as ms
from marsscene.rocks import RockConfig, make_prototypes


def test_prototypes_watertight_convex_and_in_unit_frame() -> None:
    cfg = RockConfig(prototypes=6, size_classes_m=(0.3, 1.0))
    protos = make_prototypes(cfg, rng=np.random.default_rng(2))
    assert [p.size_class for p in protos] == [0, 1, 2, 0, 1, 2]
    assert len({p.name for p in protos}) == 6
    for p in protos:
        assert p.visual.is_watertight and p.visual.is_winding_consistent and p.visual.is_volume
        assert p.visual.volume > 0.3  # a rock, not a sliver (unit box volume is 1)
        np.testing.assert_allclose(p.visual.bounds, [[-0.5, -0.5, 0.0], [0.5, 0.5, 1.0]],
                                   atol=1e-6)
        # flat base: a sizeable part of the surface lies on z = 0
        base = p.visual.area_faces[np.abs(p.visual.triangles[:, :, 2]).max(axis=1) < 1e-6].sum()
        assert base > 0.1
        (hull,) = p.collision  # convex hull by default: one part
        assert hull.is_convex and hull.is_watertight and hull.volume > 0
        assert len(hull.vertices) <= 64  # PhysX/MuJoCo friendly
        # an inscribed hull through the rock's support points: keeps the bounding box, and
        # holds ~95 % of the rock's volume (the rest is surface noise and hidden concavity)
        np.testing.assert_allclose(hull.bounds, p.visual.bounds, atol=1e-9)
        assert 0.9 * p.visual.volume < hull.volume < 1.05 * p.visual.volume
        # hull vertices are points of the rock surface (support points)
        gap = np.abs(hull.vertices[:, None, :] - p.visual.vertices[None, :, :]).sum(-1).min(1)
        assert gap.max() < 1e-9
    # different prototypes differ
    assert not np.allclose(protos[0].visual.volume, protos[3].visual.volume)


def test_prototypes_are_seeded_and_isolated_from_the_population() -> None:
    a = make_prototypes(RockConfig(), rng=np.random.default_rng(7))
    b = make_prototypes(RockConfig(), rng=np.random.default_rng(7))
    for pa, pb in zip(a, b, strict=True):
        np.testing.assert_array_equal(pa.visual.vertices, pb.visual.vertices)
        np.testing.assert_array_equal(pa.visual.faces, pb.visual.faces)
    base = {"terrain": {"source": "procedural", "size_m": [20.0, 20.0]}}
    s1 = ms.build_scene(ms.SceneConfig.from_dict({**base, "rocks": {"k": 0.1}}), seed=3)
    s2 = ms.build_scene(ms.SceneConfig.from_dict({**base, "rocks": {"k": 0.2}}), seed=3)
    assert s1.rock_prototypes is not None and s2.rock_prototypes is not None
    for pa, pb in zip(s1.rock_prototypes, s2.rock_prototypes, strict=True):
        np.testing.assert_array_equal(pa.visual.vertices, pb.visual.vertices)
    assert s1.rocks is not None and s2.rocks is not None and len(s2.rocks) > len(s1.rocks)
    np.testing.assert_array_equal(s1.heightfield.z_m, s2.heightfield.z_m)
