"""The localization benchmark's tables: ``results.csv`` (one row per cell x query x method)
and the summary in Markdown (scene x method, camera methods once per tau): median position and
heading error, success within 1 m / 2 deg and within 5 m / 5 deg, median time per query."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path
from typing import Any

import numpy as np

from marsscene._atomic import write_atomic
from marsscene.benchmark.loc.spec import LocSpec

__all__ = ["COLUMNS", "flat_rows", "summary", "summary_markdown", "write_results_csv"]

COLUMNS = ("scene", "tau", "query", "method", "kind", "status", "position_error_m",
           "heading_error_deg", "success_1m_2deg", "success_5m_5deg", "t_query_s",
           "prior_distance_m", "prior_heading_deg", "note", "cell_id")


def flat_rows(cell_rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """One row per cell x query x method, in cell order."""
    out = []
    for cell in cell_rows:
        p = cell.get("params", {})
        out += [{"scene": p.get("scene"), "tau": p.get("tau"), "cell_id": cell.get("cell_id"),
                 **r} for r in cell.get("rows", ())]
    return out


def write_results_csv(rows: list[dict[str, Any]], path: Path) -> Path:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(COLUMNS)
    for r in rows:
        w.writerow(["" if r.get(c) is None or (isinstance(r.get(c), float)
                                               and math.isnan(r[c])) else r.get(c)
                    for c in COLUMNS])
    return write_atomic(path, buf.getvalue())


def summary(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Counts, medians and success rates of one group of rows (failed and lost rows count
    as failures)."""
    ok = [r for r in rows if r.get("status") == "ok"]
    pos = np.array([r["position_error_m"] for r in ok], dtype=np.float64)
    head = np.array([r["heading_error_deg"] for r in ok], dtype=np.float64)
    t = np.array([r["t_query_s"] for r in rows if r.get("t_query_s") is not None])
    n = len(rows)
    return {"n": n, "ok": len(ok),
            "pos_median_m": float(np.median(pos)) if len(pos) else math.nan,
            "head_median_deg": float(np.median(head)) if len(head) else math.nan,
            "success_1m_2deg": sum(bool(r.get("success_1m_2deg")) for r in rows) / max(n, 1),
            "success_5m_5deg": sum(bool(r.get("success_5m_5deg")) for r in rows) / max(n, 1),
            "t_median_s": float(np.median(t)) if len(t) else math.nan}


def _groups(spec: LocSpec) -> list[tuple[str, float]]:
    out = []
    for m in spec.methods:
        out += [(m.name, t) for t in (spec.tau if m.sensor == "camera" else spec.tau[:1])]
    return out


def summary_markdown(rows: list[dict[str, Any]], spec: LocSpec) -> str:
    """The table: one line per scene x method (x tau for camera methods)."""
    lines = ["| Scene | Method | τ | Queries | Position median (m) | Heading median (°) | "
             "≤ 1 m / 2° | ≤ 5 m / 5° | Time / query (ms) |", "|---|---|---:|---:|---:|---:|"
             "---:|---:|---:|"]
    for scene in spec.scenes:
        for name, tau in _groups(spec):
            sel = [r for r in rows if r["scene"] == scene.name and r["method"] == name
                   and math.isclose(float(r["tau"]), tau)]
            if not sel:
                continue
            s = summary(sel)
            lines.append(f"| {scene.name} | {name} | {tau:g} | {s['ok']}/{s['n']} | "
                         f"{s['pos_median_m']:.2f} | {s['head_median_deg']:.2f} | "
                         f"{100 * s['success_1m_2deg']:.0f} % | "
                         f"{100 * s['success_5m_5deg']:.0f} % | {1000 * s['t_median_s']:.0f} |")
    lo, hi = spec.position_error_m
    lines += ["", f"Prior: {lo:g}-{hi:g} m off (uniform distance and direction), heading "
              f"+- {spec.heading_error_deg:g}° (uniform); local map from {spec.scans} "
              f"{spec.lidar_model} scans within {spec.radius_m:g} m; seed {spec.seed}. "
              "Queries: ok/all (failed and lost answers count as failures in the success "
              "rates)."]
    return "\n".join(lines) + "\n"
