"""Shared pieces of the perf scripts: wall time and peak memory of a call, measured in a child
process (clean peak RSS), and a paper-spec scene built once into a temporary folder."""

from __future__ import annotations

import multiprocessing as mp
import os
import resource
import subprocess
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any


def _child(fn: Callable[[], Any], queue: Any) -> None:
    t0 = time.perf_counter()
    try:
        extra = fn()
    except BaseException as err:  # the parent raises it (else it would wait for ever)
        queue.put(("error", f"{type(err).__name__}: {err}", None))
        raise
    wall = time.perf_counter() - t0
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    queue.put((wall, peak_mb, extra))


def measure(fn: Callable[[], Any]) -> tuple[float, float, Any]:
    """Run ``fn`` in a fresh process; return ``(wall_s, peak_rss_mb, fn's return value)``.

    ``fn`` must be a module-level function (picklable under the 'fork' start method too). An
    exception in the child is raised here as a ``RuntimeError`` naming it.
    """
    ctx = mp.get_context("fork")
    queue = ctx.Queue()
    proc = ctx.Process(target=_child, args=(fn, queue))
    proc.start()
    result = queue.get()
    proc.join()
    if result[0] == "error":
        raise RuntimeError(f"{getattr(fn, '__name__', fn)} failed in its process: {result[1]}")
    return result


def marsscene_build(args: list[str], out: Path) -> tuple[float, float, int]:
    """``marsscene build ARGS --seed 7 --out OUT`` niced in a fresh process: wall s, peak MB
    (``os.wait4``), exit status (its last stderr line printed when it fails)."""
    cmd = ["nice", "-n", "10", "marsscene", "build", *args, "--seed", "7", "--out", str(out)]
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    assert proc.stderr is not None
    err = proc.stderr.read()
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    wall = time.perf_counter() - t0
    if proc.returncode:
        print("   " + err.strip().splitlines()[-1] if err.strip() else "   (no message)")
    return wall, usage.ru_maxrss / 1024.0, proc.returncode


def paper_scene(name: str, seed: int = 1) -> tuple[Path, bool]:
    """Scene ``name`` of ``docs/examples/benchmark_slam_paper.toml`` as its SLAM cells build it
    (MJCF only), in a temporary folder kept between runs. Returns ``(folder, built_now)``."""
    import marsscene as ms
    from marsscene.benchmark.slam.spec import SlamSpec

    root = Path(__file__).resolve().parents[1]
    spec = SlamSpec.from_toml(root / "docs" / "examples" / "benchmark_slam_paper.toml")
    scene = next(s for s in spec.scenes if s.name == name)
    folder = Path(tempfile.gettempdir()) / f"marsscene_paper_scene_{name}_{seed}"
    if (folder / "mjcf" / "scene.xml").is_file():
        return folder, False
    cfg = ms.SceneConfig.from_dict(scene.base_config())
    ms.write_scene(ms.build_scene(cfg, seed=seed), folder, formats=("mjcf",), overwrite=True)
    return folder, True


def parse_physics(stage: Any) -> tuple[float, dict[str, int]]:
    """OpenUSD's physics parser over ``/World``: seconds, and how many of each descriptor
    (``MeshShape``, ``RigidBody``, ...) it reports."""
    from pxr import UsdPhysics

    load = getattr(UsdPhysics, "UsdPhysicsLoadStageFromPrimRange", None) or \
        UsdPhysics.LoadUsdPhysicsFromRange  # renamed in usd-core 26.08
    t0 = time.perf_counter()
    parsed = load(stage, ["/World"])
    seconds = time.perf_counter() - t0
    return seconds, {str(k).split(".")[-1]: len(v[0]) for k, v in parsed.items()}
