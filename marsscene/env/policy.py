"""A trained navigation policy, run with numpy: an MLP over the observation vector and the
height scan, as rsl-rl's PPO trains it on :class:`~marsscene.env.batch.BatchNavEnv`.

The file (``.npz``) holds the observation normaliser (mean, standard deviation, epsilon), the
layers (``w0``, ``b0``, ...; ELU between them, a linear last layer: the Gaussian policy's mean)
and the height scan it was trained on. It runs on :class:`~marsscene.env.nav.RoverNavEnv`'s
observations (MuJoCo C, mesh rocks) with no PyTorch: the sim-to-sim check before trusting a
policy trained on the GPU batch.

Examples
--------
>>> from marsscene.env import RoverNavEnv
>>> from marsscene.env.policy import MLPPolicy
>>> policy = MLPPolicy.load("policy.npz")  # doctest: +SKIP
>>> env = RoverNavEnv(observations=policy.observations())  # doctest: +SKIP
>>> obs, info = env.reset(seed=0)  # doctest: +SKIP
>>> obs, reward, terminated, truncated, info = env.step(policy(obs))  # doctest: +SKIP
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.errors import ConfigError

__all__ = ["MLPPolicy", "elu", "mlp_forward", "policy_input"]


def policy_input(obs: dict[str, Any]) -> Any:
    """(..., 17 + n*n) float32: ``observation`` then the ``height_scan`` row by row (if any);
    numpy or PyTorch arrays of any batch shape."""
    from array_api_compat import array_namespace

    vec = obs["observation"]
    if "height_scan" not in obs:
        return vec
    xp = array_namespace(vec)
    scan = obs["height_scan"]
    flat = xp.reshape(scan, (*scan.shape[:-2], scan.shape[-2] * scan.shape[-1]))
    return xp.concat([vec, xp.astype(flat, vec.dtype)], axis=-1)


def elu(x: NDArray[np.float32]) -> NDArray[np.float32]:
    """PyTorch's ``ELU`` (alpha 1): ``x`` where positive, ``exp(x) - 1`` elsewhere."""
    return np.where(x > 0, x, np.expm1(np.minimum(x, 0))).astype(np.float32)


def mlp_forward(x: NDArray[np.float32], weights: list[NDArray[np.float32]],
                biases: list[NDArray[np.float32]]) -> NDArray[np.float32]:
    """rsl-rl's ``MLP``: ``x`` (..., in) through linear layers with ELU between them and a
    linear last layer; (..., out) float32."""
    for i, (w, b) in enumerate(zip(weights, biases, strict=True)):
        x = x @ w.T + b
        if i < len(weights) - 1:
            x = elu(x)
    return np.asarray(x, dtype=np.float32)


@dataclass(frozen=True, eq=False)
class MLPPolicy:
    """An MLP policy: ``action = mlp((x - mean) / (std + eps))`` with ELU between layers."""

    weights: list[NDArray[np.float32]]
    biases: list[NDArray[np.float32]]
    mean: NDArray[np.float32]
    std: NDArray[np.float32]
    eps: float
    scan_size_m: float
    scan_resolution_m: float

    def __call__(self, obs: dict[str, Any]) -> NDArray[np.float32]:
        """The action(s) of observations (one rover's dict, or a batch's)."""
        x = (np.asarray(policy_input(obs), np.float32) - self.mean) / (self.std + self.eps)
        return mlp_forward(x, self.weights, self.biases)

    def observations(self) -> Any:
        """The :class:`~marsscene.env.observe.ObsConfig` it was trained on (noise-free, the
        true pose, its height scan)."""
        from marsscene.env.observe import HeightScan, ObsConfig

        return ObsConfig(height_scan=HeightScan(size_m=self.scan_size_m,
                                                resolution_m=self.scan_resolution_m),
                         noise_profile="none")

    def save(self, path: str | Path) -> Path:
        return save_policy_npz(path, self, {
            "scan": np.array([self.scan_size_m, self.scan_resolution_m])})

    @classmethod
    def load(cls, path: str | Path) -> MLPPolicy:
        def build(z: dict[str, Any], weights: list[Any], biases: list[Any]) -> MLPPolicy:
            return cls(weights=weights, biases=biases, mean=z["mean"], std=z["std"],
                       eps=float(z["eps"]), scan_size_m=float(z["scan"][0]),
                       scan_resolution_m=float(z["scan"][1]))
        return load_policy_npz(path, "MLPPolicy", build)

    @classmethod
    def from_rsl_rl(cls, actor: Any, scan: Any) -> MLPPolicy:
        """From rsl-rl's ``MLPModel`` actor (``obs_normalization=True``, ELU) and the
        :class:`~marsscene.env.observe.HeightScan` it observed."""
        state = {k: v.detach().cpu().numpy() for k, v in actor.state_dict().items()}
        layers = sorted({k.rsplit(".", 1)[0] for k in state if k.startswith("mlp.")
                         and k.endswith(".weight")}, key=lambda k: int(k.split(".")[1]))
        norm = actor.obs_normalizer
        return cls(weights=[state[f"{k}.weight"] for k in layers],
                   biases=[state[f"{k}.bias"] for k in layers],
                   mean=state["obs_normalizer._mean"][0], std=state["obs_normalizer._std"][0],
                   eps=float(norm.eps), scan_size_m=scan.size_m,
                   scan_resolution_m=scan.resolution_m)


def save_policy_npz(path: str | Path, policy: Any, extra: dict[str, Any]) -> Path:
    """A policy's ``.npz``: its normaliser (``mean``, ``std``, ``eps``), its MLP's layers
    (``w0``, ``b0``, ...) and ``extra`` arrays."""
    arrays: dict[str, Any] = {"mean": policy.mean, "std": policy.std, "eps": policy.eps, **extra}
    for i, (w, b) in enumerate(zip(policy.weights, policy.biases, strict=True)):
        arrays[f"w{i}"], arrays[f"b{i}"] = w, b
    with open(path, "wb") as f:
        np.savez(f, **arrays)
    return Path(path)


def load_policy_npz(path: str | Path, owner: str, build: Any) -> Any:
    """``build(arrays, weights, biases)`` from a policy ``.npz`` (:func:`save_policy_npz`),
    or a one-line :class:`ConfigError` naming ``owner``'s ``save``."""
    try:
        with np.load(Path(path)) as f:
            z = {k: f[k] for k in f.files}
        n = sum(1 for k in z if k.startswith("w"))
        return build(z, [z[f"w{i}"] for i in range(n)], [z[f"b{i}"] for i in range(n)])
    except (OSError, KeyError, ValueError) as err:
        raise ConfigError(f"{path}: not a policy written by {owner}.save ({err})") from None
