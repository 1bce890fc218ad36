"""A model of more geoms than MuJoCo's default scene buffer (1,000) renders every one: a world of
many rocks lists its rocks before its terrain, and a buffer that drops the geoms past the first
1,000 drew rocks floating over no ground."""

from __future__ import annotations

import numpy as np
import pytest

from marsscene.sensors.offscreen import OffscreenView

mujoco = pytest.importorskip("mujoco")


def test_the_geoms_after_the_first_thousand_are_drawn():
    pebbles = "".join(f'<geom type="sphere" size="0.01" pos="{-40 + 0.05 * i:.2f} 40 0"/>'
                      for i in range(1100))  # off to the side, out of view
    xml = (f'<mujoco><worldbody>{pebbles}<geom type="plane" size="20 20 0.1"/>'
           '<camera name="down" pos="0 0 5" xyaxes="1 0 0 0 1 0"/></worldbody></mujoco>')
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    try:
        view = OffscreenView(model, width=32, height=24)
    except RuntimeError as err:
        pytest.skip(f"no headless OpenGL here: {err}")
    try:
        _, depth = view.render(data, 0, {}, depth=True)
    finally:
        view.close()
    assert model.ngeom == 1101
    assert depth is not None and np.allclose(depth, 5.0, atol=0.01)  # the plane, 5 m below
