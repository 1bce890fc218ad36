"""Every scene size builds with its defaults (issue 63): wall time, peak memory and rocks written.

``marsscene build --procedural --size-m S S --seed 7`` for S = 1000 ... 3600 m, then a 2 km crop
of a full-size HiRISE-shaped DTM (6,000 samples x 18,000 lines at 1 m, valid posts in a slanted
stereo strip, ``MISSING_CONSTANT`` elsewhere; :mod:`marsscene.testing.pds3`), each in a fresh
``marsscene build`` process (peak RSS from ``os.wait4``). Rocks are counted from the manifest:
inside and outside the focus square of a two-level population, with the cut-off outside it.
Goal: each < 150 s and < 4 GB on the 2-core machine, 1 km unchanged.

Then, for comparison, the sizes of ``one_grid_sizes`` again with ``--no-lod`` (one grid at
0.25 m): since the terrain goes to two levels by itself above
:data:`marsscene.pipeline.terrain.AUTO_ONE_GRID_POSTS` posts, 2000 and 2500 m are two-level
by default, and these rows show what one grid would cost there.

Run: ``python perf/run.py scene_sizes [--sizes 1000,1500 ...] [--one-grid-sizes 2000,...]
[--no-dem]`` (quick: 1000 m only, no DTM, no one-grid rows).
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from marsscene.testing.pds3 import write_pds3_dtm
from perf._measure import marsscene_build
from perf.speed.bench_dem import dtm_surface
from perf.suite import Param, ints

SIZES_M = (1000, 1200, 1500, 2000, 2500, 3000, 3600)
DTM_LINES, DTM_SAMPLES = 18_000, 6_000
STRIP_HALF_WIDTH_POSTS = 1_100  # the 2 km crop's corners reach MISSING_CONSTANT posts
STRIP_SLANT = 0.06  # columns per line

PARAMS = (
    Param("sizes", ints, "sides of the procedural scenes built with their defaults (m)",
          quick=(1000,), full=SIZES_M),
    Param("one_grid_sizes", ints, "sides built again with --no-lod: one grid at 0.25 m (m)",
          quick=(), full=(2000, 2500)),
    Param("dem", bool, "build the 2 km crop of a full-size HiRISE-shaped DTM", quick=False,
          full=True),
)


def _dtm_blocks(rows_per_block: int = 500) -> Iterator[np.ndarray]:
    rng = np.random.default_rng(7)
    x = np.arange(DTM_SAMPLES, dtype=np.float32)
    for r0 in range(0, DTM_LINES, rows_per_block):
        y = np.arange(r0, r0 + rows_per_block, dtype=np.float32)[:, None]
        z = dtm_surface(x, y, rng)
        centre = DTM_SAMPLES / 2 + STRIP_SLANT * (y - DTM_LINES / 2)
        z[np.abs(x - centre) > STRIP_HALF_WIDTH_POSTS] = np.nan  # outside the stereo strip
        yield z.astype(np.float32)


def _rocks(manifest: Path) -> tuple[str, dict[str, Any]]:
    """The manifest's rock counts, as printed and as figures."""
    doc = json.loads(manifest.read_text())
    rocks = doc["summary"].get("rocks", {})
    levels = rocks.get("levels")
    if levels is None:
        count = rocks.get("count", 0)
        return f"{count:>9,} (one level)", {"rocks_focus": count}
    raised = ", raised to fit rocks.max_rocks" if levels["outer_d_min_raised"] else ""
    return (f"{levels['focus_count']:>9,} in focus, {levels['outer_count']:>7,} outside "
            f"(>= {levels['outer_d_min_m']:g} m{raised})",
            {"rocks_focus": levels["focus_count"], "rocks_outside": levels["outer_count"],
             "outer_d_min_m": levels["outer_d_min_m"],
             "outer_d_min_raised": levels["outer_d_min_raised"]})


def _row(name: str, args: list[str], tmp: Path) -> dict[str, Any]:
    out = tmp / "scene"
    wall, peak_mb, rc = marsscene_build(args, out)
    rocks, counts = _rocks(out / "manifest.json") if rc == 0 else (f"FAILED (exit {rc})", {})
    ok = rc == 0 and wall < 150 and peak_mb < 4096
    print(f"{name:<32} {wall:7.1f} s {peak_mb / 1024:6.2f} GB  {rocks}  "
          f"[{'ok' if ok else 'OVER GOAL'}]", flush=True)
    shutil.rmtree(out, ignore_errors=True)
    return {"scene": name, "wall_s": wall, "peak_gb": peak_mb / 1024, "exit": rc, **counts,
            "within_goal": ok}


def main(sizes: tuple[int, ...], one_grid_sizes: tuple[int, ...], dem: bool
         ) -> list[dict[str, Any]]:
    print(f"marsscene build, seed 7, niced; {os.cpu_count()} CPU cores "
          f"(load average {os.getloadavg()[0]:.1f} at the start)")
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench_scene_sizes_") as name:
        tmp = Path(name)
        for s in sizes:
            rows.append(_row(f"procedural {s} x {s} m",
                             ["--procedural", "--size-m", str(s), str(s)], tmp))
        if dem:
            t0 = time.perf_counter()
            dtm = write_pds3_dtm(tmp / "DTEEC_BENCH_U01.IMG", shape=(DTM_LINES, DTM_SAMPLES),
                                 blocks=_dtm_blocks())
            print(f"(wrote a {DTM_SAMPLES:,} x {DTM_LINES:,}-post DTM, "
                  f"{dtm.stat().st_size / 1e6:.0f} MB, in {time.perf_counter() - t0:.0f} s)")
            rows.append(_row("DTM crop 2000 x 2000 m",
                             ["--dem", str(dtm), "--size-m", "2000", "2000"], tmp))
            (tmp / dtm.name).unlink()
        for s in one_grid_sizes:
            rows.append(_row(f"procedural {s} x {s} m --no-lod",
                             ["--procedural", "--size-m", str(s), str(s), "--no-lod"], tmp))
    print(f"(load average {os.getloadavg()[0]:.1f} at the end)")
    return rows
