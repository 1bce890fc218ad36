"""Foundation benchmark: default build, and a 1 km x 1 km procedural terrain at 0.25 m posts
(16 M posts) built and written as USD + MJCF. Prints wall time and peak memory.

Run: ``python perf/run.py terrain``; ``--size-m`` shrinks the procedural square.
"""

from __future__ import annotations

import shutil
import tempfile
import time
from pathlib import Path

import marsscene as ms
from perf._measure import measure
from perf.suite import Param

PARAMS = (Param("size_m", float, "side of the procedural square (m)", quick=100.0, full=1000.0),)
_SIZE = {"m": 1000.0}  # set by main before the measured calls (forked children inherit it)


def _default_build() -> dict[str, float]:
    out = Path(tempfile.mkdtemp())
    try:
        t0 = time.perf_counter()
        scene = ms.build_scene(ms.SceneConfig(), seed=7)
        t1 = time.perf_counter()
        ms.write_scene(scene, out / "s")
        t2 = time.perf_counter()
        return {"build_s": t1 - t0, "write_s": t2 - t1, "posts": scene.heightfield.z_m.size}
    finally:
        shutil.rmtree(out)


def _km2_build() -> dict[str, float]:
    out = Path(tempfile.mkdtemp())
    cfg = ms.SceneConfig.from_dict(
        {
            "terrain": {"source": "procedural", "size_m": [_SIZE["m"], _SIZE["m"]], "post_m": 0.25,
                        "rms_height_m": 5.0},
            "craters": {"enabled": False},
            "rocks": {"enabled": False},
            "lighting": {"enabled": False},
            "export": {"usd_format": "usdc"},
        }
    )
    try:
        t0 = time.perf_counter()
        scene = ms.build_scene(cfg, seed=1)
        t1 = time.perf_counter()
        ms.write_scene(scene, out / "s")
        t2 = time.perf_counter()
        size_mb = sum(p.stat().st_size for p in (out / "s").rglob("*") if p.is_file()) / 1e6
        return {"build_s": t1 - t0, "write_s": t2 - t1, "posts": scene.heightfield.z_m.size,
                "output_mb": size_mb}
    finally:
        shutil.rmtree(out)


def main(size_m: float) -> list[dict[str, object]]:
    _SIZE["m"] = size_m
    wall, peak, extra = measure(_default_build)
    print(f"default build (Gale DEM -> 0.25 m, {extra['posts']:,} posts): "
          f"wall {wall:.2f} s (build {extra['build_s']:.2f} s, write {extra['write_s']:.2f} s), "
          f"peak RSS {peak:.0f} MB")
    figures: list[dict[str, object]] = [{"case": "default build", "wall_s": wall,
                                          "peak_rss_mb": peak, **extra}]
    wall, peak, extra = measure(_km2_build)
    print(f"{size_m:g} m x {size_m:g} m procedural @ 0.25 m ({extra['posts']:,} posts), "
          f"USD(usdc) + MJCF: "
          f"wall {wall:.2f} s (build {extra['build_s']:.2f} s, write {extra['write_s']:.2f} s), "
          f"peak RSS {peak:.0f} MB, output {extra['output_mb']:.0f} MB")
    figures.append({"case": f"{size_m:g} m procedural", "wall_s": wall, "peak_rss_mb": peak,
                    **extra})
    return figures

