"""Render a marsscene stage in Blender (``pip install bpy``; Python 3.11) from one of its cameras.

Usage::

    python examples/blender_render.py out/scene.usda navcam.png --exposure 4.2e-4 \
        [--camera Navcam] [--size 320 240] [--samples 16]

Needs only ``bpy`` (no marsscene, no usd-core: bpy pins its own numpy and bundles its own USD).
``--exposure`` is the camera's linear exposure scale, which Blender does not import; get it
with usd-core::

    from pxr import Usd, UsdGeom
    stage = Usd.Stage.Open("out/scene.usda")
    UsdGeom.Camera(stage.GetPrimAtPath("/World/Cameras/Navcam")).ComputeLinearExposureScale()

What the script does beyond ``bpy.ops.wm.usd_import``:

* creates a World first: the importer turns the first DomeLight (the lat-long sky texture)
  into the world shader only when the scene has a world;
* divides sun strengths by 4: Blender's importer multiplies a DistantLight's intensity by 4
  ("approximately matches Karma", ``usd_reader_light.cc``), while UsdLux defines it as the
  illuminance on a surface facing the light (what marsscene writes);
* sets Film exposure to ``log2(exposure)`` stops and the "Standard" view transform, so a grey
  card of albedo 0.18 on the ground renders at linear 0.18.
"""

from __future__ import annotations

import argparse
import math
import sys

#: Blender's USD importer scales DistantLight intensity by this factor (Blender 4.1-5.0);
#: the same value as marsscene.export.usd.display.BLENDER_SUN_IMPORT_FACTOR.
BLENDER_SUN_IMPORT_FACTOR = 4.0


def render(stage: str, out_png: str, *, exposure: float, camera: str = "Navcam",
           size: tuple[int, int] = (320, 240), samples: int = 16) -> None:
    """Import ``stage`` and write a Cycles (CPU) render from ``camera`` to ``out_png``."""
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.world = bpy.data.worlds.new("World")
    if bpy.ops.wm.usd_import(filepath=stage) != {"FINISHED"}:
        raise RuntimeError(f"Blender could not import {stage}")
    for obj in bpy.data.objects:
        if obj.type == "LIGHT" and obj.data.type == "SUN":
            obj.data.energy /= BLENDER_SUN_IMPORT_FACTOR
    if camera not in bpy.data.objects:
        raise KeyError(f"no camera {camera!r} in {stage}")
    scene.camera = bpy.data.objects[camera]
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.cycles.seed = 0
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.exposure = math.log2(exposure)
    scene.render.image_settings.file_format = "PNG"
    scene.render.filepath = out_png
    bpy.ops.render.render(write_still=True)


def main(argv: list[str]) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("stage")
    p.add_argument("out_png")
    p.add_argument("--exposure", type=float, required=True)
    p.add_argument("--camera", default="Navcam")
    p.add_argument("--size", type=int, nargs=2, default=(320, 240))
    p.add_argument("--samples", type=int, default=16)
    a = p.parse_args(argv)
    render(a.stage, a.out_png, exposure=a.exposure, camera=a.camera, size=tuple(a.size),
           samples=a.samples)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
