"""``marsscene export``: write a run folder as a SLAM dataset folder (TUM RGB-D, EuRoC)."""

from __future__ import annotations

from pathlib import Path

import click

from marsscene.cli._common import user_errors


@click.command(name="export", short_help="Write a run folder as a TUM RGB-D or EuRoC dataset.")
@click.argument("run_dir", type=click.Path(exists=True, file_okay=False, path_type=Path))
@click.option("--format", "fmt", type=click.Choice(["tum-rgbd", "euroc"]), required=True,
              help="Dataset layout.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              help="Output folder (default: RUN_DIR/tum_rgbd or RUN_DIR/euroc).")
@click.option("--overwrite", is_flag=True, help="Replace an existing output folder.")
def export_cmd(run_dir: Path, fmt: str, out_dir: Path | None, overwrite: bool) -> None:
    """Export RUN_DIR's camera, IMU and ground truth for SLAM stacks that read folders
    (ORB-SLAM3 settings files are written beside the data; see docs/ros.md).

    \b
    Examples:
      marsscene export runs/r1 --format tum-rgbd
      marsscene export runs/r1 --format euroc --out datasets/r1_euroc
    """
    from marsscene.runtime.datasets import export_dataset

    with user_errors():
        out = export_dataset(run_dir, fmt, out_dir, overwrite=overwrite)
    click.echo(f"  {fmt}: {out}")
