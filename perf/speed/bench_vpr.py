"""Place-recognition dataset generation: frames per second, wall time, disk, and the baseline.

Run: ``python perf/run.py vpr [--protocol P] [--length-m L] [--out DIR]`` (full: ``dust`` on the
default scene's 60 m loop instead of Mars Base, so it needs no 1 km build; ``--protocol`` may be
``dust``, ``day-low-sun``, ``day-dim`` or a spec TOML; ``--length-m none`` keeps the
protocol's route and scene). Prints per traversal the frames, wall time and frames per second
(640 x 480, a frame every 0.1 m, JPEG), the dataset's size, and the patch-normalised
baseline's Recall@N.

``--scene DIR`` reuses a built scene folder (e.g. on a GPU machine without the build's
dependencies): it is copied to ``OUT/scene``. ``--workers 2`` drives the two traversals at once
(per-traversal rates are then not printed).
"""

from __future__ import annotations

import dataclasses
import os
import shutil
import tempfile
import time
from pathlib import Path

from perf.suite import Param, optional

os.environ.setdefault("MUJOCO_GL", "egl")
PARAMS = (Param("protocol", str, "dust, day-low-sun, day-dim or a spec TOML", quick="dust",
                full="dust"),
          Param("length_m", optional(float), "route length on the default scene (m; none: the "
                "protocol's route and scene)", quick=10.0, full=60.0),
          Param("out", optional(Path), "dataset folder (none: the temporary folder's)",
                quick=None, full=None),
          Param("scene", optional(Path), "a built scene folder to reuse", quick=None, full=None),
          Param("workers", int, "traversals driven at once", quick=1, full=1))


def main(protocol: str, length_m: float | None, out: Path | None, scene: Path | None,
         workers: int) -> dict[str, object]:
    from marsscene.benchmark.vpr.dataset import generate_vpr
    from marsscene.benchmark.vpr.eval import patch_normalised, read_split, recall_at, retrieve
    from marsscene.benchmark.vpr.spec import VprSpec

    out = out or Path(tempfile.gettempdir()) / "marsscene_bench_vpr"
    spec = VprSpec.from_toml(protocol)
    if length_m is not None:
        spec = spec.with_length(length_m)
        spec = dataclasses.replace(
            spec, scene=dataclasses.replace(spec.scene, preset=None, name="default"))
    shutil.rmtree(out, ignore_errors=True)
    if scene is not None:
        shutil.copytree(scene, out / "scene")
    marks: dict[str, list[float]] = {}

    def progress(split: str, p: object) -> None:
        marks.setdefault(split, [time.perf_counter()]).append(time.perf_counter())

    t0 = time.perf_counter()
    doc = generate_vpr(spec, out, progress=progress, workers=workers)
    total = time.perf_counter() - t0
    rates = {}
    for split, info in doc["traversals"].items():
        if split in marks:
            wall = marks[split][-1] - marks[split][0]
            rates[split] = info["frames"] / wall
            print(f"vpr {spec.name}: {split:8s} tau {info['tau']:.2f} sun "
                  f"{info['sun_elevation_deg']:4.1f} deg: {info['frames']} frames in {wall:.1f} "
                  f"s of driving = {info['frames'] / wall:.1f} frames/s")
    import resource

    peak = max(resource.getrusage(who).ru_maxrss for who in
               (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN)) / 1024
    disk = sum(p.stat().st_size for p in out.rglob("*") if p.is_file())
    print(f"vpr {spec.name}: {workers} worker(s), peak RSS of one process {peak:.0f} MB, "
          f"output folder {disk / 1e6:.0f} MB")
    size = sum(p.stat().st_size for s in ("database", "queries") for p in (out / s).iterdir())
    frames = sum(t["frames"] for t in doc["traversals"].values())
    print(f"vpr {spec.name}: {frames} frames along {doc['route_length_m']:.0f} m, "
          f"{total:.1f} s in all (build, route, JPEGs), {size / 1e6:.1f} MB of JPEG "
          f"({size / frames / 1e3:.0f} kB per frame)")
    db, q = read_split(out, "database"), read_split(out, "queries")
    t1 = time.perf_counter()
    ranked = retrieve(patch_normalised(db.files), patch_normalised(q.files), k=20)
    rec = recall_at(ranked, db.xy_m, q.xy_m, spec.radius_m)
    print(f"vpr {spec.name}: patch-normalised baseline R@1 {100 * rec.recall[1]:.1f} %, "
          f"R@5 {100 * rec.recall[5]:.1f} %, R@10 {100 * rec.recall[10]:.1f} % "
          f"({time.perf_counter() - t1:.1f} s)")
    return {"protocol": spec.name, "frames": frames, "route_m": doc["route_length_m"],
            "total_s": total, "frames_per_s": rates, "peak_rss_mb": peak,
            "output_mb": disk / 1e6, "jpeg_mb": size / 1e6,
            "recall_pct": {f"R@{n}": 100 * rec.recall[n] for n in (1, 5, 10)}}

