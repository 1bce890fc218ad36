"""Level-of-detail seams: border mismatch and slopes in the blend band, per preset.

For each level-of-detail preset (seed 7) the terrain, craters and focus tiles are built as
``build_scene`` builds them; then the benchmark prints the RMS of the border mismatch (fine
surface at the coarse border posts minus the coarse surface, before stitching) and the 1 m
slopes in the ``lod_blend_m`` band outside the focus before and after stitching (median, 99th
percentile, max). Run: ``python perf/run.py lod_seams [--presets main-crater]``.
"""

from __future__ import annotations

import time

import numpy as np

from perf.suite import Param, names

PARAMS = (Param("presets", names, "level-of-detail presets, comma-separated",
                quick=("main-crater",), full=("main-crater", "grand-canyon")),)


def seams(name: str, seed: int = 7) -> dict[str, object]:
    import marsscene as ms
    from marsscene.pipeline.lod import focus_heightfield, lod_craters, lod_world
    from marsscene.terrain.lod import stitch

    cfg = ms.SceneConfig.from_dict({"preset": name})
    t0 = time.perf_counter()
    world = lod_world(cfg.terrain, seed)
    coarse, craters, _ = lod_craters(world, cfg.craters, seed)
    fine = focus_heightfield(world, craters, cfg.craters)
    t1 = time.perf_counter()
    plan, k = world.plan, world.plan.ratio
    n = plan.cells
    inner = coarse.z_m[plan.row0:plan.row0 + n + 1, plan.col0:plan.col0 + n + 1]
    fz = fine.z_m[::k, ::k]
    border = np.concatenate([fz[0] - inner[0], fz[-1] - inner[-1], fz[:, 0] - inner[:, 0],
                             fz[:, -1] - inner[:, -1]])
    after = stitch(coarse, fine, plan, blend_m=cfg.terrain.lod_blend_m)
    b = int(np.ceil(cfg.terrain.lod_blend_m / plan.coarse_post_m))
    rows, cols = coarse.shape
    r = np.arange(rows)[:, None]
    c = np.arange(cols)[None, :]
    dr = np.maximum(np.maximum(plan.row0 - r, r - (plan.row0 + n)), 0)
    dc = np.maximum(np.maximum(plan.col0 - c, c - (plan.col0 + n)), 0)
    band = (np.maximum(dr, dc) > 0) & (np.hypot(dr, dc) <= b)

    def stats(hf: ms.Heightfield) -> list[float]:
        s = hf.slope_deg()[band]
        return [round(float(np.median(s)), 1), round(float(np.percentile(s, 99)), 1),
                round(float(s.max()), 1)]

    return {"preset": name, "tiles_s": round(t1 - t0, 1),
            "border_mismatch_rms_m": round(float(np.sqrt(np.mean(border**2))), 3),
            "border_mismatch_max_m": round(float(np.abs(border).max()), 3),
            "band_slope_before_deg": stats(coarse), "band_slope_after_deg": stats(after)}


def main(presets: tuple[str, ...]) -> list[dict[str, object]]:
    figures = []
    for name in presets:
        figures.append(seams(name))
        print(figures[-1], flush=True)
    return figures

