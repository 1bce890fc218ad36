"""The batched GPU environment (MuJoCo Warp): its worlds, its agreement with MuJoCo C, its speed,
and a trained policy's sim-to-sim check in the CPU environment.

Usage::

    python perf/run.py batch_env --what pack --path OUT.npz [--folders OUT.tar]  # 16 worlds
    python perf/run.py batch_env --what agree --path OUT.npz [--posts 0.25,0.125,0.1]
    python perf/run.py batch_env --what run --path OUT.npz [--envs 1,1024,4096] [--folders DIR]
    python perf/run.py batch_env --what repro --path OUT.npz [--envs 4096]
    python perf/run.py batch_env --what sim2sim --path POLICY.npz --folders DIR [--episodes 50]
        [--workers 0]
    python perf/run.py batch_env --what curve --path run/curve.csv --out curve.png [--gpu 91]

``pack`` builds the benchmark's worlds (the three world kinds with rock abundance k = 0.2: 6
plain, 5 craters, 5 rocks) and draws 256 episodes on each. ``agree`` drives 32 rovers 10 s
from settled starts in MuJoCo C and MuJoCo Warp on the tiled heightfield at several post
spacings and prints how far apart they end. ``run`` times environment steps per second at
5 Hz control (100 Hz physics, height scan, random actions) for each batch size, and, with
``--folders`` (the scenes of ``pack --folders``), the CPU environment on one core and on every
core (one process a core). ``repro`` makes and drives the same batch twice and compares the
bytes. ``--variants`` picks the wheels' collision shape, the solver's iteration limits and
MuJoCo Warp's deterministic mode (``cylinder/100/50/det``). ``sim2sim`` runs a policy
(``examples/train_batch_ppo.py``: the height scan's MLP, or with ``--obs depth`` the depth
image's CNN, seeing the CPU camera's depth) in the CPU environment (MuJoCo C, mesh rocks) over
seeded episodes. Without ``--path`` the batch is :data:`BATCH` (in the temporary folder); quick:
``pack`` there, full: ``run`` on it.
"""

from __future__ import annotations

import functools
import importlib.util
import multiprocessing as mp
import os
import tarfile
import tempfile
import time
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np

from marsscene.errors import ConfigError
from perf.suite import Param, floats, ints, names, optional

if TYPE_CHECKING:
    from marsscene.env import ObsConfig, RoverNavEnv
    from marsscene.env.batch import WarpPhysics
    from marsscene.rover.config import RoverConfig

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "train_batch_ppo.py"
BATCH = Path(tempfile.gettempdir()) / "marsscene_bench_batch_env" / "worlds.npz"
WHAT = ("pack", "agree", "run", "repro", "sim2sim", "curve")
PARAMS = (
    Param("what", str, f"what to do: {', '.join(WHAT)} (the module's docstring)",
          quick="pack", full="run", choices=WHAT),
    Param("path", optional(Path), f"pack, agree, run, repro: the WorldBatch .npz (none: "
          f"{BATCH}); sim2sim: the policy .npz; curve: the training's curve.csv",
          quick=None, full=None),
    Param("folders", optional(Path), "pack: a .tar of the scene folders to write; run, "
          "sim2sim: the folder they were unpacked in (the CPU environment)", quick=None,
          full=None),
    Param("posts", floats, "agree: post spacings (m)", quick=(0.25,), full=(0.25, 0.125, 0.1)),
    Param("device", str, "agree: Warp device", quick="cpu", full="cpu"),
    Param("envs", ints, "run: batch sizes; repro: the first is the batch's", quick=(16,),
          full=(1, 1024, 4096, 16384)),
    Param("variants", names, "WHEELS/ITERATIONS/LS_ITERATIONS[/det]", quick=("sphere/100/50",),
          full=("sphere/100/50",)),
    Param("steps", int, "run, repro: timed steps", quick=50, full=50),
    Param("depth_px", int, "run: a square depth camera of this many pixels a side in the "
          "observations (0: none)", quick=0, full=0),
    Param("lidar", optional(str), "run: a LiDAR model in the observations (none: no LiDAR)",
          quick=None, full=None),
    Param("final_sensors", bool, "run: also cast the sensors for info['final_observation']",
          quick=True, full=True),
    Param("rgb", bool, "run: with --depth-px, observe the camera's RGB too (the shaded "
          "frame; default depth alone)", quick=False, full=False),
    Param("episodes", int, "sim2sim: seeded episodes", quick=5, full=50),
    Param("workers", int, "sim2sim: processes the episodes are spread over (0: one a core)",
          quick=1, full=0),
    Param("out", Path, "curve: the figure to write", quick=Path("curve.png"),
          full=Path("curve.png")),
    Param("gpu", optional(float), "curve: the policy's GPU success (%)", quick=None, full=None),
    Param("cpu", optional(float), "curve: the policy's CPU success (%)", quick=None, full=None),
    Param("observes", str, "curve: what the policy sees, for the title", quick="a height scan",
          full="a height scan"),
)
KINDS = {"plain": 6, "craters": 5, "rocks": 5}
SECONDS_CPU = 20.0


@functools.cache
def _example() -> ModuleType:
    """``examples/train_batch_ppo.py`` (its task, height scan and training sizes)."""
    spec = importlib.util.spec_from_file_location("train_batch_ppo", EXAMPLE)
    assert spec and spec.loader
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _samplers(cache: str | None) -> list:
    from marsscene.env import WorldSampler

    return [WorldSampler(base=kind, vary={"rocks.k": [0.2]}, count=n, seed=100 * i,
                         cache_dir=cache) for i, (kind, n) in enumerate(KINDS.items())]


def pack(out: Path, folders: Path | None) -> dict[str, Any]:
    from marsscene.env.batch import WorldBatch

    paths = [s.path(i) for s in _samplers(None) for i in range(s.count)]
    t0 = time.perf_counter()
    batch = WorldBatch.build(paths, task=_example().TASK, pool=256, seed=0)
    out.parent.mkdir(parents=True, exist_ok=True)
    batch.save(out)
    built_s = time.perf_counter() - t0
    print(f"{out}: {batch.count} worlds, {batch.pool} episodes each, "
          f"{len(batch.rock_radius_m)} rocks, {out.stat().st_size / 1e6:.1f} MB "
          f"({built_s:.1f} s)")
    if folders is not None:
        with tarfile.open(folders, "w") as tar:
            for i, p in enumerate(paths):
                tar.add(p, arcname=f"world{i:02d}")
        print(f"{folders}: the {len(paths)} scene folders")
    return {"worlds": batch.count, "episodes": batch.pool, "rocks": len(batch.rock_radius_m),
            "mb": out.stat().st_size / 1e6, "build_s": built_s}


def _variant(spec: str) -> tuple[RoverConfig, WarpPhysics]:
    """``WHEELS/ITERATIONS/LS_ITERATIONS[/det]`` -> (RoverConfig, WarpPhysics)."""
    from marsscene.env.batch import WarpPhysics
    from marsscene.rover.config import RoverConfig

    wheels, it, ls, *det = spec.split("/")
    return (RoverConfig(wheel_collision=wheels),
            WarpPhysics(iterations=int(it), ls_iterations=int(ls), deterministic=bool(det)))


def agree(batch_path: Path, posts: tuple[float, ...], variants: tuple[str, ...],
          device: str) -> list[dict[str, Any]]:
    """The CPU environment's physics (cylinder wheels, MuJoCo's solver defaults) in MuJoCo C
    against each variant in MuJoCo Warp, at each post spacing."""
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
    n, steps = 32, (300, 1000)
    out = []
    for post in posts:
        ref_model = tiled_model(terr, bare, rover=RoverConfig(), physics_hz=100.0, post_m=post)
        m, ids = ref_model.model, ref_model.ids
        qs = np.tile(m.qpos0, (n, 1))
        for k in range(n):
            w, p = k % b.count, k // b.count
            pose = spawn_pose(terr[w], tuple(b.starts_xy_m[w, p]), float(b.yaws_rad[w, p]),
                              RoverConfig())
            pose[:2] += ref_model.offsets_xy_m[w]
            qs[k, :7] = pose
        rates, steer = wheel_commands(0.5, 0.05, RoverConfig())
        ctrl = np.zeros(m.nu)
        ctrl[ids["drive_act"]], ctrl[ids["steer_act"]] = rates, steer
        ref = []
        for k in range(n):
            d = mujoco.MjData(m)
            d.qpos[:] = qs[k]
            mujoco.mj_step(m, d, nstep=steps[0])
            d.ctrl[:] = ctrl
            mujoco.mj_step(m, d, nstep=steps[1])
            ref.append(d.qpos[:2].copy())
        for spec in variants:
            rover, physics = _variant(spec)
            mv = tiled_model(terr, bare, rover=rover, physics_hz=100.0, post_m=post,
                             physics=physics).model
            with wp.ScopedDevice(device):
                mw = mjw.put_model(mv)
                dw = mjw.put_data(mv, mujoco.MjData(mv), nworld=n, nconmax=96, njmax=512)
                wp.copy(dw.qpos, wp.array(qs, dtype=float))
                for _ in range(steps[0]):
                    mjw.step(mw, dw)
                wp.copy(dw.ctrl, wp.array(np.tile(ctrl, (n, 1)), dtype=float))
                for _ in range(steps[1]):
                    mjw.step(mw, dw)
                got = dw.qpos.numpy()[:, :2]
            err = np.linalg.norm(got - np.array(ref), axis=1)
            print(f"posts {post:.3f} m, {spec}: MuJoCo Warp vs C after 3 s settling + 10 s "
                  f"driving, {n} starts: median {np.median(err):.3f} m, 90th percentile "
                  f"{np.percentile(err, 90):.2f} m, {int((err > 0.5).sum())} over 0.5 m",
                  flush=True)
            out.append({"post_m": post, "variant": spec, "starts": n,
                        "median_m": float(np.median(err)),
                        "p90_m": float(np.percentile(err, 90)),
                        "over_0_5_m": int((err > 0.5).sum())})
    return out


def run(batch_path: Path, envs: tuple[int, ...], variants: tuple[str, ...],
        folders: Path | None, steps: int, sensors: dict[str, Any] | None = None
        ) -> list[dict[str, Any]]:
    """Environment steps a second; ``sensors``: ``depth_px``, ``lidar``, ``final_sensors``."""
    import torch

    sensors = sensors or {}
    out = []
    print(f"GPU: {torch.cuda.get_device_name()}; CPU cores: {os.cpu_count()}", flush=True)
    for spec in variants:
        print(f"-- wheels/iterations/line-search iterations[/deterministic]: {spec}")
        rover, physics = _variant(spec)
        for n in envs:
            out.append({"variant": spec, **sensors,
                        **_run_one(batch_path, n, rover, physics, steps, sensors)})
    if folders is not None:
        cores = os.cpu_count() or 1
        one = _cpu_rate(str(folders))
        with mp.get_context("spawn").Pool(cores) as pool:
            every = sum(pool.map(_cpu_rate, [str(folders)] * cores))
        print(f"CPU environment (MuJoCo C, mesh rocks): {one:,.0f} env steps/s on one core, "
              f"{every:,.0f} on {cores} cores (one process a core)", flush=True)
        out.append({"variant": "cpu_env", "envs": 1, "steps_per_s": one,
                    "every_core_steps_per_s": every, "cores": cores})
    return out


def _observations(depth_px: int = 0, lidar: str | None = None, rgb: bool = False,
                  **_: Any) -> Any:
    """The batch's default observations, plus a depth camera and a LiDAR when asked."""
    from marsscene.env import ObsConfig

    camera = (depth_px, depth_px) if depth_px else None
    return ObsConfig(noise_profile="none", camera=camera, depth=bool(depth_px),
                     rgb=rgb or not depth_px, lidar=lidar)


def _run_one(batch_path: Path, n: int, rover: RoverConfig, physics: WarpPhysics,
             steps: int, sensors: dict[str, Any] | None = None) -> dict[str, Any]:
    import torch

    from marsscene.env.batch import BatchNavEnv

    sensors = sensors or {}
    t0 = time.perf_counter()
    env = BatchNavEnv(batch_path, num_envs=n, seed=0, rover=rover, physics=physics,
                      observations=_observations(**sensors),
                      final_sensors=sensors.get("final_sensors", True))
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
    per_s = n * steps * env.substeps / dt
    print(f"N = {n:6d}: {n * steps / dt:12,.0f} env steps/s ({per_s:14,.0f} physics "
          f"steps/s; made in {made:.1f} s; {env.success_rate:.3f} of "
          f"{int(env.bk.to_numpy(env.episodes)[0])} random episodes reached the goal)",
          flush=True)
    got = {"envs": n, "steps_per_s": n * steps / dt, "physics_steps_per_s": per_s,
           "made_s": made, "success": float(env.success_rate)}
    del env
    torch.cuda.empty_cache()
    return got


def repro(batch_path: Path, n: int, variants: tuple[str, ...],
          steps: int) -> list[dict[str, Any]]:
    """Two batches made and driven alike (same seed, same actions): how far apart they end."""
    import torch

    from marsscene.env.batch import BatchNavEnv

    out = []
    for spec in variants:
        rover, physics = _variant(spec)
        ends, times = [], []
        for _ in range(2):
            env = BatchNavEnv(batch_path, num_envs=n, seed=0, rover=rover, physics=physics)
            gen = torch.Generator(device=env.bk.tdevice).manual_seed(0)
            torch.cuda.synchronize()
            t0 = time.perf_counter()
            for _ in range(steps):
                env.step(torch.rand((n, 2), generator=gen, device=env.bk.tdevice) * 2 - 1)
            torch.cuda.synchronize()
            times.append(time.perf_counter() - t0)
            ends.append(env.bk.to_numpy(env._v["qpos"]).copy())
            del env
        gap = np.linalg.norm(ends[0][:, :2] - ends[1][:, :2], axis=1)
        print(f"{spec}: {n} rovers, {steps} steps twice: {ends[0].tobytes() == ends[1].tobytes()}"
              f" identical bytes; {int((gap > 0).sum())} rovers apart, median "
              f"{np.median(gap):.3f} m, max {gap.max():.2f} m; {n * steps / min(times):,.0f} "
              "env steps/s", flush=True)
        out.append({"variant": spec, "envs": n, "steps": steps,
                    "identical": ends[0].tobytes() == ends[1].tobytes(),
                    "rovers_apart": int((gap > 0).sum()), "median_gap_m": float(np.median(gap)),
                    "max_gap_m": float(gap.max()), "steps_per_s": n * steps / min(times)})
    return out


def curve(csv_path: Path, out: Path, gpu: float | None, cpu: float | None,
          observes: str = "a height scan") -> dict[str, Any]:
    """The learning curve of ``train_batch_ppo.py`` (success of the episodes ended in each
    iteration against wall time), with the trained policy's GPU and CPU success beside it."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = np.genfromtxt(csv_path, delimiter=",", names=True)
    per_env = _example().TRAIN["num_steps_per_env"]
    rovers = int(rows["env_steps"][0] / rows["iteration"][0] / per_env)
    fig, ax = plt.subplots(figsize=(6.4, 3.6), dpi=120)
    ax.set_title(f"PPO on BatchNavEnv: {rovers:,} rovers seeing {observes}, goals 20-50 m",
                 fontsize=10)
    ax.plot(rows["wall_s"] / 60.0, 100.0 * np.nan_to_num(rows["success"]), lw=1.2,
            label="episodes ended in each PPO iteration (GPU batch)")
    for value, style, what in ((gpu, "--", "trained policy, GPU batch"),
                               (cpu, ":", "trained policy, CPU env (mesh rocks)")):
        if value is not None:
            ax.axhline(value, ls=style, color="k", lw=1.0, label=f"{what}: {value:.1f} %")
    ax.set(xlabel="wall time (min)", ylabel="reached the goal (%)", ylim=(0, 100),
           xlim=(0, max(rows["wall_s"]) / 60.0))
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(out)
    print(f"{out}: {len(rows)} iterations")
    return {"iterations": len(rows), "rovers": rovers}


def _cpu_env(folders: str, observations: ObsConfig | None = None) -> RoverNavEnv:
    from marsscene.env import ObsConfig, RoverNavEnv

    example = _example()

    paths = sorted(p for p in Path(folders).iterdir() if (p / "mjcf" / "scene.xml").is_file())
    obs = observations or ObsConfig(height_scan=example.SCAN, noise_profile="none")
    return RoverNavEnv(paths, task=example.TASK, observations=obs, max_worlds_loaded=len(paths))


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


def sim2sim(policy_path: Path, folders: Path, episodes: int, workers: int = 1
            ) -> dict[str, Any]:
    """A policy (:class:`~marsscene.env.policy.MLPPolicy` with its height scan, or
    :class:`~marsscene.env.cnn_policy.CNNPolicy` with the CPU camera's depth at the batch
    camera's size and field of view) in the CPU environment over seeded episodes, spread over
    ``workers`` processes (0: one a core; an episode's end depends on its seed alone)."""
    procs = min(workers or os.cpu_count() or 1, episodes)
    ends: dict[str, int] = {}
    t0 = time.perf_counter()
    args = [(str(policy_path), str(folders), seed) for seed in range(episodes)]
    with mp.get_context("spawn").Pool(procs) as pool:
        for seed, (why, distance_m) in enumerate(pool.imap(_sim2sim_episode, args)):
            ends[why] = ends.get(why, 0) + 1
            print(f"episode {seed:3d}: {why:10s} {distance_m:6.2f} m from the goal", flush=True)
    won = ends.get("goal", 0)
    print(f"CPU environment (MuJoCo C, mesh rocks): {won}/{episodes} = {won / episodes:.0%} "
          f"reached the goal; ends {ends} ({time.perf_counter() - t0:.0f} s, {procs} "
          "processes)")
    return {"episodes": episodes, "goal": won, "success": won / episodes, "ends": ends}


@functools.cache
def _sim2sim_env(policy_path: str, folders: str) -> tuple[Any, RoverNavEnv]:
    """A worker's policy and CPU environment (made once a process)."""
    from marsscene.env.cnn_policy import load_policy

    policy = load_policy(policy_path)
    return policy, _cpu_env(folders, policy.observations())


def _sim2sim_episode(job: tuple[str, str, int]) -> tuple[str, float]:
    """One seeded episode of the policy: how it ended and how far from the goal (m)."""
    policy, env = _sim2sim_env(job[0], job[1])
    obs, info = env.reset(seed=job[2])
    done = False
    while not done:
        obs, _, te, tr, info = env.step(policy(obs))
        done = te or tr
    return info["termination"] or "time limit", float(info["distance_m"])


def main(what: str, path: Path | None, folders: Path | None, posts: tuple[float, ...],
         device: str, envs: tuple[int, ...], variants: tuple[str, ...], steps: int,
         episodes: int, workers: int, out: Path, gpu: float | None, depth_px: int,
         lidar: str | None,
         final_sensors: bool, rgb: bool,
         cpu: float | None, observes: str) -> dict[str, Any] | list[dict[str, Any]]:
    if what in ("sim2sim", "curve") and path is None:
        raise ConfigError(f"batch_env --what {what} needs --path (the "
                          f"{'policy .npz' if what == 'sim2sim' else 'curve.csv'})")
    if what == "sim2sim" and folders is None:
        raise ConfigError("batch_env --what sim2sim needs --folders (the scene folders)")
    batch = path or BATCH
    if what in ("agree", "run", "repro") and not batch.is_file():
        raise ConfigError(f"no batch {batch}: make it with "
                          f"`python perf/run.py batch_env --what pack --path {batch}`")
    if what == "pack":
        return pack(batch, folders)
    if what == "agree":
        return agree(batch, posts, variants, device)
    if what == "run":
        return run(batch, envs, variants, folders, steps,
                   {"depth_px": depth_px, "lidar": lidar, "final_sensors": final_sensors,
                    "rgb": rgb})
    if what == "repro":
        return repro(batch, envs[0], variants, steps)
    if what == "curve":
        return curve(batch, out, gpu, cpu, observes)
    assert folders is not None
    return sim2sim(batch, folders, episodes, workers)
