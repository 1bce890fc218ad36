"""``marsscene bag``: write a run folder as a ROS 2 bag (rosbag2: MCAP or sqlite3 storage)."""

from __future__ import annotations

import sys
from contextlib import ExitStack
from pathlib import Path
from typing import Any

import click

from marsscene.cli._common import compose, user_errors

#: Options shared with ``marsscene drive --bag``.
bag_options = compose(
    click.option("--bag-storage", type=click.Choice(["mcap", "sqlite3"]), default="mcap",
                 show_default=True, help="rosbag2 storage plugin."),
    click.option("--depth-encoding", type=click.Choice(["16UC1", "32FC1"]), default="16UC1",
                 show_default=True,
                 help="Depth image: mm (0 = no return; lossless) or metres (NaN = no return)."),
    click.option("--cloud-stride", type=click.IntRange(min=1), default=4, show_default=True,
                 help="Pixel stride of the organised /rover/depth/points cloud."),
    click.option("--bag-images", type=click.Choice(["compressed", "raw", "both"]),
                 default="compressed", show_default=True,
                 help="Camera images as image_transport .../compressed and "
                      ".../compressedDepth topics, raw sensor_msgs/Image, or both."),
    click.option("--bag-image-format", type=click.Choice(["jpeg", "png"]), default="jpeg",
                 show_default=True,
                 help="Compressed colour/mono images: JPEG (image_transport's default) or "
                      "lossless PNG (the run's files, ~4x larger)."),
    click.option("--jpeg-quality", type=click.IntRange(1, 100), default=95, show_default=True,
                 help="JPEG quality (image_transport's default 95)."),
    click.option("--depth-cloud/--no-depth-cloud", default=None,
                 help="Write /rover/depth/points (default: only with raw images)."),
    click.option("--bag-compression",
                 type=click.Choice(["zstd", "zstd_fast", "zstd_small", "lz4", "none"]),
                 default="zstd", show_default=True,
                 help="MCAP chunk compression (rosbag2 presets zstd_fast/zstd_small); "
                      "sqlite3: zstd message compression."),
    click.option("--ros-distro", type=click.Choice(["jazzy", "humble"]), default="jazzy",
                 show_default=True,
                 help="Message definitions and metadata.yaml version (jazzy: 9, humble: 5)."),
)


def write_run_bag(run_dir: Path, out: Path | None, *, overwrite: bool, jpeg_cache: Any = None,
                  **options: Any) -> None:
    """Write the bag with a progress bar and print a one-line summary (used by drive, too)."""
    from marsscene.runs.export.bag import write_bag

    with ExitStack() as stack:
        bars: list[Any] = []

        def progress(done: int, total: int) -> None:  # the bar starts once the input is valid
            if not bars:
                bars.append(stack.enter_context(click.progressbar(
                    length=total, label="writing bag (messages)", file=sys.stderr)))
            bars[0].update(done - bars[0].pos)

        res = write_bag(run_dir, out, overwrite=overwrite, progress=progress,
                        storage=options["bag_storage"], sensors=options.get("sensors"),
                        depth_encoding=options["depth_encoding"],
                        cloud_stride_px=options["cloud_stride"],
                        images=options.get("bag_images", "compressed"),
                        image_codec=options.get("bag_image_format", "jpeg"),
                        jpeg_quality=options.get("jpeg_quality", 95),
                        depth_cloud=options.get("depth_cloud"),
                        compression=options.get("bag_compression", "zstd"),
                        ros_distro=options.get("ros_distro", "jazzy"), jpeg_cache=jpeg_cache)
    n = sum(res.counts.values())
    click.echo(f"     bag: {res.path} ({len(res.counts)} topics, {n} messages, "
               f"{res.size_bytes / 1e6:.1f} MB)")


@click.command(short_help="Write a drive's run folder as a ROS 2 bag (no ROS needed).")
@click.argument("run_dir", type=click.Path(exists=True, file_okay=False, path_type=Path))
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              help="Bag folder (default: RUN_DIR/bag).")
@click.option("--overwrite", is_flag=True, help="Replace an existing bag folder.")
@click.option("--sensor", "sensors", multiple=True,
              type=click.Choice(["camera", "stereo", "lidar"]),
              help="Only these sensor topics; each must be in the run (default: all logged).")
@bag_options
def bag(run_dir: Path, out_dir: Path | None, overwrite: bool, sensors: tuple[str, ...],
        **options: Any) -> None:
    """Convert RUN_DIR (from `marsscene drive`) to a rosbag2 folder: /clock, /tf, /tf_static,
    cmd_vel, odometry, IMU, joint states, URDF, RGB-D, point clouds, LaserScan, ground truth.

    \b
    Examples:
      marsscene bag runs/r1
      marsscene bag runs/r1 --bag-storage sqlite3 --out runs/r1/bag_sqlite --overwrite
      marsscene bag runs/r1 --bag-images both --bag-image-format png --bag-compression none
      marsscene bag runs/r1 --ros-distro humble --out runs/r1/bag_humble
    """
    with user_errors():
        write_run_bag(run_dir, out_dir, overwrite=overwrite, sensors=sensors or None, **options)
