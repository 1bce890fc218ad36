"""The LocalCluster that run_sweep starts: worker processes whose malloc keeps numpy temporaries."""

from __future__ import annotations

import os
import platform
import subprocess
import sys

import pytest

from marsscene.sweep.run import WORKER_ENV, local_cluster

pytestmark = pytest.mark.skipif(platform.libc_ver()[0] != "glibc",
                                reason="glibc malloc tunables")

# A cell's hot loop in miniature: a 1 MiB numpy temporary (too small for a transparent huge
# page) made and freed 100 times. Where glibc serves it from the heap its 256 pages fault in
# once; where every temporary is a fresh mmap (Dask's default MALLOC_TRIM_THRESHOLD_ pins the
# mmap threshold at 128 KiB) the kernel faults them in again each time: ~25 600 faults.
PROBE = """
import resource
import numpy as np
x = np.ones(1 << 17)
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(100):
    y = x * 2.0
    del y
print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""


def _faults() -> int:
    scope: dict[str, object] = {}
    import contextlib
    import io

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(PROBE, scope)
    return int(out.getvalue())


def _probe_in_process(env: dict[str, str]) -> int:
    clean = {k: v for k, v in os.environ.items() if not k.startswith("MALLOC_")}
    res = subprocess.run([sys.executable, "-c", PROBE], env={**clean, **env},
                         capture_output=True, text=True, check=True)
    return int(res.stdout)


def test_dask_default_worker_env_refaults_every_temporary() -> None:
    """The cost the sweep's worker environment removes, shown in plain processes."""
    dask_default = _probe_in_process({"MALLOC_TRIM_THRESHOLD_": "65536"})
    ours = _probe_in_process(WORKER_ENV)
    assert dask_default > 20_000  # ~100 x 256
    assert ours < 2_000


def test_local_cluster_workers_run_with_the_sweep_malloc_settings() -> None:
    from distributed import Client

    with local_cluster(1) as cluster, Client(cluster) as client:
        (env,) = client.run(lambda: {k: os.environ.get(k) for k in WORKER_ENV}).values()
        (faults,) = client.run(_faults).values()
        (nthreads,) = client.nthreads().values()
        (profile,) = client.run(
            lambda: __import__("dask").config.get("distributed.worker.profile.enabled")
        ).values()
    assert env == WORKER_ENV
    assert faults < 2_000
    assert nthreads == 1 and profile is False


def test_local_cluster_leaves_this_process_environment_alone() -> None:
    before = {k: os.environ.get(k) for k in (*WORKER_ENV, "OMP_NUM_THREADS")}
    with local_cluster(1):
        assert {k: os.environ.get(k) for k in before} == before


def test_remote_workers_with_dask_default_malloc_get_a_warning(
        scheduler_address: str, tmp_path, caplog: pytest.LogCaptureFixture) -> None:
    from sweep_util import write_sweep

    from marsscene.sweep import SweepSpec, run_sweep

    spec = SweepSpec.from_toml(write_sweep(tmp_path / "s.toml", "seed = [3]\n"))
    with caplog.at_level("WARNING", logger="marsscene"):
        res = run_sweep(spec, tmp_path / "out", scheduler=scheduler_address)
    assert res.count("ok") == 1
    (msg,) = [r.getMessage() for r in caplog.records if "MALLOC_TRIM_THRESHOLD_" in r.getMessage()]
    assert msg.startswith("2 Dask worker(s)") and "MALLOC_TRIM_THRESHOLD_=65536" in msg
    assert "MALLOC_MMAP_THRESHOLD_=33554432 MALLOC_TRIM_THRESHOLD_=67108864" in msg
