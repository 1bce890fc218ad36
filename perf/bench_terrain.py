"""Foundation benchmark: default build, and a 1 km x 1 km procedural terrain at 0.25 m posts
(16 M posts) built and written as USD + MJCF. Prints wall time and peak memory.

Run: ``python perf/run.py terrain``
"""

from __future__ import annotations

import shutil
import tempfile
import time
from pathlib import Path

from _measure import measure

import marsscene as ms


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
            "terrain": {"source": "procedural", "size_m": [1000.0, 1000.0], "post_m": 0.25,
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


def main() -> None:
    wall, peak, extra = measure(_default_build)
    print(f"default build (Gale DEM -> 0.25 m, {extra['posts']:,} posts): "
          f"wall {wall:.2f} s (build {extra['build_s']:.2f} s, write {extra['write_s']:.2f} s), "
          f"peak RSS {peak:.0f} MB")
    wall, peak, extra = measure(_km2_build)
    print(f"1 km x 1 km procedural @ 0.25 m ({extra['posts']:,} posts), USD(usdc) + MJCF: "
          f"wall {wall:.2f} s (build {extra['build_s']:.2f} s, write {extra['write_s']:.2f} s), "
          f"peak RSS {peak:.0f} MB, output {extra['output_mb']:.0f} MB")


if __name__ == "__main__":
    main()
