"""The numpy CNN policy (marsscene.env.cnn_policy): its convolution against scipy's correlation
and hand-worked kernels, the depth normalisation, a whole forward pass against one written out
by hand, batch and single-rover calls alike, the .npz round trip and the loader's dispatch; with
PyTorch and rsl-rl installed, the export of rsl-rl's CNNModel against its own forward pass."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy import signal

from marsscene.env.cnn_policy import CNNPolicy, ConvLayer, conv2d, depth_input, load_policy
from marsscene.env.policy import MLPPolicy
from marsscene.errors import ConfigError


def _reference_conv(x: np.ndarray, layer: ConvLayer) -> np.ndarray:
    """PyTorch's Conv2d written with scipy: pad, dilate the kernel, correlate, subsample."""
    (sr, sc), (pr, pc), (dr, dc) = layer.stride, layer.padding, layer.dilation
    xp = np.pad(x.astype(np.float64), ((0, 0), (0, 0), (pr, pr), (pc, pc)))
    out_ch, in_ch, kr, kc = layer.weight.shape
    kernel = np.zeros((out_ch, in_ch, dr * (kr - 1) + 1, dc * (kc - 1) + 1))
    kernel[:, :, ::dr, ::dc] = layer.weight
    rows = []
    for n in range(x.shape[0]):
        chans = [sum(signal.correlate(xp[n, c], kernel[o, c], mode="valid")
                     for c in range(in_ch))[::sr, ::sc] + layer.bias[o]
                 for o in range(out_ch)]
        rows.append(np.stack(chans))
    return np.stack(rows)


def _elu(x: np.ndarray) -> np.ndarray:
    return np.where(x > 0, x, np.exp(np.minimum(x, 0)) - 1)


def _policy(rng: np.random.Generator, width: int = 16, height: int = 12) -> CNNPolicy:
    """Two convolutions (1 -> 3 -> 2 channels) and an MLP (17 + latent -> 8 -> 2)."""
    c1 = ConvLayer(rng.normal(0, 0.5, (3, 1, 3, 3)).astype(np.float32),
                   rng.normal(0, 0.1, 3).astype(np.float32), stride=(2, 2))
    c2 = ConvLayer(rng.normal(0, 0.5, (2, 3, 3, 3)).astype(np.float32),
                   rng.normal(0, 0.1, 2).astype(np.float32), padding=(1, 1))
    r1, k1 = (height - 3) // 2 + 1, (width - 3) // 2 + 1  # c2 keeps the size (padding 1)
    latent = 17 + 2 * r1 * k1
    return CNNPolicy(convs=[c1, c2],
                     weights=[rng.normal(0, 0.2, (8, latent)).astype(np.float32),
                              rng.normal(0, 0.2, (2, 8)).astype(np.float32)],
                     biases=[rng.normal(0, 0.1, 8).astype(np.float32),
                             rng.normal(0, 0.1, 2).astype(np.float32)],
                     mean=rng.normal(0, 1, 17).astype(np.float32),
                     std=rng.uniform(0.5, 2.0, 17).astype(np.float32), eps=0.01,
                     camera_px=(width, height), depth_max_m=20.0)


def _obs(rng: np.random.Generator, n: int, width: int = 16, height: int = 12) -> dict:
    depth = rng.uniform(0.0, 30.0, (n, height, width)).astype(np.float32)
    depth[rng.random(depth.shape) < 0.2] = 0.0  # no return
    return {"observation": rng.normal(0, 2, (n, 17)).astype(np.float32), "depth": depth}


@pytest.mark.parametrize(("stride", "padding", "dilation"),
                         [((1, 1), (0, 0), (1, 1)), ((2, 1), (1, 2), (1, 2)),
                          ((3, 2), (0, 1), (2, 1))])
def test_conv2d_matches_scipy_correlation(stride: tuple[int, int], padding: tuple[int, int],
                                          dilation: tuple[int, int]) -> None:
    rng = np.random.RandomState(7)
    x = rng.normal(size=(2, 3, 11, 13)).astype(np.float32)
    layer = ConvLayer(rng.normal(size=(4, 3, 3, 2)).astype(np.float32),
                      rng.normal(size=4).astype(np.float32), stride, padding, dilation)
    got = conv2d(x, layer)
    want = _reference_conv(x, layer)
    assert got.shape == want.shape and got.dtype == np.float32
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-5)


def test_conv2d_hand_kernels() -> None:
    x = np.arange(16, dtype=np.float32).reshape(1, 1, 4, 4)
    corner = ConvLayer(np.array([[[[1, 0], [0, 0]]]], np.float32), np.zeros(1, np.float32),
                       stride=(2, 2))
    np.testing.assert_array_equal(conv2d(x, corner)[0, 0], [[0, 2], [8, 10]])
    # a correlation, not a convolution: the kernel's right column weighs the right pixel
    right = ConvLayer(np.array([[[[0, 1]]]], np.float32), np.full(1, 0.5, np.float32))
    np.testing.assert_array_equal(conv2d(x, right)[0, 0], x[0, 0, :, 1:] + 0.5)
    ones = ConvLayer(np.ones((2, 1, 3, 3), np.float32), np.array([0, -1], np.float32),
                     padding=(1, 1))
    out = conv2d(x, ones)
    assert out.shape == (1, 2, 4, 4)
    assert out[0, 0, 0, 0] == 0 + 1 + 4 + 5 and out[0, 0, 1, 1] == x[0, 0, :3, :3].sum()
    np.testing.assert_array_equal(out[0, 1], out[0, 0] - 1)


def test_conv2d_rejects_what_it_cannot_run() -> None:
    layer = ConvLayer(np.ones((1, 2, 3, 3), np.float32), np.zeros(1, np.float32))
    with pytest.raises(ConfigError, match="takes"):
        conv2d(np.ones((1, 1, 8, 8), np.float32), layer)
    with pytest.raises(ConfigError, match="does not fit"):
        conv2d(np.ones((1, 2, 2, 8), np.float32), layer)


def test_depth_input_clips_scales_and_fills_no_return() -> None:
    depth = np.array([[0.0, 5.0, 20.0], [40.0, 0.05, 10.0]], np.float32)
    got = depth_input(depth, 20.0)
    assert got.dtype == np.float32 and got.shape == depth.shape
    np.testing.assert_allclose(got, [[1.0, 0.25, 1.0], [1.0, 0.0025, 0.5]], rtol=1e-6)
    np.testing.assert_allclose(depth_input(depth, 10.0)[0], [1.0, 0.5, 1.0], rtol=1e-6)


def test_forward_pass_against_one_written_out() -> None:
    rng = np.random.default_rng(3)
    policy, obs = _policy(rng), _obs(rng, 5)
    got = policy(obs)
    image = np.where(obs["depth"] > 0, np.minimum(obs["depth"], 20.0), 20.0)[:, None] / 20.0
    for layer in policy.convs:
        image = _elu(_reference_conv(image, layer))
    x = np.concatenate([(obs["observation"] - policy.mean) / (policy.std + policy.eps),
                        image.reshape(5, -1)], axis=1)
    want = _elu(x @ policy.weights[0].T + policy.biases[0]) @ policy.weights[1].T
    want += policy.biases[1]
    assert got.shape == (5, 2) and got.dtype == np.float32
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-5)
    assert np.ptp(got[:, 0]) > 1e-3  # the rovers' actions differ: the input matters


def test_single_rover_and_channel_axis_give_the_batch_rows() -> None:
    rng = np.random.default_rng(4)
    policy, obs = _policy(rng), _obs(rng, 3)
    batch = policy(obs)
    for i in range(3):
        one = policy({"observation": obs["observation"][i], "depth": obs["depth"][i]})
        assert one.shape == (2,)
        np.testing.assert_allclose(one, batch[i], rtol=0, atol=1e-6)
    channels = policy({**obs, "depth": obs["depth"][:, None]})  # (N, 1, H, W): the batch's
    np.testing.assert_array_equal(channels, batch)
    with pytest.raises(ConfigError, match="sees"):
        policy({**obs, "depth": obs["depth"][:, :, :8]})


def test_save_load_round_trip_and_dispatch(tmp_path: Path) -> None:
    rng = np.random.default_rng(5)
    policy, obs = _policy(rng), _obs(rng, 4)
    path = policy.save(tmp_path / "cnn.npz")
    back = CNNPolicy.load(path)
    assert back.camera_px == (16, 12) and back.depth_max_m == 20.0 and back.eps == 0.01
    assert [c.stride for c in back.convs] == [(2, 2), (1, 1)]
    assert [c.padding for c in back.convs] == [(0, 0), (1, 1)]
    np.testing.assert_array_equal(back(obs), policy(obs))
    assert isinstance(load_policy(path), CNNPolicy)
    mlp = MLPPolicy(weights=[np.eye(2, 17, dtype=np.float32)], biases=[np.zeros(2, np.float32)],
                    mean=np.zeros(17, np.float32), std=np.ones(17, np.float32), eps=0.0,
                    scan_size_m=5.0, scan_resolution_m=0.25)
    assert isinstance(load_policy(mlp.save(tmp_path / "mlp.npz")), MLPPolicy)
    with pytest.raises(ConfigError, match="CNNPolicy"):
        CNNPolicy.load(tmp_path / "mlp.npz")
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(ConfigError, match="not a policy"):
        load_policy(tmp_path / "junk.npz")


def test_observations_are_the_depth_camera_alone() -> None:
    obs = _policy(np.random.default_rng(6), width=64, height=48).observations()
    assert obs.camera == (64, 48) and obs.depth and obs.height_scan is None
    assert obs.noise_profile == "none" and obs.pose_source == "truth"


def test_export_of_rsl_rl_cnn_model_matches_its_forward() -> None:
    torch = pytest.importorskip("torch")
    pytest.importorskip("rsl_rl")
    from rsl_rl.models import CNNModel
    from tensordict import TensorDict

    gen = torch.Generator().manual_seed(0)
    n, w, h = 6, 20, 16
    depth = torch.rand((n, 1, h, w), generator=gen) * 30.0
    td = TensorDict({"policy": torch.randn((n, 17), generator=gen),
                     "depth": depth_input(depth)}, batch_size=[n])
    cnn = {"output_channels": [4, 6], "kernel_size": [3, 3], "stride": [2, 1],
           "dilation": [1, 2], "padding": "zeros", "activation": "elu", "flatten": True}
    actor = CNNModel(td, {"actor": ["policy", "depth"]}, "actor", 2, hidden_dims=[16, 8],
                     obs_normalization=True, cnn_cfg=cnn,
                     distribution_cfg={"class_name": "GaussianDistribution", "init_std": 0.6})
    actor.obs_normalizer.update(td["policy"] * 3.0 + 1.0)
    actor.eval()
    with torch.inference_mode():
        want = actor(td).numpy()
    policy = CNNPolicy.from_rsl_rl(actor)
    got = policy({"observation": td["policy"].numpy(), "depth": depth.numpy()})
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-5)
