"""Whole-build benchmark: 1 km x 1 km procedural scene at 0.25 m posts, craters >= 1 m,
~1e6 rocks (k = 0.05, D >= 0.1 m), written as ``.usdc`` + MJCF + catalogues + manifest.

Compared, in the same run, with the *floor*: a plain-numpy script doing the irreducible work
(a spectral-synthesis heightfield of the same shape, the terrain mesh arrays -- points,
normals, st, triangle indices -- the rock arrays, and writing as many bytes as the build
wrote, once). Runs are interleaved (floor, build, floor, build, ...) with ``os.sync()``
between them, each in a fresh process (``_measure.measure``); the figures are medians.
Targets: build <= 1.5 x floor, peak RSS < 4 GB.
Run: ``python benchmarks/run.py build`` (``BENCH_ROUNDS`` rounds, default 3).
"""

from __future__ import annotations

import os
import shutil
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

SIZE_M = 1000.0
POST_M = 0.25
CONFIG = {
    "terrain": {"source": "procedural", "size_m": [SIZE_M, SIZE_M], "post_m": POST_M},
    "craters": {"d_min_m": 1.0},
    "rocks": {"k": 0.05, "d_min_m": 0.1},
    "export": {"usd_format": "usdc", "formats": ["usd", "mjcf"]},
}
_OUT = Path(tempfile.gettempdir()) / f"marsscene-bench-build-{os.getpid()}"


def _build() -> dict[str, Any]:
    import marsscene as ms

    t0 = time.perf_counter()
    scene = ms.build_scene(ms.SceneConfig.from_dict(CONFIG), seed=7)
    t1 = time.perf_counter()
    written = ms.write_scene(scene, _OUT / "build")
    t2 = time.perf_counter()
    files = [p for paths in written.values() for p in paths]
    nbytes = sum(p.stat().st_size for p in (_OUT / "build").rglob("*") if p.is_file())
    timings = dict(scene.provenance.timings_s)
    return {"build_s": t1 - t0, "write_s": t2 - t1, "bytes": nbytes, "files": len(files),
            "rocks": len(scene.rocks or ()), "stages": timings}


def _floor() -> dict[str, Any]:
    """The irreducible work in plain numpy (no USD, no MJCF, no Python per element)."""
    n = int(SIZE_M / POST_M) + 1
    rng = np.random.default_rng(7)
    # procedural heightfield: spectral synthesis (red-noise spectrum), as plain numpy FFTs
    from scipy import fft

    m = fft.next_fast_len(n, real=True)  # 4001 is prime: synthesise on a fast size, crop
    spec = fft.rfft2(rng.standard_normal((m, m), dtype=np.float32), workers=1)
    k = np.hypot(fft.fftfreq(m)[:, None], fft.rfftfreq(m)[None, :]).astype(np.float32)
    spec /= np.maximum(k, 1.0 / m) ** 1.5
    z = np.ascontiguousarray(fft.irfft2(spec, s=(m, m), workers=1)[:n, :n], dtype=np.float32)
    gy, gx = np.gradient(z, POST_M)
    inv = 1.0 / np.sqrt(gx * gx + gy * gy + 1.0)
    normals = np.empty((n, n, 3), np.float32)
    normals[..., 0], normals[..., 1], normals[..., 2] = -gx * inv, -gy * inv, inv
    xs = np.arange(n, dtype=np.float32) * POST_M
    points = np.empty((n, n, 3), np.float32)
    points[..., 0], points[..., 1], points[..., 2] = xs[None, :], xs[:, None], z
    st = points[..., :2] / SIZE_M
    idx = np.arange(n * n, dtype=np.int32).reshape(n, n)
    faces = np.empty((n - 1, n - 1, 6), np.int32)
    faces[..., 0] = faces[..., 3] = idx[:-1, :-1]
    faces[..., 1] = idx[:-1, 1:]
    faces[..., 2] = faces[..., 4] = idx[1:, 1:]
    faces[..., 5] = idx[1:, :-1]
    r = 1_000_000
    rocks = [rng.random((r, 3), np.float32), rng.random((r, 4)).astype(np.float16),
             rng.random((r, 3), np.float32), rng.integers(0, 8, r, dtype=np.int32)]
    blobs = [z, normals, points, st, faces, *rocks]
    target = int(os.environ.get("BENCH_FLOOR_BYTES", "0"))
    out = _OUT / "floor"
    out.mkdir(parents=True, exist_ok=True)
    written = 0
    with open(out / "blob.bin", "wb") as fh:
        while written < target or written == 0:  # the build's byte count, written once
            for arr in blobs:
                mv = memoryview(np.ascontiguousarray(arr)).cast("B")
                take = mv[: max(0, target - written)] if target else mv
                fh.write(take)
                written += len(take)
                if target and written >= target:
                    break
    return {"bytes": written}


def _sync_clean() -> None:
    shutil.rmtree(_OUT, ignore_errors=True)
    os.sync()


def main() -> None:
    from _measure import measure

    rounds = int(os.environ.get("BENCH_ROUNDS", "3"))
    floor_s, build_s, floor_mb, build_mb = [], [], [], []
    last: dict[str, Any] = {}
    try:
        _sync_clean()
        wall, peak, last = measure(_build)  # warm-up: file cache, byte count for the floor
        os.environ["BENCH_FLOOR_BYTES"] = str(last["bytes"])
        print(f"warm-up build {wall:.2f} s ({last['rocks']:,} rocks, "
              f"{last['bytes'] / 1e6:,.0f} MB in {last['files']} files)", flush=True)
        for i in range(rounds):
            for fn, secs, mbs in ((_floor, floor_s, floor_mb), (_build, build_s, build_mb)):
                _sync_clean()
                wall, peak, r = measure(fn)
                secs.append(wall)
                mbs.append(peak)
                if fn is _build:
                    last = r
            print(f"round {i + 1}: floor {floor_s[-1]:6.2f} s, build {build_s[-1]:6.2f} s "
                  f"(stages {last['build_s']:.2f} s + write {last['write_s']:.2f} s)",
                  flush=True)
    finally:
        _sync_clean()
    f, b = statistics.median(floor_s), statistics.median(build_s)
    stages = ", ".join(f"{k} {v:.2f}" for k, v in sorted(last["stages"].items()))
    print(f"stage timings (last build, s): {stages}")
    print(f"floor (plain numpy, same bytes): median {f:6.2f} s, peak RSS {max(floor_mb):,.0f} MB")
    print(f"whole build                     : median {b:6.2f} s, peak RSS {max(build_mb):,.0f} MB")
    print(f"build / floor                   : {b / f:5.2f} x (target <= 1.5; peak < 4096 MB)")


if __name__ == "__main__":
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    main()
