"""Terrain shadows at a low sun against a penumbra-aware truth (issue 36).

The rock-free default scene (seed 7, ``rocks.enabled = false``), dust tau = 0.1, sun azimuth
30 deg, 640 x 480, auto exposure off (fixed, so the two renders compare linearly): from
``VIEWS`` poses the camera renders each frame with and without shadows; per ground pixel
within 30 m the ratio of the two linear renders is what the renderer drew. The truth: a ray
march from the pixel's world point toward the sun over the heightfield gives the terrain's
horizon elevation there; the visible fraction of the sun's disc (0.35 deg wide: the circular
segment above that horizon) gives the expected ratio ``(sky + v E cos) / (sky + E cos)``.

Printed per elevation (2, 5, 13 deg): among **fully lit** pixels (horizon more than
``MARGIN_DEG`` below the sun's lower limb) the share rendered at ratio < 0.8 (the issue's
figure: 7.5 % at 2 deg before issue 36) and < 0.95; among **fully shadowed** ones (horizon more
than ``MARGIN_DEG`` above the upper limb) the share rendered lit (ratio above halfway); the mean
absolute ratio error in the penumbra; and where the lit ones rendered dark sit (their horizon
below the sun's centre, deg). ``--figure DIR`` writes one frame per elevation with the spurious
pixels in red.

Run: ``python perf/run.py shadow_accuracy [--elevations 2,5,13]`` (the full size's).
"""

from __future__ import annotations

import math
import os
import tempfile
import time
from pathlib import Path
from typing import Any

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np

from marsscene.testing.shadow_truth import disc_visible, horizon_excess_deg
from perf.suite import Param, floats, optional

PARAMS = (Param("elevations", floats, "sun elevations (deg), comma-separated", quick=(13.0,),
                full=(2.0, 5.0, 13.0)),
          Param("views", int, "camera poses of the 12 (across, toward, away from the sun)",
                quick=2, full=12),
          Param("figure", optional(Path), "folder to write one frame per elevation into",
                quick=None, full=None))

_SCENE = Path(tempfile.gettempdir()) / "marsscene_bench_rockfree_scene"
#: (x, y) m, heading (rad): across, toward and away from the sun (azimuth 30 deg)
VIEWS = [((x, y), math.radians(h)) for (x, y) in ((20.0, 20.0), (-40.0, 10.0), (0.0, -45.0))
         for h in (300.0, 30.0, 120.0, 210.0)]
#: Distance (deg) of the horizon from the sun's limb for a pixel to count as fully lit or shadowed
MARGIN_DEG = 0.025
_SIZE = {"width_px": 640, "height_px": 480, "tau": 0.1, "sun_azimuth_deg": 30.0,
         "exposure": "fixed"}


def _build() -> None:
    import marsscene as ms

    cfg = ms.SceneConfig.from_dict({"rocks": {"enabled": False}})
    ms.write_scene(ms.build_scene(cfg, seed=7), _SCENE, formats=("mjcf",), overwrite=True)


def world_points(cam, depth_m: np.ndarray) -> np.ndarray:  # type: ignore[no-untyped-def]
    """World points (H, W, 3) of a depth image of the camera's current pose."""
    m, d, cid = cam.model, cam.data, cam.camera_id
    h, w = depth_m.shape
    f = 0.5 * h / math.tan(math.radians(float(m.cam_fovy[cid])) / 2.0)
    u, v = np.meshgrid(np.arange(w) + 0.5 - w / 2, np.arange(h) + 0.5 - h / 2)
    ray = np.stack([u / f, -v / f, -np.ones_like(u)], axis=-1) * depth_m[..., None]
    return d.cam_xpos[cid] + ray @ d.cam_xmat[cid].reshape(3, 3).T


def measure(elevation_deg: float, figure: Path | None = None,
            views: int = len(VIEWS)) -> dict[str, Any]:
    from marsscene.runtime import CameraConfig, RunConfig
    from marsscene.sim.rover_sim import RoverSim

    sims, cams = [], []
    for shadows in (True, False):
        run = RunConfig(camera=CameraConfig(**_SIZE, sun_elevation_deg=elevation_deg,
                                            shadows=shadows))
        sims.append(RoverSim(_SCENE, run=run, start_xy_m=VIEWS[0][0], settle_s=0.2))
        cam = sims[-1].make_renderer()
        if not os.environ.get("MARSSCENE_BENCH_ROVER_SHADOW"):
            cam.model.geom_castshadow[cam.model.geom_bodyid != 0] = 0  # the rover casts none
        cams.append(cam)
    lt = cams[0].lighting
    sun = np.asarray(lt.sun_direction_enu)
    radius_deg = lt.sun_angular_diameter_deg / 2.0
    hf = sims[0].heightfield
    lit_n = lit_dark = lit_grey = shade_n = shade_lit = pen_n = 0
    pen_err = 0.0
    where: list[np.ndarray] = []
    for k, (xy, yaw) in enumerate(VIEWS[:views]):
        lin = []
        for sim, cam in zip(sims, cams, strict=True):
            sim.reset(xy_m=xy, yaw_rad=yaw)
            cam._sync(sim)
            lin.append(cam._render(cam.camera_id, True))
        (shadowed, depth), (plain, _) = lin
        assert depth is not None
        pts = world_points(cams[0], depth)
        on_ground = (depth > 0) & (depth < 30.0)
        on_ground &= np.abs(pts[..., 2] - hf.sample(pts[..., 0], pts[..., 1])) < 0.05
        on_ground[::2] = False  # every other row and column: a quarter of the pixels
        on_ground[:, ::2] = False
        p = pts[on_ground]
        facing = np.maximum(hf.normal(p[:, 0], p[:, 1]) @ sun, 0.0)
        sky, direct = lt.diffuse_horizontal_w_m2, lt.direct_normal_w_m2 * facing
        plain_sum = plain[on_ground].sum(axis=-1)
        ratio = shadowed[on_ground].sum(axis=-1) / np.maximum(plain_sum, 1e-6)
        usable = (sky / (sky + direct) < 0.6) & (plain_sum > 8 / 255)
        excess = horizon_excess_deg(hf, p, sun, step_m=0.02, growth=0.005, reach_m=150.0)
        want = (sky + disc_visible(excess, radius_deg) * direct) / (sky + direct)
        lit = usable & (excess < -radius_deg - MARGIN_DEG)
        shade = usable & (excess > radius_deg + MARGIN_DEG)
        pen = usable & (np.abs(excess) <= radius_deg)
        lit_n += int(lit.sum())
        lit_dark += int((lit & (ratio < 0.8)).sum())
        lit_grey += int((lit & (ratio < 0.95)).sum())
        shade_n += int(shade.sum())
        shade_lit += int((shade & (ratio > (1.0 + want) / 2.0)).sum())
        pen_n += int(pen.sum())
        pen_err += float(np.abs(ratio - want)[pen].sum())
        where.append(excess[lit & (ratio < 0.8)])
        if os.environ.get("MARSSCENE_BENCH_VERBOSE"):
            print(f"  view {k}: lit {int(lit.sum())}, dark {int((lit & (ratio < 0.8)).sum())}, "
                  f"shadowed {int(shade.sum())}, rendered lit "
                  f"{int((shade & (ratio > (1.0 + want) / 2.0)).sum())}", flush=True)
        if figure is not None and k == 1:
            from PIL import Image

            img = np.clip(np.asarray(shadowed) * 255.0 * 2.0, 0, 255).astype(np.uint8)
            bad = np.zeros(on_ground.shape, bool)
            bad[on_ground] = lit & (ratio < 0.8)
            img[bad] = (255, 0, 0)
            Image.fromarray(img).save(figure / f"shadow_accuracy_{elevation_deg:g}deg.png")
    for cam in cams:
        cam.close()
    dark = np.concatenate(where) if where else np.zeros(0)
    return {"lit": lit_n, "lit_dark_pct": 100.0 * lit_dark / max(lit_n, 1),
            "lit_grey_pct": 100.0 * lit_grey / max(lit_n, 1), "shadowed": shade_n,
            "shadow_lit_pct": 100.0 * shade_lit / max(shade_n, 1), "penumbra": pen_n,
            "penumbra_err": pen_err / max(pen_n, 1),
            "dark_at_deg": (float(np.percentile(dark, 5)), float(np.percentile(dark, 95)))
            if len(dark) else (math.nan, math.nan)}


def main(elevations: tuple[float, ...], views: int, figure: Path | None) -> list[dict[str, Any]]:
    figures: list[dict[str, Any]] = []
    if not (_SCENE / "mjcf" / "scene.xml").is_file():
        _build()
    for e in elevations:
        t0 = time.perf_counter()
        r = measure(e, figure, views)
        lo, hi = r["dark_at_deg"]
        print(f"shadow accuracy: sun {e:g} deg, {views} views: fully lit {r['lit']} px, "
              f"rendered darker (ratio < 0.8) {r['lit_dark_pct']:.2f} % (< 0.95: "
              f"{r['lit_grey_pct']:.2f} %; their horizon {-hi:.2f}-{-lo:.2f} deg below the "
              f"sun's centre); fully shadowed {r['shadowed']} px, rendered lit "
              f"{r['shadow_lit_pct']:.2f} %; penumbra {r['penumbra']} px, mean |ratio error| "
              f"{r['penumbra_err']:.3f} ({time.perf_counter() - t0:.0f} s)", flush=True)
        figures.append({"elevation_deg": e, "views": views, **r,
                        "wall_s": time.perf_counter() - t0})
    return figures

