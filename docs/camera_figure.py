"""Regenerate docs/img/camera_tau_sun.png: frames at tau = 0.3, 1, 3 and two sun elevations.

Usage: ``MUJOCO_GL=egl python docs/camera_figure.py SCENE_DIR`` (e.g. ``marsscene build
--seed 7 --out scenes/demo``). Fixed exposure (gain 1.6 for every frame) so that dust and a
low sun visibly darken the image; the bottom line of each label gives the auto-exposure gain a
camera would pick instead.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from marsscene.runtime import CameraConfig, RunConfig
from marsscene.sensors.exposure import Exposure
from marsscene.sim.rover_sim import RoverSim


def main(scene: str) -> None:
    rows = []
    for el in (40.0, 15.0):
        tiles = []
        for tau in (0.3, 1.0, 3.0):
            cam = CameraConfig(width_px=480, height_px=360, exposure="fixed", exposure_gain=1.6,
                               tau=tau, sun_elevation_deg=el, sun_azimuth_deg=100.0)
            sim = RoverSim(scene, run=RunConfig(camera=cam), start_xy_m=(20.0, 20.0),
                           settle_s=0.5)
            r = sim.make_renderer()
            rgb, _ = sim.render(r)
            auto = Exposure()
            auto.apply(r._linear(r.camera_id))
            r.close()
            img = Image.fromarray(rgb)
            ImageDraw.Draw(img).text(
                (8, 8), f"tau {tau:g}, sun elevation {el:g} deg\nAE gain {auto.gain:.2f}",
                fill=(255, 255, 255))
            tiles.append(np.asarray(img))
        rows.append(np.concatenate(tiles, axis=1))
    out = Path(__file__).parent / "img" / "camera_tau_sun.png"
    Image.fromarray(np.concatenate(rows, axis=0)).save(out, optimize=True)
    sys.stdout.write(f"{out}\n")


if __name__ == "__main__":
    main(sys.argv[1])
