"""The MJCF hfield texture is draped north-up: rendered from above, image NW lands at world NW."""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import marsscene as ms


def test_hfield_texture_orientation(tmp_path: Path) -> None:
    pytest.importorskip("mujoco")
    from marsscene.export.mjcf import write_mjcf

    cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [20.0, 10.0],
                                                "post_m": 0.5, "rms_height_m": 0.01}})
    tex = np.zeros((50, 100, 3), np.uint8)
    tex[:, :] = (0, 0, 255)  # south half blue
    tex[:25, :50] = (255, 0, 0)  # row 0 = north, col 0 = west: NW red
    tex[:25, 50:] = (0, 255, 0)  # NE green
    scene = dataclasses.replace(ms.build_scene(cfg, seed=1), texture_rgb=tex)
    write_mjcf(scene, tmp_path)
    xml = (tmp_path / "mjcf/scene.xml").read_text().replace("<worldbody>", (
        '<worldbody><camera name="top" pos="0 0 30" xyaxes="1 0 0 0 1 0" fovy="60"/>'
        '<light pos="0 0 50" dir="0 0 -1" directional="true"/>'), 1)
    (tmp_path / "mjcf/top.xml").write_text(xml)
    # render in a fresh process so MUJOCO_GL=egl applies whatever this process imported first
    script = (
        "import json, sys, mujoco\n"
        "m = mujoco.MjModel.from_xml_path(sys.argv[1]); d = mujoco.MjData(m)\n"
        "mujoco.mj_forward(m, d)\n"
        "r = mujoco.Renderer(m, 200, 200); r.update_scene(d, camera='top')\n"
        "img = r.render()\n"
        "print(json.dumps([img[85, 60].tolist(), img[85, 140].tolist(), img[115, 60].tolist()]))\n"
    )
    env = {**os.environ, "MUJOCO_GL": "egl"}
    res = subprocess.run([sys.executable, "-c", script, str(tmp_path / "mjcf/top.xml")],
                         capture_output=True, text=True, env=env, timeout=120)
    if res.returncode != 0:
        pytest.skip(f"offscreen rendering unavailable: {res.stderr.strip()[-200:]}")
    nw, ne, sw = (np.array(v) for v in json.loads(res.stdout.strip().splitlines()[-1]))
    # camera x = world east (image right), camera y = world north (image up); 200 px ~ 34.6 m
    assert nw.argmax() == 0 and nw[0] > 150  # red
    assert ne.argmax() == 1 and ne[1] > 150  # green
    assert sw.argmax() == 2 and sw[2] > 150  # blue
