"""The Gymnasium navigation environment: physics rate and fidelity, steps per second, vector
environments, reset times, and the classical navigator's success rate.

Usage: ``python perf/run.py env [--sections physics,steps,vector,reset,navigator]`` (full: all
of them; quick: steps).

* physics: the rover's bare physics (CPU seconds; the real-time factor) at 500, 100 and 50 Hz
  with cylinder and sphere wheels, and how far each drives from the 500 Hz cylinder reference
  on the same route (a 30 m route with two turns on a gentle world).
* steps: environment steps per second at 5 Hz control (random actions) for state + height
  scan, + 128 x 128 RGB-D navcam, + VLP-16 LiDAR range image.
* vector: ``AsyncVectorEnv`` of 2 workers against one env (the speed-up on 2 cores).
* reset: reset times for the same world, a new world from the cache, a new world built.
* navigator: :class:`marsscene.env.ArcNavigator`'s success rate on 50 seeded episodes in each
  of the ``plain``, ``craters`` and ``rocks`` (k = 0.2) world kinds.
"""

from __future__ import annotations

import os
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np

from perf.suite import Param, names

CACHE = Path(tempfile.gettempdir()) / "marsscene_bench_env"


def _world(kind: str = "plain", seed: int = 0) -> Path:
    from marsscene.env import WorldSampler

    return WorldSampler(base=kind, count=1, seed=seed, cache_dir=str(CACHE)).path(0)


def physics() -> list[dict[str, Any]]:
    import mujoco

    import marsscene as ms
    from marsscene.rover.config import RoverConfig
    from marsscene.sim.rover_sim import RoverSim

    world = _world("plain")
    wp = [[-15.0, -10.0], [5.0, -10.0], [8.0, 10.0]]
    ref, out = None, []
    print("physics Hz  wheels    CPU x real time   max gap to 500 Hz cylinder   cross-track RMS")
    for hz in (500.0, 100.0, 50.0):
        for wheel in ("cylinder", "sphere"):
            rover = RoverConfig(wheel_collision=wheel)
            run_cfg = ms.RunConfig(physics_hz=hz, imu_hz=min(100.0, hz))
            sim = RoverSim(world, rover=rover, run=run_cfg, settle_s=0.0)
            sim.apply(0.5, 0.05)
            t0 = time.process_time()
            mujoco.mj_step(sim.model, sim.data, nstep=round(20.0 * hz))
            rtf = 20.0 / (time.process_time() - t0)
            run: Any = _route_drive(world, wp, hz, wheel)
            if ref is None:
                ref = run
            n = min(len(ref.gt), len(run.gt))
            gap = float(np.hypot(*(ref.gt.xyz_m[:n, :2] - run.gt.xyz_m[:n, :2]).T).max())
            print(f"{hz:10.0f}  {wheel:8s}  {rtf:14.0f}x   {gap:24.3f} m   "
                  f"{run.summary['cross_track_rms_m']:.3f} m")
            out.append({"section": "physics", "physics_hz": hz, "wheels": wheel,
                        "real_time_factor": rtf, "max_gap_m": gap,
                        "cross_track_rms_m": float(run.summary["cross_track_rms_m"])})
    return out


def _route_drive(world: Path, wp: list[list[float]], hz: float, wheel: str) -> object:
    """Pure pursuit along the route through ``wp`` at ``hz`` physics with ``wheel`` wheels."""
    import math

    import marsscene as ms
    from marsscene.rover.config import RoverConfig
    from marsscene.seeding import stage_rng
    from marsscene.sim.driver import drive_sim
    from marsscene.sim.route import author_route
    from marsscene.sim.rover_sim import RoverSim
    from marsscene.sim.world import load_world

    w = load_world(world)
    route = author_route(wp, w.heightfield, obstacles=w.obstacles)
    a, b = route.xy_m[0], route.xy_m[5]
    sim = RoverSim(world, rover=RoverConfig(wheel_collision=wheel),
                   run=ms.RunConfig(physics_hz=hz, imu_hz=min(100.0, hz)),
                   start_xy_m=(float(a[0]), float(a[1])),
                   start_yaw_rad=math.atan2(b[1] - a[1], b[0] - a[0]))
    return drive_sim(sim, route=route, rng=stage_rng(1, "sensors"))


def _rate(env: object, n: int, rng: np.random.Generator) -> tuple[float, float]:
    env.reset(seed=0)  # type: ignore[attr-defined]
    actions = rng.uniform(-1, 1, (n, 2)).astype(np.float32)
    w0, c0 = time.perf_counter(), time.process_time()
    for a in actions:
        *_, term, trunc, _ = env.step(a)  # type: ignore[attr-defined]
        if term or trunc:
            env.reset()  # type: ignore[attr-defined]
    return n / (time.perf_counter() - w0), n / (time.process_time() - c0)


def steps() -> list[dict[str, Any]]:
    import marsscene.env as me

    world = _world("plain")
    cases = {"state + height scan (5 m at 0.1 m)": me.ObsConfig(),
             "+ RGB-D 128 x 128": me.ObsConfig(camera=(128, 128), depth=True),
             "+ VLP-16 range image": me.ObsConfig(lidar="vlp16")}
    out = []
    for name, obs in cases.items():
        for wheel in ("cylinder", "sphere"):
            from marsscene.rover.config import RoverConfig

            env = me.RoverNavEnv(world, observations=obs,
                                 rover=RoverConfig(wheel_collision=wheel))
            n = 1500 if obs.camera is None and obs.lidar is None else 150
            wall, cpu = _rate(env, n, np.random.default_rng(0))
            env.close()
            print(f"{name:38s} {wheel:8s}: {wall:7.0f} steps/s wall, {cpu:7.0f} per CPU second")
            out.append({"section": "steps", "case": name, "wheels": wheel,
                        "steps_per_s": wall, "steps_per_cpu_s": cpu})
    return out


def _make(world: str) -> Any:
    import marsscene.env as me

    return me.RoverNavEnv(world)


def vector() -> dict[str, Any]:
    import functools

    import gymnasium as gym

    world = str(_world("plain"))
    one = _make(world)
    single, _ = _rate(one, 1500, np.random.default_rng(0))
    one.close()
    vec = gym.vector.AsyncVectorEnv([functools.partial(_make, world)] * 2, shared_memory=True)
    vec.reset(seed=[0, 1])
    act = np.random.default_rng(0).uniform(-1, 1, (1500, 2, 2)).astype(np.float32)
    t0 = time.perf_counter()
    for a in act:
        vec.step(a)
    both = 2 * len(act) / (time.perf_counter() - t0)
    vec.close()
    print(f"one env {single:.0f} steps/s; AsyncVectorEnv(2) {both:.0f} steps/s "
          f"(x{both / single:.2f})")
    return {"section": "vector", "one_env_steps_per_s": single, "async2_steps_per_s": both,
            "speedup": both / single}


def reset() -> dict[str, Any]:
    import marsscene.env as me

    fresh = Path(tempfile.mkdtemp(prefix="marsscene-worlds-"))
    sampler = me.WorldSampler(base="plain", count=3, seed=7, cache_dir=str(fresh))
    env = me.RoverNavEnv(sampler)
    t0 = time.perf_counter()
    env.reset(seed=0, options={"world": 0})
    built = time.perf_counter() - t0
    t0 = time.perf_counter()
    for i in range(20):
        env.reset(seed=i, options={"world": 0})
    same = (time.perf_counter() - t0) / 20
    sampler.path(1)  # on disk, not loaded
    t0 = time.perf_counter()
    env.reset(seed=0, options={"world": 1})
    cached = time.perf_counter() - t0
    env.close()
    print(f"reset: same world {same * 1e3:.0f} ms, new world from the cache {cached:.2f} s, "
          f"new world built {built:.2f} s")
    return {"section": "reset", "same_world_s": same, "cached_world_s": cached,
            "built_world_s": built}


def navigator(episodes: int = 50) -> list[dict[str, Any]]:
    import marsscene.env as me

    scan = me.HeightScan(size_m=10.0, resolution_m=0.1)
    nav = me.ArcNavigator(scan)
    out = []
    for kind in ("plain", "craters", "rocks"):
        sampler = me.WorldSampler(base=kind, count=5, seed=11, cache_dir=str(CACHE))
        env = me.RoverNavEnv(sampler, observations=me.ObsConfig(height_scan=scan),
                             task=me.NavTask(distance_m=(5.0, 20.0)))
        ends: dict[str, int] = {}
        times, steps, t0 = [], 0, time.perf_counter()
        for ep in range(episodes):
            obs, info = env.reset(seed=ep)
            while True:
                obs, _, term, trunc, info = env.step(nav(obs))
                steps += 1
                if term or trunc:
                    break
            why = info["termination"] or "timeout"
            ends[why] = ends.get(why, 0) + 1
            if why == "goal":
                times.append(info["t_s"])
        env.close()
        rate = ends.get("goal", 0) / episodes
        per_s = steps / (time.perf_counter() - t0)
        print(f"{kind:8s}: success {100 * rate:5.1f} % of {episodes} ({ends}); goal in "
              f"{np.mean(times) if times else float('nan'):.0f} s on average; "
              f"{per_s:.0f} steps/s")
        out.append({"section": "navigator", "kind": kind, "episodes": episodes,
                    "success": rate, "ends": ends,
                    "goal_time_s": float(np.mean(times)) if times else None,
                    "steps_per_s": per_s})
    return out


SECTIONS: dict[str, Callable[[], Any]] = {
    "physics": physics, "steps": steps, "vector": vector, "reset": reset, "navigator": navigator}


def section_names(text: str) -> tuple[str, ...]:
    """A comma-separated list of section names (of :data:`SECTIONS`)."""
    out = names(text)
    for name in out:
        if name not in SECTIONS:
            raise ValueError(f"no section {name!r} (sections: {', '.join(SECTIONS)})")
    return out


PARAMS = (Param("sections", section_names, f"what to measure ({', '.join(SECTIONS)})",
                quick=("steps",), full=tuple(SECTIONS)),)


def main(sections: tuple[str, ...]) -> list[dict[str, Any]]:
    out: list[dict[str, Any]] = []
    for name in sections:
        print(f"-- {name}", flush=True)
        got = SECTIONS[name]()
        out += got if isinstance(got, list) else [got]
    return out
