"""Whole-build benchmark: 1 km x 1 km procedural scene at 0.25 m posts, craters >= 1 m,
~1e6 rocks (k = 0.05, D >= 0.1 m), written as ``.usdc`` + MJCF + catalogues + manifest.

Compared, in the same run, with the *floor*: a plain-numpy script doing the irreducible work
(a spectral-synthesis heightfield of the same shape, the terrain mesh arrays -- points,
normals, st, triangle indices -- the rock arrays, and writing as many bytes as the build
wrote, once) as whole-grid arrays, as issue 14 defines it; and a stricter *tiled floor*, the
same work done tile by tile into reused buffers as a careful script would. Runs are
interleaved (floor, tiled floor, build, ...) with ``os.sync()`` between them, each in a fresh
process (``_measure.measure``); the figures are medians.
Targets: build <= 1.5 x floor, peak RSS < 4 GB.
Run: ``python perf/run.py build`` (``--rounds``, full 3; ``--size-m`` shrinks the square and
the floor's rock count with its area).
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

from perf.suite import Param

PARAMS = (Param("rounds", int, "interleaved rounds (floor, tiled floor, build)", quick=1, full=3),
          Param("size_m", float, "side of the square scene (m)", quick=100.0, full=1000.0))
POST_M = 0.25
_SET = {"size_m": 1000.0}  # set by main before the measured calls (forked children inherit it)


def _config() -> dict[str, Any]:
    size_m = _SET["size_m"]
    return {
        "terrain": {"source": "procedural", "size_m": [size_m, size_m], "post_m": POST_M},
        "craters": {"d_min_m": 1.0},
        "rocks": {"k": 0.05, "d_min_m": 0.1},
        "export": {"usd_format": "usdc", "formats": ["usd", "mjcf"]},
    }
_OUT = Path(tempfile.gettempdir()) / f"marsscene-bench-build-{os.getpid()}"


def _build() -> dict[str, Any]:
    import marsscene as ms

    t0 = time.perf_counter()
    scene = ms.build_scene(ms.SceneConfig.from_dict(_config()), seed=7)
    t1 = time.perf_counter()
    written = ms.write_scene(scene, _OUT / "build")
    t2 = time.perf_counter()
    files = [p for paths in written.values() for p in paths]
    nbytes = sum(p.stat().st_size for p in (_OUT / "build").rglob("*") if p.is_file())
    timings = dict(scene.provenance.timings_s)
    return {"build_s": t1 - t0, "write_s": t2 - t1, "bytes": nbytes, "files": len(files),
            "rocks": len(scene.rocks or ()), "stages": timings}


def _heightfield(n: int, rng: np.random.Generator) -> np.ndarray:
    """Procedural heightfield: spectral synthesis (red-noise spectrum), plain numpy FFTs."""
    from scipy import fft

    m = fft.next_fast_len(n, real=True)  # 4001 is prime: synthesise on a fast size, crop
    spec = fft.rfft2(rng.standard_normal((m, m), dtype=np.float32), workers=1)
    k = np.hypot(fft.fftfreq(m)[:, None], fft.rfftfreq(m)[None, :]).astype(np.float32)
    spec /= np.maximum(k, 1.0 / m) ** 1.5
    return np.ascontiguousarray(fft.irfft2(spec, s=(m, m), workers=1)[:n, :n],
                                dtype=np.float32)


def _rock_arrays(rng: np.random.Generator) -> list[np.ndarray]:
    r = round(1_000_000 * (_SET["size_m"] / 1000.0) ** 2)  # the build's ~1e6 rocks per km^2
    return [rng.random((r, 3), np.float32), rng.random((r, 4)).astype(np.float16),
            rng.random((r, 3), np.float32), rng.integers(0, 8, r, dtype=np.int32)]


def _floor_tiled() -> dict[str, Any]:
    """A stricter floor: the same work as :func:`_floor_whole`, done as a careful plain-numpy
    script would: mesh arrays made tile by tile (513 x 513 posts) into reused buffers and
    written as they are made, one face array per tile shape, no whole-grid temporaries."""
    t0 = time.perf_counter()
    size_m = _SET["size_m"]
    n = int(size_m / POST_M) + 1
    rng = np.random.default_rng(7)
    z = _heightfield(n, rng)
    target = int(os.environ.get("BENCH_FLOOR_BYTES", "0"))
    out = _OUT / "floor"
    out.mkdir(parents=True, exist_ok=True)
    xs = np.arange(n, dtype=np.float32) * POST_M
    t = 512
    idx = np.arange((t + 1) ** 2, dtype=np.int32).reshape(t + 1, t + 1)
    faces = np.zeros((t, t, 6), np.int32)
    faces[..., 0] = faces[..., 3] = idx[:-1, :-1]
    faces[..., 1] = idx[:-1, 1:]
    faces[..., 2] = faces[..., 4] = idx[1:, 1:]
    faces[..., 5] = idx[1:, :-1]
    normals = np.zeros((t + 1, t + 1, 3), np.float32)
    points = np.zeros((t + 1, t + 1, 3), np.float32)
    st = np.zeros((t + 1, t + 1, 2), np.float32)
    written = 0
    shapes: set[tuple[int, int]] = set()
    with open(out / "blob.bin", "wb") as fh:

        def put(arr: np.ndarray) -> None:  # up to the build's byte count
            nonlocal written
            mv = memoryview(np.ascontiguousarray(arr)).cast("B")
            take = mv[: max(0, target - written)] if target else mv
            fh.write(take)
            written += len(take)

        put(z)
        for r0 in range(0, n - 1, t):
            r1 = min(r0 + t, n - 1) + 1
            for c0 in range(0, n - 1, t):
                c1 = min(c0 + t, n - 1) + 1
                a, b, c, d = max(r0 - 1, 0), min(r1 + 1, n), max(c0 - 1, 0), min(c1 + 1, n)
                gy, gx = np.gradient(z[a:b, c:d], POST_M)
                gx, gy = gx[r0 - a:r1 - a, c0 - c:c1 - c], gy[r0 - a:r1 - a, c0 - c:c1 - c]
                rows, cols = r1 - r0, c1 - c0
                inv = 1.0 / np.sqrt(gx * gx + gy * gy + 1.0)
                nv, pv, sv = normals[:rows, :cols], points[:rows, :cols], st[:rows, :cols]
                np.multiply(-gx, inv, out=nv[..., 0])
                np.multiply(-gy, inv, out=nv[..., 1])
                nv[..., 2] = inv
                pv[..., 0], pv[..., 1] = xs[None, c0:c1], xs[r0:r1, None]
                pv[..., 2] = z[r0:r1, c0:c1]
                np.multiply(pv[..., :2], 1.0 / size_m, out=sv)
                for arr in (nv, pv, sv):
                    put(arr)
                if (rows, cols) not in shapes:  # one face array per tile shape, as in USD
                    shapes.add((rows, cols))
                    put(faces[:rows - 1, :cols - 1])
        for arr in _rock_arrays(rng):
            put(arr)
        flat = memoryview(z).cast("B")
        while written < target:  # the build's byte count, written once
            take = flat[: target - written]
            fh.write(take)
            written += len(take)
    return {"bytes": written, "compute_s": time.perf_counter() - t0, "write_s": 0.0}


def _floor_whole() -> dict[str, Any]:
    """The floor as issue 14 defines it: the irreducible work in plain numpy, as whole-grid
    arrays (no USD, no MJCF, no Python per element). It allocates 1.35 GB of fresh memory,
    which on a virtual machine makes it slow and noisy; :func:`_floor_tiled` is stricter."""
    t0 = time.perf_counter()
    size_m = _SET["size_m"]
    n = int(size_m / POST_M) + 1
    rng = np.random.default_rng(7)
    z = _heightfield(n, rng)
    gy, gx = np.gradient(z, POST_M)
    inv = 1.0 / np.sqrt(gx * gx + gy * gy + 1.0)
    normals = np.empty((n, n, 3), np.float32)
    normals[..., 0], normals[..., 1], normals[..., 2] = -gx * inv, -gy * inv, inv
    xs = np.arange(n, dtype=np.float32) * POST_M
    points = np.empty((n, n, 3), np.float32)
    points[..., 0], points[..., 1], points[..., 2] = xs[None, :], xs[:, None], z
    st = points[..., :2] / size_m
    idx = np.arange(n * n, dtype=np.int32).reshape(n, n)
    faces = np.empty((n - 1, n - 1, 6), np.int32)
    faces[..., 0] = faces[..., 3] = idx[:-1, :-1]
    faces[..., 1] = idx[:-1, 1:]
    faces[..., 2] = faces[..., 4] = idx[1:, 1:]
    faces[..., 5] = idx[1:, :-1]
    blobs = [z, normals, points, st, faces, *_rock_arrays(rng)]
    t1 = time.perf_counter()
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
    return {"bytes": written, "compute_s": t1 - t0, "write_s": time.perf_counter() - t1}


def _sync_clean() -> None:
    shutil.rmtree(_OUT, ignore_errors=True)
    os.sync()


def main(rounds: int, size_m: float) -> dict[str, Any]:
    from perf._measure import measure

    _SET["size_m"] = size_m
    runs = {"floor": _floor_whole, "tiled": _floor_tiled, "build": _build}
    secs: dict[str, list[float]] = {k: [] for k in runs}
    peak: dict[str, list[float]] = {k: [] for k in runs}
    last: dict[str, Any] = {}
    try:
        _sync_clean()
        wall, _, last = measure(_build)  # warm-up: file cache, byte count for the floor
        os.environ["BENCH_FLOOR_BYTES"] = str(last["bytes"])
        print(f"warm-up build {wall:.2f} s ({last['rocks']:,} rocks, "
              f"{last['bytes'] / 1e6:,.0f} MB in {last['files']} files)", flush=True)
        for i in range(rounds):
            for name, fn in runs.items():
                _sync_clean()
                wall, mb, r = measure(fn)
                secs[name].append(wall)
                peak[name].append(mb)
                if name == "build":
                    last = r
            print(f"round {i + 1}: floor {secs['floor'][-1]:5.2f} s, tiled floor "
                  f"{secs['tiled'][-1]:5.2f} s, build {secs['build'][-1]:5.2f} s (stages "
                  f"{last['build_s']:.2f} s + write {last['write_s']:.2f} s)", flush=True)
    finally:
        _sync_clean()
    med = {k: statistics.median(v) for k, v in secs.items()}
    stages = ", ".join(f"{k} {v:.2f}" for k, v in sorted(last["stages"].items()))
    print(f"stage timings (last build, s): {stages}")
    print(f"floor (issue 14's: plain numpy, whole grids): median {med['floor']:6.2f} s, "
          f"peak RSS {max(peak['floor']):,.0f} MB")
    print(f"tiled floor (stricter, same work)          : median {med['tiled']:6.2f} s, "
          f"peak RSS {max(peak['tiled']):,.0f} MB")
    print(f"whole build                                : median {med['build']:6.2f} s, "
          f"peak RSS {max(peak['build']):,.0f} MB")
    print(f"build / floor: {med['build'] / med['floor']:5.2f} x (target <= 1.5; peak < 4096 MB); "
          f"build / tiled floor: {med['build'] / med['tiled']:.2f} x")
    return {"floor_s": med["floor"], "tiled_floor_s": med["tiled"], "build_s": med["build"],
            "floor_peak_mb": max(peak["floor"]), "tiled_floor_peak_mb": max(peak["tiled"]),
            "build_peak_mb": max(peak["build"]), "build_over_floor": med["build"] / med["floor"],
            "build_over_tiled_floor": med["build"] / med["tiled"], "rocks": last["rocks"],
            "bytes": last["bytes"], "files": last["files"], "stages_s": last["stages"]}

