"""Train a small PPO policy on ``marsscene/RoverNav-v0`` with Stable-Baselines3, then plot its
learning curve and a rollout (``pip install -e ".[rl]"``; not part of the test suite).

Usage::

    python examples/train_ppo.py OUT_DIR [--steps 300000] [--envs 8]

Writes ``OUT_DIR/ppo_rovernav.zip`` (the policy), ``OUT_DIR/progress.csv`` (the learning curve
as Stable-Baselines3 logs it), ``OUT_DIR/learning_curve.png`` (mean episode return and success
rate against environment steps) and ``OUT_DIR/rollout.png`` (one evaluation episode over the
height map, with the arc navigator's path on the same episode for comparison).

The task is shortened to goals 3-8 m away with 60 s episodes (a curriculum's first stage);
the observation is the state vector plus a 5 m height scan at 0.2 m, flattened into an MLP.
"""

from __future__ import annotations

import argparse
import csv
import os
import sys
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np


def make_env(cache: str, seed: int = 0) -> object:
    import marsscene.env as me

    scan = me.HeightScan(size_m=5.0, resolution_m=0.2)
    return me.RoverNavEnv(
        me.WorldSampler(base="plain", count=8, seed=seed, cache_dir=cache,
                        vary={"rocks.k": [0.05, 0.15]}),
        task=me.NavTask(distance_m=(3.0, 8.0), max_episode_s=60.0),
        observations=me.ObsConfig(height_scan=scan))


def train(out: Path, steps: int, envs: int) -> None:
    from functools import partial

    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.logger import configure
    from stable_baselines3.common.vec_env import SubprocVecEnv

    cache = str(out / "worlds")
    for i in range(8):  # build the worlds once, before the workers start
        make_env(cache).worlds.path(i)  # type: ignore[attr-defined]
    vec = make_vec_env(partial(make_env, cache), n_envs=envs, seed=0,
                       vec_env_cls=SubprocVecEnv if envs > 1 else None)
    model = PPO("MultiInputPolicy", vec, n_steps=512, batch_size=512, learning_rate=3e-4,
                gamma=0.99, gae_lambda=0.95, ent_coef=0.0, seed=0, verbose=0,
                policy_kwargs={"net_arch": [256, 256]})
    model.set_logger(configure(str(out), ["csv", "stdout"]))
    model.learn(total_timesteps=steps)
    model.save(out / "ppo_rovernav")
    vec.close()


def plot(out: Path) -> None:
    import matplotlib.pyplot as plt

    with open(out / "progress.csv", encoding="utf-8") as fh:
        rows = [r for r in csv.DictReader(fh) if r.get("rollout/ep_rew_mean")]
    x = np.array([float(r["time/total_timesteps"]) for r in rows])
    ret = np.array([float(r["rollout/ep_rew_mean"]) for r in rows])
    fig, ax = plt.subplots(figsize=(6, 3.5))
    ax.plot(x, ret, label="mean episode return")
    if rows and rows[0].get("rollout/success_rate"):
        ax2 = ax.twinx()
        ax2.plot(x, [100 * float(r["rollout/success_rate"]) for r in rows], "C1",
                 label="success rate")
        ax2.set_ylabel("goals reached (%)")
    ax.set_xlabel("environment steps")
    ax.set_ylabel("return")
    ax.set_title("PPO on marsscene/RoverNav-v0 (goals 3-8 m)")
    fig.tight_layout()
    fig.savefig(out / "learning_curve.png", dpi=120)


def rollout(out: Path, seed: int = 1234) -> None:
    import matplotlib.pyplot as plt
    from stable_baselines3 import PPO

    import marsscene.env as me

    env = make_env(str(out / "worlds"))
    nav = me.ArcNavigator(env.obs_config.height_scan)  # type: ignore[attr-defined]
    model = PPO.load(out / "ppo_rovernav")
    paths, ends = {}, {}
    for name, act in (("PPO", lambda o: model.predict(o, deterministic=True)[0]),
                      ("arc navigator", nav)):
        obs, info = env.reset(seed=seed)  # type: ignore[attr-defined]
        xy = [obs["achieved_goal"]]
        while True:
            obs, _, term, trunc, info = env.step(act(obs))  # type: ignore[attr-defined]
            xy.append(obs["achieved_goal"])
            if term or trunc:
                break
        paths[name], ends[name] = np.array(xy), info["termination"] or "timeout"
    world = env._world  # type: ignore[attr-defined]
    hf = world.sim.heightfield
    goal = obs["desired_goal"]
    fig, ax = plt.subplots(figsize=(5.5, 5))
    x0, y0, x1, y1 = hf.bounds_xy_m
    ax.imshow(world.scanner.terrain.z_m, origin="lower", extent=(x0, x1, y0, y1), cmap="gray")
    for name, p in paths.items():
        ax.plot(p[:, 0], p[:, 1], label=f"{name} ({ends[name]})")
    ax.plot(*paths["PPO"][0], "go", label="start")
    ax.plot(*goal, "r*", ms=14, label="goal")
    lo = np.minimum(paths["PPO"].min(0), goal) - 4
    hi = np.maximum(paths["PPO"].max(0), goal) + 4
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_xlabel("x east (m)")
    ax.set_ylabel("y north (m)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "rollout.png", dpi=120)
    env.close()  # type: ignore[attr-defined]


def main(argv: list[str]) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--steps", type=int, default=300_000)
    ap.add_argument("--envs", type=int, default=8)
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    train(args.out, args.steps, args.envs)
    plot(args.out)
    rollout(args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main(sys.argv[1:])
