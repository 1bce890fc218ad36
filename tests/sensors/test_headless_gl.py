"""MuJoCo's offscreen backend is chosen at its first import: marsscene must set it first."""

from __future__ import annotations

import os
import subprocess
import sys

from marsscene._gl import default_headless_gl

# A module that imports mujoco without going through the rover simulator (the path a benchmark
# worker takes: the world is compiled alone before the camera is made).
_SCRIPT = """
import marsscene.sim.world
import mujoco
m = mujoco.MjModel.from_xml_string('<mujoco><worldbody><geom size="1"/></worldbody></mujoco>')
r = mujoco.Renderer(m, height=24, width=32)
r.update_scene(mujoco.MjData(m))
print(r.render().shape)
"""


def test_headless_import_order_renders():
    unset = ("MUJOCO_GL", "DISPLAY", "PYOPENGL_PLATFORM")
    env = {k: v for k, v in os.environ.items() if k not in unset}
    out = subprocess.run(
        [sys.executable, "-c", _SCRIPT], env=env, capture_output=True, text=True, timeout=120
    )
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "(24, 32, 3)"


def test_user_choice_and_display_respected():
    assert default_headless_gl({}) == "egl"
    assert default_headless_gl({"MUJOCO_GL": "osmesa"}) == "osmesa"
    env = {"DISPLAY": ":0"}
    assert default_headless_gl(env) is None and "MUJOCO_GL" not in env
