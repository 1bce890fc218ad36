"""Reference-scene presets at full size: build + write (usdc + MJCF + manifest) per preset.

Each preset is built in a fresh process (``_measure.measure``): wall time, peak RSS, terrain
posts, rocks and craters, and the stage timings. The 3-3.6 km scenes use the two-level terrain
(0.25 m over the central 1 km, 1 m outside): ``posts_M`` is focus + outer posts and
``lod1_tiles`` the number of outer USD tile payloads. The scaling run keeps the 1 km focus and
grows the footprint from 1.2 km to 3.6 km. Run: ``python perf/run.py worlds`` (about
5 min on the 2-core machine), or ``python perf/run.py worlds --presets main-crater
--scaling-m none``; ``python perf/run.py worlds --tile`` builds one 500 m focus tile of
main-crater alone (``pipeline_lod.build_tile``: the coarse 3.6 km grid, the crater table and one
tile).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from marsscene.presets import PRESET_NAMES
from perf._measure import measure
from perf.suite import Param, floats, names

PARAMS = (Param("presets", names, "presets to build at full size, comma-separated",
                quick=("mars-base",), full=PRESET_NAMES),
          Param("scaling_m", floats, "main-crater footprints of the scaling run (m; none: skip)",
                quick=(), full=(1200.0, 2000.0, 2800.0, 3600.0)),
          Param("tile", bool, "build one focus tile of main-crater alone instead", quick=False,
                full=False))

_NAME = ""
_SIZE_M: float | None = None


def _build() -> dict[str, object]:
    import marsscene as ms

    mapping: dict[str, object] = {"preset": _NAME, "export": {"formats": ["usd", "mjcf"],
                                                              "usd_format": "usdc"}}
    if _SIZE_M is not None:
        mapping["terrain"] = {"size_m": [_SIZE_M, _SIZE_M]}
    cfg = ms.SceneConfig.from_dict(mapping)
    t0 = time.perf_counter()
    scene = ms.build_scene(cfg, seed=7)
    t1 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        ms.write_scene(scene, Path(tmp) / "out")
        size_mb = sum(p.stat().st_size for p in (Path(tmp) / "out").rglob("*")
                      if p.is_file()) / 1e6
    t2 = time.perf_counter()
    posts = scene.heightfield.z_m.size
    tiles = 0
    if scene.outer is not None:
        from marsscene.terrain.mesh import tile_ranges

        posts += scene.outer.heightfield.z_m.size
        rows, cols = scene.outer.heightfield.shape
        tiles = len(tile_ranges(rows, cfg.export.max_tile_posts)) * len(
            tile_ranges(cols, cfg.export.max_tile_posts))
    return {"build_s": round(t1 - t0, 1), "write_s": round(t2 - t1, 1),
            "posts_M": round(posts / 1e6, 2), "lod1_tiles": tiles,
            "rocks": len(scene.rocks) if scene.rocks is not None else 0,
            "craters": len(scene.craters) if scene.craters is not None else 0,
            "output_MB": round(size_mb, 1), "stages_s": scene.provenance.timings_s}


def _one_tile() -> dict[str, object]:
    """One focus tile of main-crater built alone (``pipeline_lod.build_tile``)."""
    import marsscene as ms
    from marsscene.pipeline.tile import build_tile

    cfg = ms.SceneConfig.from_dict({"preset": "main-crater"})
    t0 = time.perf_counter()
    hf, rocks = build_tile(cfg, seed=7, row=0, col=0)
    return {"tile_s": round(time.perf_counter() - t0, 1), "tile_posts_M": hf.z_m.size / 1e6,
            "rocks": len(rocks) if rocks is not None else 0}


def main(presets: tuple[str, ...], scaling_m: tuple[float, ...],
         tile: bool) -> list[dict[str, object]]:
    global _NAME, _SIZE_M
    if tile:
        wall, peak_mb, extra = measure(_one_tile)
        print(f"main-crater tile (0, 0) alone: {wall:6.1f} s, peak {peak_mb / 1024:5.2f} GB, "
              f"{extra}", flush=True)
        return [{"case": "main-crater tile (0, 0)", "wall_s": wall, "peak_rss_mb": peak_mb,
                 **extra}]
    figures: list[dict[str, object]] = []
    for name in presets:
        _NAME, _SIZE_M = name, None
        wall, peak_mb, extra = measure(_build)
        print(f"{name:>13}: {wall:6.1f} s, peak {peak_mb / 1024:5.2f} GB, {extra}", flush=True)
        figures.append({"case": name, "wall_s": wall, "peak_rss_mb": peak_mb, **extra})
    if not scaling_m:
        return figures
    print("scaling: main-crater (1 km focus at 0.25 m, 1 m outside) from 1.2 km to 3.6 km",
          flush=True)
    for size in scaling_m:
        _NAME, _SIZE_M = "main-crater", size
        wall, peak_mb, extra = measure(_build)
        km2 = (size / 1000.0) ** 2
        print(f"  {size / 1000:.1f} km: {wall:6.1f} s ({wall / km2:5.2f} s/km^2), peak "
              f"{peak_mb / 1024:5.2f} GB, posts {extra['posts_M']} M, rocks {extra['rocks']}",
              flush=True)
        figures.append({"case": f"main-crater {size:g} m", "size_m": size, "wall_s": wall,
                        "s_per_km2": wall / km2, "peak_rss_mb": peak_mb, **extra})
    return figures

