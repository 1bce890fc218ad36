"""The batched GPU environment (MuJoCo Warp): its worlds, its agreement with MuJoCo C, its speed,
and a trained policy's sim-to-sim check in the CPU environment.

Usage::

    python perf/bench_batch_env.py pack OUT.npz [--folders OUT.tar]   # 16 worlds, goals 20-50 m
    python perf/bench_batch_env.py agree OUT.npz [--posts 0.25,0.125,0.1] [--device cpu]
    python perf/bench_batch_env.py run OUT.npz [--envs 1,1024,4096,16384] [--folders DIR]
    python perf/bench_batch_env.py sim2sim POLICY.npz --folders DIR [--episodes 50]

``pack`` builds the benchmark's worlds (the three world kinds with rock abundance k = 0.2: 6
plain, 5 craters, 5 rocks) and draws 256 episodes on each. ``agree`` drives 32 rovers 10 s
from settled starts in MuJoCo C and MuJoCo Warp on the tiled heightfield at several post
spacings and prints how far apart they end. ``run`` times environment steps per second at
5 Hz control (100 Hz physics, height scan, random actions) for each batch size, and, with
``--folders`` (the scenes of ``pack --folders``), the CPU environment on one core and on every
core (one process a core). ``sim2sim`` runs a policy (``examples/train_batch_ppo.py``) in the
CPU environment (MuJoCo C, mesh rocks) over seeded episodes.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import sys
import tarfile
import tempfile
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))
KINDS = {"plain": 6, "craters": 5, "rocks": 5}
SECONDS_CPU = 20.0


def _samplers(cache: str) -> list:
    from marsscene.env import WorldSampler

    return [WorldSampler(base=kind, vary={"rocks.k": [0.2]}, count=n, seed=100 * i,
                         cache_dir=cache) for i, (kind, n) in enumerate(KINDS.items())]


def pack(out: Path, folders: Path | None) -> None:
    from train_batch_ppo import TASK

    from marsscene.env.batch import WorldBatch

    cache = (os.environ.get("MARSSCENE_CACHE")
             or str(Path(tempfile.gettempdir()) / "marsscene-worlds"))
    paths = [s.path(i) for s in _samplers(cache) for i in range(s.count)]
    t0 = time.perf_counter()
    batch = WorldBatch.build(paths, task=TASK, pool=256, seed=0)
    batch.save(out)
    print(f"{out}: {batch.count} worlds, {batch.pool} episodes each, "
          f"{len(batch.rock_radius_m)} rocks, {out.stat().st_size / 1e6:.1f} MB "
          f"({time.perf_counter() - t0:.1f} s)")
    if folders is not None:
        with tarfile.open(folders, "w") as tar:
            for i, p in enumerate(paths):
                tar.add(p, arcname=f"world{i:02d}")
        print(f"{folders}: the {len(paths)} scene folders")


def agree(batch_path: Path, posts: list[float], device: str) -> None:
    import mujoco
    import mujoco_warp as mjw
    import warp as wp

    from marsscene.env.batch import WorldBatch
    from marsscene.env.batch.model import tiled_model
    from marsscene.rover.config import RoverConfig
    from marsscene.rover.geometry import wheel_commands
    from marsscene.rover.spawn import spawn_pose

    b = WorldBatch.load(batch_path)
    terr = b.rock_terrains()
    bare = [b.heightfield(w) for w in range(b.count)]
    rover, n = RoverConfig(), 32
    for post in posts:
        t = tiled_model(terr, bare, rover=rover, physics_hz=100.0, post_m=post)
        m, ids = t.model, t.ids
        qs = np.tile(m.qpos0, (n, 1))
        for k in range(n):
            w, p = k % b.count, k // b.count
            pose = spawn_pose(terr[w], tuple(b.starts_xy_m[w, p]), float(b.yaws_rad[w, p]), rover)
            pose[:2] += t.offsets_xy_m[w]
            qs[k, :7] = pose
        rates, steer = wheel_commands(0.5, 0.05, rover)
        ctrl = np.zeros(m.nu)
        ctrl[ids["drive_act"]], ctrl[ids["steer_act"]] = rates, steer
        ref = []
        for k in range(n):
            d = mujoco.MjData(m)
            d.qpos[:] = qs[k]
            mujoco.mj_step(m, d, nstep=300)
            d.ctrl[:] = ctrl
            mujoco.mj_step(m, d, nstep=1000)
            ref.append(d.qpos[:2].copy())
        with wp.ScopedDevice(device):
            mw = mjw.put_model(m)
            dw = mjw.put_data(m, mujoco.MjData(m), nworld=n, nconmax=96, njmax=512)
            wp.copy(dw.qpos, wp.array(qs, dtype=float))
            for _ in range(300):
                mjw.step(mw, dw)
            wp.copy(dw.ctrl, wp.array(np.tile(ctrl, (n, 1)), dtype=float))
            for _ in range(1000):
                mjw.step(mw, dw)
            got = dw.qpos.numpy()[:, :2]
        err = np.linalg.norm(got - np.array(ref), axis=1)
        print(f"posts {post:.3f} m: MuJoCo Warp vs C after 3 s settling + 10 s driving, "
              f"{n} starts: median {np.median(err):.3f} m, 90th percentile "
              f"{np.percentile(err, 90):.2f} m, {int((err > 0.5).sum())} over 0.5 m", flush=True)


def run(batch_path: Path, envs: list[int], folders: Path | None, steps: int) -> None:
    import torch

    from marsscene.env.batch import BatchNavEnv

    print(f"GPU: {torch.cuda.get_device_name()}; CPU cores: {os.cpu_count()}", flush=True)
    for n in envs:
        t0 = time.perf_counter()
        env = BatchNavEnv(batch_path, num_envs=n, seed=0)
        made = time.perf_counter() - t0
        gen = torch.Generator(device=env.bk.tdevice).manual_seed(0)
        actions = torch.rand((steps + 3, n, 2), generator=gen, device=env.bk.tdevice) * 2 - 1
        for a in actions[:3]:
            env.step(a)
        torch.cuda.synchronize()
        t0 = time.perf_counter()
        for a in actions[3:]:
            env.step(a)
        torch.cuda.synchronize()
        dt = time.perf_counter() - t0
        physics = n * steps * env.substeps / dt
        print(f"N = {n:6d}: {n * steps / dt:12,.0f} env steps/s ({physics:14,.0f} physics "
              f"steps/s; made in {made:.1f} s; {env.success_rate:.3f} of "
              f"{int(env.bk.to_numpy(env.episodes)[0])} random episodes reached the goal)",
              flush=True)
        del env
        torch.cuda.empty_cache()
    if folders is not None:
        cores = os.cpu_count() or 1
        one = _cpu_rate(str(folders))
        with mp.get_context("spawn").Pool(cores) as pool:
            every = sum(pool.map(_cpu_rate, [str(folders)] * cores))
        print(f"CPU environment (MuJoCo C, mesh rocks): {one:,.0f} env steps/s on one core, "
              f"{every:,.0f} on {cores} cores (one process a core)", flush=True)


def _cpu_env(folders: str, observations: object = None) -> object:
    from train_batch_ppo import SCAN, TASK

    from marsscene.env import ObsConfig, RoverNavEnv

    paths = sorted(p for p in Path(folders).iterdir() if (p / "mjcf" / "scene.xml").is_file())
    obs = observations or ObsConfig(height_scan=SCAN, noise_profile="none")
    return RoverNavEnv(paths, task=TASK, observations=obs, max_worlds_loaded=len(paths))


def _cpu_rate(folders: str) -> float:
    env = _cpu_env(folders)
    rng = np.random.default_rng(os.getpid())
    env.reset(seed=int(rng.integers(1 << 30)))
    n, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < SECONDS_CPU:
        _, _, te, tr, _ = env.step(rng.uniform(-1, 1, 2))
        n += 1
        if te or tr:
            env.reset()
    return n / (time.perf_counter() - t0)


def sim2sim(policy_path: Path, folders: Path, episodes: int) -> None:
    from marsscene.env.policy import MLPPolicy

    policy = MLPPolicy.load(policy_path)
    env = _cpu_env(str(folders), policy.observations())
    ends: dict[str, int] = {}
    t0 = time.perf_counter()
    for seed in range(episodes):
        obs, info = env.reset(seed=seed)
        done = False
        while not done:
            obs, _, te, tr, info = env.step(policy(obs))
            done = te or tr
        why = info["termination"] or "time limit"
        ends[why] = ends.get(why, 0) + 1
        print(f"episode {seed:3d}: {why:10s} {info['distance_m']:6.2f} m from the goal",
              flush=True)
    won = ends.get("goal", 0)
    print(f"CPU environment (MuJoCo C, mesh rocks): {won}/{episodes} = {won / episodes:.0%} "
          f"reached the goal; ends {ends} ({time.perf_counter() - t0:.0f} s)")


def main(argv: list[str]) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=["pack", "agree", "run", "sim2sim"])
    ap.add_argument("path", type=Path)
    ap.add_argument("--folders", type=Path)
    ap.add_argument("--posts", default="0.25,0.125,0.1")
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--envs", default="1,1024,4096,16384")
    ap.add_argument("--steps", type=int, default=50)
    ap.add_argument("--episodes", type=int, default=50)
    a = ap.parse_args(argv)
    if a.what == "pack":
        pack(a.path, a.folders)
    elif a.what == "agree":
        agree(a.path, [float(p) for p in a.posts.split(",")], a.device)
    elif a.what == "run":
        run(a.path, [int(n) for n in a.envs.split(",")], a.folders, a.steps)
    else:
        sim2sim(a.path, a.folders, a.episodes)


if __name__ == "__main__":
    main(sys.argv[1:])
