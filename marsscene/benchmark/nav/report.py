"""The navigation benchmark's plots and report: each scene's driven paths over its
ground-truth traversability map, success against start-goal distance, ``report.md``."""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import numpy as np

from marsscene._atomic import write_atomic
from marsscene.benchmark.nav.scenes import load_grids
from marsscene.benchmark.nav.spec import NavSpec
from marsscene.benchmark.nav.table import markdown_table, summary_rows

__all__ = ["write_report"]

_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:purple", "tab:brown", "tab:pink")


def _plt() -> Any:
    from marsscene.errors import missing_dependency

    try:
        import matplotlib  # noqa: TID251  (the report's figures are this module's product)

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt  # noqa: TID251
    except ImportError:
        raise missing_dependency("matplotlib", "bench") from None
    return plt


def plot_paths(rows: list[dict[str, Any]], meta: dict[str, Any], spec: NavSpec, root: Path
               ) -> Path:
    """The scene's driven paths (one colour per method) over its ground-truth cost (grey) and
    hazards (red), starts (circles) and goals (stars)."""
    plt = _plt()
    grid = load_grids(root, meta["name"])["gt"]
    rgb = np.repeat((1.0 - 0.6 * grid.cost)[..., None], 3, axis=2)
    rgb[grid.hazard] = (0.85, 0.25, 0.2)
    rows_, cols_ = grid.shape
    x0, y0 = grid.origin_xy_m
    h = 0.5 * grid.cell_m
    extent = (x0 - h, x0 + (cols_ - 1) * grid.cell_m + h, y0 - h,
              y0 + (rows_ - 1) * grid.cell_m + h)
    fig, ax = plt.subplots(figsize=(7, 7))
    ax.imshow(rgb, origin="lower", extent=extent, interpolation="nearest")
    for k, m in enumerate(spec.methods):
        mine = [r for r in rows if r.get("scene") == meta["name"] and r.get("method") == m.name
                and r.get("path_xy_m")]
        for i, r in enumerate(mine):
            xy = np.asarray(r["path_xy_m"])
            ax.plot(xy[:, 0], xy[:, 1], color=_COLOURS[k % len(_COLOURS)], lw=1.0,
                    label=m.name if i == 0 else None)
    for p in meta["pairs"]:
        ax.plot(*p["start_xy_m"], "o", color="black", ms=4)
        ax.plot(*p["goal_xy_m"], "*", color="black", ms=8)
    ax.set_xlabel("x east (m)")
    ax.set_ylabel("y north (m)")
    ax.set_title(f"{meta['name']}: paths over the ground-truth traversability")
    ax.legend(loc="upper right", fontsize=8)
    out = root / f"paths_{meta['name']}.png"
    fig.savefig(out, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return out


def plot_success(rows: list[dict[str, Any]], spec: NavSpec, root: Path) -> Path:
    """Success rate per method in distance bins (quartiles of the pairs' distances)."""
    plt = _plt()
    d = np.array([float(r["distance_m"]) for r in rows if "distance_m" in r])
    edges = np.unique(np.quantile(d, np.linspace(0, 1, 5))) if d.size else np.array([0, 1.0])
    fig, ax = plt.subplots(figsize=(6, 4))
    mids = 0.5 * (edges[:-1] + edges[1:])
    for k, m in enumerate(spec.methods):
        rate = []
        for lo, hi in itertools.pairwise(edges):
            sel = [r for r in rows if r.get("method") == m.name and "distance_m" in r
                   and lo <= float(r["distance_m"]) <= hi]
            rate.append(np.mean([bool(r.get("success")) for r in sel]) if sel else np.nan)
        ax.plot(mids, rate, "o-", color=_COLOURS[k % len(_COLOURS)], label=m.name)
    ax.set_xlabel("start-goal distance (m)")
    ax.set_ylabel("success rate")
    ax.set_ylim(-0.05, 1.05)
    ax.legend(fontsize=8)
    out = root / "success_vs_distance.png"
    fig.savefig(out, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return out


def write_report(rows: list[dict[str, Any]], scenes: list[dict[str, Any]], spec: NavSpec,
                 root: Path) -> list[Path]:
    """The plots and ``report.md``; returns the paths."""
    files = [plot_paths(rows, meta, spec, root) for meta in scenes]
    files.append(plot_success(rows, spec, root))
    failed = [r for r in rows if r["status"] == "failed"]
    lines = [f"# {spec.name}: planning and navigation benchmark", "",
             f"{len(scenes)} scene(s) x {spec.pairs} pairs ({spec.distance_m[0]:g}-"
             f"{spec.distance_m[1]:g} m, seed {spec.seed}) x {len(spec.methods)} methods: "
             f"{len(rows)} episodes, {len(failed)} failed.", "",
             markdown_table(summary_rows(rows, spec)), "## Scenes", ""]
    for meta in scenes:
        t = meta["timings_s"]
        lines.append(f"- {meta['name']}: hazard share {meta['hazard_fraction_gt']:.3f} "
                     f"(ground truth), {meta['hazard_fraction_orbital']:.3f} (orbital); "
                     f"build {t['build_s']:.1f} s, traversability {t['traversability_s']:.1f}"
                     f" s, orbital {t['orbital_s']:.1f} s, pairs {t['pairs_s']:.1f} s; "
                     f"![paths](paths_{meta['name']}.png)")
    lines += ["", "![success against distance](success_vs_distance.png)", ""]
    if failed:
        lines += ["## Failed episodes", ""]
        lines += [f"- {r['cell_id']}: {r.get('error', '')}" for r in failed]
    files.append(write_atomic(root / "report.md", "\n".join(lines) + "\n"))
    return files
