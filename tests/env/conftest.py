"""A small world for the environment tests: 30 m x 30 m, a few rocks, built once."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("mujoco")
pytest.importorskip("gymnasium")


@pytest.fixture(scope="session")
def nav_world(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from marsscene.env import WorldSampler

    sampler = WorldSampler(base={"terrain": {"source": "procedural", "size_m": [30.0, 30.0],
                                             "post_m": 0.25, "rms_height_m": 0.05},
                                 "craters": {"enabled": False},
                                 "rocks": {"k": 0.05, "mjcf_min_diameter_m": 0.3}},
                           count=1, seed=3, cache_dir=str(tmp_path_factory.mktemp("worlds")))
    return sampler.path(0)
