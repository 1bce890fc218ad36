"""The SLAM benchmark's tables: ``results.csv`` (one row per cell x method) and the paper-style
ATE table in Markdown (scenes x methods, camera methods once per tau, LiDAR / wheel odometry
once per scene; per-row best in bold; ✗ marks a tracking failure)."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path
from typing import Any

from marsscene._atomic import write_atomic
from marsscene.benchmark.slam.spec import SlamSpec

__all__ = ["COLUMNS", "ate_table_markdown", "method_rows", "write_results_csv"]

#: Columns of ``results.csv``.
COLUMNS = ("scene", "tau", "seed", "method", "kind", "status", "ate_rmse_m", "ate_pct_of_path",
           "rpe_trans_m", "rpe_rot_deg", "rpe_distance_m", "tracked_fraction", "poses", "path_m",
           "route_m", "scale", "align", "t_method_s", "note", "cell_id")

FAIL = "✗"


def method_rows(cell_rows: list[dict[str, Any]], spec: SlamSpec) -> list[dict[str, Any]]:
    """One flat row per cell x method (``results.csv``), in cell then method order."""
    out = []
    for cell in cell_rows:
        params = cell.get("params", {})
        route_m = (cell.get("drive") or {}).get("route_m")
        for m in cell.get("methods", ()):
            out.append({"scene": params.get("scene"), "tau": params.get("tau"),
                        "seed": params.get("seed"), "rpe_distance_m": spec.rpe_distance_m,
                        "route_m": route_m, "cell_id": cell.get("cell_id"), **m})
    return out


def write_results_csv(rows: list[dict[str, Any]], path: Path) -> Path:
    """Write ``rows`` with :data:`COLUMNS` (NaN and None as empty cells)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(COLUMNS)
    for r in rows:
        values = [r.get(c) for c in COLUMNS]
        w.writerow(["" if v is None or (isinstance(v, float) and math.isnan(v)) else v
                    for v in values])
    return write_atomic(path, buf.getvalue())


def table_columns(spec: SlamSpec) -> list[tuple[str, float | None]]:
    """(method, tau) per column: camera methods once per tau, the others once (tau None)."""
    cols: list[tuple[str, float | None]] = []
    for m in spec.methods:
        if m.sensor == "camera":
            cols += [(m.name, t) for t in spec.tau]
        else:
            cols.append((m.name, None))
    return cols


def _cell_value(rows: list[dict[str, Any]]) -> tuple[float | None, str]:
    """Mean ATE of the ok seeds and its text: ``mean ± sd`` over several seeds (sample
    standard deviation), ✗ when no seed tracked, '(k ✗)' when some lost."""
    ok = [float(r["ate_rmse_m"]) for r in rows if r.get("status") == "ok"
          and isinstance(r.get("ate_rmse_m"), int | float) and math.isfinite(r["ate_rmse_m"])]
    bad = len(rows) - len(ok)
    if not rows:
        return None, "–"
    if not ok:
        statuses = sorted({str(r.get("status")) for r in rows})
        return None, FAIL if statuses in (["lost"], ["failed"], ["failed", "lost"]) else (
            "n/a (" + "/".join(statuses) + ")")
    mean = sum(ok) / len(ok)
    spread = ""
    if len(ok) > 1:
        sd = math.sqrt(sum((v - mean) ** 2 for v in ok) / (len(ok) - 1))
        spread = f" ± {sd:.2f}"
    return mean, f"{mean:.2f}{spread}" + (f" ({bad} {FAIL})" if bad else "")


def ate_table_markdown(rows: list[dict[str, Any]], spec: SlamSpec) -> str:
    """The paper-style table: ATE RMSE (m) per scene and method (x tau), mean over seeds."""
    cols = table_columns(spec)
    head = ["Scene", "Route (m)"] + [f"{name} τ={tau:g}" if tau is not None else name
                                     for name, tau in cols]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * 2 + "---:|" * len(cols)]
    for scene in spec.scenes:
        mine = [r for r in rows if r["scene"] == scene.name]
        routes = [float(r["route_m"]) for r in mine if isinstance(r.get("route_m"), int | float)
                  and r.get("seed") == spec.seeds[0]]
        cells = []
        for name, tau in cols:
            sel = [r for r in mine if r["method"] == name
                   and (tau is None or math.isclose(float(r["tau"]), tau))]
            cells.append(_cell_value(sel))
        values = [v for v, _ in cells if v is not None]
        best = min(values) if values else None
        texts = [f"**{t}**" if v is not None and v == best and len(values) > 1 else t
                 for v, t in cells]
        route = f"{sum(routes) / len(routes):.0f}" if routes else "–"
        lines.append("| " + " | ".join([scene.name, route, *texts]) + " |")
    seeds = (f"seed {spec.seeds[0]}" if len(spec.seeds) == 1
             else f"mean over seeds {', '.join(str(s) for s in spec.seeds)}")
    more = "; ".join(f"{m.name} over seeds {', '.join(map(str, m.seeds))} (mean ± sd)"
                     for m in spec.methods if m.seeds is not None and m.seeds != spec.seeds)
    lines += ["", f"ATE RMSE in m after Umeyama alignment (SE(3); Sim(3) for "
              f"{', '.join(m.name for m in spec.methods if m.align == 'sim3') or 'none'}), "
              f"{seeds}{'; ' + more if more else ''}; route of seed "
              f"{spec.seeds[0]}. Per-row best in **bold**; {FAIL} = tracking failure "
              "(no usable trajectory or tracked on less than "
              f"{100 * spec.min_tracked_fraction:.0f} % of the frames)."]
    return "\n".join(lines) + "\n"
