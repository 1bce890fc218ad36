"""The wheel prior's gates of the LiDAR odometry (:func:`passes_gate`): the step gate keeps ICP
steps near the wheel step; the slip gate keeps any step the wheels can make by slipping
(longitudinal slip 0-100 %, side slip up to ``SIDE_SLIP_RATIO``) and nothing that outruns them."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from marsscene.benchmark.slam.items import MethodSpec
from marsscene.benchmark.slam.kiss_icp import SIDE_SLIP_RATIO, passes_gate
from marsscene.errors import ConfigError

TOL_M, TOL_DEG = 0.05, 1.0


def _step(xyz, yaw_deg: float = 0.0, pitch_deg: float = 0.0) -> np.ndarray:
    step = np.eye(4)
    step[:3, :3] = Rotation.from_euler("zy", [yaw_deg, pitch_deg], degrees=True).as_matrix()
    step[:3, 3] = xyz
    return step


def _gates(wheel, icp):
    return tuple(passes_gate(wheel, icp, gate, max_step_dev_m=TOL_M, max_step_dev_deg=TOL_DEG)
                 for gate in ("step", "slip"))


@settings(max_examples=200, deadline=None)
@given(slip=st.floats(0.0, 1.0), step_m=st.floats(0.0, 0.3), heading_deg=st.floats(-180, 180),
       yaw_deg=st.floats(-0.9, 0.9))
def test_any_longitudinal_slip_passes_the_slip_gate(slip, step_m, heading_deg, yaw_deg):
    ahead = np.array([np.cos(np.radians(heading_deg)), np.sin(np.radians(heading_deg)), 0.0])
    wheel = _step(step_m * ahead, yaw_deg)
    icp = _step((1.0 - slip) * step_m * ahead, yaw_deg)
    step_gate, slip_gate = _gates(wheel, icp)
    assert slip_gate
    # the step gate keeps it only while the slip is within its tolerance
    if abs(slip * step_m - TOL_M) > 1e-9:
        assert step_gate == (slip * step_m < TOL_M)


def test_slip_gate_rejects_what_the_wheels_cannot_do():
    wheel = _step([0.05, 0.0, 0.0])  # 0.5 m/s, a scan every 0.1 s
    assert _gates(wheel, wheel) == (True, True)
    # a standing start's ring lock: the ICP jumps ahead of the wheels (measured 0.1-0.3 m a scan)
    assert _gates(wheel, _step([0.2, 0.0, 0.0])) == (False, False)
    # backwards while the wheels drive forwards, beyond the tolerance
    assert _gates(wheel, _step([-0.06, 0.0, 0.0])) == (False, False)
    # side slip: within tolerance + SIDE_SLIP_RATIO of the wheel step, not beyond
    side_m = TOL_M + SIDE_SLIP_RATIO * 0.05
    assert _gates(wheel, _step([0.03, side_m - 1e-3, 0.0]))[1]
    assert not _gates(wheel, _step([0.03, side_m + 1e-3, 0.0]))[1]
    # a rotation the wheels did not make fails both, whatever the translation
    assert _gates(wheel, _step([0.05, 0.0, 0.0], yaw_deg=1.5)) == (False, False)
    assert _gates(wheel, _step([0.05, 0.0, 0.0], pitch_deg=1.5)) == (False, False)
    # standing still: the slip gate is a box of the tolerance around it
    still = np.eye(4)
    assert _gates(still, _step([0.04, 0.0, 0.0])) == (True, True)
    assert _gates(still, _step([0.06, 0.0, 0.0])) == (False, False)


def test_the_gate_option_is_checked_in_the_spec():
    spec = MethodSpec(name="k", kind="kiss-icp", options={"wheel_prior": True, "gate": "slip"})
    assert spec.options["gate"] == "slip"
    with pytest.raises(ConfigError, match="gate") as err:
        MethodSpec(name="k", kind="kiss-icp", options={"wheel_prior": True, "gate": "slipp"})
    assert "\n" not in str(err.value) and "step" in str(err.value)
