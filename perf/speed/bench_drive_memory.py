"""Where a benchmark drive's memory and time go: a SLAM cell's drive, stage by stage (issue 36).

Run: ``python perf/run.py drive_memory [--scene NAME] [--seconds S] [--length-m L]`` (full:
``grand-canyon``, 12 sim s on a 60 m route of its shape). Builds the paper spec's scene (seed
1, MJCF only) into a temporary folder unless it is there, then drives with the paper spec's
sensors (640 x 480 RGB-D at 10 Hz, the spec's LiDAR, ``ln200s`` noise) the way a benchmark
cell does, printing the resident memory (RSS) and its peak after each stage: loading the
world for the route, the route, the simulator, the camera's renderer (world, textures,
terrain shadows, the GL context), the LiDAR's caster, every 4 sim s of the drive, and the
exports (the LiDAR bag, TUM RGB-D and EuRoC folders). ``--profile`` also prints the 20 largest
cumulative times of the drive (cProfile).

Before issue 36 the camera's model kept the scene's hidden terrain hfields, which MuJoCo's GL
context uploads as triangles: grand-canyon's 25 M posts took 4.3 GB and 28 s there (peak
6.4 GB per benchmark worker); the renderer now peaks at ~1.5 GB and the drive at ~2.0 GB.
"""

from __future__ import annotations

import dataclasses
import gc
import os
import sys
import tempfile
import time
from pathlib import Path

from perf.suite import Param

os.environ.setdefault("MUJOCO_GL", "egl")
ROOT = Path(__file__).resolve().parents[2]
_T0 = time.perf_counter()
_MARKS: list[dict[str, object]] = []
PARAMS = (Param("scene", str, "paper-spec scene (built once, seed 1)", quick="main-crater",
                full="grand-canyon"),
          Param("seconds", float, "simulated seconds of the drive", quick=4.0, full=12.0),
          Param("length_m", float, "route length (m)", quick=20.0, full=60.0),
          Param("profile", bool, "print the drive's 20 largest cumulative times (cProfile)",
                quick=False, full=False))


def _mark(what: str) -> None:
    gc.collect()
    vals = {}
    with open("/proc/self/status", encoding="ascii") as fh:
        for line in fh:
            key, _, value = line.partition(":")
            if key in ("VmRSS", "VmHWM"):
                vals[key] = int(value.split()[0]) / 1024
    print(f"drive memory: {time.perf_counter() - _T0:7.1f} s  {what:38s} RSS "
          f"{vals['VmRSS']:6.0f} MB, peak {vals['VmHWM']:6.0f} MB", flush=True)
    _MARKS.append({"stage": what, "t_s": time.perf_counter() - _T0, "rss_mb": vals["VmRSS"],
                   "peak_mb": vals["VmHWM"]})


def main(scene: str, seconds: float, length_m: float, profile: bool) -> dict[str, object]:
    import marsscene as ms
    from marsscene.benchmark.routes import auto_route, centred_on_asset
    from marsscene.benchmark.slam.spec import SlamSpec
    from marsscene.sensors.camera_world import read_rock_catalog
    from marsscene.sensors.lidar import Lidar
    from marsscene.sim.mission import DriveOptions, prepare_drive
    from marsscene.sim.world import load_world
    from perf._measure import paper_scene

    name, length = scene, length_m
    spec = SlamSpec.from_toml(ROOT / "docs" / "examples" / "benchmark_slam_paper.toml")
    spec_scene = next(s for s in spec.scenes if s.name == name)
    folder, built = paper_scene(name)
    if built:
        _mark(f"built {name} (seed 1)")
        os.execv(sys.executable, [sys.executable, *sys.argv])  # measure in a fresh process
    _mark("start")
    world = load_world(folder)
    _mark("load_world (route planning)")
    route = auto_route(centred_on_asset(dataclasses.replace(spec_scene.route, length_m=length),
                                        folder), world.heightfield, world.obstacles)
    del world
    _mark(f"route {route.length_m:.0f} m")
    run = spec.run_config(lidar=True)
    sim, path = prepare_drive(folder, run, route=route, options=DriveOptions())
    _mark("simulator (scene + rover)")
    t0 = time.perf_counter()
    cam = sim.make_renderer()
    _mark(f"camera renderer ({time.perf_counter() - t0:.1f} s)")
    cam.close()
    del cam
    t0 = time.perf_counter()
    lidar = Lidar(run.lidar, rng=__import__("numpy").random.default_rng(0),
                  rocks=read_rock_catalog(folder))
    lidar.prepare(sim.model, sim.data, sim.lidar_site, sim.heightfield)()
    _mark(f"LiDAR caster, first scan ({time.perf_counter() - t0:.1f} s)")
    del lidar
    out = Path(tempfile.mkdtemp(prefix="marsscene_bench_memory_run_"))

    def progress(p: object) -> None:
        t = getattr(p, "sim_time_s", None)
        if t is not None and int(t) % 4 == 0:
            _mark(f"drive, {t:.0f} sim s")

    profiler = None
    if profile:
        import cProfile

        profiler = cProfile.Profile()
        profiler.enable()
    t0 = time.perf_counter()
    drv = ms.drive(folder, route=path, seconds=seconds, config=run, out_dir=out / "run",
                   progress=progress, export=ms.ExportOptions(
                       bag=ms.BagOptions(sensors=("lidar",)), datasets=("tum-rgbd", "euroc")))
    wall = time.perf_counter() - t0
    if profiler is not None:
        import pstats

        profiler.disable()
        pstats.Stats(profiler).sort_stats("cumulative").print_stats(20)
    _mark(f"drive {seconds:g} sim s in {drv.wall_s:.0f} s ({seconds / drv.wall_s:.2f}x real "
          f"time), exports {drv.export_s:.1f} s, all {wall:.0f} s")
    size = sum(p.stat().st_size for p in (out / "run").rglob("*") if p.is_file()) / 1e6
    print(f"drive memory: run folder {size:.0f} MB ({size / seconds:.1f} MB per sim s)",
          flush=True)
    return {"scene": name, "sim_s": seconds, "drive_wall_s": drv.wall_s,
            "export_s": drv.export_s, "all_s": wall, "run_folder_mb": size,
            "peak_mb": max(float(m["peak_mb"]) for m in _MARKS), "stages": _MARKS}

