"""``marsscene sweep``: build (and drive) a grid of scene variants on Dask or serially."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from marsscene.cli._common import dask_options, dask_where, user_errors


@click.command(short_help="Run a grid of scene variants (seeds x tau x sun x rocks) on Dask.")
@click.argument("sweep_toml", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              required=True, help="Sweep folder: one sub-folder per cell + results.csv.")
@dask_options
@click.option("--force", is_flag=True, help="Rebuild cells that are already finished.")
def sweep(sweep_toml: Path, out_dir: Path, workers: int | None, scheduler: str | None,
          serial: bool, force: bool) -> None:
    """Build every cell of SWEEP_TOML into OUT/<cell_id>/ and write OUT/results.csv.

    SWEEP_TOML is a scene config plus a [sweep] table of dotted keys mapped to lists (their
    Cartesian product is the grid) and an optional [drive] table (each cell is then driven and
    its odometry evaluated). Finished cells are skipped on a re-run; a failing cell is recorded
    and the others go on.

    \b
    Examples:
      marsscene sweep sweep.toml --out sweeps/tau --workers 2
      marsscene sweep sweep.toml --out /shared/sweeps/tau --scheduler tcp://head:8786
    """
    from marsscene.sweep import SweepSpec, expand_grid, run_sweep

    where = dask_where(workers, scheduler, serial)

    def show(p: Any) -> None:
        row = p.row
        mark = {"ok": "ok", "skipped": "skipped", "failed": "FAILED"}[row["status"]]
        extra = f": {row['error']}" if row["status"] == "failed" else (
            f" ({row['t_total_s']:.1f} s)" if row["status"] == "ok" else "")
        click.echo(f"[{p.done}/{p.total}] {mark} {row['cell_id']}{extra}  "
                   f"(done {p.done}, running {p.running}, failed {p.failed})", err=True)

    with user_errors():
        spec = SweepSpec.from_toml(sweep_toml)
        n = len(expand_grid(spec))
        click.echo(f"sweep: {n} cells {where}", err=True)
        res = run_sweep(spec, out_dir, workers=workers, scheduler=scheduler, serial=serial,
                        force=force, progress=show)
    click.echo(f"cells: {res.count('ok')} ok, {res.count('skipped')} skipped, "
               f"{res.count('failed')} failed")
    for f in res.files:
        click.echo(f"results: {f}")
    if res.count("failed"):
        raise SystemExit(1)
