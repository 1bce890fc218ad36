"""Reference-scene presets at full size: build + write (usdc + MJCF + manifest) per preset.

Each preset is built in a fresh process (``_measure.measure``): wall time, peak RSS, terrain
posts, rocks and craters, and the stage timings. These are the interim resolutions of
``marsscene/data/presets.toml`` (1 m posts for the 3-3.6 km scenes) until tiled LOD terrain
exists. Run: ``python benchmarks/run.py worlds`` (about 3-4 min on the 2-core machine), or
``python benchmarks/bench_worlds.py jezero-plain`` for one preset.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._measure import measure

_NAME = ""


def _build() -> dict[str, object]:
    import marsscene as ms

    cfg = ms.SceneConfig.from_dict({"preset": _NAME, "export": {"formats": ["usd", "mjcf"],
                                                                "usd_format": "usdc"}})
    t0 = time.perf_counter()
    scene = ms.build_scene(cfg, seed=7)
    t1 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        ms.write_scene(scene, Path(tmp) / "out")
        size_mb = sum(p.stat().st_size for p in (Path(tmp) / "out").rglob("*")
                      if p.is_file()) / 1e6
    t2 = time.perf_counter()
    rows, cols = scene.heightfield.shape
    return {"build_s": round(t1 - t0, 1), "write_s": round(t2 - t1, 1),
            "posts_M": round(rows * cols / 1e6, 2),
            "rocks": len(scene.rocks) if scene.rocks is not None else 0,
            "craters": len(scene.craters) if scene.craters is not None else 0,
            "output_MB": round(size_mb, 1), "stages_s": scene.provenance.timings_s}


def main(names: list[str] | None = None) -> None:
    global _NAME
    from marsscene.presets import PRESET_NAMES

    for name in names or list(PRESET_NAMES):
        _NAME = name
        wall, peak_mb, extra = measure(_build)
        print(f"{name:>13}: {wall:6.1f} s, peak {peak_mb / 1024:5.2f} GB, {extra}", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:] or None)
