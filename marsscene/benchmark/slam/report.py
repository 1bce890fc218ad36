"""The SLAM benchmark's pictures and its one-page ``report.md``.

Per scene, ``traj_<scene>.png``: top-down ground truth and every method's trajectory after its
alignment, one panel per tau (first seed; side by side, or stacked for a long thin route);
``ate_summary.png``: ATE per scene and method (log scale, ✗ for failures). Matplotlib (Agg)
is imported here only, when a report is written: this is the one library module that draws,
because the figures are this command's product.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from marsscene._atomic import write_atomic
from marsscene.benchmark.slam.methods import CellData
from marsscene.benchmark.slam.metrics import aligned_xyz
from marsscene.benchmark.slam.spec import SlamSpec
from marsscene.benchmark.slam.table import FAIL, ate_table_markdown, table_columns
from marsscene.errors import MarsSceneError, missing_dependency
from marsscene.runs.tum import read_tum

__all__ = ["cost_lines", "write_report"]

_COLORS = ("#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2",
           "#17becf", "#bcbd22", "#7f7f7f")


def _plt() -> Any:
    try:
        import matplotlib  # noqa: TID251  (the report's figures are this module's product)

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt  # noqa: TID251
    except ImportError:
        raise missing_dependency("matplotlib", "bench") from None
    return plt


_Panel = tuple[float, list[dict[str, Any]], CellData | None, Any]


def _ground_truths(spec: SlamSpec, scene: str, rows: list[dict[str, Any]],
                   cells_dir: Path) -> list[_Panel]:
    """Per tau (first seed): the scene's rows, its cell and its ground truth (None: unreadable)."""
    seed = spec.seeds[0]
    panels = []
    for tau in spec.tau:
        mine = [r for r in rows if r["scene"] == scene and r["seed"] == seed
                and math.isclose(float(r["tau"]), tau)]
        cell, gt = None, None
        if mine:
            cell = CellData(cells_dir / str(mine[0]["cell_id"]), scene, tau, seed)
            try:
                gt = read_tum(cell.run_dir / "gt.tum")
            except (MarsSceneError, OSError):
                gt = None
        panels.append((tau, mine, cell, gt))
    return panels


def _panel_grid(plt: Any, n: int, extents_m: list[Any]) -> tuple[Any, Any, bool]:
    """Side-by-side panels, or stacked wide ones for a long thin route (an out-and-back)."""
    span = np.ptp(np.concatenate(extents_m), axis=0) if extents_m else np.ones(2)
    aspect = float(span[0] / max(span[1], 1.0))  # east extent / north extent
    if aspect <= 2.5:
        fig, axes = plt.subplots(1, n, figsize=(5.2 * n, 5.0), squeeze=False,
                                 constrained_layout=True)
        return fig, axes[0], False
    panel_h = float(np.clip(9.0 / aspect + 1.3, 2.4, 5.0))
    fig, axes = plt.subplots(n, 1, figsize=(12.0, panel_h * n), squeeze=False,
                             constrained_layout=True)
    return fig, axes[:, 0], True


def _trajectory_figure(plt: Any, spec: SlamSpec, scene: str, rows: list[dict[str, Any]],
                       cells_dir: Path, out: Path) -> Path | None:
    seed = spec.seeds[0]
    colors = {m.name: _COLORS[i % len(_COLORS)] for i, m in enumerate(spec.methods)}
    panels = _ground_truths(spec, scene, rows, cells_dir)
    if all(gt is None for *_, gt in panels):
        return None
    fig, axes, stacked = _panel_grid(plt, len(panels),
                                     [gt.xyz_m[:, :2] for *_, gt in panels if gt is not None])
    for ax, (tau, mine, cell, gt) in zip(axes, panels, strict=True):
        ax.set_title(f"{scene}  τ = {tau:g}  (seed {seed})", fontsize=10)
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(alpha=0.3)
        ax.set_xlabel("x east (m)")
        ax.set_ylabel("y north (m)")
        if gt is None or cell is None:
            continue
        ax.plot(gt.xyz_m[:, 0], gt.xyz_m[:, 1], color="k", lw=2.4, label="ground truth",
                zorder=1)
        ax.plot(*gt.xyz_m[0, :2], marker="*", ms=14, color="#2ca02c", mec="w", zorder=5)
        for r in mine:
            path = cell.cell_dir / "estimates" / f"{r['method']}.tum"
            if not path.is_file():
                continue
            try:
                est = read_tum(path)
                xyz = aligned_xyz(est, cell.ground_truth(str(_frame(spec, r["method"]))),
                                  align=str(r.get("align", "se3")))
            except (MarsSceneError, OSError):
                continue
            ate = r.get("ate_rmse_m")
            lost = r.get("status") != "ok"
            label = (f"{r['method']}  {ate:.2f} m" if isinstance(ate, float)
                     and math.isfinite(ate) else str(r["method"])) + (f"  {FAIL}" if lost else "")
            ax.plot(xyz[:, 0], xyz[:, 1], color=colors.get(r["method"], "0.5"), lw=1.3,
                    ls="--" if lost else "-", label=label, zorder=2)
        if stacked:  # beside the panel: inside, it would hide a thin route
            ax.legend(fontsize=8, loc="center left", bbox_to_anchor=(1.01, 0.5),
                      framealpha=0.85)
        else:
            ax.legend(fontsize=8, loc="best", framealpha=0.85)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def _frame(spec: SlamSpec, method: str) -> str:
    return str(next(m.frame for m in spec.methods if m.name == method))


def _summary_figure(plt: Any, spec: SlamSpec, rows: list[dict[str, Any]], out: Path) -> Path:
    cols = table_columns(spec)
    fig, ax = plt.subplots(figsize=(max(6.0, 1.5 + 0.4 * len(cols) * len(spec.scenes)), 4.2),
                           constrained_layout=True)
    width = 0.8 / max(len(cols), 1)
    colors = {m.name: _COLORS[i % len(_COLORS)] for i, m in enumerate(spec.methods)}
    for j, (name, tau) in enumerate(cols):
        for i, scene in enumerate(spec.scenes):
            sel = [r for r in rows if r["scene"] == scene.name and r["method"] == name
                   and (tau is None or math.isclose(float(r["tau"]), tau))]
            ok = [r["ate_rmse_m"] for r in sel if r.get("status") == "ok"]
            x = i + (j - (len(cols) - 1) / 2) * width
            if ok:
                ax.bar(x, float(np.mean(ok)), width * 0.92, color=colors[name],
                       alpha=1.0 if tau in (None, spec.tau[0]) else 0.55,
                       hatch="" if tau in (None, spec.tau[0]) else "//", edgecolor="w")
            elif any(r.get("status") in ("lost", "failed") for r in sel):
                ax.text(x, 0.0, FAIL, ha="center", va="bottom", color=colors[name],
                        fontsize=12, transform=ax.get_xaxis_transform())
    for name, tau in cols:
        faded = tau not in (None, spec.tau[0])
        ax.bar(np.nan, np.nan, color=colors[name], alpha=0.55 if faded else 1.0,
               hatch="//" if faded else "", edgecolor="w",
               label=name if tau is None else f"{name} τ={tau:g}")
    ax.set_yscale("log")
    ax.set_xticks(range(len(spec.scenes)), [s.name for s in spec.scenes])
    ax.set_ylabel("ATE RMSE (m, log)")
    ax.grid(axis="y", alpha=0.3, which="both")
    ax.set_title(f"ATE RMSE per scene and method ({FAIL} = tracking failure)", fontsize=10)
    ax.legend(fontsize=8, ncol=min(4, len(cols)), loc="upper center",
              bbox_to_anchor=(0.5, -0.1), frameon=False)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def _fmt(v: Any, spec: str = ".2f") -> str:
    return format(v, spec) if isinstance(v, int | float) and math.isfinite(v) else "–"


def _seconds(v: Any) -> float:
    return float(v) if isinstance(v, int | float) and math.isfinite(v) else 0.0


def cost_lines(rows: list[dict[str, Any]], cell_rows: list[dict[str, Any]]) -> list[str]:
    """The report's ``## Cost`` section: each cell's stage times as stored with it (a resumed
    cell keeps the times of the run that made it), and their sum over the benchmark."""
    lines = ["## Cost", "",
             "Each stage's own wall time, as stored with the cell (a resumed cell keeps the "
             "times of the run that made it). The live LiDAR odometry registers each scan "
             "during the drive, so its time is part of the drive's; the exports (TUM RGB-D, "
             "EuRoC, bag) are in no column. A cell's methods run side by side on "
             "`--method-workers` threads, so stage time is work done, not the time a cell "
             "took.", "",
             "| cell | build (s) | drive (s) | of which live LiDAR (s) | methods (s) | "
             "stage time (h) |",
             "|---|---:|---:|---:|---:|---:|"]
    total_s = 0.0
    for c in cell_rows:
        p = c.get("params", {})
        build_s = _seconds(c.get("t_total_s"))
        drive_s = _seconds(c.get("t_drive_s"))
        live_s = sum(_seconds(v) for v in (c.get("drive") or {}).get("t_live_s", {}).values())
        method_s = sum(_seconds(r.get("t_method_s")) for r in rows
                       if r.get("cell_id") == c["cell_id"])
        cell_s = build_s + drive_s + method_s
        total_s += cell_s
        lines.append(f"| {p.get('scene')} τ {_fmt(p.get('tau'), 'g')} seed {p.get('seed')} | "
                     f"{build_s:,.0f} | {drive_s:,.0f} | {live_s:,.0f} | {method_s:,.0f} | "
                     f"{cell_s / 3600:.2f} |")
    lines += ["", f"{len(cell_rows)} cells: {total_s / 3600:.2f} h of stage time (build, "
              "drive and methods).", ""]
    return lines


def write_report(spec: SlamSpec, rows: list[dict[str, Any]], cell_rows: list[dict[str, Any]],
                 out_dir: Path) -> list[Path]:
    """Write ``table.md``, ``ate_summary.png``, ``traj_<scene>.png`` and ``report.md``."""
    plt = _plt()
    cells_dir = out_dir / "cells"
    table = ate_table_markdown(rows, spec)
    written = [out_dir / "table.md"]
    write_atomic(written[0], f"# {spec.name}: ATE RMSE (m)\n\n" + table)
    summary = _summary_figure(plt, spec, rows, out_dir / "ate_summary.png")
    written.append(summary)
    lines = [f"# SLAM benchmark `{spec.name}`", "",
             f"Scenes {', '.join(s.name for s in spec.scenes)} × τ "
             f"{', '.join(f'{t:g}' for t in spec.tau)} × seeds {', '.join(map(str, spec.seeds))}: "
             f"{len(cell_rows)} cells, {len(spec.methods)} methods; "
             f"{sum(r['status'] == 'ok' for r in rows)} of {len(rows)} runs tracked.",
             "", table, f"![ATE per scene and method]({summary.name})", ""]
    for scene in spec.scenes:
        fig = _trajectory_figure(plt, spec, scene.name, rows, cells_dir,
                                 out_dir / f"traj_{scene.name}.png")
        mine = [r for r in rows if r["scene"] == scene.name]
        route = next((r["route_m"] for r in mine if r.get("route_m")), None)
        shape = scene.route.shape or ("waypoints" if scene.route.waypoints else "route file")
        lines += [f"## {scene.name}", "",
                  f"Route: {_fmt(route, '.0f')} m ({shape}); ★ start, black ground truth."]
        if fig is not None:
            written.append(fig)
            lines += ["", f"![{scene.name} trajectories]({fig.name})"]
        lines += ["", "| method | τ | seed | status | ATE (m) | % of path | RPE/"
                  f"{spec.rpe_distance_m:g} m (m, deg) | tracked | note |",
                  "|---|---:|---:|---|---:|---:|---:|---:|---|"]
        for r in mine:
            note = str(r.get("note") or "").replace("|", "/")[:120]
            lines.append(
                f"| {r['method']} | {_fmt(r['tau'], 'g')} | {r['seed']} | {r['status']} | "
                f"{_fmt(r.get('ate_rmse_m'))} | {_fmt(r.get('ate_pct_of_path'))} | "
                f"{_fmt(r.get('rpe_trans_m'))}, {_fmt(r.get('rpe_rot_deg'))} | "
                f"{_fmt(100 * float(r.get('tracked_fraction') or 0.0), '.0f')} % | {note} |")
        lines.append("")
    failed = [c for c in cell_rows if c.get("status") == "failed"]
    if failed:
        lines += ["## Failed cells", ""] + [f"* `{c['cell_id']}`: {c.get('error')}"
                                             for c in failed] + [""]
    lines += cost_lines(rows, cell_rows)
    lines += ["Rows: `results.csv`; cells: `cells/<cell_id>/` (scene, drive with TUM RGB-D / "
              "EuRoC exports, estimates); see docs/benchmark.md.", ""]
    report = out_dir / "report.md"
    write_atomic(report, "\n".join(lines))
    return [*written, report]
