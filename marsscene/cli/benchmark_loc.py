"""``marsscene benchmark loc``: localization against the orbital map (docs/benchmark_loc.md)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from marsscene.cli._common import dask_options, dask_where, user_errors


@click.command(short_help="Localize seeded queries against the orbital map; score methods.")
@click.argument("spec_toml", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.argument("out_dir", type=click.Path(file_okay=False, path_type=Path))
@dask_options
@click.option("--resume", is_flag=True,
              help="Continue the benchmark in OUT_DIR: finished queries and methods are reused.")
def loc(spec_toml: Path, out_dir: Path, workers: int | None, scheduler: str | None,
        serial: bool, resume: bool) -> None:
    """Run the localization benchmark SPEC_TOML into OUT_DIR.

    Each cell (scene x tau) builds its scene and orbital map, drives the rover a few metres
    to each seeded query place with the LiDAR and camera, writes the query folder (map tile,
    local data, prior) and runs every method on it: position and heading error, success
    within 1 m / 2 deg and 5 m / 5 deg, time per query.

    \b
    Examples:
      marsscene benchmark loc examples/benchmark/loc-quick.toml bench/loc-quick
      marsscene benchmark loc examples/benchmark/loc-paper.toml bench/loc --workers 2 --resume
    """
    from marsscene.benchmark.loc.run import loc_cells, run_loc_benchmark
    from marsscene.benchmark.loc.spec import LocSpec

    where = dask_where(workers, scheduler, serial)

    def show(p: Any) -> None:
        row = p.row
        ok = sum(r.get("status") == "ok" for r in row.get("rows", ()))
        click.echo(f"[{p.done}/{p.total}] {row['status']} {row['cell_id']}: {ok}/"
                   f"{len(row.get('rows', ()))} answers {row.get('error') or ''}", err=True)

    with user_errors():
        spec = LocSpec.from_toml(spec_toml)
        click.echo(f"benchmark loc: {len(loc_cells(spec))} cells x {spec.queries} queries x "
                   f"{len(spec.methods)} methods {where}", err=True)
        res = run_loc_benchmark(spec, out_dir, workers=workers, scheduler=scheduler,
                                serial=serial, resume=resume, progress=show)
    click.echo(f"answers: {res.count('ok')} ok, {res.count('lost')} lost, "
               f"{res.count('failed')} failed")
    for f in res.files:
        click.echo(f"wrote: {f}")
    if any(c["status"] == "failed" for c in res.cells):
        raise SystemExit(1)
