"""Rocks outside the route corridor are left out of the simulation; nearby ones stay."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import marsscene as ms
from marsscene.sim.corridor import distance_to_polyline

mujoco = pytest.importorskip("mujoco")
from marsscene.sim.rover_sim import RoverSim  # noqa: E402


def test_distance_to_polyline_matches_geometry() -> None:
    line = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]])
    p = np.array([[5.0, 3.0], [-4.0, 3.0], [13.0, 5.0], [12.0, 14.0]])
    np.testing.assert_allclose(distance_to_polyline(p, line), [3.0, 5.0, 3.0, np.hypot(2, 4)])
    np.testing.assert_allclose(distance_to_polyline(p[:1], line[:1]), [np.hypot(5, 3)])


@pytest.fixture(scope="module")
def rocky_scene(tmp_path_factory: pytest.TempPathFactory) -> Path:
    cfg = ms.SceneConfig.from_dict(
        {"terrain": {"source": "procedural", "size_m": [60, 60], "rms_height_m": 0.05},
         "craters": {"enabled": False}, "lighting": {"enabled": False},
         "rocks": {"k": 0.2, "d_min_m": 0.3, "placement": "uniform", "mjcf_max_rocks": 300},
         "export": {"formats": ["mjcf"]}}
    )
    out = tmp_path_factory.mktemp("rocky") / "scene"
    ms.write_scene(ms.build_scene(cfg, seed=2), out)
    return out


def test_corridor_keeps_exactly_the_rocks_near_the_route(rocky_scene: Path) -> None:
    full = RoverSim(rocky_scene, settle_s=0.0)
    kept, total = full.rocks_kept
    assert kept == total > 50
    route = np.array([[-20.0, -20.0], [0.0, -20.0], [0.0, 0.0]])
    sim = RoverSim(rocky_scene, settle_s=0.0, contact_corridor_xy_m=route, contact_corridor_m=8.0)
    m = full.model
    rock_ids = [g for g in range(m.ngeom) if m.geom(g).name.startswith("rock_")]
    xy = full.data.geom_xpos[rock_ids, :2]
    near = distance_to_polyline(xy, route) <= 8.0
    assert sim.rocks_kept == (int(near.sum()), total)
    assert 0 < sim.rocks_kept[0] < total
    kept_names = {sim.model.geom(g).name for g in range(sim.model.ngeom)}
    expected = {m.geom(g).name for g, n in zip(rock_ids, near, strict=True) if n}
    assert {n for n in kept_names if n.startswith("rock_")} == expected
    assert sim.model.ngeom == full.model.ngeom - (total - sim.rocks_kept[0])
