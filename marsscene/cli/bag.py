"""``marsscene bag``: write a run folder as a ROS 2 bag (rosbag2: MCAP or sqlite3 storage)."""

from __future__ import annotations

from contextlib import ExitStack
from pathlib import Path
from typing import Any

import click

from marsscene.cli._common import compose, user_errors
from marsscene.cli._progress import ProgressBar
from marsscene.runs.export.options import (
    COMPRESSIONS,
    DEPTH_ENCODINGS,
    DISTROS,
    IMAGE_CODECS,
    IMAGES,
    STORAGES,
    BagOptions,
)

_D = BagOptions()  # the defaults live in BagOptions only

#: Options shared with ``marsscene drive --bag``; :func:`bag_options_of` reads them back.
bag_options = compose(
    click.option("--bag-storage", type=click.Choice(STORAGES), default=_D.storage,
                 show_default=True, help="rosbag2 storage plugin."),
    click.option("--depth-encoding", type=click.Choice(DEPTH_ENCODINGS),
                 default=_D.depth_encoding, show_default=True,
                 help="Depth image: mm (0 = no return; lossless) or metres (NaN = no return)."),
    click.option("--cloud-stride", type=click.IntRange(min=1), default=_D.cloud_stride_px,
                 show_default=True,
                 help="Pixel stride of the organised /rover/depth/points cloud."),
    click.option("--bag-images", type=click.Choice(IMAGES), default=_D.images, show_default=True,
                 help="Camera images as image_transport .../compressed and "
                      ".../compressedDepth topics, raw sensor_msgs/Image, or both."),
    click.option("--bag-image-format", type=click.Choice(IMAGE_CODECS), default=_D.image_codec,
                 show_default=True,
                 help="Compressed colour/mono images: JPEG (image_transport's default) or "
                      "lossless PNG (the run's files, ~4x larger)."),
    click.option("--jpeg-quality", type=click.IntRange(1, 100), default=_D.jpeg_quality,
                 show_default=True, help="JPEG quality (image_transport's default 95)."),
    click.option("--depth-cloud/--no-depth-cloud", default=_D.depth_cloud,
                 help="Write /rover/depth/points (default: only with raw images)."),
    click.option("--bag-compression", type=click.Choice(COMPRESSIONS), default=_D.compression,
                 show_default=True,
                 help="MCAP chunk compression (rosbag2 presets zstd_fast/zstd_small); "
                      "sqlite3: zstd message compression."),
    click.option("--ros-distro", type=click.Choice(DISTROS), default=_D.ros_distro,
                 show_default=True,
                 help="Message definitions and metadata.yaml version (jazzy: 9, humble: 5)."),
)

#: click parameter -> BagOptions field
_FIELDS = {"bag_storage": "storage", "depth_encoding": "depth_encoding",
           "cloud_stride": "cloud_stride_px", "bag_images": "images",
           "bag_image_format": "image_codec", "jpeg_quality": "jpeg_quality",
           "depth_cloud": "depth_cloud", "bag_compression": "compression",
           "ros_distro": "ros_distro"}
#: The click parameter names of :data:`bag_options`.
BAG_OPTION_NAMES = frozenset(_FIELDS)


def bag_options_of(values: dict[str, Any], sensors: tuple[str, ...] | None = None
                   ) -> BagOptions:
    """The :class:`BagOptions` of the :data:`bag_options` given on the command line."""
    return BagOptions(sensors=sensors, **{_FIELDS[k]: v for k, v in values.items()})


def echo_bag(res: Any) -> None:
    """One line: where the bag is, topics, messages and size."""
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
    from marsscene.runs.export.bag import write_bag

    with user_errors():
        opts = bag_options_of(options, sensors or None)
        with ExitStack() as stack:
            bar = ProgressBar(stack, "writing bag (messages)")
            res = write_bag(run_dir, out_dir, opts, overwrite=overwrite, progress=bar)
    echo_bag(res)
