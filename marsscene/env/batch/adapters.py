"""The batched environment behind the interfaces trainers take: rsl-rl's ``VecEnv`` (tensors in a
``TensorDict``, the runner of ETH Zurich's legged-robot and Isaac Lab / mjlab training) and
Gymnasium's vector API (``gymnasium.vector.VectorEnv``, same-step autoreset as Isaac Lab's).

The policy input of :class:`RslRlVecEnv` is one flat vector a rover: the 17 ``observation``
values, then the height scan row by row (:func:`~marsscene.env.policy.policy_input`); a policy
trained on it runs on :class:`~marsscene.env.nav.RoverNavEnv`'s observations through the same
function. The camera's and the LiDAR's observations (:mod:`.sensing`) come as groups of
their own, channels first, for a CNN encoder (rsl-rl's ``ActorCriticCNN`` takes the groups of
three dimensions a rover to its CNNs, the others to its MLP): ``"rgb"`` (N, 3, H, W) the sRGB
codes over 255, ``"depth"`` (N, 1, H, W) in m and ``"lidar"`` (N, 2, channels, columns), the
range in m then the mask (1: a return), float32.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from marsscene.env.batch.env import BatchNavEnv
from marsscene.env.policy import policy_input

__all__ = ["BatchVectorEnv", "RslRlVecEnv", "groups"]


class RslRlVecEnv:
    """:class:`BatchNavEnv` as rsl-rl's ``VecEnv`` (``rsl-rl-lib`` 3 or later; PyTorch).

    Observations: a ``TensorDict`` with the group ``"policy"`` (the flat vector) and, where
    observed, ``"rgb"``, ``"depth"`` and ``"lidar"`` (the module's docstring); give the runner e.g.
    ``obs_groups={"actor": ["policy"], "critic": ["policy"]}`` (a blind MLP) or
    ``{"actor": ["policy", "depth"], "critic": ["policy", "depth"]}``. ``dones`` is terminated
    or truncated; ``extras["time_outs"]`` the truncations (bootstrapped by PPO). rsl-rl does
    not read the final observation: make the environment with ``final_sensors=False`` to cast
    its camera and LiDAR once a step instead of twice.
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

        return TensorDict(groups(obs), batch_size=[self.num_envs], device=self.device)

    def get_observations(self) -> Any:
        return self._group(self._obs)

    def step(self, actions: Any) -> tuple[Any, Any, Any, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(actions)
        self._obs = obs
        dones = (terminated | truncated).long()
        return self._group(obs), reward.float(), dones, {"time_outs": truncated,
                                                         "termination": info["termination"]}


def groups(obs: dict[str, Any]) -> dict[str, Any]:
    """rsl-rl's observation groups of the batch's observations (PyTorch tensors or numpy
    arrays): ``"policy"``, and ``"rgb"``, ``"depth"`` and ``"lidar"`` where observed."""
    from array_api_compat import array_namespace

    out = {"policy": policy_input(obs)}
    if "rgb" in obs:
        xp = array_namespace(obs["rgb"])
        out["rgb"] = xp.astype(obs["rgb"], xp.float32) / 255.0
    if "depth" in obs:
        out["depth"] = obs["depth"]
    if "lidar_range" in obs:
        rng = obs["lidar_range"]
        xp = array_namespace(rng)
        out["lidar"] = xp.concat([rng, xp.astype(obs["lidar_mask"], rng.dtype)], axis=1)
    return out


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
        self.single_observation_space = spaces.Dict(env.spaces())
        self.single_action_space = spaces.Box(-1.0, 1.0, (2,), np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[dict[str, Any], dict[str, Any]]:
        if seed is not None:
            self.env.seed(seed)
        return self.env.reset(), {}

    def step(self, actions: Any) -> tuple[Any, Any, Any, Any, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(actions)
        return obs, reward, terminated, truncated, {
            "termination": info["termination"], "final_obs": info["final_observation"],
            "_final_obs": terminated | truncated}
