"""Rock export round trips: USD PointInstancer (pxr + UsdValidation), MJCF (MuJoCo compile,
step, a box resting on a rock), the CSV catalogue, byte reproducibility."""

from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import marsscene as ms
from marsscene.rocks import RockTable
from marsscene.rocks.report import mjcf_rock_selection

pxr = pytest.importorskip("pxr")
mujoco = pytest.importorskip("mujoco")

BASE = {
    "terrain": {"source": "procedural", "size_m": [24.0, 20.0], "post_m": 0.25,
                "rms_height_m": 0.2},
    "rocks": {"k": 0.1, "d_min_m": 0.1, "mjcf_max_rocks": 40},
}


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> tuple[ms.Scene, Path]:
    scene = ms.build_scene(ms.SceneConfig.from_dict(BASE), seed=5)
    out = tmp_path_factory.mktemp("rocks") / "scene"
    ms.write_scene(scene, out)
    return scene, out


@pytest.mark.usd
def test_usd_round_trip(written: tuple[ms.Scene, Path]) -> None:
    from pxr import Usd, UsdGeom, UsdPhysics

    from marsscene.export.usd import validate_stage
    from marsscene.export.usd.rock_colliders_read import merged_rocks

    scene, out = written
    rocks = scene.rocks
    assert rocks is not None and scene.rock_prototypes is not None and len(rocks) > 500
    assert (out / "assets" / "rocks.usdc").read_bytes()[:8] == b"PXR-USDC"
    stage = Usd.Stage.Open(str(out / "scene.usda"))
    assert validate_stage(stage) == []
    inst = UsdGeom.PointInstancer(stage.GetPrimAtPath("/World/Rocks/Instancer"))
    assert inst
    targets = [str(p) for p in inst.GetPrototypesRel().GetTargets()]
    assert targets == [f"/World/Rocks/Instancer/Prototypes/rock_{i:02d}"
                       for i in range(len(scene.rock_prototypes))]
    np.testing.assert_array_equal(np.asarray(inst.GetProtoIndicesAttr().Get()), rocks.prototype)
    np.testing.assert_allclose(np.asarray(inst.GetPositionsAttr().Get()), rocks.position_xyz_m,
                               atol=1e-5)
    np.testing.assert_allclose(np.asarray(inst.GetScalesAttr().Get()), rocks.scale_xyz_m,
                               rtol=1e-6)
    quat = np.array([[q.GetReal(), *q.GetImaginary()] for q in inst.GetOrientationsAttr().Get()])
    np.testing.assert_allclose(quat, rocks.orientation_wxyz, atol=2e-3)
    # each instancer prototype: a visual mesh (render only: no collision under the instancer)
    for path in targets:
        assert UsdGeom.Mesh(stage.GetPrimAtPath(f"{path}/Visual"))
        assert not [p for p in Usd.PrimRange(stage.GetPrimAtPath(path))
                    if p.HasAPI(UsdPhysics.CollisionAPI)]
    # the colliders: one instance per obstacle rock of a class prototype with convex-hull
    # parts; the other rocks from the collider minimum up in merged meshes
    export = scene.config.export
    big = np.flatnonzero(rocks.diameter_m >= export.rock_instance_min_diameter_m)
    mid = np.flatnonzero((rocks.diameter_m >= export.rock_collider_min_diameter_m)
                         & (rocks.diameter_m < export.rock_instance_min_diameter_m))
    merged = np.concatenate([t.rows for t in merged_rocks(stage)])
    assert len(big) and len(mid) and sorted(merged.tolist()) == mid.tolist()
    for i in (big[0], big[-1]):
        prim = stage.GetPrimAtPath(f"/World/RockColliders/rock_{i}")
        parts = prim.GetPrototype().GetChildren()
        assert prim.IsInstance() and parts
        for part in parts:
            assert part.HasAPI(UsdPhysics.CollisionAPI)
            approx = UsdPhysics.MeshCollisionAPI(part).GetApproximationAttr().Get()
            assert approx == UsdPhysics.Tokens.convexHull
            assert UsdGeom.Imageable(part).GetPurposeAttr().Get() == UsdGeom.Tokens.guide
    # world-space instance transforms: prototype base (0,0,0) lands on the rock position
    xforms = inst.ComputeInstanceTransformsAtTime(Usd.TimeCode.Default(), Usd.TimeCode.Default())
    base = np.array([np.asarray(m)[3, :3] for m in xforms[:50]])
    np.testing.assert_allclose(base, rocks.position_xyz_m[:50], atol=1e-4)


@pytest.mark.sim
def test_mjcf_compiles_steps_and_follows_the_rule(written: tuple[ms.Scene, Path]) -> None:
    from marsscene.export.mjcf import validate_mjcf

    scene, out = written
    assert scene.rocks is not None
    model, _ = validate_mjcf(out / "mjcf" / "scene.xml")
    sel = mjcf_rock_selection(scene.rocks, scene.config.rocks)
    assert len(sel) == 40  # capped by mjcf_max_rocks
    assert scene.rocks.diameter_m[sel].min() >= np.sort(scene.rocks.diameter_m)[-40]
    names = [model.geom(i).name for i in range(model.ngeom)]
    assert sum(n.startswith("rock_") for n in names) == 40
    assert any("rocks/mjcf" in n and "largest first" in n for n in scene.provenance.notes)
    summary = scene.provenance.extra["rocks"]
    assert summary["count"] == len(scene.rocks) and summary["mjcf_rocks"] == 40
    assert any(m.stage == "rocks" and "Golombek" in m.citation for m in scene.provenance.models)
    csv = np.loadtxt(out / "rocks.csv", delimiter=",", skiprows=1)
    assert csv.shape == (len(scene.rocks), 9)
    np.testing.assert_allclose(csv[:, 1:4], scene.rocks.position_xyz_m, atol=6e-5)
    np.testing.assert_allclose(csv[:, 4], scene.rocks.diameter_m, atol=6e-5)
    np.testing.assert_array_equal(csv[:, 7], scene.rocks.prototype)
    assert sorted(np.flatnonzero(csv[:, 8])) == sorted(sel)


@pytest.mark.sim
def test_box_dropped_on_a_large_rock_rests_on_it(tmp_path: Path) -> None:
    from marsscene.export.mjcf import to_mjcf

    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "procedural", "size_m": [10.0, 10.0], "rms_height_m": 0.0},
        "rocks": {"d_min_m": 0.5},
    })
    scene = ms.build_scene(cfg, seed=1)
    rock = RockTable(np.array([[0.0, 0.0, -0.1]]), [1.6], [0.7], [0.1], np.array([[1, 0, 0, 0]]),
                     [2])
    scene = dataclasses.replace(scene, rocks=rock)
    xml, assets = to_mjcf(scene)
    root = ET.fromstring(xml)
    world = root.find("worldbody")
    assert world is not None
    body = ET.SubElement(world, "body", name="box", pos="0.05 -0.03 1.5")
    ET.SubElement(body, "freejoint")
    ET.SubElement(body, "geom", name="box", type="box", size="0.08 0.08 0.08", mass="5")
    for rel, blob in assets.items():
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_bytes(blob)
    (tmp_path / "scene.xml").write_text(ET.tostring(root, encoding="unicode"))
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "scene.xml"))
    data = mujoco.MjData(model)
    for _ in range(int(3.0 / model.opt.timestep)):
        mujoco.mj_step(model, data)
    assert not any(w.number for w in data.warning)
    box_z = data.qpos[2]
    assert np.linalg.norm(data.qvel[:3]) < 0.05  # at rest
    # the box rests on the rock, far above the ground (z = 0) ...
    assert box_z > 0.4
    # ... with its underside on the rock's surface (ray cast down past the box)
    geomid = np.zeros(1, np.int32)
    hit = mujoco.mj_ray(model, data, np.array([data.qpos[0], data.qpos[1], 3.0]),
                        np.array([0.0, 0.0, -1.0]), None, 1, model.body("box").id, geomid)
    assert model.geom(int(geomid[0])).name.startswith("rock_")
    surface_z = 3.0 - hit
    assert abs((box_z - 0.08) - surface_z) < 0.08  # tilted box on a curved top


@pytest.mark.sim
def test_bake_rule_raises_the_hfield(tmp_path: Path) -> None:
    from marsscene.export.mjcf import to_mjcf, validate_mjcf

    cfg = dict(BASE, rocks={**BASE["rocks"], "mjcf_small_rocks": "bake"})
    scene = ms.build_scene(ms.SceneConfig.from_dict(cfg), seed=5)
    _, drop_assets = to_mjcf(dataclasses.replace(
        scene, config=scene.config.replace(rocks=dataclasses.replace(
            scene.config.rocks, mjcf_small_rocks="drop"))))
    xml, assets = to_mjcf(scene)
    assert assets["assets/terrain.bin"] != drop_assets["assets/terrain.bin"]
    for rel, blob in assets.items():
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_bytes(blob)
    (tmp_path / "scene.xml").write_text(xml)
    model, _ = validate_mjcf(tmp_path / "scene.xml")
    z_range_m = model.hfield_size[0][2]
    assert z_range_m > float(np.ptp(scene.heightfield.z_m))


def test_rock_outputs_are_byte_reproducible(tmp_path: Path) -> None:
    outs = []
    for i in range(2):
        np.random.seed(1000 + i)  # global state must not matter
        scene = ms.build_scene(ms.SceneConfig.from_dict(BASE), seed=5)
        ms.write_scene(scene, tmp_path / f"s{i}")
        outs.append(tmp_path / f"s{i}")
    objs = sorted(p.relative_to(outs[0]).as_posix() for p in outs[0].glob("mjcf/assets/*.obj"))
    assert objs
    for rel in ("assets/rocks.usdc", "rocks.csv", "mjcf/scene.xml", "scene.usda", *objs):
        assert (outs[0] / rel).read_bytes() == (outs[1] / rel).read_bytes(), rel


def _formatted(values: np.ndarray, decimals: int) -> list[str]:
    from marsscene.export.catalog_rocks import _Field, _text_rows

    return _text_rows([_Field(values, decimals, "\n")], len(values)).decode().splitlines()


def test_catalog_fixed_point_formatting() -> None:
    values = np.array([0.0, -0.00004, 1.23456, -12.5, 123.0001, -0.5, 9.99999, -40000.0001,
                       99.99999, 123456789.5])
    assert _formatted(values, 4) == [
        "0.0000", "0.0000", "1.2346", "-12.5000", "123.0001", "-0.5000", "10.0000",
        "-40000.0001", "100.0000", "123456789.5000"]
    assert _formatted(np.array([0.0, 7, 10, 9999]), 0) == ["0", "7", "10", "9999"]


def test_catalog_formatting_across_chunks_matches_python() -> None:
    from marsscene.export.catalog_rocks import _CHUNK_ROWS

    rng = np.random.default_rng(4)
    n = 2 * _CHUNK_ROWS + 123  # three chunks, the last one partial
    values = rng.normal(0, 1, n) * 10.0 ** rng.integers(-5, 6, n)
    text = _formatted(values, 4)
    assert len(text) == n
    assert text == [f"{v:.4f}".replace("-0.0000", "0.0000") for v in values]  # no signed 0
    ints = rng.integers(0, 10**7, n).astype(np.float64)
    assert _formatted(ints, 0) == [str(int(i)) for i in ints]
