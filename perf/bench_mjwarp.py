"""MuJoCo Warp (MJWarp) running the rover on a marsscene heightfield, batched on a GPU.

Usage::

    python perf/bench_mjwarp.py export OUT.mjb          # here: the rover on a 60 m world (MJB)
    python perf/bench_mjwarp.py run OUT.mjb [--device cuda:0] [--worlds 1024,4096,8192]

``run`` loads the model with ``mujoco``, copies it to Warp (``mujoco_warp.put_model``), drives
every world straight for 10 s of simulated time (the wheel-speed and steering targets of
``cmd_vel = (0.5, 0)``), checks the first world against MuJoCo's own C step (the distance
between the two rovers after 10 s), and times batched steps per second (CUDA graph of 100
steps). Needs ``mujoco``, ``mujoco-warp`` and ``warp-lang`` (a GPU for the figures).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np


def export(out: Path) -> None:
    import mujoco

    import marsscene as ms
    from marsscene.env import WorldSampler
    from marsscene.sim.rover_sim import RoverSim

    world = WorldSampler(base="plain", count=1, cache_dir=str(
        Path(tempfile.gettempdir()) / "marsscene_bench_env")).path(0)
    sim = RoverSim(world, run=ms.RunConfig(physics_hz=100.0))
    sim.apply(0.5, 0.0)
    mujoco.mj_saveModel(sim.model, str(out), None)
    np.savez(out.with_suffix(".npz"), qpos=sim.data.qpos, qvel=sim.data.qvel,
             ctrl=sim.data.ctrl)
    print(f"wrote {out} ({out.stat().st_size / 1e6:.1f} MB): {sim.model.ngeom} geoms, "
          f"hfield {sim.model.hfield_nrow[0]} x {sim.model.hfield_ncol[0]}, "
          f"timestep {sim.model.opt.timestep} s")


def run(path: Path, device: str, worlds: list[int]) -> None:
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


def _yaw(q: np.ndarray) -> float:
    w, x, y, z = q
    return float(np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))


def main(argv: list[str]) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=["export", "run"])
    ap.add_argument("path", type=Path)
    ap.add_argument("--device", default="cuda:0")
    ap.add_argument("--worlds", default="1024,4096,8192")
    args = ap.parse_args(argv)
    if args.what == "export":
        export(args.path)
    else:
        run(args.path, args.device, [int(w) for w in args.worlds.split(",")])


if __name__ == "__main__":
    main(sys.argv[1:])
