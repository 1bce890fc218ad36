"""Train a navigation policy on thousands of rovers on one GPU: PPO from rsl-rl on
:class:`marsscene.env.batch.BatchNavEnv` (MuJoCo Warp), then save it for numpy.

Usage (a GPU machine, ``pip install "marsscene[gpu]" rsl-rl-lib``)::

    python perf/run.py batch_env --what pack --path worlds.npz   # 16 worlds, goals 20-50 m (CPU)
    python examples/train_batch_ppo.py worlds.npz --minutes 9 --out run/

It writes ``run/curve.csv`` (per PPO iteration: wall time, environment steps, the share of the
episodes ended in it that reached their goal) and ``run/policy.npz``
(:class:`~marsscene.env.policy.MLPPolicy`), which ``python perf/run.py batch_env --what sim2sim``
runs in the CPU environment (MuJoCo C, mesh rocks).

A policy that sees (``--obs depth``): the navcam's depth, 64 x 64, through rsl-rl's
``CNNModel`` (:data:`CNN`, then the MLP) beside the observation vector and the goal, no height
scan; ``run/policy.npz`` is then a :class:`~marsscene.env.cnn_policy.CNNPolicy` (numpy), which
``sim2sim`` runs on the CPU camera's depth at the same intrinsics::

    python examples/train_batch_ppo.py worlds.npz --obs depth --minutes 9 --out run/

Training resumes from ``run/checkpoint.pt`` (the PPO state, the iteration and the curve, saved
every ``--save-every`` iterations and at the end): ``--resume run/checkpoint.pt``. ``--deadline
MIN`` stops training that many minutes after the process started (making the environment
included), for calls of a limited length; ``--total-minutes`` once the run's training time,
resumed calls included, reaches it. A resumed call starts every rover afresh: its first ten
iterations or so end few episodes at a goal (none has had the time to drive there yet).

The CPU baseline: the same PPO on the CPU environment (:class:`~marsscene.env.RoverNavEnv`, the
scene folders of ``pack --folders``), N rovers in worker processes, the policy on PyTorch's CPU::

    python examples/train_batch_ppo.py worlds.npz --cpu-envs 60 --workers 15 --folders SCENES
"""

from __future__ import annotations

import argparse
import copy
import csv
import multiprocessing as mp
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from marsscene.env import HeightScan, NavTask, ObsConfig, RewardConfig
from marsscene.env.batch import BatchNavEnv, RslRlVecEnv, WarpPhysics
from marsscene.env.cnn_policy import DEPTH_MAX_M, CNNPolicy, depth_input
from marsscene.env.policy import MLPPolicy, policy_input
from marsscene.rover.config import RoverConfig

#: When the process started (``--deadline`` counts from here).
STARTED_S = time.perf_counter()

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
TRAIN: dict[str, Any] = {
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
#: ``--obs depth``: the navcam's depth image (width, height in px), no height scan.
DEPTH_PX = (64, 64)
#: Its encoder (rsl-rl's ``CNN``, one per model): 64 -> 30 -> 14 -> 6 px, 16/32/32 channels,
#: ELU, flattened (1,152 values) beside the 17 of the normalised vector into the MLP.
CNN = {"output_channels": [16, 32, 32], "kernel_size": [5, 3, 3], "stride": [2, 2, 2],
       "padding": "none", "activation": "elu", "flatten": True}
#: rsl-rl's runner configuration with the depth image: a ``CNNModel`` actor and critic.
VISION = {**TRAIN, "obs_groups": {"actor": ["policy", "depth"], "critic": ["policy", "depth"]},
          "actor": {**TRAIN["actor"], "class_name": "CNNModel", "cnn_cfg": CNN},
          "critic": {**TRAIN["critic"], "class_name": "CNNModel", "cnn_cfg": CNN}}
CURVE = ["iteration", "wall_s", "env_steps", "episodes", "success"]


def train(batch: Path, minutes: float, envs: int, out: Path, seed: int,
          wheels: str = "sphere", iterations: tuple[int, int] = (100, 50),
          folders: Path | None = None, workers: int = 0, *, obs: str = "scan",
          resume: Path | None = None, save_every: int = 10, deadline_min: float | None = None,
          total_min: float | None = None, eval_s: float = 150.0,
          device: str | None = None) -> None:
    """PPO for ``minutes`` of wall time: on ``envs`` rovers of the GPU batch, or (``folders``)
    of the CPU environment in ``workers`` processes; ``obs``: ``scan`` (the height scan, an
    MLP) or ``depth`` (the navcam's depth, a CNN; GPU batch only)."""
    import torch
    from rsl_rl.runners import OnPolicyRunner

    out.mkdir(parents=True, exist_ok=True)
    saved = _read_checkpoint(resume, obs) if resume is not None else None
    done_its = int(saved["iteration"]) if saved is not None else 0
    seed_now = seed + done_its  # a resumed run draws new episodes
    torch.manual_seed(seed_now)  # the policy's initial weights and its action noise
    t0 = time.perf_counter()
    if folders is not None:
        torch.set_num_threads(4)
        vec: Any = CpuVecEnv(folders, envs, workers, seed_now, wheels)
        counts, where = (lambda: vec.episodes.copy()), f"{workers} CPU processes"
    else:
        env = _batch_env(batch, envs, seed_now, wheels, iterations, obs, device)
        vec = RslRlVecEnv(env) if obs == "scan" else DepthGroups(RslRlVecEnv(env))
        counts, where = (lambda: env.bk.to_numpy(env.episodes)), f"{env.batch.count} worlds"
    cfg = copy.deepcopy(TRAIN if obs == "scan" else VISION)
    runner = OnPolicyRunner(vec, {**cfg, "seed": seed_now}, log_dir=None, device=str(vec.device))
    rows: list[list[Any]] = []
    if saved is not None:
        runner.alg.load(saved, None, strict=True)
        rows = [list(r) for r in saved["curve"]]
    print(f"environment ready in {time.perf_counter() - t0:.1f} s ({envs} rovers on {where}, "
          f"{vec.device}; observing {obs}; from iteration {done_its})", flush=True)

    def export() -> Any:
        actor = runner.alg.get_policy()
        return (MLPPolicy.from_rsl_rl(actor, SCAN) if obs == "scan"
                else CNNPolicy.from_rsl_rl(actor, DEPTH_MAX_M))

    deadline_s = None if deadline_min is None else deadline_min * 60.0
    if total_min is not None and rows:  # the training time left of a resumed run's total
        minutes = min(minutes, total_min - float(rows[-1][1]) / 60.0)
    elif total_min is not None:
        minutes = min(minutes, total_min)
    it = learn(runner, counts, out=out, minutes=minutes, envs=envs, export=export,
               rows=rows, save_every=save_every, deadline_s=deadline_s, meta={"obs": obs})
    if folders is not None:
        vec.close()
        return
    if eval_s <= 0:
        return
    won, n, going = evaluate(vec, runner.alg.get_policy(), max_s=eval_s)
    print(f"deterministic policy on the batch ({vec.device}): {won}/{n} = {won / n:.1%} of "
          f"first episodes reached the goal (after {it} iterations; {going} still driving "
          f"after {eval_s:g} s counted as failures)", flush=True)


def _batch_env(batch: Path, envs: int, seed: int, wheels: str, iterations: tuple[int, int],
               obs: str, device: str | None) -> BatchNavEnv:
    """The GPU batch observing the height scan (``obs="scan"``) or the navcam's depth."""
    if obs == "scan":
        observe = ObsConfig(height_scan=SCAN, noise_profile="none")
    else:
        observe = ObsConfig(height_scan=None, camera=DEPTH_PX, depth=True, rgb=False,
                            noise_profile="none")
    return BatchNavEnv(batch, num_envs=envs, task=TASK, seed=seed, reward=REWARD,
                       observations=observe, rover=RoverConfig(wheel_collision=wheels),
                       physics=WarpPhysics(iterations=iterations[0],
                                           ls_iterations=iterations[1]),
                       device=device, final_sensors=False)


def learn(runner: Any, counts: Callable[[], np.ndarray], *, out: Path, minutes: float,
          envs: int, export: Callable[[], Any], rows: list[list[Any]], save_every: int = 10,
          deadline_s: float | None = None, meta: dict[str, Any] | None = None) -> int:
    """PPO iterations for ``minutes`` (and, with ``deadline_s``, until that long after the
    process started, less one iteration's time), after the ``rows`` of a resumed curve; the
    curve (``curve.csv``), ``checkpoint.pt`` and ``policy.npz`` (``export()``) written every
    ``save_every`` iterations and at the end (``meta`` beside the state in the checkpoint). The
    iterations done in all."""
    it = it0 = int(rows[-1][0]) if rows else 0
    wall0_s, steps0 = (float(rows[-1][1]), int(rows[-1][2])) if rows else (0.0, 0)
    per_it = envs * int(runner.cfg["num_steps_per_env"])
    start, last, first, took_s = time.perf_counter(), counts(), True, 0.0
    with open(out / "curve.csv", "w", newline="") as f:
        log = csv.writer(f)
        log.writerow(CURVE)
        log.writerows(rows)
        while time.perf_counter() - start < minutes * 60.0 and not (
                deadline_s is not None
                and time.perf_counter() - STARTED_S + took_s > deadline_s):
            t_it = time.perf_counter()
            runner.learn(num_learning_iterations=1, init_at_random_ep_len=first)
            now, first = counts(), False
            ended, won = (int(v) for v in now - last)
            last, it, took_s = now, it + 1, time.perf_counter() - t_it
            row = [it, round(wall0_s + time.perf_counter() - start, 2),
                   steps0 + per_it * (it - it0), ended, round(won / ended, 4) if ended else ""]
            log.writerow(row)
            f.flush()
            rows.append(row)
            if it % 5 == 0:
                print(f"it {it:4d}  {row[1]:7.1f} s  {took_s:5.2f} s/it  success {row[4]}  "
                      f"action std {float(runner.alg.get_policy().output_std.detach().mean()):.2f}",
                      flush=True)
            if it % save_every == 0:
                _save(runner, out, {"iteration": it, "curve": rows, **(meta or {})}, export)
    _save(runner, out, {"iteration": it, "curve": rows, **(meta or {})}, export)
    print(f"{it} iterations ({wall0_s + time.perf_counter() - start:.0f} s of training in all); "
          f"checkpoint {out / 'checkpoint.pt'}, policy {out / 'policy.npz'}", flush=True)
    return it


def _read_checkpoint(path: Path, obs: str) -> dict[str, Any]:
    import torch

    saved = torch.load(path, weights_only=False, map_location="cpu")
    if "iteration" not in saved or "curve" not in saved:
        raise SystemExit(f"{path}: not a checkpoint of this trainer (no iteration, no curve)")
    if saved.get("obs", obs) != obs:
        raise SystemExit(f"{path} was trained with --obs {saved['obs']}, not --obs {obs}")
    return dict(saved)


def _save(runner: Any, out: Path, extra: dict[str, Any], export: Callable[[], Any]) -> None:
    """``checkpoint.pt`` (rsl-rl's PPO state and ``extra``: the iteration, the curve) and
    ``policy.npz``, each written beside and then renamed over the last (a kill leaves the
    previous one)."""
    import torch

    tmp = out / "checkpoint.pt.tmp"
    torch.save({**runner.alg.save(), **extra}, tmp)
    os.replace(tmp, out / "checkpoint.pt")
    export().save(out / "policy.npz.tmp")
    os.replace(out / "policy.npz.tmp", out / "policy.npz")


class DepthGroups:
    """:class:`RslRlVecEnv` for a CNN: its groups ``"policy"`` and ``"depth"`` only, the depth
    as the encoder's input (:func:`~marsscene.env.cnn_policy.depth_input`: clipped to
    ``max_m`` and over it, no return as far)."""

    def __init__(self, vec: RslRlVecEnv, max_m: float = DEPTH_MAX_M) -> None:
        self.vec, self.env, self.max_m = vec, vec.env, float(max_m)
        self.num_envs, self.num_actions = vec.num_envs, vec.num_actions
        self.max_episode_length, self.device, self.cfg = (vec.max_episode_length, vec.device,
                                                          {**vec.cfg, "depth_max_m": max_m})

    @property
    def episode_length_buf(self) -> Any:
        return self.vec.episode_length_buf

    @episode_length_buf.setter
    def episode_length_buf(self, value: Any) -> None:
        self.vec.episode_length_buf = value

    def _groups(self, td: Any) -> Any:
        from tensordict import TensorDict

        return TensorDict({"policy": td["policy"],
                           "depth": depth_input(td["depth"], self.max_m)},
                          batch_size=td.batch_size, device=td.device)

    def get_observations(self) -> Any:
        return self._groups(self.vec.get_observations())

    def step(self, actions: Any) -> tuple[Any, Any, Any, dict[str, Any]]:
        obs, reward, dones, extras = self.vec.step(actions)
        return self._groups(obs), reward, dones, extras


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


def evaluate(vec: RslRlVecEnv | DepthGroups, actor: object, max_s: float = 150.0
             ) -> tuple[int, int, int]:
    """Run the policy's mean action until every rover ended one episode from a fresh reset (or
    ``max_s`` passed: rovers still driving then count as failures); (goals reached, rovers,
    rovers still driving)."""
    import torch

    base = vec.vec if isinstance(vec, DepthGroups) else vec
    env = base.env
    base._obs = env.reset()
    obs = vec.get_observations()
    first = torch.zeros(env.num_envs, dtype=torch.long, device=vec.device)  # 0: still going
    t0 = time.perf_counter()
    with torch.inference_mode():
        for step in range(env.steps_total):
            if time.perf_counter() - t0 > max_s or (step % 10 == 0 and bool((first > 0).all())):
                break
            obs, _, dones, extras = vec.step(actor(obs))  # type: ignore[operator]
            code = extras["termination"].long()
            first = torch.where((first == 0) & (dones > 0), torch.where(code == 1, 1, 2), first)
    return int((first == 1).sum()), env.num_envs, int((first == 0).sum())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("batch", type=Path,
                    help="a WorldBatch .npz (python perf/run.py batch_env --what pack)")
    ap.add_argument("--obs", choices=["scan", "depth"], default="scan",
                    help="what the policy sees besides the vector: the height scan (an MLP) or "
                    f"the navcam's depth, {DEPTH_PX[0]} x {DEPTH_PX[1]} (a CNN)")
    ap.add_argument("--minutes", type=float, default=9.0, help="training time of this call")
    ap.add_argument("--deadline", type=float, metavar="MIN",
                    help="stop training this many minutes after the process started")
    ap.add_argument("--total-minutes", type=float, metavar="MIN",
                    help="stop once the run's training time, resumed calls included, is this")
    ap.add_argument("--resume", type=Path, metavar="CKPT",
                    help="go on from a checkpoint.pt (its iteration and curve continue)")
    ap.add_argument("--save-every", type=int, default=10, metavar="ITS",
                    help="write checkpoint.pt and policy.npz every this many iterations")
    ap.add_argument("--eval-s", type=float, default=150.0,
                    help="at most this many seconds of the trained policy's evaluation on the "
                    "batch, one episode a rover (0: none; 4,096 rovers seeing depth on an H200 "
                    "take about 130 s for a whole 150 s episode)")
    ap.add_argument("--envs", type=int, default=4096)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=Path("run"))
    ap.add_argument("--device", help="Warp device (default: cuda:0 where there is a GPU)")
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
    if cpu and args.obs != "scan":
        ap.error("--cpu-envs trains the height-scan MLP only (--obs scan)")
    if args.save_every < 1:
        ap.error("--save-every must be 1 or more")
    train(args.batch, args.minutes, args.cpu_envs if cpu else args.envs, args.out, args.seed,
          args.wheels, (its[0], its[1]), args.folders if cpu else None,
          min(args.workers, args.cpu_envs), obs=args.obs, resume=args.resume,
          save_every=args.save_every, deadline_min=args.deadline,
          total_min=args.total_minutes, eval_s=args.eval_s,
          device=args.device)


if __name__ == "__main__":
    main()
