"""Hand-built policy files for the tests: a goal-seeking MLP on the height scan and a CNN that
drives only while its depth image sees the ground (so a run it finishes proves the frames
reached it)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from marsscene.env.cnn_policy import CNNPolicy, ConvLayer
from marsscene.env.observe import OBSERVATION_SIZE, HeightScan
from marsscene.env.policy import MLPPolicy

#: The ``observation`` vector's sine of the goal bearing (:mod:`marsscene.env.observe`).
SIN_BEARING = 3
#: The CNN's camera (width, height) px.
CNN_PX = (32, 24)


def goal_seeking_mlp(path: Path, scan: HeightScan) -> Path:
    """Full speed ahead, turning by 3 x the sine of the goal bearing; the scan read with
    zero weights (its size still checked)."""
    n_in = OBSERVATION_SIZE + scan.points ** 2
    w = np.zeros((2, n_in), np.float32)
    w[1, SIN_BEARING] = 3.0
    return MLPPolicy(weights=[w], biases=[np.array([1.0, 0.0], np.float32)],
                     mean=np.zeros(n_in, np.float32), std=np.ones(n_in, np.float32), eps=1e-8,
                     scan_size_m=scan.size_m, scan_resolution_m=scan.resolution_m).save(path)


def ground_seeing_cnn(path: Path) -> Path:
    """Speed 10 x (1 - the mean depth input of the image's lower half): 0 when nothing is
    seen (every pixel reads far), full speed with ground within a few metres; turning as
    :func:`goal_seeking_mlp`."""
    w_px, h_px = CNN_PX
    kernel = np.zeros((1, 1, h_px, w_px), np.float32)
    kernel[0, 0, h_px // 2:, :] = -1.0 / (w_px * (h_px - h_px // 2))
    conv = ConvLayer(kernel, np.array([1.0], np.float32))
    w = np.zeros((2, OBSERVATION_SIZE + 1), np.float32)
    w[0, OBSERVATION_SIZE] = 10.0
    w[1, SIN_BEARING] = 3.0
    return CNNPolicy(convs=[conv], weights=[w], biases=[np.zeros(2, np.float32)],
                     mean=np.zeros(OBSERVATION_SIZE, np.float32),
                     std=np.ones(OBSERVATION_SIZE, np.float32), eps=1e-8,
                     camera_px=CNN_PX).save(path)
