"""``run_sweep``: run every cell of a sweep serially or on Dask (the one module importing Dask).

Dask runs on a ``distributed.LocalCluster`` (one single-threaded worker process per core) by
default, or on any running scheduler given by address (dask-jobqueue, dask-kubernetes,
dask-gateway ...). Tasks carry only a cell (its parameters and config mapping) and the output
path; workers write their cell folders themselves, so remote workers need the output folder on
a shared filesystem (checked before any cell is submitted).
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

from marsscene.errors import SweepError, missing_dependency
from marsscene.sweep.cell import run_cell
from marsscene.sweep.grid import Cell, expand_grid
from marsscene.sweep.spec import SweepSpec
from marsscene.sweep.table import write_results

__all__ = ["WORKER_ENV", "Progress", "SweepResult", "local_cluster", "map_cells", "run_sweep"]

log = logging.getLogger("marsscene")


@dataclass(frozen=True)
class Progress:
    """Where a sweep stands after a cell finished (passed to the ``progress`` callback)."""

    total: int
    done: int
    running: int
    failed: int
    row: dict[str, Any]
    """The results row of the cell that just finished."""


@dataclass(frozen=True)
class SweepResult:
    """The rows of every cell (grid order) and the results files written."""

    rows: list[dict[str, Any]]
    files: list[Path] = field(default_factory=list)

    def count(self, status: str) -> int:
        """Number of cells with ``status`` (``ok`` / ``failed`` / ``skipped``)."""
        return sum(r["status"] == status for r in self.rows)


def _failed_row(cell: Cell, err: BaseException) -> dict[str, Any]:
    return {"cell_id": cell.cell_id, "params": dict(cell.params), "status": "failed",
            "error": " ".join(f"{type(err).__name__}: {err}".split())}


#: Environment of LocalCluster worker processes (glibc reads it when a process starts). Dask's
#: default ``MALLOC_TRIM_THRESHOLD_=65536`` also pins glibc's mmap threshold at 128 KiB, so every
#: numpy temporary above it is a fresh ``mmap`` that the kernel zero-fills page by page: in
#: ``bench_sweep`` a 200 m cell then took ~185 000 page faults and +0.35-0.45 s of kernel time,
#: ~50 % more CPU time than in a plain process. These two values are the limits glibc's own
#: adaptive thresholds reach in a plain Python process (mmap above 32 MiB, trim above 64 MiB),
#: fixed from the first cell on. Variables already in this process's environment win (Dask's
#: rule), and the environment is left as it was found.
WORKER_ENV = {"MALLOC_MMAP_THRESHOLD_": str(32 << 20), "MALLOC_TRIM_THRESHOLD_": str(64 << 20)}


def local_cluster(n_workers: int) -> Any:
    """A ``distributed.LocalCluster`` set up for sweep cells (what ``run_sweep`` starts).

    One single-threaded worker process per core, :data:`WORKER_ENV` in the workers'
    environment, Dask's statistical profiler off (its 10 ms stack sampling cost ~8 % of cell
    time in ``bench_sweep``) and one task per worker at a time, so that the last cells go to
    whichever worker frees first instead of queueing behind a busy one.
    """
    try:
        import dask
        from distributed import LocalCluster
    except ImportError:
        raise missing_dependency("distributed", "sweep") from None
    env = {**dask.config.get("distributed.nanny.pre-spawn-environ", {}), **WORKER_ENV}
    settings = {"distributed.worker.profile.enabled": False,
                "distributed.nanny.pre-spawn-environ": env,
                "distributed.scheduler.worker-saturation": 1.0}
    before = {k: os.environ.get(k) for k in env}
    try:
        with dask.config.set(settings):
            return LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                                dashboard_address=None, silence_logs=logging.ERROR)
    except RuntimeError as err:
        raise SweepError(
            f"cannot start a LocalCluster of {n_workers} worker processes ({err}); a script "
            "that calls run_sweep needs an `if __name__ == \"__main__\":` guard (workers are "
            "spawned)"
        ) from None
    finally:  # the nannies set the workers' variables in this process's environment: undo
        for key, value in before.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


def _client(workers: int | None, scheduler: str | None, timeout_s: float) -> tuple[Any, Any]:
    try:
        from distributed import Client
    except ImportError:
        raise missing_dependency("distributed", "sweep") from None
    if scheduler is not None:
        try:
            return Client(scheduler, timeout=f"{timeout_s}s"), None
        except (OSError, TimeoutError) as err:
            raise SweepError(f"cannot reach Dask scheduler {scheduler!r}: {err}") from None
    cluster = local_cluster(workers if workers is not None else max(1, os.cpu_count() or 1))
    return Client(cluster), cluster


def _worker_facts(root: str) -> tuple[bool, str | None]:
    return os.path.isdir(root), os.environ.get("MALLOC_TRIM_THRESHOLD_")


def _check_workers(client: Any, root: Path) -> None:
    facts = client.run(_worker_facts, str(root))
    blind = sorted(w for w, (seen, _) in facts.items() if not seen)
    if blind:
        raise SweepError(
            f"{len(blind)} Dask worker(s) (e.g. {blind[0]}) cannot see {root}; remote workers "
            "need the output folder on a shared filesystem at the same path"
        )
    small = sorted(w for w, (_, trim) in facts.items()
                   if trim is not None and trim.isdigit() and int(trim) < 1 << 20)
    if small:
        env = " ".join(f"{k}={v}" for k, v in WORKER_ENV.items())
        log.warning("%d Dask worker(s) (e.g. %s) run with MALLOC_TRIM_THRESHOLD_=%s (Dask's "
                    "default): numpy temporaries are re-faulted every time and cells take up "
                    "to ~50%% more CPU; start the workers with %s (docs/sweep.md)",
                    len(small), small[0], facts[small[0]][1], env)


def _seed_affinity(cells: list[Cell], addresses: list[str]) -> dict[str, list[str]]:
    """A preferred worker per cell: cells of one seed go to one worker (seed groups dealt out
    in turn), so the work that depends on the seed alone (the regolith textures) is done once
    per worker and seed, not by every worker. Loose: Dask still balances the load."""
    if not addresses:
        return {c.cell_id: [] for c in cells}
    groups = {seed: i for i, seed in enumerate(dict.fromkeys(c.seed for c in cells))}
    return {c.cell_id: [addresses[groups[c.seed] % len(addresses)]] for c in cells}


def _run_dask(cells: list[Cell], root: Path, task: Callable[[Cell], dict[str, Any]],
              workers: int | None, scheduler: str | None, timeout_s: float,
              report: Callable[[dict[str, Any]], None], counts: dict[str, int]
              ) -> dict[str, dict[str, Any]]:
    from distributed import as_completed

    client, cluster = _client(workers, scheduler, timeout_s)
    rows: dict[str, dict[str, Any]] = {}
    try:
        _check_workers(client, root)
        counts["capacity"] = max(1, sum(client.nthreads().values()))
        prefer = _seed_affinity(cells, sorted(client.nthreads()))
        futures = {
            client.submit(task, c, pure=False,
                          key=f"marsscene-cell-{c.cell_id}-{os.urandom(4).hex()}",
                          workers=prefer[c.cell_id], allow_other_workers=True): c
            for c in cells
        }
        for fut in as_completed(futures):
            cell = futures[fut]
            try:
                row = fut.result()
            except Exception as err:  # a lost worker or an unpicklable result
                row = _failed_row(cell, err)
            rows[cell.cell_id] = row
            report(row)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    return rows


def run_sweep(
    spec: SweepSpec,
    out_dir: str | os.PathLike[str],
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    serial: bool = False,
    force: bool = False,
    progress: Callable[[Progress], None] | None = None,
    connect_timeout_s: float = 10.0,
) -> SweepResult:
    """Build (and drive) every cell of ``spec`` into ``out_dir`` and write the results table.

    Parameters
    ----------
    spec : SweepSpec
        From :func:`~marsscene.sweep.SweepSpec`.
    out_dir : path-like
        Sweep folder: one sub-folder per cell plus ``results.csv`` (+ ``results.parquet``).
    workers : int, optional
        Worker processes of the LocalCluster (default: one per CPU core).
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://host:8786``) instead of a LocalCluster.
    serial : bool
        Run in this process, without Dask (same bytes; for debugging and comparisons).
    force : bool
        Rebuild cells that are already finished.
    progress : callable, optional
        Called with a :class:`Progress` after every cell.
    connect_timeout_s : float
        How long to try reaching ``scheduler`` before giving up (in s).

    Returns
    -------
    SweepResult
        Rows in grid order; a failed cell has ``status == "failed"`` and its ``error``.
    """
    cells = expand_grid(spec)
    root = Path(out_dir).resolve()
    task = partial(run_cell, out_dir=str(root), drive=spec.drive, force=force)
    ordered = map_cells(cells, task, root, workers=workers, scheduler=scheduler, serial=serial,
                        progress=progress, connect_timeout_s=connect_timeout_s)
    files = write_results(ordered, [k for k, _ in spec.axes], root)
    return SweepResult(ordered, files)


def map_cells(
    cells: list[Cell],
    task: Callable[[Cell], dict[str, Any]],
    out_dir: str | os.PathLike[str],
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    serial: bool = False,
    progress: Callable[[Progress], None] | None = None,
    connect_timeout_s: float = 10.0,
) -> list[dict[str, Any]]:
    """Run ``task(cell)`` for every cell, serially or on Dask, and return the rows in order.

    The engine under :func:`run_sweep`, for protocols whose cells do more than build and
    drive (``marsscene.benchmark``): ``task`` must be picklable (a module-level function or a
    ``functools.partial`` of one), write into ``out_dir`` and return a row dict with
    ``cell_id`` and ``status``. Parameters as for :func:`run_sweep`; a task that raises (or a
    lost worker) gives a ``failed`` row.
    """
    if scheduler is not None and (workers is not None or serial):
        raise SweepError("give at most one of workers / serial and scheduler")
    if workers is not None and workers < 1:
        raise SweepError(f"workers = {workers!r}; must be >= 1")
    root = Path(out_dir).resolve()
    root.mkdir(parents=True, exist_ok=True)
    total = len(cells)
    counts = {"done": 0, "failed": 0, "capacity": 1 if serial else (workers or os.cpu_count() or 1)}

    def report(row: dict[str, Any]) -> None:
        counts["done"] += 1
        counts["failed"] += row["status"] == "failed"
        if progress is not None:
            running = min(counts["capacity"], total - counts["done"])
            progress(Progress(total, counts["done"], running, counts["failed"], row))

    if serial:
        rows = {}
        for c in cells:
            try:
                rows[c.cell_id] = task(c)
            except Exception as err:  # a task that broke its promise not to raise
                rows[c.cell_id] = _failed_row(c, err)
            report(rows[c.cell_id])
    else:
        rows = _run_dask(cells, root, task, workers, scheduler, connect_timeout_s, report,
                         counts)
    return [rows[c.cell_id] for c in cells]
