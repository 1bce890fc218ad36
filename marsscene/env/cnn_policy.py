"""A trained navigation policy that sees, run with numpy: rsl-rl's ``CNNModel`` as its PPO trains
it on :class:`~marsscene.env.batch.BatchNavEnv` from the navcam's depth, the observation vector
and the goal (no height scan).

The depth image (planar, m, 0 where nothing is seen) enters the encoder as
:func:`depth_input`: clipped to :data:`DEPTH_MAX_M` and divided by it, a pixel with no return
counted as far as the clip (1.0), so the sky continues the far ground. The encoder is a few
convolutions with ELU after each, flattened (channels, rows, columns); its latent follows the
normalised ``observation`` vector (:func:`~marsscene.env.policy.policy_input`) into the MLP whose
last layer is the Gaussian policy's mean.

The file (``.npz``) holds the convolutions (``cw0``, ``cb0``, ...; ``cgeom0``: stride, padding,
dilation, rows then columns), the MLP (``w0``, ``b0``, ...), the vector's normaliser (mean,
standard deviation, epsilon), the camera's size and the depth clip. It runs on
:class:`~marsscene.env.nav.RoverNavEnv`'s observations (MuJoCo C, the CPU camera at the batch
camera's intrinsics: the same :class:`~marsscene.rover.config.CameraConfig`) with no PyTorch.

Examples
--------
>>> from marsscene.env import RoverNavEnv
>>> from marsscene.env.cnn_policy import CNNPolicy
>>> policy = CNNPolicy.load("policy.npz")  # doctest: +SKIP
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

from marsscene.env.policy import (
    MLPPolicy,
    elu,
    load_policy_npz,
    mlp_forward,
    policy_input,
    save_policy_npz,
)
from marsscene.errors import ConfigError

__all__ = ["DEPTH_MAX_M", "CNNPolicy", "ConvLayer", "conv2d", "depth_input",
           "load_policy"]

#: Depth beyond this (m), and pixels with no return, read as this far.
DEPTH_MAX_M = 20.0
#: The 2-D observation group the encoder reads (rsl-rl's group of :class:`RslRlVecEnv`).
DEPTH_GROUP = "depth"


def load_policy(path: str | Path) -> MLPPolicy | CNNPolicy:
    """The policy of a ``.npz`` written by :meth:`CNNPolicy.save` (it holds ``cw0``) or by
    :meth:`MLPPolicy.save <marsscene.env.policy.MLPPolicy.save>`."""
    try:
        with np.load(Path(path)) as z:
            cnn = "cw0" in z.files
    except (OSError, ValueError) as err:
        raise ConfigError(f"{path}: not a policy .npz ({err})") from None
    return CNNPolicy.load(path) if cnn else MLPPolicy.load(path)


def depth_input(depth: Any, max_m: float = DEPTH_MAX_M) -> Any:
    """The encoder's input of a depth image (any shape; numpy or PyTorch): ``min(depth, max_m) /
    max_m``, 1.0 where nothing is seen (depth 0), float32 in [0, 1]."""
    from array_api_compat import array_namespace

    xp = array_namespace(depth)
    d = xp.astype(depth, xp.float32)
    far = xp.full_like(d, float(max_m))
    return xp.where(d > 0, xp.minimum(d, far), far) / float(max_m)


@dataclass(frozen=True, eq=False)
class ConvLayer:
    """One ``torch.nn.Conv2d`` (zero padding): ``weight`` (out, in, rows, cols), ``bias``
    (out,), and ``stride``, ``padding``, ``dilation`` as (rows, cols) pixels."""

    weight: NDArray[np.float32]
    bias: NDArray[np.float32]
    stride: tuple[int, int] = (1, 1)
    padding: tuple[int, int] = (0, 0)
    dilation: tuple[int, int] = (1, 1)

    def geometry(self) -> NDArray[np.int64]:
        """(6,) stride, padding, dilation (rows, cols each): the file's ``cgeom``."""
        return np.array([*self.stride, *self.padding, *self.dilation], np.int64)


def conv2d(x: NDArray[np.float32], layer: ConvLayer) -> NDArray[np.float32]:
    """PyTorch's ``Conv2d`` (a cross-correlation) of ``x`` (N, in, H, W): (N, out, H', W'),
    ``H' = (H + 2 pad - dil (k - 1) - 1) // stride + 1`` (and so for W)."""
    (sr, sc), (pr, pc), (dr, dc) = layer.stride, layer.padding, layer.dilation
    _, in_ch, kr, kc = layer.weight.shape
    if x.ndim != 4 or x.shape[1] != in_ch:
        raise ConfigError(f"conv2d: input {x.shape}; the layer takes (N, {in_ch}, H, W)")
    x = np.ascontiguousarray(np.pad(x, ((0, 0), (0, 0), (pr, pr), (pc, pc))), np.float32)
    n, _, h, w = x.shape
    rows, cols = (h - dr * (kr - 1) - 1) // sr + 1, (w - dc * (kc - 1) - 1) // sc + 1
    if rows < 1 or cols < 1:
        raise ConfigError(f"conv2d: a {kr} x {kc} kernel does not fit a {h} x {w} input")
    s = x.strides
    windows = np.lib.stride_tricks.as_strided(
        x, shape=(n, in_ch, rows, cols, kr, kc),
        strides=(s[0], s[1], s[2] * sr, s[3] * sc, s[2] * dr, s[3] * dc), writeable=False)
    out = np.tensordot(windows, layer.weight, axes=([1, 4, 5], [1, 2, 3]))  # (n, r, c, out)
    return np.ascontiguousarray(out.transpose(0, 3, 1, 2) + layer.bias[:, None, None],
                                dtype=np.float32)


@dataclass(frozen=True, eq=False)
class CNNPolicy:
    """``action = mlp([(x - mean) / (std + eps), flatten(cnn(depth_input(depth)))])``: ELU after
    every convolution and between the MLP's layers, a linear last layer."""

    convs: list[ConvLayer]
    weights: list[NDArray[np.float32]]
    biases: list[NDArray[np.float32]]
    mean: NDArray[np.float32]
    std: NDArray[np.float32]
    eps: float
    camera_px: tuple[int, int]  # (width, height)
    depth_max_m: float = DEPTH_MAX_M

    def encode(self, image: NDArray[np.float32]) -> NDArray[np.float32]:
        """The encoder's latent (N, features) of :func:`depth_input` images (N, 1, H, W)."""
        x = np.asarray(image, np.float32)
        for layer in self.convs:
            x = elu(conv2d(x, layer))
        return x.reshape(x.shape[0], -1)

    def __call__(self, obs: dict[str, Any]) -> NDArray[np.float32]:
        """The action(s) of observations: one rover's dict (``observation`` (17,), ``depth``
        (H, W), as :class:`~marsscene.env.nav.RoverNavEnv` gives) or a batch's (``depth``
        (N, H, W) or (N, 1, H, W))."""
        vec = np.asarray(policy_input(obs), np.float32)
        single = vec.ndim == 1
        vec = vec.reshape(-1, vec.shape[-1])
        w, h = self.camera_px
        depth = np.asarray(obs[DEPTH_GROUP])
        if depth.shape[-2:] != (h, w) or depth.size != len(vec) * h * w:
            raise ConfigError(f"depth {depth.shape}; the policy sees {len(vec)} x {h} x {w} "
                              "(camera = (width, height) = "
                              f"{self.camera_px})")
        image = depth_input(depth.reshape(len(vec), 1, h, w), self.depth_max_m)
        latent = np.concatenate([(vec - self.mean) / (self.std + self.eps),
                                 self.encode(image)], axis=-1)
        act = mlp_forward(latent, self.weights, self.biases)
        return act[0] if single else act

    def observations(self) -> Any:
        """The :class:`~marsscene.env.observe.ObsConfig` it was trained on: the navcam's
        depth at its size, no height scan, noise-free, the true pose."""
        from marsscene.env.observe import ObsConfig

        return ObsConfig(height_scan=None, camera=self.camera_px, depth=True,
                         noise_profile="none")

    def save(self, path: str | Path) -> Path:
        arrays: dict[str, Any] = {"camera": np.array(self.camera_px, np.int64),
                                  "depth_max_m": self.depth_max_m}
        for i, c in enumerate(self.convs):
            arrays[f"cw{i}"], arrays[f"cb{i}"], arrays[f"cgeom{i}"] = (c.weight, c.bias,
                                                                       c.geometry())
        return save_policy_npz(path, self, arrays)

    @classmethod
    def load(cls, path: str | Path) -> CNNPolicy:
        return load_policy_npz(path, "CNNPolicy", cls._of_arrays)

    @classmethod
    def _of_arrays(cls, z: dict[str, Any], weights: list[Any], biases: list[Any]) -> CNNPolicy:
        n_conv = sum(1 for k in z if k.startswith("cw"))
        if not n_conv:
            raise KeyError("cw0")
        convs = []
        for i in range(n_conv):
            g = [int(v) for v in z[f"cgeom{i}"]]
            convs.append(ConvLayer(z[f"cw{i}"], z[f"cb{i}"], (g[0], g[1]), (g[2], g[3]),
                                   (g[4], g[5])))
        cam = [int(v) for v in z["camera"]]
        return cls(convs=convs, weights=weights, biases=biases, mean=z["mean"], std=z["std"],
                   eps=float(z["eps"]), camera_px=(cam[0], cam[1]),
                   depth_max_m=float(z["depth_max_m"]))

    @classmethod
    def from_rsl_rl(cls, actor: Any, depth_max_m: float = DEPTH_MAX_M) -> CNNPolicy:
        """From rsl-rl's ``CNNModel`` actor: one 2-D group (``"depth"``, one channel) through
        a ``CNN`` of ``Conv2d`` + ELU layers (zero or no padding, no pooling or norm layers,
        flattened), the 1-D groups normalised (``obs_normalization=True``), an ELU MLP."""
        groups_2d = list(actor.obs_groups_2d)
        if groups_2d != [DEPTH_GROUP] or list(actor.obs_channels_2d) != [1]:
            raise ConfigError(f"a CNN of the one-channel group {DEPTH_GROUP!r}, not of "
                              f"{groups_2d}")
        h, w = (int(v) for v in actor.obs_dims_2d[0])
        convs = [_conv_layer(m) for m in actor.cnns[DEPTH_GROUP]
                 if type(m).__name__ == "Conv2d"]
        kinds = {type(m).__name__ for m in actor.cnns[DEPTH_GROUP]}
        if not kinds <= {"Conv2d", "ELU", "Flatten"} or "Flatten" not in kinds:
            raise ConfigError(f"the CNN has layers {sorted(kinds)}; the numpy policy runs "
                              "Conv2d, ELU and Flatten")
        linear = [m for m in actor.mlp if type(m).__name__ == "Linear"]
        norm = actor.obs_normalizer
        return cls(convs=convs, weights=[_np(m.weight) for m in linear],
                   biases=[_np(m.bias) for m in linear], mean=_np(norm._mean)[0],
                   std=_np(norm._std)[0], eps=float(norm.eps), camera_px=(w, h),
                   depth_max_m=float(depth_max_m))


def _np(tensor: Any) -> NDArray[np.float32]:
    return np.asarray(tensor.detach().cpu().numpy(), np.float32)


def _conv_layer(m: Any) -> ConvLayer:
    if m.padding_mode != "zeros" or isinstance(m.padding, str) or m.groups != 1:
        raise ConfigError(f"{m}: the numpy policy runs zero-padded, ungrouped convolutions")
    return ConvLayer(_np(m.weight), _np(m.bias), _pair(m.stride), _pair(m.padding),
                     _pair(m.dilation))


def _pair(v: Any) -> tuple[int, int]:
    return int(v[0]), int(v[1])
