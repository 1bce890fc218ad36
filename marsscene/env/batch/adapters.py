"""The batched environment behind the interfaces trainers take: rsl-rl's ``VecEnv`` (tensors in a
``TensorDict``, the runner of ETH Zurich's legged-robot and Isaac Lab / mjlab training) and
Gymnasium's vector API (``gymnasium.vector.VectorEnv``, same-step autoreset as Isaac Lab's).

The policy input of :class:`RslRlVecEnv` is one flat vector a rover: the 17 ``observation``
values, then the height scan row by row (:func:`~marsscene.env.policy.policy_input`); a policy
trained on it runs on :class:`~marsscene.env.nav.RoverNavEnv`'s observations through the same
function.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from marsscene.env.batch.env import BatchNavEnv
from marsscene.env.policy import policy_input

__all__ = ["BatchVectorEnv", "RslRlVecEnv"]


class RslRlVecEnv:
    """:class:`BatchNavEnv` as rsl-rl's ``VecEnv`` (``rsl-rl-lib`` 3 or later; PyTorch).

    Observations: a ``TensorDict`` with the group ``"policy"`` (the flat vector); give the
    runner ``obs_groups={"actor": ["policy"], "critic": ["policy"]}``. ``dones`` is terminated
    or truncated; ``extras["time_outs"]`` the truncations (bootstrapped by PPO).
    """

    def __init__(self, env: BatchNavEnv) -> None:
        if env.bk.torch is None:
            from marsscene.errors import ConfigError

            raise ConfigError("rsl-rl trains PyTorch tensors: make the BatchNavEnv with "
                              "library='torch'")
        self.env = env
        self.num_envs, self.num_actions = env.num_envs, 2
        self.max_episode_length = env.steps_total
        self.device = env.bk.tdevice
        self.cfg = {"task": env.task, "observations": env.obs_config,
                    "reward": env.reward_config, "control_hz": env.control_hz}
        self._obs = env.observe()

    @property
    def episode_length_buf(self) -> Any:
        """Steps done in each rover's episode (rsl-rl may spread them at the start)."""
        return self.env.steps_done

    @episode_length_buf.setter
    def episode_length_buf(self, value: Any) -> None:
        self.env.steps_done = value.to(self.env.steps_done.dtype)

    def _group(self, obs: dict[str, Any]) -> Any:
        from tensordict import TensorDict

        return TensorDict({"policy": policy_input(obs)}, batch_size=[self.num_envs],
                          device=self.device)

    def get_observations(self) -> Any:
        return self._group(self._obs)

    def step(self, actions: Any) -> tuple[Any, Any, Any, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(actions)
        self._obs = obs
        dones = (terminated | truncated).long()
        return self._group(obs), reward.float(), dones, {"time_outs": truncated,
                                                         "termination": info["termination"]}


def _vector_base() -> Any:
    import gymnasium as gym

    return gym.vector.VectorEnv


class BatchVectorEnv(_vector_base()):  # type: ignore[misc]
    """:class:`BatchNavEnv` as a ``gymnasium.vector.VectorEnv`` (arrays of its library:
    PyTorch tensors on a GPU; wrap in ``gymnasium.wrappers.vector.TorchToNumpy`` for numpy).

    Autoreset is same-step: a rover whose episode ended comes back at the start of the next,
    its last observation in ``info["final_obs"]`` (where ``info["_final_obs"]``)."""

    def __init__(self, env: BatchNavEnv) -> None:
        from gymnasium import spaces
        from gymnasium.vector import AutoresetMode
        from gymnasium.vector.utils import batch_space

        self.env = env
        self.num_envs = env.num_envs
        self.metadata = {"autoreset_mode": AutoresetMode.SAME_STEP}
        self.single_observation_space = spaces.Dict(env.obs_config.spaces())
        self.single_action_space = spaces.Box(-1.0, 1.0, (2,), np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[dict[str, Any], dict[str, Any]]:
        if seed is not None:
            self.env.bk.seed(seed)
        return self.env.reset(), {}

    def step(self, actions: Any) -> tuple[Any, Any, Any, Any, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(actions)
        return obs, reward, terminated, truncated, {
            "termination": info["termination"], "final_obs": info["final_observation"],
            "_final_obs": terminated | truncated}
