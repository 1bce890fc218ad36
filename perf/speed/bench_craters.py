"""Crater sampling + stamping benchmark (issue: craters).

All craters >= 1 m on a 1 km x 1 km terrain at 0.25 m posts (4001 x 4001), 3.5 Ga surface,
``hartmann-daubar-2016`` system, Hartmann (1984) equilibrium cap, up to 1 km diameter. Reported
for the default diffusion degradation and for fresh craters (``degradation = "none"``, every
sampled crater stamped), plus the default ``marsscene build`` crater stage (Gale DEM).
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from perf._measure import measure
from perf.suite import Param

PARAMS = (Param("posts", int, "posts along each side of the terrain (0.25 m apart)", quick=1001,
                full=4001),
          Param("default_build", bool, "also time the default build's crater stage", quick=False,
                full=True))
_POSTS = {"n": 4001}  # set by main before the measured calls (forked children inherit it)


def _run(degradation: str) -> dict[str, float]:
    from marsscene.craters import CraterConfig, sample_craters, stamp_craters
    from marsscene.craters.stamp import _families, _Params
    from marsscene.terrain.heightfield import Heightfield

    hf = Heightfield.centered(np.zeros((_POSTS["n"], _POSTS["n"]), np.float32), 0.25)
    cfg = CraterConfig(system="hartmann-daubar-2016", age_ga=3.5, d_min_m=1.0, d_max_m=1000.0,
                       degradation=degradation)
    t0 = time.perf_counter()
    table, st = sample_craters(hf.bounds_xy_m, cfg, rng=np.random.default_rng(7))
    t1 = time.perf_counter()
    stamp_craters(hf, table, profile_kwargs=cfg.profile_kwargs())
    t2 = time.perf_counter()
    p = _Params(table, _families(cfg.profile_kwargs(), table.profile))
    side = np.minimum(2 * p.reach * p.semi_major / 0.25 + 1, _POSTS["n"])
    return {"sample_s": t1 - t0, "stamp_s": t2 - t1, "n": float(len(table)),
            "sampled": float(st.sampled), "footprint_posts": float((side**2).sum())}


def _degraded() -> dict[str, float]:
    return _run("diffusion")


def _fresh() -> dict[str, float]:
    return _run("none")


def _default_build() -> dict[str, float]:
    import marsscene as ms

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = ms.build_scene(seed=7)
    return {"craters_s": scene.provenance.timings_s["craters"], "n": float(len(scene.craters)),
            "terrain_s": scene.provenance.timings_s["terrain"]}


def main(posts: int, default_build: bool) -> list[dict[str, object]]:
    _POSTS["n"] = posts
    figures: list[dict[str, object]] = []
    area_km2 = ((posts - 1) * 0.25 / 1000.0) ** 2
    for label, fn in ((f"{area_km2:g} km^2, default degradation", _degraded),
                      (f"{area_km2:g} km^2, fresh (degradation none)", _fresh)):
        wall, peak, r = measure(fn)
        total = r["sample_s"] + r["stamp_s"]
        print(f"{label}: {int(r['n'])} craters stamped ({int(r['sampled'])} sampled over the "
              f"grown area); sample {r['sample_s']:.2f} s, stamp {r['stamp_s']:.2f} s, "
              f"total {total:.2f} s ({r['n'] / total:,.0f} craters/s); summed footprints "
              f"{r['footprint_posts']:.3g} posts ({1e9 * r['stamp_s'] / r['footprint_posts']:.0f} "
              f"ns/post); wall {wall:.2f} s incl. setup; peak RSS {peak:.0f} MB")
        figures.append({"case": label, "craters": int(r["n"]), "sampled": int(r["sampled"]),
                        "sample_s": r["sample_s"], "stamp_s": r["stamp_s"], "total_s": total,
                        "craters_per_s": r["n"] / total,
                        "footprint_posts": r["footprint_posts"],
                        "ns_per_post": 1e9 * r["stamp_s"] / r["footprint_posts"],
                        "wall_s": wall, "peak_rss_mb": peak})
    if not default_build:
        return figures
    wall, peak, r = measure(_default_build)
    print(f"default build (Gale DEM 347 x 336 m at 0.25 m): crater stage {r['craters_s']:.2f} s "
          f"for {int(r['n'])} craters (terrain stage {r['terrain_s']:.2f} s); peak RSS "
          f"{peak:.0f} MB")
    figures.append({"case": "default build", "craters": int(r["n"]),
                    "craters_stage_s": r["craters_s"], "terrain_stage_s": r["terrain_s"],
                    "peak_rss_mb": peak})
    return figures

