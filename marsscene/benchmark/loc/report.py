"""The localization benchmark's pictures and its one-page ``report.md``: per scene,
``cdf_<scene>.png``, the cumulative distribution of the position error of every method (camera
methods per tau), the 1 m and 5 m success radii marked. Matplotlib (Agg) is imported here only,
when a report is written."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from marsscene._atomic import write_atomic
from marsscene.benchmark.loc.spec import LocSpec
from marsscene.benchmark.loc.table import summary_markdown
from marsscene.errors import missing_dependency

__all__ = ["write_report"]


def _plt() -> Any:
    try:
        import matplotlib  # noqa: TID251  (the report's figures are this module's product)

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt  # noqa: TID251
    except ImportError:
        raise missing_dependency("matplotlib", "bench") from None
    return plt


def _cdf(plt: Any, spec: LocSpec, scene: str, rows: list[dict[str, Any]], out: Path) -> Path:
    fig, ax = plt.subplots(figsize=(6.0, 4.0), constrained_layout=True)
    for m in spec.methods:
        for tau in spec.tau if m.sensor == "camera" else spec.tau[:1]:
            sel = [r for r in rows if r["scene"] == scene and r["method"] == m.name
                   and math.isclose(float(r["tau"]), tau)]
            if not sel:
                continue
            err = np.sort([r["position_error_m"] if r.get("status") == "ok" else np.inf
                           for r in sel])
            frac = np.arange(1, len(err) + 1) / len(err)
            label = m.name + (f" τ={tau:g}" if m.sensor == "camera" else "")
            ax.step(np.clip(err, 1e-3, 1e3), frac, where="post", label=label)
    for r_m in (1.0, 5.0):
        ax.axvline(r_m, color="0.6", lw=0.8, ls="--")
    ax.set(xscale="log", xlim=(0.01, 200), ylim=(0, 1), xlabel="position error (m)",
           ylabel="fraction of queries", title=f"{scene}: error CDF")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="lower right", fontsize=8)
    path = out / f"cdf_{scene}.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def write_report(spec: LocSpec, rows: list[dict[str, Any]], cell_rows: list[dict[str, Any]],
                 out: Path) -> list[Path]:
    """``table.md``, one CDF per scene and ``report.md``; returns the files."""
    table = summary_markdown(rows, spec)
    files = [write_atomic(out / "table.md", table)]
    plt = _plt()
    files += [_cdf(plt, spec, s.name, rows, out) for s in spec.scenes]
    cost = [f"- {c['cell_id']}: {c.get('t_cell_s', 0):.0f} s, route "
            f"{c.get('route_m', '–')} m, {c['status']}"
            + (f" ({c['error']})" if c.get("error") else "") for c in cell_rows]
    failed = [r for r in rows if r.get("status") == "failed"]
    notes = sorted({f"{r['method']}: {r.get('note', '')}" for r in failed})[:10]
    text = "\n".join([f"# Localization benchmark: {spec.name}", "", table,
                      *[f"![{s.name}](cdf_{s.name}.png)" for s in spec.scenes], "",
                      "## Cost (wall time per cell)", "", *cost, "",
                      *(["## Failures", "", *[f"- {n}" for n in notes], ""] if notes else [])])
    files.append(write_atomic(out / "report.md", text + "\n"))
    return files
