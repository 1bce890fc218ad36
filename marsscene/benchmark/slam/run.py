"""``run_slam_benchmark``: every cell (scene x tau x seed) of a :class:`SlamSpec` on the sweep
engine (:func:`marsscene.sweep.run.map_cells`: serial, LocalCluster or a running Dask
scheduler), then ``results.csv``, ``table.md``, the plots and ``report.md``.

Output folder::

    benchmark.json     the spec this folder was made with (a resumed run must match it)
    cells/<cell_id>/   one cell (see :mod:`marsscene.benchmark.slam.cell`)
    cells/results.csv  one row per cell: build and drive (the sweep's table)
    results.csv        one row per cell x method
    table.md, ate_summary.png, traj_<scene>.png, report.md
"""

from __future__ import annotations

import dataclasses
import json
import logging
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

from marsscene._atomic import write_atomic
from marsscene.benchmark.slam.cell import run_slam_cell
from marsscene.benchmark.slam.spec import SlamSpec
from marsscene.benchmark.slam.table import method_rows, write_results_csv
from marsscene.errors import ConfigError
from marsscene.sweep.grid import Cell, cell_id
from marsscene.sweep.spec import set_dotted

log = logging.getLogger("marsscene")

__all__ = ["SPEC_FILE", "SlamBenchmarkResult", "run_slam_benchmark", "slam_cells"]

SPEC_FILE = "benchmark.json"


@dataclass(frozen=True)
class SlamBenchmarkResult:
    """Rows per cell x method (``results.csv``), rows per cell, and the files written."""

    rows: list[dict[str, Any]]
    cells: list[dict[str, Any]]
    files: list[Path] = field(default_factory=list)

    def count(self, status: str) -> int:
        """Method runs with ``status`` (``ok``, ``lost``, ``failed``, ``missing``)."""
        return sum(r["status"] == status for r in self.rows)


def slam_cells(spec: SlamSpec) -> list[Cell]:
    """The cells, scene slowest then tau then seed (ids ``scene=NAME__tau=T__seed=S``)."""
    cells = []
    for scene in spec.scenes:
        base = scene.base_config()
        for tau in spec.tau:
            for seed in spec.all_seeds:
                if not spec.methods_for(tau, seed):
                    continue  # an extra seed of a method that runs in another tau's cell
                params = {"scene": scene.name, "tau": tau, "seed": seed}
                config = set_dotted(set_dotted(base, "lighting.tau", tau), "seed", seed)
                cells.append(Cell(cell_id(params), params, config, seed))
    return cells


def _spec_doc(spec: SlamSpec) -> dict[str, Any]:
    doc = dataclasses.asdict(spec)
    doc.pop("source", None)
    return json.loads(json.dumps(doc, default=str))


def _claim(root: Path, spec: SlamSpec, resume: bool) -> None:
    path = root / SPEC_FILE
    doc = _spec_doc(spec)
    if path.is_file():
        if not resume:
            raise ConfigError(f"{root} already holds a benchmark; pass --resume (resume=True) to "
                              "continue it, or choose another --out folder")
        try:
            old = json.loads(path.read_text(encoding="utf-8"))
        except ValueError:
            old = None
        if old is not None and old != doc:
            changed = sorted(k for k in doc if doc.get(k) != (old or {}).get(k))
            raise ConfigError(f"{root} holds a benchmark of another spec (differs in "
                              f"{', '.join(changed)}); use another --out folder")
    root.mkdir(parents=True, exist_ok=True)
    write_atomic(path, json.dumps(doc, indent=1, sort_keys=True) + "\n")


def run_slam_benchmark(
    spec: SlamSpec,
    out_dir: str | os.PathLike[str],
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    serial: bool = False,
    resume: bool = False,
    progress: Callable[[Any], None] | None = None,
    report: bool = True,
    method_workers: int = 2,
    method_processes: int = 1,
    device: str | None = None,
) -> SlamBenchmarkResult:
    """Run the benchmark ``spec`` into ``out_dir``.

    Parameters
    ----------
    spec : SlamSpec
        From :func:`~marsscene.benchmark.slam.spec.SlamSpec`.
    out_dir : path-like
        Benchmark folder (see the module docstring).
    workers, scheduler, serial
        As for :func:`marsscene.sweep.run_sweep`: LocalCluster worker processes, the address
        of a running Dask scheduler, or no Dask at all.
    resume : bool
        Continue a benchmark already in ``out_dir`` (finished builds, drives and method runs
        are reused; method rows of ``tum-file`` methods are always re-scored). Without it an
        existing benchmark folder is an error.
    progress : callable, optional
        Called with a :class:`marsscene.sweep.run.Progress` after every cell.
    report : bool
        Also write ``table.md``, the plots and ``report.md`` (needs matplotlib).
    method_workers : int
        Threads that run the methods of one cell side by side once its drive is done (a cell
        whose neighbour finished early then uses the idle core; KISS-ICP and ``command``
        methods are separate processes). Rows and files do not depend on it.
    method_processes : int
        Processes that share a method's work where it splits: Open3D RGB-D's frame pairs, in
        chunks (for cores no cell is using, e.g. one long cell on a many-core machine). Rows
        do not depend on it.
    device : str, optional
        Drive the cells as batches on this Warp device (``"cuda"``, ``"cpu"``;
        :mod:`.device`), then run the methods as usual. Without it each cell drives on the CPU.
    """
    from marsscene.sweep.run import map_cells
    from marsscene.sweep.table import write_results

    root = Path(out_dir).resolve()
    _claim(root, spec, resume)
    cells_dir = root / "cells"
    cells = slam_cells(spec)
    if device is not None:
        from marsscene.benchmark.slam.device import drive_cells

        drive_cells(spec, cells, cells_dir, device=device, workers=workers,
                    progress=(lambda msg: log.info("%s", msg)))
    task = partial(run_slam_cell, out_dir=str(cells_dir), spec=spec,
                   method_workers=method_workers, method_processes=method_processes,
                   device=device)
    cell_rows = map_cells(cells, task, cells_dir, workers=workers,
                          scheduler=scheduler, serial=serial, progress=progress)
    for row in cell_rows:  # a cell lost with its worker has no method rows: give them
        if "methods" not in row:
            p = row.get("params", {})
            row["methods"] = [{"method": m.name, "kind": m.kind, "status": "failed",
                               "note": row.get("error", "")}
                              for m in spec.methods_for(float(p["tau"]), int(p["seed"]))]
    files = write_results(cell_rows, ["scene", "tau", "seed"], cells_dir)
    rows = method_rows(cell_rows, spec)
    files.insert(0, write_results_csv(rows, root / "results.csv"))
    if report:
        from marsscene.benchmark.slam.report import write_report

        files += write_report(spec, rows, cell_rows, root)
    return SlamBenchmarkResult(rows, cell_rows, files)
