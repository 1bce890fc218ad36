"""Same inputs + same seed => identical bytes; stages draw from isolated streams."""

from __future__ import annotations

import dataclasses
import json
import random
from pathlib import Path

import numpy as np
import pytest

import marsscene as ms
from marsscene.seeding import STAGE_IDS, stage_rng

pytest.importorskip("pxr")

FILES = ("scene.usda", "assets/terrain.usdc", "assets/rock_colliders.usdc", "assets/rover.usda",
         "mjcf/scene.xml", "mjcf/assets/terrain.bin")


def _build(tmp: Path, seed: int, name: str, cfg: ms.SceneConfig) -> Path:
    out = tmp / name
    ms.write_scene(ms.build_scene(cfg, seed=seed), out)
    return out


def _manifest_without_timings(path: Path) -> dict:
    doc = json.loads((path / "manifest.json").read_text())
    doc.pop("timings_s")
    return doc


@pytest.fixture(scope="module")
def config() -> ms.SceneConfig:
    # The embedded default DEM, cropped by post spacing and with rocks from 0.2 m (28 000, not
    # 120 000: the rock collider layer costs ~30 us a rock to write) to keep the test quick.
    return ms.SceneConfig.from_dict({"terrain": {"post_m": 0.5}, "rocks": {"d_min_m": 0.2},
                                     "export": {"rover": True}})


def test_same_seed_gives_identical_bytes(tmp_path: Path, config: ms.SceneConfig) -> None:
    a = _build(tmp_path, 7, "a", config)
    np.random.seed(12456)  # disturb global state: it must not matter
    random.seed(99)
    np.random.standard_normal(1000)
    b = _build(tmp_path, 7, "b", config)
    for rel in FILES:
        assert (a / rel).read_bytes() == (b / rel).read_bytes(), rel
    assert _manifest_without_timings(a) == _manifest_without_timings(b)
    assert (a / "manifest.json").read_bytes() != b""


def test_different_seed_changes_terrain_detail(tmp_path: Path, config: ms.SceneConfig) -> None:
    a = _build(tmp_path, 7, "a", config)
    c = _build(tmp_path, 8, "c", config)
    za = np.frombuffer((a / "mjcf/assets/terrain.bin").read_bytes()[8:], "<f4")
    zc = np.frombuffer((c / "mjcf/assets/terrain.bin").read_bytes()[8:], "<f4")
    assert za.shape == zc.shape and not np.array_equal(za, zc)


def test_stage_streams_are_independent_and_stable() -> None:
    draws = {name: stage_rng(7, name).random(4) for name in STAGE_IDS}
    assert len({tuple(v) for v in draws.values()}) == len(STAGE_IDS)
    assert np.array_equal(stage_rng(7, "rocks").random(4), draws["rocks"])
    assert STAGE_IDS["terrain"] == 0 and STAGE_IDS["craters"] == 1 and STAGE_IDS["rocks"] == 2


def test_changing_one_stage_leaves_other_stages_draws_unchanged() -> None:
    base = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [16, 16]}})
    a = ms.build_scene(base, seed=4)
    other = base.replace(
        lighting=dataclasses.replace(base.lighting, enabled=False),
        rocks=dataclasses.replace(base.rocks, enabled=False),
    )
    b = ms.build_scene(other, seed=4)
    assert np.array_equal(a.heightfield.z_m, b.heightfield.z_m)


def test_rock_parameters_do_not_move_a_single_crater() -> None:
    base = ms.SceneConfig.from_dict(
        {"terrain": {"source": "procedural", "size_m": [40, 40], "rms_height_m": 0.3},
         "craters": {"d_min_m": 1.0, "d_max_m": 10.0}}
    )
    a = ms.build_scene(base, seed=11)
    b = ms.build_scene(
        base.replace(rocks=dataclasses.replace(base.rocks, k=0.15, d_min_m=0.3)), seed=11
    )
    assert a.craters is not None and b.craters is not None and len(a.craters) > 0
    assert np.array_equal(a.craters.center_xy_m, b.craters.center_xy_m)
    assert np.array_equal(a.craters.diameter_m, b.craters.diameter_m)
    assert np.array_equal(a.heightfield.z_m, b.heightfield.z_m)
    assert a.rocks is not None and b.rocks is not None and len(a.rocks) != len(b.rocks)


def test_crater_parameters_do_not_change_rock_draws() -> None:
    base = ms.SceneConfig.from_dict(
        {"terrain": {"source": "procedural", "size_m": [40, 40], "rms_height_m": 0.3},
         "rocks": {"placement": "uniform", "max_slope_deg": 90.0}}
    )
    a = ms.build_scene(base, seed=11)
    b = ms.build_scene(
        base.replace(craters=dataclasses.replace(base.craters, age_ga=1.0, d_max_m=15.0)),
        seed=11,
    )
    assert a.rocks is not None and b.rocks is not None
    assert not np.array_equal(a.heightfield.z_m, b.heightfield.z_m)  # craters differ
    np.testing.assert_array_equal(a.rocks.diameter_m, b.rocks.diameter_m)
    np.testing.assert_array_equal(a.rocks.position_xyz_m[:, :2], b.rocks.position_xyz_m[:, :2])
