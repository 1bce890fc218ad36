"""The navigation benchmark's tables: ``results.csv`` / ``results.json`` (one row per
episode), ``summary.csv`` and ``table.md`` (one row per scene x method, and per method over
all scenes)."""

from __future__ import annotations

import csv
import io
import json
import math
from pathlib import Path
from typing import Any

from marsscene._atomic import write_atomic
from marsscene.benchmark.nav.metrics import summarise
from marsscene.benchmark.nav.spec import NavSpec

__all__ = ["EPISODE_COLUMNS", "SUMMARY_COLUMNS", "summary_rows", "write_tables"]

EPISODE_COLUMNS = ("scene", "pair", "method", "kind", "status", "distance_m", "shortest_m",
                   "success", "spl", "path_m", "path_ratio", "final_distance_m", "time_s",
                   "slip", "hazard_entries", "hazard_time_s", "max_tilt_deg", "tip_over",
                   "stuck", "plan_calls", "plan_s", "route_m", "time_limit_s", "wall_s",
                   "error")
SUMMARY_COLUMNS = ("scene", "method", "episodes", "failed", "success", "spl", "path_ratio",
                   "time_s", "slip", "hazard_entries", "tip_overs", "stuck", "plan_s")
_HEADS = {"success": "success", "spl": "SPL", "path_ratio": "path / shortest",
          "time_s": "time (s)", "slip": "slip", "hazard_entries": "hazard entries",
          "tip_overs": "tip-overs", "stuck": "stuck", "plan_s": "plan (s/call)",
          "episodes": "episodes", "failed": "failed"}


def summary_rows(rows: list[dict[str, Any]], spec: NavSpec) -> list[dict[str, Any]]:
    """Per scene x method, then per method over all scenes (scene ``all``)."""
    out = []
    for scene in [*(s.name for s in spec.scenes), "all"]:
        for m in spec.methods:
            mine = [r for r in rows if r.get("method") == m.name
                    and (scene == "all" or r.get("scene") == scene)]
            out.append({"scene": scene, "method": m.name, **summarise(mine)})
    return out


def _csv(rows: list[dict[str, Any]], columns: tuple[str, ...]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(columns)
    for r in rows:
        w.writerow(["" if r.get(c) is None else r.get(c) for c in columns])
    return buf.getvalue()


def _cell(v: Any) -> str:
    if isinstance(v, float):
        return "–" if math.isnan(v) else f"{v:.3f}" if abs(v) < 10 else f"{v:.1f}"
    return str(v)


def markdown_table(summary: list[dict[str, Any]]) -> str:
    """The summary as a markdown table."""
    cols = SUMMARY_COLUMNS
    head = "| " + " | ".join(_HEADS.get(c, c) for c in cols) + " |"
    rule = "|" + "|".join("---" for _ in cols) + "|"
    body = ["| " + " | ".join(_cell(r[c]) for c in cols) + " |" for r in summary]
    return "\n".join([head, rule, *body]) + "\n"


def write_tables(rows: list[dict[str, Any]], spec: NavSpec, root: Path) -> list[Path]:
    """Write the episode and summary tables into ``root``; returns the paths."""
    summary = summary_rows(rows, spec)
    slim = [{k: v for k, v in r.items() if k != "path_xy_m"} for r in rows]
    files = [write_atomic(root / "results.csv", _csv(slim, EPISODE_COLUMNS)),
             write_atomic(root / "results.json", json.dumps(
                 {"episodes": slim, "summary": summary}, indent=1, sort_keys=True,
                 default=str) + "\n"),
             write_atomic(root / "summary.csv", _csv(summary, SUMMARY_COLUMNS)),
             write_atomic(root / "table.md", f"# {spec.name}: navigation benchmark\n\n"
                          + markdown_table(summary))]
    return files
