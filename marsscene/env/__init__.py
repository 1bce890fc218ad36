"""Gymnasium environments: the MuJoCo rover navigating to goals on generated Mars worlds.

Importing this module registers the environment ids (``pip install "marsscene[gym]"``):

=================================  =====================================================
id                                 observations and reward
=================================  =====================================================
``marsscene/RoverNav-v0``          state + a 5 m height scan; dense reward
``marsscene/RoverNavSparse-v0``    the same; sparse reward (-1 a step until the goal)
``marsscene/RoverNavCamera-v0``    + navcam RGB-D 128 x 128; dense reward
``marsscene/RoverNavLidar-v0``     + a VLP-16 range image and its mask; dense reward
=================================  =====================================================

Examples
--------
>>> import gymnasium as gym
>>> import marsscene.env  # registers the ids
>>> env = gym.make("marsscene/RoverNav-v0")  # doctest: +SKIP
>>> obs, info = env.reset(seed=0)  # doctest: +SKIP
>>> obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
... # doctest: +SKIP

Each id is registered with ``max_episode_steps`` (:meth:`NavTask.episode_steps` of its task at
the default control rate: 750), so :func:`gymnasium.make` wraps it in a ``TimeLimit`` that cuts
at the step the environment truncates; pass ``max_episode_steps=`` to ``make`` with another
``task.max_episode_s`` or ``control_hz``.

The classical baseline: :class:`ArcNavigator` (arc evaluation on the height scan).
"""

from __future__ import annotations

from typing import Any

from gymnasium.envs.registration import register, registry

from marsscene.env.episode import NavEpisode
from marsscene.env.nav import CONTROL_HZ, RoverNavEnv
from marsscene.env.navigator import ArcNavigator
from marsscene.env.observe import HeightScan, ObsConfig
from marsscene.env.reward import RewardConfig
from marsscene.env.task import NavTask
from marsscene.env.worlds import WORLD_KINDS, WorldSampler

__all__ = ["WORLD_KINDS", "ArcNavigator", "HeightScan", "NavEpisode", "NavTask", "ObsConfig",
           "RewardConfig", "RoverNavEnv", "WorldSampler"]

_IDS: dict[str, dict[str, Any]] = {
    "marsscene/RoverNav-v0": {},
    "marsscene/RoverNavSparse-v0": {"reward": RewardConfig(kind="sparse")},
    "marsscene/RoverNavCamera-v0": {"observations": ObsConfig(camera=(128, 128), depth=True)},
    "marsscene/RoverNavLidar-v0": {"observations": ObsConfig(lidar="vlp16")},
}


def _max_episode_steps(kwargs: dict[str, Any]) -> int:
    """The steps of a full episode of :class:`RoverNavEnv` built with ``kwargs``."""
    task = kwargs.get("task") or NavTask()
    return task.episode_steps(kwargs.get("control_hz", CONTROL_HZ))


for _id, _kwargs in _IDS.items():
    if _id not in registry:
        register(id=_id, entry_point="marsscene.env.nav:RoverNavEnv", kwargs=_kwargs,
                 max_episode_steps=_max_episode_steps(_kwargs))
