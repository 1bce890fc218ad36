"""``marsscene benchmark vpr`` and ``vpr-eval``: the paper's place-recognition protocol."""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Any

import click

from marsscene.cli._common import user_errors

__all__ = ["vpr", "vpr_eval"]

BASELINES = ("sift-vlad", "patch-normalised")


@click.command(short_help="Generate a VPR dataset (database + queries traversals, frames every "
               "0.1 m) and score the baseline.")
@click.argument("protocol")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              required=True, help="Dataset folder: database/, queries/, poses.csv, results.")
@click.option("--length-m", type=click.FloatRange(min=5.0), default=None,
              help="Shorten (or lengthen) the automatic route, e.g. 40 for a quick look.")
@click.option("--overwrite", is_flag=True, help="Replace a dataset in --out.")
@click.option("--resume", is_flag=True,
              help="Reuse traversals already finished in --out (same spec).")
@click.option("--no-eval", is_flag=True, help="Only write the dataset.")
@click.option("--baseline", type=click.Choice(BASELINES), default="sift-vlad",
              show_default=True, help="The classical baseline scored after generation.")
@click.option("--workers", type=click.IntRange(1, 2), default=None,
              help="Drive the two traversals in this many processes at once (default: 2 on a "
              "machine with 2 or more cores; the same bytes either way).")
def vpr(protocol: str, out_dir: Path, length_m: float | None, overwrite: bool, resume: bool,
        no_eval: bool, baseline: str, workers: int | None) -> None:
    """Generate the VPR dataset of PROTOCOL (`dust`, `day-dark` or a spec TOML) into OUT, then
    score a classical baseline (vpr-eval): VLAD over RootSIFT, or patch-normalised thumbnails.

    \b
    Examples:
      marsscene benchmark vpr dust --out vpr/dust
      marsscene benchmark vpr day-dark --out vpr/daydark --length-m 40
    Then any method: marsscene benchmark vpr-eval vpr/dust --descriptors my_descs/
    """
    from marsscene.benchmark.vpr_dataset import generate_vpr
    from marsscene.benchmark.vpr_spec import load_vpr_spec
    from marsscene.cli._progress import DriveMeter

    with user_errors():
        spec = load_vpr_spec(protocol)
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
        if workers > 1:
            click.echo("     vpr: driving the database and the queries traversals in two "
                       "processes", err=True)
        doc = generate_vpr(spec, out_dir, overwrite=overwrite, resume=resume, workers=workers,
                           progress=progress)
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
    from marsscene.benchmark.vpr_eval import (
        load_descriptors,
        pairs_figure,
        patch_normalised,
        read_split,
        recall_at,
        retrieve,
        write_results,
    )

    with user_errors():
        db, q = read_split(dataset, "database"), read_split(dataset, "queries")
        if descriptors is None:
            n = len(db.files) + len(q.files)
            with click.progressbar(length=n, label=f"{baseline} descriptors ({n} images)",
                                   file=sys.stderr) as bar:
                if baseline == "sift-vlad":
                    from marsscene.benchmark.vpr_vlad import sift_vlad

                    d_db, d_q = sift_vlad(db.files, q.files, tick=lambda: bar.update(1))
                else:
                    d_db, d_q = patch_normalised(db.files), patch_normalised(q.files)
                    bar.update(n)
            name = method or baseline
        else:
            d_db, d_q = load_descriptors(descriptors, db), load_descriptors(descriptors, q)
            name = method or descriptors.name
        ranked = retrieve(d_db, d_q, k=20)
        results = [recall_at(ranked, db.xy_m, q.xy_m, r, name) for r in radii]
        write_results(out, results)
        pairs_figure(out / "pairs.png", db, q, ranked, radii[0],
                     title=f"{dataset.name}: {name}, top-1 within {radii[0]:g} m")
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
