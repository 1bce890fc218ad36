"""What ``--traversability`` adds to a build (issue 66): wall time, peak memory and disk of
``marsscene build --traversability`` against the same ``marsscene build`` without it, each in a
fresh niced process (peak RSS from ``os.wait4``), on the embedded default scene and on the
3.6 km ``main-crater`` preset (0.25 m posts in its central 1 km, 1 m outside), seed 7.

The layers are computed from the built scene (``marsscene.traversability``: slope, roughness,
step, rocks against the rover, soil slip, cost and hazard on their grid) and written as one
GeoTIFF, a PNG preview and a summary.

Run: ``python perf/run.py traversability [--scenes default,main-crater] [--rounds N]``
(quick: the default scene, one round).
"""

from __future__ import annotations

import os
import shutil
import statistics
import tempfile
from pathlib import Path
from typing import Any

from perf._measure import marsscene_build
from perf.suite import Param, names

SCENES = {"default": [], "main-crater": ["--preset", "main-crater"]}

PARAMS = (Param("scenes", names, "scenes: default (embedded), main-crater (3.6 km preset)",
                quick=("default",), full=("default", "main-crater")),
          Param("rounds", int, "alternating builds with and without the layers", quick=1,
                full=3))


def _disk_mb(folder: Path) -> float:
    return sum(p.stat().st_size for p in folder.rglob("*") if p.is_file()) / 1e6


def _scene(name: str, rounds: int, tmp: Path) -> dict[str, Any]:
    runs: dict[bool, list[tuple[float, float]]] = {False: [], True: []}
    layers_mb = 0.0
    for _ in range(rounds):
        for layers in (False, True):
            out = tmp / "scene"
            args = [*SCENES[name], *(["--traversability"] if layers else [])]
            wall, peak_mb, rc = marsscene_build(args, out)
            if rc:
                raise RuntimeError(f"marsscene build {' '.join(args)} exited {rc}")
            runs[layers].append((wall, peak_mb))
            if layers:
                layers_mb = _disk_mb(out / "traversability")
            shutil.rmtree(out, ignore_errors=True)
    (w0, m0), (w1, m1) = ((statistics.median(r[0] for r in runs[k]),
                           max(r[1] for r in runs[k])) for k in (False, True))
    print(f"{name:<12} build {w0:6.1f} s {m0 / 1024:5.2f} GB | with layers {w1:6.1f} s "
          f"{m1 / 1024:5.2f} GB | added {w1 - w0:+6.1f} s {(m1 - m0) / 1024:+5.2f} GB, "
          f"{layers_mb:.1f} MB on disk", flush=True)
    return {"scene": name, "build_s": w0, "build_peak_gb": m0 / 1024, "with_layers_s": w1,
            "with_layers_peak_gb": m1 / 1024, "added_s": w1 - w0,
            "added_peak_gb": (m1 - m0) / 1024, "layers_mb": layers_mb}


def main(scenes: tuple[str, ...], rounds: int) -> list[dict[str, Any]]:
    unknown = sorted(set(scenes) - set(SCENES))
    if unknown:
        raise SystemExit(f"unknown scene {unknown[0]!r}; choose from {', '.join(SCENES)}")
    print(f"marsscene build [--traversability], seed 7, niced, median of {rounds} round(s); "
          f"{os.cpu_count()} CPU cores (load average {os.getloadavg()[0]:.1f} at the start)")
    with tempfile.TemporaryDirectory(prefix="bench_traversability_") as name:
        rows = [_scene(s, rounds, Path(name)) for s in scenes]
    print(f"(load average {os.getloadavg()[0]:.1f} at the end)")
    return rows
