"""``marsscene export``: write a run folder as a SLAM dataset folder (TUM RGB-D, EuRoC)."""

from __future__ import annotations

import sys
from contextlib import ExitStack
from pathlib import Path
from typing import Any

import click

from marsscene.cli._common import user_errors
from marsscene.runs.export.options import DATASET_IMAGES, DATASET_IMAGES_HELP, ExportOptions


@click.command(name="export", short_help="Write a run folder as a TUM RGB-D or EuRoC dataset.")
@click.argument("run_dir", type=click.Path(exists=True, file_okay=False, path_type=Path))
@click.option("--format", "fmt", type=click.Choice(["tum-rgbd", "euroc"]), required=True,
              help="Dataset layout.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              help="Output folder (default: RUN_DIR/tum_rgbd or RUN_DIR/euroc).")
@click.option("--overwrite", is_flag=True, help="Replace an existing output folder.")
@click.option("--images", type=click.Choice(DATASET_IMAGES),
              default=ExportOptions().dataset_images,
              show_default=True, help=DATASET_IMAGES_HELP)
def export_cmd(run_dir: Path, fmt: str, out_dir: Path | None, overwrite: bool,
               images: str) -> None:
    """Export RUN_DIR's camera, IMU and ground truth for SLAM stacks that read folders
    (ORB-SLAM3 settings files are written beside the data; see docs/ros.md).

    \b
    Examples:
      marsscene export runs/r1 --format tum-rgbd
      marsscene export runs/r1 --format euroc --out datasets/r1_euroc
      marsscene export runs/r1 --format tum-rgbd --images convert   # depth at 5000 per m
    """
    from marsscene.runs.export.datasets import export_dataset

    with user_errors(), ExitStack() as stack:
        bars: list[Any] = []

        def progress(done: int, total: int) -> None:  # the bar starts once the input is valid
            if not bars:
                bars.append(stack.enter_context(click.progressbar(
                    length=total, label=f"writing {fmt} (images)", file=sys.stderr)))
            bars[0].update(1)

        out = export_dataset(run_dir, fmt, out_dir, overwrite=overwrite, progress=progress,
                             images=images)
    click.echo(f"  {fmt}: {out}")
