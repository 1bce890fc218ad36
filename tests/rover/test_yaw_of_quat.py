"""Heading from a quaternion: one definition for one quaternion, numpy batches and PyTorch."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from marsscene.transforms import quat_from_yaw_normal, quat_to_matrix, yaw_of_quat


@given(yaw=st.floats(-math.pi + 1e-6, math.pi - 1e-6),
       nx=st.floats(-0.4, 0.4), ny=st.floats(-0.4, 0.4))
def test_the_heading_is_the_forward_axis_seen_from_above(yaw, nx, ny):
    q = quat_from_yaw_normal(yaw, (nx, ny, 1.0))
    one = yaw_of_quat(q)
    assert isinstance(one, float) and one == math.atan2(
        2 * (q[0] * q[3] + q[1] * q[2]), 1 - 2 * (q[2] ** 2 + q[3] ** 2))
    batch = yaw_of_quat(np.stack([q, q]))
    assert batch.shape == (2,) and abs(batch[0] - one) < 1e-12
    r = quat_to_matrix(q)  # the heading is the body's x axis seen from above
    assert abs(math.remainder(one - math.atan2(r[1, 0], r[0, 0]), 2 * math.pi)) < 1e-9
    level = quat_from_yaw_normal(yaw, (0.0, 0.0, 1.0))
    assert abs(math.remainder(yaw_of_quat(level) - yaw, 2 * math.pi)) < 1e-9


def test_pytorch_tensors_stay_tensors():
    torch = pytest.importorskip("torch")
    q = torch.tensor([[math.cos(0.3), 0.0, 0.0, math.sin(0.3)]], dtype=torch.float64)
    out = yaw_of_quat(q)
    assert isinstance(out, torch.Tensor) and abs(float(out[0]) - 0.6) < 1e-12
