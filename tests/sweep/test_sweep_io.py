"""Results table formats, import hygiene and scheduler errors of the sweep."""

from __future__ import annotations

import csv
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest
from sweep_util import write_sweep

from marsscene.errors import SweepError
from marsscene.sweep import SweepSpec, run_sweep


def test_importing_the_sweep_package_loads_no_heavy_dependency() -> None:
    code = (
        "import sys, marsscene.sweep, marsscene.sweep.cell; "
        "bad = [m for m in ('dask', 'distributed', 'mujoco', 'pxr', 'click') if m in sys.modules]; "
        "print(bad)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_unreachable_scheduler_is_a_one_line_error(tmp_path: Path) -> None:
    spec = SweepSpec.from_toml(write_sweep(tmp_path / "s.toml", "seed = [1]\n"))
    t0 = time.perf_counter()
    addr = "tcp://127.0.0.1:9"  # discard port: nothing listens there
    with pytest.raises(SweepError, match=re.escape(f"cannot reach Dask scheduler {addr!r}")) as e:
        run_sweep(spec, tmp_path / "out", scheduler=addr, connect_timeout_s=1.0)
    assert "\n" not in str(e.value) and time.perf_counter() - t0 < 30
    with pytest.raises(SweepError, match="at most one of workers"):
        run_sweep(spec, tmp_path / "out", scheduler="tcp://127.0.0.1:9", workers=2)


def test_parquet_table_matches_the_csv(tmp_path: Path) -> None:
    pq = pytest.importorskip("pyarrow.parquet")
    spec = SweepSpec.from_toml(write_sweep(tmp_path / "s.toml", '"rocks.k" = [0.05, 2.0]\n'))
    res = run_sweep(spec, tmp_path / "out", serial=True)
    assert [f.name for f in res.files] == ["results.csv", "results.parquet"]
    table = pq.read_table(tmp_path / "out" / "results.parquet").to_pylist()
    with open(tmp_path / "out" / "results.csv", newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["cell_id"] for r in table] == [r["cell_id"] for r in rows] == [
        "rocks.k=0.05", "rocks.k=2.0"]
    assert [r["status"] for r in table] == ["ok", "failed"]
    assert table[0]["n_rocks"] == int(rows[0]["n_rocks"]) > 0 and table[1]["n_rocks"] is None
    assert table[0]["rocks.k"] == 0.05 and "out of range" in table[1]["error"]
