"""MuJoCo Warp (MJWarp) running the rover on a marsscene heightfield, batched on a GPU.

Usage::

    python perf/run.py mjwarp --what export [--path OUT.mjb]   # the rover on a 60 m world (MJB)
    python perf/run.py mjwarp --what run [--path OUT.mjb] [--device cuda:0] [--worlds 1024,4096]

``run`` loads the model with ``mujoco``, copies it to Warp (``mujoco_warp.put_model``), drives
every world straight for 10 s of simulated time (the wheel-speed and steering targets of
``cmd_vel = (0.5, 0)``), checks the first world against MuJoCo's own C step (the distance
between the two rovers after 10 s), and times batched steps per second (CUDA graph of 100
steps). Needs ``mujoco``, ``mujoco-warp`` and ``warp-lang`` (a GPU for the figures). The
model's default path is in the temporary folder (:data:`MODEL`); quick: ``export``, full: ``run``.
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path
from typing import Any

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np

from marsscene.errors import ConfigError
from perf.suite import Param, ints, optional

MODEL = Path(tempfile.gettempdir()) / "marsscene_bench_mjwarp" / "rover.mjb"

PARAMS = (
    Param("what", str, "export the model, or run it in MuJoCo C and MJWarp", quick="export",
          full="run", choices=("export", "run")),
    Param("path", optional(Path), f"the model (.mjb, its start state beside it as .npz; none: "
          f"{MODEL})", quick=None, full=None),
    Param("device", str, "Warp device of run", quick="cuda:0", full="cuda:0"),
    Param("worlds", ints, "batch sizes run times", quick=(64,), full=(1024, 4096, 8192)),
)


def export(out: Path) -> dict[str, Any]:
    import mujoco

    import marsscene as ms
    from marsscene.env import WorldSampler
    from marsscene.sim.rover_sim import RoverSim

    world = WorldSampler(base="plain", count=1, cache_dir=str(
        Path(tempfile.gettempdir()) / "marsscene_bench_env")).path(0)
    sim = RoverSim(world, run=ms.RunConfig(physics_hz=100.0))
    sim.apply(0.5, 0.0)
    out.parent.mkdir(parents=True, exist_ok=True)
    mujoco.mj_saveModel(sim.model, str(out), None)
    np.savez(out.with_suffix(".npz"), qpos=sim.data.qpos, qvel=sim.data.qvel,
             ctrl=sim.data.ctrl)
    print(f"wrote {out} ({out.stat().st_size / 1e6:.1f} MB): {sim.model.ngeom} geoms, "
          f"hfield {sim.model.hfield_nrow[0]} x {sim.model.hfield_ncol[0]}, "
          f"timestep {sim.model.opt.timestep} s")
    return {"mb": out.stat().st_size / 1e6, "geoms": int(sim.model.ngeom),
            "hfield_rows": int(sim.model.hfield_nrow[0]),
            "hfield_cols": int(sim.model.hfield_ncol[0]), "timestep_s": sim.model.opt.timestep}


def run(path: Path, device: str, worlds: tuple[int, ...]) -> list[dict[str, Any]]:
    import mujoco
    import mujoco_warp as mjw
    import warp as wp

    m = mujoco.MjModel.from_binary_path(str(path))
    init = np.load(path.with_suffix(".npz"))
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:], d.ctrl[:] = init["qpos"], init["qvel"], init["ctrl"]
    mujoco.mj_forward(m, d)
    steps_10s = round(10.0 / m.opt.timestep)
    ref = mujoco.MjData(m)
    ref.qpos[:], ref.qvel[:], ref.ctrl[:] = d.qpos, d.qvel, d.ctrl
    t0 = time.perf_counter()
    mujoco.mj_step(m, ref, nstep=steps_10s)
    cpu_s = time.perf_counter() - t0
    print(f"MuJoCo C: 10 s in {cpu_s:.3f} s ({10.0 / cpu_s:.0f}x real time, one core); "
          f"rover moved {np.hypot(*(ref.qpos[:2] - d.qpos[:2])):.2f} m")
    out: list[dict[str, Any]] = [{"case": "mujoco_c", "worlds": 1,
                                  "real_time_factor": 10.0 / cpu_s,
                                  "moved_m": float(np.hypot(*(ref.qpos[:2] - d.qpos[:2])))}]
    with wp.ScopedDevice(device):
        mw = mjw.put_model(m)
        one = mjw.put_data(m, d, nworld=1, nconmax=64, njmax=256)
        t0 = time.perf_counter()
        for _ in range(steps_10s):
            mjw.step(mw, one)
        wp.synchronize()
        first = time.perf_counter() - t0
        q = one.qpos.numpy()[0]
        print(f"MJWarp, 1 world, plain steps: rover moved {np.hypot(*(q[:2] - d.qpos[:2])):.2f} m "
              f"in 10 s, {np.hypot(*(q[:2] - ref.qpos[:2])):.3f} m from MuJoCo C's rover, "
              f"heading {np.degrees(_yaw(q[3:7]) - _yaw(ref.qpos[3:7])):+.2f} deg apart "
              f"({first:.1f} s wall, kernel compilation included)")
        out.append({"case": "mjwarp_plain", "worlds": 1,
                    "moved_m": float(np.hypot(*(q[:2] - d.qpos[:2]))),
                    "gap_to_c_m": float(np.hypot(*(q[:2] - ref.qpos[:2]))),
                    "heading_gap_deg": float(np.degrees(_yaw(q[3:7]) - _yaw(ref.qpos[3:7]))),
                    "wall_s": first})
        for n in worlds:
            dw = mjw.put_data(m, d, nworld=n, nconmax=64, njmax=256)
            mjw.step(mw, dw)
            wp.synchronize()
            graph = device.startswith("cuda")
            if graph:
                with wp.ScopedCapture() as cap:
                    for _ in range(100):
                        mjw.step(mw, dw)
            launches = 10
            t0 = time.perf_counter()
            for _ in range(launches):
                if graph:
                    wp.capture_launch(cap.graph)
                else:
                    for _ in range(100):
                        mjw.step(mw, dw)
            wp.synchronize()
            rate = n * launches * 100 / (time.perf_counter() - t0)
            qpos = dw.qpos.numpy()
            spread = float(np.ptp(qpos[:, 0]))
            print(f"MJWarp {n:6d} worlds on {device}: {rate:,.0f} steps/s "
                  f"({rate * m.opt.timestep:,.0f}x real time in all; x spread over worlds "
                  f"{spread:.1e} m)")
            out.append({"case": "mjwarp", "worlds": n, "device": device, "steps_per_s": rate,
                        "real_time_factor": rate * m.opt.timestep, "x_spread_m": spread})
    return out


def _yaw(q: np.ndarray) -> float:
    w, x, y, z = q
    return float(np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))


def main(what: str, path: Path | None, device: str,
         worlds: tuple[int, ...]) -> dict[str, Any] | list[dict[str, Any]]:
    model = path or MODEL
    if what == "run" and not model.is_file():
        raise ConfigError(f"no model {model}: make it with "
                          f"`python perf/run.py mjwarp --what export --path {model}`")
    return export(model) if what == "export" else run(model, device, worlds)
