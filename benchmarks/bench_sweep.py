"""Sweep throughput: 16 cells of 200 m x 200 m procedural scenes (4 seeds x 4 dust tau).

Wall times of the whole sweep (fresh processes, imports included):

* serial: ``run_sweep(serial=True)``, one process, no Dask;
* 2 plain processes: the cells split over two forked processes calling ``run_cell`` (no Dask):
  the parallel ceiling on this machine as loaded now;
* LocalCluster(2) cold: ``run_sweep(workers=2)``, cluster start-up included;
* LocalCluster(2) warm: a running cluster (workers started and imports done), reached by
  address as a remote scheduler would be.

Dask overhead per cell: the warm cluster re-runs the finished sweep (every task only reads its
cell's result.json and compares a hash), so wall x 2 workers / 16 cells bounds the worker time
Dask adds per cell (scheduling, transfer, result) from above; the difference between the warm and
the 2-process walls is also printed (noisy on a shared machine). Targets (issue 12): speed-up
>= 1.7x, overhead < 0.2 s per cell.
"""

from __future__ import annotations

import multiprocessing as mp
import shutil
import tempfile
import time
from pathlib import Path

from _measure import measure

WORKERS = 2
_ROOT = Path(tempfile.gettempdir()) / "marsscene_bench_sweep"
_SPEC = """
[terrain]
source = "procedural"
size_m = [200.0, 200.0]
post_m = 0.25
[sweep]
seed = [1, 2, 3, 4]
"lighting.tau" = [0.3, 1.0, 2.0, 3.0]
"""


def _spec():  # type: ignore[no-untyped-def]
    from marsscene.sweep import load_sweep

    return load_sweep(_ROOT / "sweep.toml")


def _serial() -> float:
    from marsscene.sweep import run_sweep

    t0 = time.perf_counter()
    res = run_sweep(_spec(), _ROOT / "serial", serial=True)
    assert res.count("ok") == 16
    return time.perf_counter() - t0


def _half(part: int) -> None:
    from marsscene.sweep import expand_grid, run_cell

    for cell in expand_grid(_spec())[part::WORKERS]:
        assert run_cell(cell, _ROOT / "plain")["status"] == "ok"


def _plain() -> float:
    ctx = mp.get_context("fork")
    t0 = time.perf_counter()
    procs = [ctx.Process(target=_half, args=(i,)) for i in range(WORKERS)]
    for p in procs:
        p.start()
    for p in procs:
        p.join()
    return time.perf_counter() - t0


def _cold(out: str = "cold") -> float:
    from marsscene.sweep import run_sweep

    t0 = time.perf_counter()
    res = run_sweep(_spec(), _ROOT / out, workers=WORKERS)
    assert res.count("failed") == 0
    return time.perf_counter() - t0


def _warm() -> tuple[float, float]:
    import dask
    from distributed import Client, LocalCluster

    from marsscene.sweep import run_sweep

    with dask.config.set({"distributed.worker.profile.enabled": False}), LocalCluster(
        n_workers=WORKERS, threads_per_worker=1, dashboard_address=None
    ) as lc:
        with Client(lc) as client:
            client.run(lambda: __import__("marsscene.export.usd"))
            client.run(lambda: __import__("marsscene.export.mjcf"))
            client.run(lambda: __import__("marsscene.pipeline"))
        t0 = time.perf_counter()
        res = run_sweep(_spec(), _ROOT / "warm", scheduler=lc.scheduler_address)
        wall = time.perf_counter() - t0
        t0 = time.perf_counter()
        again = run_sweep(_spec(), _ROOT / "warm", scheduler=lc.scheduler_address)
        rerun = time.perf_counter() - t0
    assert res.count("ok") == 16 and again.count("skipped") == 16
    return wall, rerun


def main() -> None:
    shutil.rmtree(_ROOT, ignore_errors=True)
    _ROOT.mkdir(parents=True)
    (_ROOT / "sweep.toml").write_text(_SPEC, encoding="utf-8")
    try:
        ser = measure(_serial)[2]
        plain = measure(_plain)[2]
        cold = measure(_cold)[2]
        warm, rerun = measure(_warm)[2]
    finally:
        shutil.rmtree(_ROOT, ignore_errors=True)
    print(f"16 cells, 200 m scenes: serial {ser:.1f} s; 2 plain processes {plain:.1f} s "
          f"({ser / plain:.2f}x, the ceiling now)")
    print(f"LocalCluster({WORKERS}) cold {cold:.1f} s ({ser / cold:.2f}x), warm {warm:.1f} s "
          f"({ser / warm:.2f}x) (target >= 1.7x)")
    print(f"Dask overhead per cell: <= {rerun * WORKERS / 16:.3f} s (warm re-run of 16 finished "
          f"cells: {rerun:.2f} s) (target < 0.2 s); (warm - 2-process) x {WORKERS} / 16 = "
          f"{(warm - plain) * WORKERS / 16:+.3f} s")
