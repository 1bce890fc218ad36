"""Batched navigation on a GPU: thousands of rovers stepped together by MuJoCo Warp
(``pip install "marsscene[gpu]"``), the task of :mod:`marsscene.env` computed on the device.

- :class:`BatchNavEnv`: N rovers on W worlds; arrays (PyTorch, or numpy on Warp's CPU device)
  in and out.
- :class:`WorldBatch`: the worlds as arrays, built once from scene folders or a
  :class:`~marsscene.env.worlds.WorldSampler` and saved as one ``.npz``.
- :class:`RslRlVecEnv`: the interface rsl-rl's runners train (``rsl-rl-lib``).
- :class:`BatchVectorEnv`: Gymnasium's vector API.
- :class:`WarpPhysics`: heightfield posts, solver limits and determinism of MuJoCo Warp.
- :mod:`.sensing`: the navcam's depth and a LiDAR range image as observations
  (``ObsConfig(camera=(W, H), depth=True, lidar=...)``), cast on the device.

Docs: :doc:`/gym` (the batched environment); figures: :doc:`/results/gym`.
"""

from __future__ import annotations

from marsscene._lazy import lazy_attributes

__all__ = ["BatchNavEnv", "BatchVectorEnv", "RslRlVecEnv", "WarpPhysics", "WorldBatch"]

__getattr__ = lazy_attributes(__name__, {
    "BatchNavEnv": "marsscene.env.batch.env",
    "BatchVectorEnv": "marsscene.env.batch.adapters",
    "RslRlVecEnv": "marsscene.env.batch.adapters",
    "WarpPhysics": "marsscene.env.batch.model",
    "WorldBatch": "marsscene.env.batch.worlds",
})
