"""``marsscene benchmark vpr`` and ``vpr-eval``: the paper's place-recognition protocol."""

from __future__ import annotations

import os
import sys
from contextlib import ExitStack
from pathlib import Path
from typing import Any

import click

from marsscene.benchmark.vpr.score import BASELINES
from marsscene.cli._common import user_errors
from marsscene.cli._progress import ProgressBar

__all__ = ["vpr", "vpr_eval"]


@click.command(short_help="Generate a VPR dataset (database + queries traversals, frames every "
               "0.1 m) and score the baseline.")
@click.argument("protocol")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              required=True, help="Dataset folder: database/, queries/, poses.csv, results.")
@click.option("--length-m", type=click.FloatRange(min=5.0), default=None,
              help="Shorten (or lengthen) the automatic route, e.g. 60 for a quick look.")
@click.option("--overwrite", is_flag=True, help="Replace a dataset in --out.")
@click.option("--resume", is_flag=True,
              help="Reuse traversals already finished in --out (same spec).")
@click.option("--no-eval", is_flag=True, help="Only write the dataset.")
@click.option("--baseline", type=click.Choice(BASELINES), default="sift-vlad",
              show_default=True, help="The classical baseline scored after generation.")
@click.option("--workers", type=click.IntRange(1, 2), default=None,
              help="Drive the two traversals in this many processes at once (default: 2 on a "
              "machine with 2 or more cores; the same bytes either way).")
@click.option("--device", default=None, metavar="DEVICE",
              help="Drive both traversals at once on MuJoCo Warp on this Warp device (cuda, "
              "cuda:1, cpu): the batch's physics and camera, a dataset keyed apart.")
def vpr(protocol: str, out_dir: Path, length_m: float | None, overwrite: bool, resume: bool,
        no_eval: bool, baseline: str, workers: int | None, device: str | None) -> None:
    """Generate the VPR dataset of PROTOCOL (`dust`, `day-low-sun`, `day-dim` or a spec TOML)
    into OUT, then score a classical baseline (vpr-eval): VLAD over RootSIFT, or
    patch-normalised thumbnails.

    \b
    Examples:
      marsscene benchmark vpr dust --out vpr/dust
      marsscene benchmark vpr day-dim --out vpr/dim --length-m 60
      marsscene benchmark vpr day-dim --out vpr/dim-gpu --device cuda
    Then any method: marsscene benchmark vpr-eval vpr/dust --descriptors my_descs/
    """
    from marsscene.benchmark.vpr.dataset import generate_vpr
    from marsscene.benchmark.vpr.spec import VprSpec
    from marsscene.cli._progress import DriveMeter

    with user_errors():
        spec = VprSpec.from_toml(protocol)
        if length_m is not None:
            spec = spec.with_length(length_m)
        meters: dict[str, DriveMeter] = {}

        def progress(split: str, p: Any) -> None:
            if split not in meters:
                for m in meters.values():
                    m.close()
                click.echo(f"     vpr: {split} traversal (tau {getattr(spec, split).tau:g}, sun "
                           f"{getattr(spec, split).sun_elevation_deg:g} deg)", err=True)
                meters[split] = DriveMeter()
            meters[split](p)

        if workers is None:
            workers = 2 if (os.cpu_count() or 1) >= 2 else 1
        if device is not None:
            click.echo(f"     vpr: driving the database and the queries traversals at once on "
                       f"{device} (MuJoCo Warp)", err=True)
        elif workers > 1:
            click.echo("     vpr: driving the database and the queries traversals in two "
                       "processes", err=True)
        doc = generate_vpr(spec, out_dir, overwrite=overwrite, resume=resume, workers=workers,
                           device=device, progress=progress)
        for m in meters.values():
            m.close()
    t = doc["traversals"]
    click.echo(f"     vpr: {out_dir}: {t['database']['frames']} database and "
               f"{t['queries']['frames']} query frames along {doc['route_length_m']:.1f} m")
    if not no_eval:
        _evaluate(out_dir, None, (spec.radius_m,), out_dir / "results" / baseline,
                  baseline=baseline)


def _evaluate(dataset: Path, descriptors: Path | None, radii: tuple[float, ...],
              out: Path, method: str | None = None, baseline: str = "sift-vlad") -> None:
    from marsscene.benchmark.vpr.score import evaluate_vpr

    with user_errors(), ExitStack() as stack:
        bar = ProgressBar(stack, f"{baseline} descriptors")
        evaluate_vpr(dataset, descriptors, radii_m=radii, out_dir=out, method=method,
                     baseline=baseline, progress=bar if descriptors is None else None)
    sys.stdout.write((out / "recall.md").read_text(encoding="utf-8"))
    click.echo(f"    eval: {out / 'recall.csv'}, {out / 'recall.md'}, {out / 'pairs.png'}")


@click.command("vpr-eval", short_help="Recall@1/5/10/20 of descriptors on a VPR dataset.")
@click.argument("dataset", type=click.Path(exists=True, file_okay=False, path_type=Path))
@click.option("--descriptors", type=click.Path(exists=True, file_okay=False, path_type=Path),
              default=None, help="database.npy + queries.npy, or <split>/<image>.npy per image "
              "(default: the --baseline).")
@click.option("--baseline", type=click.Choice(BASELINES), default="sift-vlad",
              show_default=True, help="Classical baseline scored without --descriptors.")
@click.option("--radius-m", "radii", type=click.FloatRange(min=0.0, min_open=True),
              multiple=True, default=(2.0,), show_default=True,
              help="Positive radius (repeatable).")
@click.option("--method", default=None, help="Name in the table (default: the folder name).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              default=None, help="Results folder (default: DATASET/results/<method>).")
def vpr_eval(dataset: Path, descriptors: Path | None, baseline: str, radii: tuple[float, ...],
             method: str | None, out_dir: Path | None) -> None:
    """Score place-recognition descriptors on DATASET (from `marsscene benchmark vpr`): a query
    is recognised at N when one of its N nearest database descriptors (L2) lies within the
    radius. Writes recall.csv, recall.md and pairs.png (query / top-1 pairs).

    \b
    Examples:
      marsscene benchmark vpr-eval vpr/dust
      marsscene benchmark vpr-eval vpr/dust --descriptors boq_descs --radius-m 2 --radius-m 5
    """
    name = method or (descriptors.name if descriptors is not None else baseline)
    _evaluate(dataset, descriptors, radii, out_dir or dataset / "results" / name, name,
              baseline=baseline)
