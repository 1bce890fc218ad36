"""``run_loc_benchmark``: every cell (scene x tau) of a :class:`LocSpec` on the sweep engine
(:func:`marsscene.sweep.run.map_cells`: serial, LocalCluster or a running Dask scheduler),
then ``results.csv``, ``table.md``, the error CDF plots and ``report.md``.

Output folder::

    benchmark.json     the spec this folder was made with (a resumed run must match it)
    cells/<cell_id>/   one cell (:mod:`marsscene.benchmark.loc.cell`)
    results.csv        one row per cell x query x method
    table.md, cdf_<scene>.png, report.md
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
from marsscene.benchmark.loc.cell import run_loc_cell
from marsscene.benchmark.loc.spec import LocSpec
from marsscene.benchmark.loc.table import flat_rows, write_results_csv
from marsscene.errors import ConfigError
from marsscene.sweep.grid import Cell, cell_id

__all__ = ["SPEC_FILE", "LocBenchmarkResult", "loc_cells", "run_loc_benchmark"]

SPEC_FILE = "benchmark.json"


@dataclass(frozen=True)
class LocBenchmarkResult:
    """Rows per cell x query x method (``results.csv``), rows per cell, the files written."""

    rows: list[dict[str, Any]]
    cells: list[dict[str, Any]]
    files: list[Path] = field(default_factory=list)

    def count(self, status: str) -> int:
        return sum(r.get("status") == status for r in self.rows)


def loc_cells(spec: LocSpec) -> list[Cell]:
    """The cells, scene slowest then tau (ids ``scene=NAME__tau=T``)."""
    cells = []
    for scene in spec.scenes:
        for tau in spec.tau:
            params = {"scene": scene.name, "tau": tau}
            cells.append(Cell(cell_id(params), params, {}, spec.seed))
    return cells


def _claim(root: Path, spec: LocSpec, resume: bool) -> None:
    path = root / SPEC_FILE
    doc = json.loads(json.dumps(spec.doc(), default=str))
    if path.is_file():
        if not resume:
            raise ConfigError(f"{root} already holds a benchmark; pass --resume to continue "
                              "it, or choose another output folder")
        old = json.loads(path.read_text(encoding="utf-8"))
        if old != doc:
            changed = sorted(k for k in doc if doc.get(k) != old.get(k))
            raise ConfigError(f"{root} holds a benchmark of another spec (differs in "
                              f"{', '.join(changed)}); use another output folder")
    root.mkdir(parents=True, exist_ok=True)
    write_atomic(path, json.dumps(doc, indent=1, sort_keys=True) + "\n")


def run_loc_benchmark(spec: LocSpec, out_dir: str | os.PathLike[str], *,
                      workers: int | None = None, scheduler: str | None = None,
                      serial: bool = False, resume: bool = False,
                      progress: Callable[[Any], None] | None = None, report: bool = True
                      ) -> LocBenchmarkResult:
    """Run the benchmark ``spec`` into ``out_dir``.

    ``workers``, ``scheduler``, ``serial`` as for :func:`marsscene.sweep.run_sweep`;
    ``resume`` continues a benchmark already in ``out_dir`` (finished queries and method rows
    are reused); ``report`` also writes ``table.md``, the plots and ``report.md``.
    """
    from marsscene.sweep.run import map_cells

    root = Path(out_dir).resolve()
    _claim(root, spec, resume)
    cells_dir = root / "cells"
    task = partial(run_loc_cell, out_dir=str(cells_dir), spec=spec)
    cell_rows = map_cells(loc_cells(spec), task, cells_dir, workers=workers,
                          scheduler=scheduler, serial=serial, progress=progress)
    rows = flat_rows(cell_rows)
    files = [write_results_csv(rows, root / "results.csv")]
    if report:
        from marsscene.benchmark.loc.report import write_report

        files += write_report(spec, rows, cell_rows, root)
    return LocBenchmarkResult(rows, cell_rows, files)
