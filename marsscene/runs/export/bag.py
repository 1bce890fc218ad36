"""ROS 2 bags from a run folder, with no ROS installation.

Messages are built from ROS 2 Jazzy (or Humble) message classes of a ``rosbags`` typestore,
serialised to CDR by ``rosbags`` and written by ``rosbags.rosbag2.Writer`` (MCAP storage by
default, sqlite3 as an alternative; compression and metadata version:
:mod:`.bag_writer`). Images go in as image_transport's ``compressed`` / ``compressedDepth``
sub-topics (:mod:`.bag_images`), raw, or both. Topics, frames and units: :doc:`/ros`.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from marsscene._atomic import replacing_dir
from marsscene.errors import RuntimeSimError
from marsscene.runs.export import bag_topics as bt
from marsscene.runs.export.bag_images import JpegCache
from marsscene.runs.export.bag_messages import MessageBuilder
from marsscene.runs.export.options import BagOptions
from marsscene.runs.export.topic_table import RosNames
from marsscene.runs.runlog import RunLog

__all__ = ["BagOptions", "BagSummary", "MessageBuilder", "write_bag"]


@dataclass
class BagSummary:
    """What :func:`write_bag` wrote: the bag folder, message counts per topic, bytes on disk."""

    path: Path
    counts: dict[str, int] = field(default_factory=dict)
    size_bytes: int = 0


def write_bag(
    run_dir: str | os.PathLike[str],
    out_dir: str | os.PathLike[str] | None = None,
    options: BagOptions | None = None,
    *,
    overwrite: bool = False,
    progress: Callable[[int, int], None] | None = None,
    jpeg_cache: JpegCache | None = None,
    **option_values: Any,
) -> BagSummary:
    """Write a run folder as a rosbag2 folder (``metadata.yaml`` + MCAP or sqlite3 storage).

    Parameters
    ----------
    run_dir : path
        A run folder of :func:`marsscene.drive`.
    out_dir : path, optional
        Bag folder (default ``RUN_DIR/bag``); written to a temporary folder and renamed.
    options : BagOptions, optional
        Storage, sensors, image and depth encodings, compression, ROS distro (the defaults:
        MCAP, zstd chunks, every logged sensor, JPEG images, Jazzy).
    overwrite : bool
        Replace an existing bag folder (else :class:`~marsscene.errors.ExportError`).
    progress : callable, optional
        ``progress(messages_done, messages_total)``.
    jpeg_cache : JpegCache, optional
        JPEGs the drive encoded from its renders; used for the colour frames it holds at
        ``jpeg_quality``, the same bytes as encoding the PNGs here.
    **option_values
        Any :class:`BagOptions` field, e.g. ``storage="sqlite3"``, over ``options``.

    Raises
    ------
    ExportError
        Bad options, or the bag folder exists without ``overwrite``.
    RuntimeSimError
        A sensor asked for in ``options.sensors`` is not in the run.
    """
    opts = options if options is not None else BagOptions()
    if option_values:
        unknown = sorted(set(option_values) - {f.name for f in fields(BagOptions)})
        if unknown:
            raise TypeError(f"write_bag() got unexpected keyword argument(s) {unknown}")
        opts = dataclasses.replace(opts, **option_values)
    run = RunLog(run_dir)
    final = Path(out_dir) if out_dir is not None else run.path / "bag"
    cams = run.camera_streams()
    lidar = run.lidar
    have = {"camera": bool(cams), "stereo": len(cams) > 1, "lidar": lidar is not None}
    wanted = (set(opts.sensors) if opts.sensors is not None
              else {s for s, ok in have.items() if ok})
    for s in sorted(wanted):
        if not have[s]:
            raise RuntimeSimError(f"{run.path} has no {s} logs; drive with --{s} to get "
                                  f"{s} topics" if s != "stereo" else
                                  f"{run.path} has no stereo camera folders (camera/left, "
                                  "camera/right)")
    image_opts = bt.ImageOptions(
        images=opts.images, codec=opts.image_codec, jpeg_quality=opts.jpeg_quality,
        depth_encoding=opts.depth_encoding, cloud_stride_px=opts.cloud_stride_px,
        depth_cloud=opts.depth_cloud_on, jpeg_cache=jpeg_cache,
    )
    bag = MessageBuilder(opts.ros_distro, RosNames.of_meta(run.meta))  # a team robot's names
    bt.add_state(bag, run, cams, "stereo" in wanted)
    if "camera" in wanted:
        bt.add_camera(bag, cams[0], image_opts)
    if "stereo" in wanted:
        for cam in cams[1:]:
            bt.add_stereo(bag, cam, image_opts)
    if "lidar" in wanted and lidar is not None:
        bt.add_lidar(bag, run, *lidar)
    with replacing_dir(final, overwrite=overwrite, create=False) as tmp:
        counts = bag.write(tmp, opts.storage, opts.compression, progress)
    size = sum(p.stat().st_size for p in final.rglob("*") if p.is_file())
    return BagSummary(final, counts, size)
