"""Train a navigation policy on thousands of rovers on one GPU: PPO from rsl-rl on
:class:`marsscene.env.batch.BatchNavEnv` (MuJoCo Warp), then save it for numpy.

Usage (a GPU machine, ``pip install "marsscene[gpu]" rsl-rl-lib``)::

    python perf/run.py batch_env --what pack --path worlds.npz   # 16 worlds, goals 20-50 m (CPU)
    python examples/train_batch_ppo.py worlds.npz --minutes 9 --out run/

It writes ``run/curve.csv`` (per PPO iteration: wall time, environment steps, the share of the
episodes ended in it that reached their goal) and ``run/policy.npz``
(:class:`~marsscene.env.policy.MLPPolicy`), which ``python perf/run.py batch_env --what sim2sim``
runs in the CPU environment (MuJoCo C, mesh rocks).

The CPU baseline: the same PPO on the CPU environment (:class:`~marsscene.env.RoverNavEnv`, the
scene folders of ``pack --folders``), N rovers in worker processes, the policy on PyTorch's CPU::

    python examples/train_batch_ppo.py worlds.npz --cpu-envs 60 --workers 15 --folders SCENES
"""

from __future__ import annotations

import argparse
import csv
import multiprocessing as mp
import os
import time
from pathlib import Path
from typing import Any

import numpy as np

from marsscene.env import HeightScan, NavTask, ObsConfig, RewardConfig
from marsscene.env.batch import BatchNavEnv, RslRlVecEnv, WarpPhysics
from marsscene.env.policy import MLPPolicy, policy_input
from marsscene.rover.config import RoverConfig

#: The task of the benchmark: goals 20-50 m away (the CPU example's are 5-20 m). Among rocks of
#: abundance k = 0.2, free ground for starts and goals (the route planner's rule) is rock-free up
#: to 0.4 m within 1 m (0.3 m by default leaves no 20 m of connected free ground on most worlds).
TASK = NavTask(distance_m=(20.0, 50.0), max_obstacle_height_m=0.4)
#: A 5 m height scan at 0.25 m (21 x 21 points) beside the state vector.
SCAN = HeightScan(size_m=5.0, resolution_m=0.25)
#: RLRoverLab's terms and progress towards the goal (0.2 a metre): their pull alone is too weak
#: for goals 20-50 m away (:mod:`marsscene.env.reward`).
REWARD = RewardConfig(progress=0.2)
MLP = {"hidden_dims": [256, 128, 64], "activation": "elu", "obs_normalization": True}
#: rsl-rl's runner configuration (its PPO defaults, Isaac Lab's navigation-task sizes).
TRAIN = {
    "num_steps_per_env": 24,
    "save_interval": 10**9,
    "obs_groups": {"actor": ["policy"], "critic": ["policy"]},
    "actor": {"class_name": "MLPModel", **MLP,
              "distribution_cfg": {"class_name": "GaussianDistribution", "init_std": 0.6}},
    "critic": {"class_name": "MLPModel", **MLP},
    "algorithm": {"class_name": "PPO", "learning_rate": 1e-3, "num_learning_epochs": 5,
                  "num_mini_batches": 4, "gamma": 0.99, "lam": 0.95, "entropy_coef": 0.005,
                  "desired_kl": 0.01, "schedule": "adaptive", "clip_param": 0.2,
                  "max_grad_norm": 1.0},
}


def train(batch: Path, minutes: float, envs: int, out: Path, seed: int,
          wheels: str = "sphere", iterations: tuple[int, int] = (100, 50),
          folders: Path | None = None, workers: int = 0) -> None:
    """PPO for ``minutes`` of wall time: on ``envs`` rovers of the GPU batch, or (``folders``)
    of the CPU environment in ``workers`` processes."""
    from rsl_rl.runners import OnPolicyRunner

    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    if folders is not None:
        import torch

        torch.set_num_threads(4)
        vec: Any = CpuVecEnv(folders, envs, workers, seed, wheels)
        counts, where = (lambda: vec.episodes.copy()), f"{workers} CPU processes"
    else:
        env = BatchNavEnv(batch, num_envs=envs, task=TASK, seed=seed, reward=REWARD,
                          observations=ObsConfig(height_scan=SCAN, noise_profile="none"),
                          rover=RoverConfig(wheel_collision=wheels),
                          physics=WarpPhysics(iterations=iterations[0],
                                              ls_iterations=iterations[1]))
        vec = RslRlVecEnv(env)
        counts, where = (lambda: env.bk.to_numpy(env.episodes)), f"{env.batch.count} worlds"
    runner = OnPolicyRunner(vec, {**TRAIN, "seed": seed}, log_dir=None, device=str(vec.device))
    print(f"environment ready in {time.perf_counter() - t0:.1f} s ({envs} rovers on {where}, "
          f"{vec.device})", flush=True)
    start, rows, it = time.perf_counter(), [], 0
    last = counts()
    with open(out / "curve.csv", "w", newline="") as f:
        log = csv.writer(f)
        log.writerow(["iteration", "wall_s", "env_steps", "episodes", "success"])
        while time.perf_counter() - start < minutes * 60.0:
            runner.learn(num_learning_iterations=1, init_at_random_ep_len=it == 0)
            now = counts()
            ended, won = (int(v) for v in now - last)
            last, it = now, it + 1
            row = [it, round(time.perf_counter() - start, 2), it * envs * TRAIN[
                "num_steps_per_env"], ended, round(won / ended, 4) if ended else ""]
            log.writerow(row)
            f.flush()
            rows.append(row)
            if it % 10 == 0:
                print(f"it {it:4d}  {row[1]:7.1f} s  success {row[4]}", flush=True)
                MLPPolicy.from_rsl_rl(runner.alg.get_policy(), SCAN).save(out / "policy.npz")
    policy = MLPPolicy.from_rsl_rl(runner.alg.get_policy(), SCAN)
    policy.save(out / "policy.npz")
    print(f"{it} iterations in {time.perf_counter() - start:.0f} s; policy in "
          f"{out / 'policy.npz'}")
    if folders is not None:
        vec.close()
        return
    won, n = evaluate(vec, runner.alg.get_policy())
    print(f"deterministic policy on the GPU batch: {won}/{n} = {won / n:.1%} of first episodes "
          "reached the goal", flush=True)


class CpuVecEnv:
    """``n`` :class:`~marsscene.env.RoverNavEnv` (MuJoCo C, mesh rocks) in ``workers`` processes
    behind :class:`~marsscene.env.batch.RslRlVecEnv`'s interface: same-step autoreset, the same
    policy input; ``episodes`` counts the episodes ended and those that reached the goal."""

    def __init__(self, folders: Path, n: int, workers: int, seed: int, wheels: str) -> None:
        import torch

        if n % workers:
            raise ValueError(f"{n} rovers do not split evenly over {workers} processes")
        ctx, k = mp.get_context("spawn"), n // workers
        self.pipes, self.procs = [], []
        for w in range(workers):
            here, there = ctx.Pipe()
            proc = ctx.Process(target=_cpu_worker, daemon=True,
                               args=(there, str(folders), k, seed + k * w, wheels))
            proc.start()
            self.pipes.append(here)
            self.procs.append(proc)
        first = [p.recv() for p in self.pipes]
        self.num_envs, self.num_actions, self.device = n, 2, "cpu"
        self.max_episode_length = first[0][1]
        self.episode_length_buf = torch.zeros(n, dtype=torch.long)  # not passed to the workers
        self.cfg = {"task": TASK, "reward": REWARD, "wheels": wheels}
        self._obs = torch.from_numpy(np.concatenate([f[0] for f in first]))
        self.episodes = np.zeros(2, np.int64)

    def get_observations(self) -> Any:
        from tensordict import TensorDict

        return TensorDict({"policy": self._obs}, batch_size=[self.num_envs])

    def step(self, actions: Any) -> tuple[Any, Any, Any, dict[str, Any]]:
        import torch

        for pipe, a in zip(self.pipes, np.array_split(actions.detach().numpy(), len(self.pipes)),
                           strict=True):
            pipe.send(a)
        obs, reward, term, trunc, goal = (np.concatenate(v) for v in
                                          zip(*(p.recv() for p in self.pipes), strict=True))
        self._obs = torch.from_numpy(obs)
        done = term | trunc
        self.episodes += (int(done.sum()), int(goal.sum()))
        return (self.get_observations(), torch.from_numpy(reward).float(),
                torch.from_numpy(done).long(), {"time_outs": torch.from_numpy(trunc)})

    def close(self) -> None:
        for pipe, proc in zip(self.pipes, self.procs, strict=True):
            pipe.send(None)
            proc.join(timeout=10)


def _cpu_worker(pipe: Any, folders: str, k: int, seed: int, wheels: str) -> None:
    from marsscene.env import RoverNavEnv

    paths = sorted(p for p in Path(folders).iterdir() if (p / "mjcf" / "scene.xml").is_file())
    envs = [RoverNavEnv(paths, task=TASK, reward=REWARD, rover=RoverConfig(wheel_collision=wheels),
                        observations=ObsConfig(height_scan=SCAN, noise_profile="none"),
                        max_worlds_loaded=len(paths)) for _ in range(k)]
    obs = []
    for i, env in enumerate(envs):
        for w in range(len(paths)):  # compile every world before the clock starts
            _reset(env, seed=seed + i, options={"world": w})
        obs.append(policy_input(_reset(env, seed=seed + i)))
    pipe.send((np.stack(obs).astype(np.float32), envs[0].steps_total))
    while (actions := pipe.recv()) is not None:
        rows = []
        for env, a in zip(envs, actions, strict=True):
            o, r, te, tr, info = env.step(a)
            if te or tr:
                o = _reset(env)
            rows.append((policy_input(o), r, te, tr, info["termination"] == "goal"))
        pipe.send(tuple(np.asarray(v) for v in zip(*rows, strict=True)))
    for env in envs:
        env.close()


def _reset(env: Any, **kw: Any) -> Any:
    return env.reset(**kw)[0]


def evaluate(vec: RslRlVecEnv, actor: object, max_s: float = 60.0) -> tuple[int, int]:
    """Run the policy's mean action until every rover ended one episode from a fresh reset (or
    ``max_s`` passed: rovers still driving then count as failures); (goals reached, rovers)."""
    import torch

    env = vec.env
    vec._obs = env.reset()
    first = torch.zeros(env.num_envs, dtype=torch.long, device=vec.device)  # 0: still going
    t0 = time.perf_counter()
    with torch.inference_mode():
        for _ in range(env.steps_total):
            if time.perf_counter() - t0 > max_s:
                break
            _, _, dones, extras = vec.step(actor(vec.get_observations()))  # type: ignore[operator]
            code = extras["termination"].long()
            first = torch.where((first == 0) & (dones > 0), torch.where(code == 1, 1, 2), first)
    return int((first == 1).sum()), env.num_envs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("batch", type=Path,
                    help="a WorldBatch .npz (python perf/run.py batch_env --what pack)")
    ap.add_argument("--minutes", type=float, default=9.0)
    ap.add_argument("--envs", type=int, default=4096)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=Path("run"))
    ap.add_argument("--wheels", choices=["cylinder", "sphere"], default="sphere",
                    help="the wheels' collision shape (RoverConfig.wheel_collision)")
    ap.add_argument("--iterations", default="100/50",
                    help="solver and line-search iteration limits (WarpPhysics)")
    ap.add_argument("--cpu-envs", type=int, default=0,
                    help="train on this many rovers of the CPU environment instead (--folders)")
    ap.add_argument("--workers", type=int, default=max(1, (os.cpu_count() or 2) - 1),
                    help="--cpu-envs: worker processes (default: one a core but one)")
    ap.add_argument("--folders", type=Path, help="--cpu-envs: the scene folders (pack --folders)")
    args = ap.parse_args()
    its = tuple(int(v) for v in args.iterations.split("/"))
    cpu = args.cpu_envs > 0
    if cpu and args.folders is None:
        ap.error("--cpu-envs needs --folders")
    train(args.batch, args.minutes, args.cpu_envs if cpu else args.envs, args.out, args.seed,
          args.wheels, (its[0], its[1]), args.folders if cpu else None,
          min(args.workers, args.cpu_envs))


if __name__ == "__main__":
    main()
