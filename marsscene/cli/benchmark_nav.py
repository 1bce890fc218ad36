"""``marsscene benchmark nav``: the planning and navigation benchmark."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from marsscene.cli._common import dask_options, dask_where, user_errors

__all__ = ["nav"]


@click.command(short_help="Seeded start-goal pairs x methods (straight, A* on the ground "
               "truth and the orbital map, arc navigator, yours): drive and score.")
@click.argument("spec_toml", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.argument("out_dir", type=click.Path(file_okay=False, path_type=Path))
@dask_options
@click.option("--resume", is_flag=True,
              help="Continue the benchmark in OUT: built scenes and finished episodes are "
              "reused, failed ones run again.")
def nav(spec_toml: Path, out_dir: Path, workers: int | None, scheduler: str | None,
        serial: bool, resume: bool) -> None:
    """Run the navigation benchmark SPEC_TOML into OUT_DIR.

    Each scene is built with its ground-truth and orbital traversability; its seeded pairs
    (pairs.json) are driven by every method and scored: success, SPL, path length over the
    shortest traversable path, time, slip, hazard entries, tip-over, stuck, planning time.
    A method that fails is a row with its error, not an error.

    \b
    Examples:
      marsscene benchmark nav examples/benchmark/nav-quick.toml bench/nav-quick
      marsscene benchmark nav examples/benchmark/nav-paper.toml bench/nav --workers 8
      marsscene benchmark nav examples/benchmark/nav-paper.toml bench/nav --resume
    """
    from marsscene.benchmark.nav.run import nav_cells, run_nav_benchmark
    from marsscene.benchmark.nav.spec import NavSpec

    where = dask_where(workers, scheduler, serial)

    def show(p: Any) -> None:
        r = p.row
        what = (r.get("error") if r["status"] == "failed" else
                f"{'arrived' if r.get('success') else 'missed'} SPL {r.get('spl', 0):.2f}")
        click.echo(f"[{p.done}/{p.total}] {r['status']} {r['cell_id']}: {what}", err=True)

    with user_errors():
        spec = NavSpec.from_toml(spec_toml)
        click.echo(f"benchmark nav: {len(nav_cells(spec))} episodes {where}", err=True)
        res = run_nav_benchmark(spec, out_dir, workers=workers, scheduler=scheduler,
                                serial=serial, resume=resume, progress=show)
    click.echo(f"episodes: {res.count('ok')} ok, {res.count('failed')} failed")
    for f in res.files:
        click.echo(f"wrote: {f}")
    if res.count("failed"):
        raise SystemExit(1)
