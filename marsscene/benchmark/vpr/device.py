"""The VPR dataset's two traversals driven at once on MuJoCo Warp (``benchmark vpr --device``).

Each traversal is a :class:`marsscene.BatchDrive` of one batch: its offset route, its seeded
lookahead, its lighting (dust, sun, the irradiance of another sun's elevation, exposure) and
its noise seed as :func:`.dataset.generate_vpr` gives a CPU drive; the camera (size, sensor
noise, a frame every ``spacing_m`` driven) is the spec's. The batch's physics (sphere wheels,
heightfield rocks) and camera (:class:`~marsscene.sensors.batch.BatchCamera`) are not the CPU
drive's, so its datasets are keyed apart. The frames are then written as the CPU path writes
them (:func:`.traversal.write_traversal`).
"""

from __future__ import annotations

from contextlib import ExitStack
from pathlib import Path
from typing import Any

from marsscene._atomic import replacing_dir
from marsscene.benchmark.vpr.spec import SPLITS

__all__ = ["BATCH_ENGINE", "drive_traversals"]

#: The dataset key's engine entry of batch-driven traversals.
BATCH_ENGINE = "mujoco_warp"


def drive_traversals(jobs: list[tuple[Any, ...]], device: str) -> None:
    """Drive the traversals of ``jobs`` (:func:`.dataset.generate_vpr`'s: spec, split, scene,
    route, offset, lookahead, out, key) in one batch on ``device`` and write each one's
    images, poses and key; a failure leaves no traversal half written."""
    import marsscene as ms
    from marsscene.benchmark.vpr.traversal import (
        irradiance_scale,
        offset_route,
        write_traversal,
    )
    from marsscene.sim.route import Route

    spec, scene_dir = jobs[0][0], Path(jobs[0][2])
    with ExitStack() as stack:
        drives, dirs = [], []
        for _, split, _, route_xy, offset_m, lookahead_m, out, _ in jobs:
            lighting = getattr(spec, split)
            run_dir = stack.enter_context(replacing_dir(out / "traversals" / split))
            dest = stack.enter_context(replacing_dir(out / split, create=False))
            dirs.append((run_dir, dest))
            drives.append(ms.BatchDrive(
                scene=scene_dir, route=Route(offset_route(route_xy, offset_m)), out_dir=run_dir,
                seed=spec.seed + 1000 * SPLITS.index(split), tau=lighting.tau,
                sun_elevation_deg=lighting.sun_elevation_deg,
                sun_azimuth_deg=lighting.sun_azimuth_deg,
                irradiance_scale=irradiance_scale(lighting, scene_dir),
                exposure=lighting.exposure, lookahead_m=lookahead_m, lidar=False))
        camera = spec.camera_config(getattr(spec, jobs[0][1]))
        ms.drive_batch(drives, config=ms.RunConfig(camera=camera), device=device)
        for job, (run_dir, dest) in zip(jobs, dirs, strict=True):
            write_traversal(spec, job[1], run_dir, dest, job[7])
