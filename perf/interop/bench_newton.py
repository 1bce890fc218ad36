"""The USD rover in Newton on CPU (issue 34): checks and figures. Needs the extra ``newton``.

Real client: Newton 1.8 (``pip install "marsscene[newton]"``), CPU through Warp, solver
``SolverSteel`` through :class:`marsscene.sim.newton_rover.NewtonRover`. Each part prints its
figures; ``tests/usd_clients/test_newton_rover.py`` asserts the same checks when newton is
installed::

    python perf/run.py newton                     # every part (about 20 min on 2 cores)
    python perf/run.py newton --parts compile     # Warp's CPU kernel compile, cold cache
    python perf/run.py newton --parts load        # default scene + rover: load, finalize, rate
    python perf/run.py newton --parts drive       # 10 m straight + 90 deg turn, vs MuJoCo
    python perf/run.py newton --parts gentle      # 4 m + 45 deg on a 40 m scene, vs MuJoCo
    python perf/run.py newton --parts slope,rock,sphere
    python perf/run.py newton --parts load --device cuda:0 --scene scenes/demo   # on a GPU

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

from perf.suite import Param, names, optional

PARTS = ("compile", "load", "drive", "gentle", "slope", "rock", "sphere")
PARAMS = (Param("parts", names, f"parts to run, comma-separated, of {','.join(PARTS)}",
                quick=("slope",), full=PARTS),
          Param("device", str, "Warp device of compile and load", quick="cpu", full="cpu"),
          Param("scene", optional(Path), "scene folder (with the rover) for load/drive (none: "
                "the default scene, seed 7)", quick=None, full=None),
          Param("within", str, "load: rock radii (m) or 'all', comma-separated", quick="30",
                full="30,all"))

from marsscene.testing.newton_checks import (  # noqa: E402
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


def main(parts: tuple[str, ...], device: str, scene: Path | None,
         within: str) -> list[dict[str, Any]]:
    radii = [None if w == "all" else float(w) for w in within.split(",")]
    out: list[dict[str, Any]] = []

    def show(label: str, figures: dict[str, Any]) -> None:
        print(f"{label}:", json.dumps(figures), flush=True)
        out.append({"part": label, **figures})
    with tempfile.TemporaryDirectory() as name:
        tmp = Path(name)
        if "compile" in parts:
            show("compile", compile_cold(device))
        if {"load", "drive"} & set(parts):
            scene = scene or default_scene(tmp)
            if "load" in parts:
                for radius in radii:
                    show("load", load_figures(scene, radius, device))
            if "drive" in parts:
                for same in (True, False):
                    res = compare_drive(scene, same_rocks=same)
                    show(f"drive (same_rocks={same})", res)
        if "gentle" in parts:
            res = compare_drive(gentle_scene(tmp), straight_m=4.0, turn_deg=45.0)
            show("gentle drive", res)
        for name_, fn in (("slope", check_slope), ("rock", check_rock), ("sphere", check_sphere)):
            if name_ in parts:
                show(name_, fn(tmp))
    return out

