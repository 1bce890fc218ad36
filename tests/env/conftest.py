"""A small world for the environment tests: 30 m x 30 m, a few rocks, built once."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.session_cache import shared_folder

pytest.importorskip("mujoco")
pytest.importorskip("gymnasium")


_BASE = {"terrain": {"source": "procedural", "size_m": [30.0, 30.0], "post_m": 0.25,
                     "rms_height_m": 0.05},
         "craters": {"enabled": False},
         "rocks": {"k": 0.05, "mjcf_min_diameter_m": 0.3}}


@pytest.fixture(scope="session")
def nav_world(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The world, built once for every xdist worker (the sampler's cache in a shared folder)."""
    from marsscene.env import WorldSampler

    def sampler(folder: Path) -> WorldSampler:
        return WorldSampler(base=_BASE, count=1, seed=3, cache_dir=str(folder))

    folder = shared_folder(tmp_path_factory, "navworld", [_BASE, 3],
                           lambda folder: sampler(folder).path(0))
    return sampler(folder).path(0)


@pytest.fixture(scope="session")
def batch(tmp_path_factory: pytest.TempPathFactory) -> object:
    """The batched environments' two ``rocks`` worlds as a ``WorldBatch``, their scenes built
    once for every xdist worker."""
    pytest.importorskip("mujoco_warp")
    from marsscene.env import WorldSampler
    from marsscene.env.batch import WorldBatch

    def sampler(folder: Path) -> WorldSampler:
        return WorldSampler(base="rocks", count=2, cache_dir=str(folder))

    folder = shared_folder(tmp_path_factory, "rocksworlds", ["rocks", 2],
                           lambda folder: [sampler(folder).path(i) for i in range(2)])
    return WorldBatch.build(sampler(folder), pool=4)
