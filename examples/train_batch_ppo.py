"""Train a navigation policy on thousands of rovers on one GPU: PPO from rsl-rl on
:class:`marsscene.env.batch.BatchNavEnv` (MuJoCo Warp), then save it for numpy.

Usage (a GPU machine, ``pip install "marsscene[gpu]" rsl-rl-lib``)::

    python perf/bench_batch_env.py pack worlds.npz         # 16 worlds, goals 20-50 m (CPU)
    python examples/train_batch_ppo.py worlds.npz --minutes 9 --out run/

It writes ``run/curve.csv`` (per PPO iteration: wall time, environment steps, the share of the
episodes ended in it that reached their goal) and ``run/policy.npz``
(:class:`~marsscene.env.policy.MLPPolicy`), which ``perf/bench_batch_env.py sim2sim`` runs in the
CPU environment (MuJoCo C, mesh rocks).
"""

from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path

from marsscene.env import HeightScan, NavTask, ObsConfig, RewardConfig
from marsscene.env.batch import BatchNavEnv, RslRlVecEnv, WarpPhysics
from marsscene.env.policy import MLPPolicy
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
          wheels: str = "sphere", iterations: tuple[int, int] = (100, 50)) -> None:
    from rsl_rl.runners import OnPolicyRunner

    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    env = BatchNavEnv(batch, num_envs=envs, task=TASK, seed=seed, reward=REWARD,
                      observations=ObsConfig(height_scan=SCAN, noise_profile="none"),
                      rover=RoverConfig(wheel_collision=wheels),
                      physics=WarpPhysics(iterations=iterations[0], ls_iterations=iterations[1]))
    vec = RslRlVecEnv(env)
    runner = OnPolicyRunner(vec, {**TRAIN, "seed": seed}, log_dir=None, device=env.device)
    print(f"environment ready in {time.perf_counter() - t0:.1f} s ({envs} rovers on "
          f"{env.batch.count} worlds, {env.device})", flush=True)
    start, rows, it = time.perf_counter(), [], 0
    last = env.bk.to_numpy(env.episodes)
    with open(out / "curve.csv", "w", newline="") as f:
        log = csv.writer(f)
        log.writerow(["iteration", "wall_s", "env_steps", "episodes", "success"])
        while time.perf_counter() - start < minutes * 60.0:
            runner.learn(num_learning_iterations=1, init_at_random_ep_len=it == 0)
            now = env.bk.to_numpy(env.episodes)
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
    won, n = evaluate(vec, runner.alg.get_policy())
    print(f"deterministic policy on the GPU batch: {won}/{n} = {won / n:.1%} of first episodes "
          "reached the goal", flush=True)


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
    ap.add_argument("batch", type=Path, help="a WorldBatch .npz (perf/bench_batch_env.py pack)")
    ap.add_argument("--minutes", type=float, default=9.0)
    ap.add_argument("--envs", type=int, default=4096)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=Path("run"))
    ap.add_argument("--wheels", choices=["cylinder", "sphere"], default="sphere",
                    help="the wheels' collision shape (RoverConfig.wheel_collision)")
    ap.add_argument("--iterations", default="100/50",
                    help="solver and line-search iteration limits (WarpPhysics)")
    args = ap.parse_args()
    its = tuple(int(v) for v in args.iterations.split("/"))
    train(args.batch, args.minutes, args.envs, args.out, args.seed, args.wheels,
          (its[0], its[1]))


if __name__ == "__main__":
    main()
