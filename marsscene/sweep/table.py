"""``results.csv`` (and ``results.parquet`` when pyarrow is installed): one row per cell."""

from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import Any

from marsscene._atomic import write_atomic

__all__ = ["COLUMNS", "flatten_rows", "write_results"]

#: Fixed columns after ``cell_id`` and the swept keys (stage timings ``t_<stage>_s`` follow).
COLUMNS = (
    "status", "error", "seed",
    "t_total_s", "t_build_s", "t_write_s", "t_drive_s",
    "n_craters", "n_rocks",
    "tau", "sun_azimuth_deg", "sun_elevation_deg", "direct_normal_w_m2",
    "diffuse_horizontal_w_m2", "visibility_m",
    "distance_m", "sim_time_s", "goal_reached", "cross_track_rms_m",
    "ate_rmse_m", "rpe_trans_rmse_m", "rpe_rot_rmse_deg", "sim_wall_ratio", "bag_s",
    "config_hash",
)


def _cell_text(value: Any) -> Any:
    if isinstance(value, list | tuple):
        return " ".join(str(_cell_text(v)) for v in value)
    return value


def flatten_rows(rows: list[dict[str, Any]], keys: list[str]) -> tuple[list[str], list[list[Any]]]:
    """Header and values: ``cell_id``, every swept key, :data:`COLUMNS`, stage timings."""
    stage_cols = sorted(
        {k for r in rows for k in r if k.startswith("t_") and k not in COLUMNS}
    )
    fixed = [c for c in COLUMNS if c not in keys]
    header = ["cell_id", *keys, *fixed, *stage_cols]
    table = []
    for r in rows:
        params = r.get("params", {})
        values = [r["cell_id"], *(_cell_text(params.get(k)) for k in keys)]
        values += [r.get(c) for c in (*fixed, *stage_cols)]
        table.append(values)
    return header, table


def write_results(rows: list[dict[str, Any]], keys: list[str], out_dir: Path) -> list[Path]:
    """Write ``results.csv`` (always) and ``results.parquet`` (if pyarrow is importable)."""
    header, table = flatten_rows(rows, keys)
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(header)
    writer.writerows([["" if v is None else v for v in row] for row in table])
    written = [out_dir / "results.csv"]
    write_atomic(written[0], buf.getvalue().encode("utf-8"))
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return written
    columns = {}
    for i, name in enumerate(header):
        col = [row[i] for row in table]
        if any(isinstance(v, str) for v in col) and not all(
            v is None or isinstance(v, str) for v in col
        ):
            col = [None if v is None else str(v) for v in col]
        columns[name] = col
    sink = pa.BufferOutputStream()
    pq.write_table(pa.table(columns), sink)
    written.append(out_dir / "results.parquet")
    write_atomic(written[1], sink.getvalue().to_pybytes())
    return written
