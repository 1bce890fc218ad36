"""The USD rover in Newton on CPU (issue 34): checks and figures. Needs the extra ``newton``.

Real client: Newton 1.8 (``pip install "marsscene[newton]"``), CPU through Warp, solver
``SolverSteel`` through :class:`marsscene.sim.newton_rover.NewtonRover`. Each part prints its
figures; ``tests/usd_clients/test_newton_rover.py`` asserts the same checks when newton is
installed::

    python perf/bench_newton.py            # every part (about 20 min on 2 cores)
    python perf/bench_newton.py compile    # Warp's CPU kernel compile, cold cache
    python perf/bench_newton.py load       # default scene + rover: load, finalize, rate
    python perf/bench_newton.py drive      # 10 m straight + 90 deg turn, vs MuJoCo
    python perf/bench_newton.py gentle     # 4 m + 45 deg on a 40 m scene, vs MuJoCo
    python perf/bench_newton.py slope rock sphere
    python perf/bench_newton.py load --device cuda:0 --scene scenes/demo   # on a GPU

``--device``: the Warp device of ``compile`` and ``load`` (default ``cpu``); ``--scene``: a
scene folder written with ``--rover`` for ``load`` / ``drive`` instead of building the default
scene (seed 7); ``--within``: the ``load`` cases, rock radii in m or ``all`` (default
``30,all``).

* ``slope``: a 15 deg plane; the rover parked across it and driven up it.
* ``rock``: a 0.35 m rock under the left wheels (climbed), a 1.2 m rock across the path
  (stops the rover or is climbed, never passed through).
* ``sphere``: a 0.3 m sphere dropped on a 1.2 m rock comes to rest on its top.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository root: tests.support

from tests.support.newton_checks import (
    V_M_S,
    check_rock,
    check_slope,
    check_sphere,
    compare_drive,
    flat,
    gentle_scene,
    write_world,
)


def load_figures(scene: Path, rocks_within_m: float | None,
                 device: str = "cpu") -> dict[str, Any]:
    """Newton on the default scene + rover: add_usd, finalize, and the simulation rate.

    ``first_step_s``: the first physics step after loading (Warp compiles the stepping
    kernels there when its kernel cache is cold)."""
    from pxr import Usd

    from marsscene.sim.newton_rover import NewtonRover, _newton

    newton, wp = _newton()
    t0 = time.perf_counter()
    sim = NewtonRover(scene / "scene.usda", rocks_within_m=rocks_within_m, device=device)
    wp.synchronize_device(device)
    total = time.perf_counter() - t0
    t0 = time.perf_counter()
    sim.advance(1)
    first_s = time.perf_counter() - t0
    b = newton.ModelBuilder(up_axis=newton.Axis.Z)  # the parts, timed apart
    stage = Usd.Stage.Open(str(scene / "scene.usda"))
    t0 = time.perf_counter()
    b.add_usd(stage, ignore_paths=["/World/RockColliders"])
    add_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    b.finalize(device=device)
    wp.synchronize_device(device)
    fin_s = time.perf_counter() - t0
    slow = rocks_within_m is None and device == "cpu"  # every rock: the CPU broad phase is slow
    sim.advance(9 if slow else 499)
    n = 5 if slow else 250
    t0 = time.perf_counter()
    for _ in range(n):
        sim.step(V_M_S, 0.0)
    rate = n / 50 / (time.perf_counter() - t0)
    return {"device": str(wp.get_device(device).name), "rocks_within_m": rocks_within_m,
            "rocks_loaded": sim.load_info["rocks_loaded"],
            "NewtonRover_init_s": round(total, 1), "first_step_s": round(first_s, 2),
            "add_usd_terrain_rover_s": round(add_s, 2),
            "finalize_terrain_rover_s": round(fin_s, 2), "rate_steps": n * sim.substeps,
            "sim_s_per_wall_s": round(rate, 3), "dt_s": sim.dt_s}


def compile_cold(device: str = "cpu") -> dict[str, Any]:
    """Warp's kernel compile time for a first NewtonRover run (empty kernel cache)."""
    with tempfile.TemporaryDirectory() as tmp:
        scene = write_world(Path(tmp) / "w", flat(41), rover_xy_m=(0.0, 0.0))
        code = ("import time, warp as wp; wp.config.kernel_cache_dir = {c!r}; t = time.time();"
                "from marsscene.sim.newton_rover import NewtonRover;"
                "s = NewtonRover({p!r}, device={d!r}); s.step(0.3, 0.0); print(time.time() - t)")
        out = {}
        for label in ("cold", "warm"):
            res = subprocess.run([sys.executable, "-c", code.format(
                c=str(Path(tmp) / "kernels"), p=str(scene / "scene.usda"), d=device)],
                capture_output=True, text=True, check=True, env={**os.environ})
            out[f"{label}_first_step_s"] = round(float(res.stdout.split()[-1]), 1)
    return out


def default_scene(tmp: Path) -> Path:
    import marsscene as ms

    scene = ms.build_scene(ms.SceneConfig.from_dict({"export": {"rover": True}}), seed=7)
    ms.write_scene(scene, tmp / "default")
    return tmp / "default"


def main(argv: list[str] | None = None) -> None:
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    ap.add_argument("parts", nargs="*")
    ap.add_argument("--device", default="cpu", help="Warp device of compile and load")
    ap.add_argument("--scene", type=Path, help="scene folder (with the rover) for load/drive")
    ap.add_argument("--within", default="30,all", help="load: rock radii (m) or 'all'")
    args = ap.parse_args(argv or [])
    parts = args.parts or ["compile", "load", "drive", "gentle", "slope", "rock", "sphere"]
    radii = [None if w == "all" else float(w) for w in args.within.split(",")]
    with tempfile.TemporaryDirectory() as name:
        tmp = Path(name)
        if "compile" in parts:
            print("compile:", json.dumps(compile_cold(args.device)), flush=True)
        if {"load", "drive"} & set(parts):
            scene = args.scene or default_scene(tmp)
            if "load" in parts:
                for within in radii:
                    print("load:", json.dumps(load_figures(scene, within, args.device)),
                          flush=True)
            if "drive" in parts:
                for same in (True, False):
                    res = compare_drive(scene, same_rocks=same)
                    print(f"drive (same_rocks={same}):", json.dumps(res), flush=True)
        if "gentle" in parts:
            res = compare_drive(gentle_scene(tmp), straight_m=4.0, turn_deg=45.0)
            print("gentle drive:", json.dumps(res), flush=True)
        for name_, fn in (("slope", check_slope), ("rock", check_rock), ("sphere", check_sphere)):
            if name_ in parts:
                print(f"{name_}:", json.dumps(fn(tmp)), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
