"""The navigation benchmark's ``policy`` method (``PolicyController``) feeds a trained policy
exactly what :class:`RoverNavEnv` gives it, step by step: the observation vector, the height
scan and the navcam depth."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import marsscene.env as me
from marsscene.benchmark.nav.methods import PolicyController
from marsscene.env.cnn_policy import load_policy
from marsscene.env.observe import HeightScan
from tests.support.nav_policies import goal_seeking_mlp, ground_seeing_cnn


@pytest.mark.parametrize("kind", ["mlp", "cnn"])
def test_the_controller_observes_as_the_environment(nav_world: Path, tmp_path: Path,
                                                    kind: str) -> None:
    path = (goal_seeking_mlp(tmp_path / "p.npz", HeightScan(size_m=2.0, resolution_m=0.5))
            if kind == "mlp" else ground_seeing_cnn(tmp_path / "p.npz"))
    policy = load_policy(path)
    env = me.RoverNavEnv(nav_world, observations=policy.observations(), control_hz=5.0,
                         physics_hz=100.0)
    try:
        obs, _ = env.reset(seed=1)
        assert env._world is not None and env._session is not None
        ctl = PolicyController(env._world.sim, env.episode.goal_xy_m, policy)
        keys = ("observation", "height_scan") if kind == "mlp" else ("observation", "depth")
        for _ in range(6):
            mine = ctl.observe(env._session.observe())
            for key in keys:
                np.testing.assert_array_equal(mine[key], obs[key], err_msg=key)
            action = policy(obs)
            ctl.last_action = np.clip(action, -1.0, 1.0)
            obs, *_ = env.step(action)
        assert np.abs(obs["observation"][15:17]).max() > 0.1  # the actions were fed back
    finally:
        env.close()
