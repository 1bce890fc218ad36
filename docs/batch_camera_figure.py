"""Regenerate a figure of one frame from the CPU camera (MastCamera, MuJoCo's OpenGL renderer)
and the batch camera (BatchCamera, Warp: the scene's terrain, MJCF rocks, catalogue rocks and
placed assets), same world and pose; RGB above, depth below (0-20 m, black: sky).

Usage: ``MUJOCO_GL=egl python docs/batch_camera_figure.py SCENE_DIR [X Y [NAME]]`` (the rover's
start, default -5 1; NAME default ``batch_camera_cpu_gpu``: ``docs/img/NAME.png``), e.g. a
``WorldSampler(base="rocks")`` world. Runs on Warp's CPU device; prints the frame's statistics
(depth median difference, mean sRGB of terrain and sky).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import mujoco
import numpy as np
import warp as wp
from PIL import Image, ImageDraw

from marsscene.rover.config import CameraConfig, RunConfig
from marsscene.sensors.batch import BatchCamera
from marsscene.sensors.batch.rgbd import scene_lights
from marsscene.sensors.camera_scene import scene_seed
from marsscene.sim.rover_sim import RoverSim

CAM = CameraConfig(width_px=320, height_px=240, texture_px=1024)


def main(scene: str, start_xy_m: tuple[float, float] = (-5.0, 1.0),
         name: str = "batch_camera_cpu_gpu") -> None:
    from marsscene.sim.batch.setup import scene_camera_world

    folder = Path(scene)
    sim = RoverSim(folder, run=RunConfig(camera=CAM), start_xy_m=start_xy_m, settle_s=0.3)
    renderer = sim.make_renderer()
    rgb, depth = sim.render(renderer)
    renderer.close()
    cid = mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_CAMERA, "rover/navcam")
    batch, catalogue, assets = scene_camera_world(folder)
    cam = BatchCamera(batch, 1, config=CAM, lighting=scene_lights(CAM, folder),
                      seeds=[scene_seed(folder)], catalogue=catalogue, assets=assets,
                      device="cpu")
    pos = wp.array(sim.data.cam_xpos[cid][None, None].astype(np.float32), dtype=wp.vec3,
                   device="cpu")
    mat = wp.array(sim.data.cam_xmat[cid].reshape(1, 1, 3, 3).astype(np.float32),
                   dtype=wp.mat33, device="cpu")
    cam.render(pos, mat, [0])
    g_rgb, g_depth = cam.rgb.numpy()[0].transpose(1, 2, 0), cam.depth.numpy()[0]
    seg = cam.segmentation.numpy()[0]
    both = (g_depth > 0) & (depth > 0) & (depth < 20)
    ground, sky = (seg == 1) & (depth > 0), (seg == 0) & (depth == 0)
    sys.stdout.write(
        f"depth median |diff| {np.median(np.abs(g_depth[both] - depth[both])) * 100:.2f} cm; "
        f"terrain mean sRGB CPU {rgb[ground].mean(0).round(1)} GPU "
        f"{g_rgb[ground].mean(0).round(1)}; sky CPU {rgb[sky].mean(0).round(1)} GPU "
        f"{g_rgb[sky].mean(0).round(1)}\n")
    shade = lambda d: np.repeat((np.clip(d / 20.0, 0, 1) * 255).astype(np.uint8)[..., None],  # noqa: E731
                                3, axis=2)
    top = np.concatenate([rgb, g_rgb], axis=1)
    bottom = np.concatenate([shade(depth), shade(g_depth)], axis=1)
    img = Image.fromarray(np.concatenate([top, bottom], axis=0))
    draw = ImageDraw.Draw(img)
    for x, label in ((8, "CPU camera (MuJoCo OpenGL)"), (328, "BatchCamera (Warp)")):
        draw.text((x, 8), label, fill=(255, 255, 255))
    out = Path(__file__).parent / "img" / f"{name}.png"
    img.save(out, optimize=True)
    sys.stdout.write(f"{out}\n")


if __name__ == "__main__":
    args = sys.argv[1:]
    main(args[0], (float(args[1]), float(args[2])) if len(args) >= 3 else (-5.0, 1.0),
         *(args[3:4]))
