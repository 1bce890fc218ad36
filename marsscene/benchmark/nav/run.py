"""``run_nav_benchmark``: every episode (scene x pair x method) of a :class:`NavSpec` on the
sweep engine (:func:`marsscene.sweep.run.map_cells`: serial, LocalCluster or a running Dask
scheduler), then the tables, plots and report.

Output folder::

    benchmark.json        the spec this folder was made with (a resumed run must match it)
    pairs.json            the fixed start-goal pairs of every scene (seeded by the spec)
    scenes/<name>/        the built scene, its planning grids, scene.json
    episodes/<id>.json    one row per episode (ids ``scene=S__pair=P__method=M``)
    results.csv, results.json, summary.csv, table.md
    paths_<scene>.png, success_vs_distance.png, report.md
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

from marsscene._atomic import write_atomic
from marsscene.benchmark.nav.episode import run_episode
from marsscene.benchmark.nav.scenes import prepare_scene
from marsscene.benchmark.nav.spec import NavSpec
from marsscene.errors import ConfigError
from marsscene.sweep.grid import Cell, cell_id

__all__ = ["SPEC_FILE", "NavBenchmarkResult", "nav_cells", "run_nav_benchmark"]

SPEC_FILE = "benchmark.json"


@dataclass(frozen=True)
class NavBenchmarkResult:
    """One row per episode, the scenes' metadata and the files written."""

    rows: list[dict[str, Any]]
    scenes: list[dict[str, Any]]
    files: list[Path] = field(default_factory=list)

    def count(self, status: str) -> int:
        return sum(r["status"] == status for r in self.rows)


def nav_cells(spec: NavSpec) -> list[Cell]:
    """The episodes, scene slowest, then pair, then method."""
    cells = []
    for scene in spec.scenes:
        for pair in range(spec.pairs):
            for m in spec.methods:
                params = {"scene": scene.name, "pair": pair, "method": m.name}
                cells.append(Cell(cell_id(params), params, {}, spec.seed))
    return cells


def _claim(root: Path, spec: NavSpec, resume: bool) -> None:
    path = root / SPEC_FILE
    doc = spec.doc()
    if path.is_file():
        if not resume:
            raise ConfigError(f"{root} already holds a benchmark; pass --resume to continue "
                              "it, or choose another OUT folder")
        try:
            old = json.loads(path.read_text(encoding="utf-8"))
        except ValueError:
            old = None
        if old is not None and old != doc:
            changed = sorted(k for k in doc if doc.get(k) != old.get(k))
            raise ConfigError(f"{root} holds a benchmark of another spec (differs in "
                              f"{', '.join(changed)}); use another OUT folder")
    root.mkdir(parents=True, exist_ok=True)
    write_atomic(path, json.dumps(doc, indent=1, sort_keys=True) + "\n")


def run_nav_benchmark(
    spec: NavSpec,
    out_dir: str | os.PathLike[str],
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    serial: bool = False,
    resume: bool = False,
    progress: Callable[[Any], None] | None = None,
    report: bool = True,
) -> NavBenchmarkResult:
    """Run the navigation benchmark ``spec`` into ``out_dir``.

    Parameters
    ----------
    spec : NavSpec
    out_dir : path-like
        Benchmark folder (see the module docstring).
    workers, scheduler, serial
        As for :func:`marsscene.sweep.run_sweep` (the scenes are built first, in this
        process; the episodes then run on the workers).
    resume : bool
        Continue a benchmark in ``out_dir``: built scenes and ``ok`` episodes are reused,
        failed ones run again.
    progress : callable, optional
        Called with a :class:`marsscene.sweep.run.Progress` after every episode.
    report : bool
        Also write ``table.md``, the plots and ``report.md`` (needs matplotlib).
    """
    from marsscene.benchmark.nav.table import write_tables
    from marsscene.sweep.run import map_cells

    root = Path(out_dir).resolve()
    _claim(root, spec, resume)
    scenes = [prepare_scene(s, spec, root) for s in spec.scenes]
    pairs = {m["name"]: m["pairs"] for m in scenes}
    write_atomic(root / "pairs.json", json.dumps(
        {"seed": spec.seed, "distance_m": list(spec.distance_m), "scenes": pairs},
        indent=1, sort_keys=True) + "\n")
    (root / "episodes").mkdir(exist_ok=True)
    task = partial(run_episode, root=str(root), spec=spec)
    rows = map_cells(nav_cells(spec), task, root / "episodes", workers=workers,
                     scheduler=scheduler, serial=serial, progress=progress)
    for row in rows:  # a row lost with its worker
        row.setdefault("method", row.get("params", {}).get("method"))
        row.setdefault("scene", row.get("params", {}).get("scene"))
    files = write_tables(rows, spec, root)
    if report:
        from marsscene.benchmark.nav.report import write_report

        files += write_report(rows, scenes, spec, root)
    return NavBenchmarkResult(rows, scenes, files)
