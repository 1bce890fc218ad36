"""One mast-camera frame and the camera's baked ground textures of a scene, as PNG files.

Usage: ``MUJOCO_GL=egl python examples/camera_ground.py SCENE_DIR OUT_DIR [X Y]`` (e.g. after
``marsscene build --seed 7 --out scenes/demo``; a scene built with ``--ortho`` shows the
orthoimage in the far texture). Writes ``frame.png`` (exposed sRGB), ``depth.png`` (mm),
``ground_near.png`` (16 m at 3.9 mm texels) and ``ground_far.png`` (the 60 m window at 3.1 cm
texels), north up; see docs/camera.md.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from PIL import Image

from marsscene.runtime import CameraConfig, RunConfig
from marsscene.sim.rover_sim import RoverSim


def main(scene: str, out: str, x_m: float = 0.0, y_m: float = 0.0) -> None:
    import mujoco

    out_dir = Path(out)
    out_dir.mkdir(parents=True, exist_ok=True)
    sim = RoverSim(scene, run=RunConfig(camera=CameraConfig()), start_xy_m=(x_m, y_m))
    cam = sim.make_renderer()
    rgb, depth = sim.render(cam)
    Image.fromarray(rgb).save(out_dir / "frame.png")
    if depth is not None:
        Image.fromarray(np.clip(np.rint(depth * 1000), 0, 65535).astype(np.uint16)).save(
            out_dir / "depth.png")
    m = cam.model
    for name in ("near", "far"):
        tid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_TEXTURE, f"cam_ground_{name}")
        h, w, adr = int(m.tex_height[tid]), int(m.tex_width[tid]), int(m.tex_adr[tid])
        tex = m.tex_data[adr : adr + h * w * 3].reshape(h, w, 3)
        Image.fromarray(np.ascontiguousarray(tex[::-1])).save(out_dir / f"ground_{name}.png")
    cam.close()
    sys.stdout.write(f"wrote {out_dir}/frame.png, depth.png, ground_near.png, ground_far.png\n")


if __name__ == "__main__":
    if len(sys.argv) not in (3, 5):
        raise SystemExit(__doc__)
    main(sys.argv[1], sys.argv[2], *(float(v) for v in sys.argv[3:5]))
