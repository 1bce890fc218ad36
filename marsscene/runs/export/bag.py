"""ROS 2 bags from a run folder, with no ROS installation.

Messages are built from ROS 2 Jazzy (or Humble) message classes of a ``rosbags`` typestore,
serialised to CDR by ``rosbags`` and written by ``rosbags.rosbag2.Writer`` (MCAP storage by
default, sqlite3 as an alternative; compression and metadata version:
:mod:`.bag_writer`). Images go in as image_transport's ``compressed`` / ``compressedDepth``
sub-topics (:mod:`.bag_images`), raw, or both. Topics, frames and units: ``docs/ros.md``.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Collection
from dataclasses import dataclass, field
from pathlib import Path

from marsscene._atomic import replacing_dir
from marsscene.errors import ExportError, RuntimeSimError
from marsscene.runs.export import bag_topics as bt
from marsscene.runs.export.bag_images import IMAGE_CODECS, JpegCache
from marsscene.runs.export.bag_messages import MessageBuilder
from marsscene.runs.export.bag_writer import check_options
from marsscene.runs.runlog import RunLog

__all__ = ["BagSummary", "MessageBuilder", "write_bag"]

STORAGES = ("mcap", "sqlite3")
DEPTH_ENCODINGS = ("32FC1", "16UC1")
SENSORS = ("camera", "stereo", "lidar")
IMAGES = ("compressed", "raw", "both")


@dataclass
class BagSummary:
    """What :func:`write_bag` wrote: the bag folder, message counts per topic, bytes on disk."""

    path: Path
    counts: dict[str, int] = field(default_factory=dict)
    size_bytes: int = 0


def write_bag(
    run_dir: str | os.PathLike[str],
    out_dir: str | os.PathLike[str] | None = None,
    *,
    storage: str = "mcap",
    overwrite: bool = False,
    sensors: Collection[str] | None = None,
    depth_encoding: str = "16UC1",
    cloud_stride_px: int = 4,
    images: str = "compressed",
    image_codec: str = "jpeg",
    jpeg_quality: int = 95,
    depth_cloud: bool | None = None,
    compression: str = "zstd",
    ros_distro: str = "jazzy",
    progress: Callable[[int, int], None] | None = None,
    jpeg_cache: JpegCache | None = None,
) -> BagSummary:
    """Write a run folder as a rosbag2 folder (``metadata.yaml`` + MCAP or sqlite3 storage).

    Parameters
    ----------
    run_dir : path
        A run folder of :func:`marsscene.sim.driver.drive`.
    out_dir : path, optional
        Bag folder (default ``RUN_DIR/bag``); written to a temporary folder and renamed.
    storage : {"mcap", "sqlite3"}
    overwrite : bool
        Replace an existing bag folder (else :class:`~marsscene.errors.ExportError`).
    sensors : collection of {"camera", "stereo", "lidar"}, optional
        Sensor topics to write; each one named must be in the run (else
        :class:`~marsscene.errors.RuntimeSimError`). Default: every sensor the run has.
    depth_encoding : {"16UC1", "32FC1"}
        Depth images in millimetres (0 = no return; the default: lossless, and the
        compressedDepth PNG is the run's own file) or in metres (NaN = no return, REP-118's
        float form; its compressedDepth is image_transport's quantised inverse depth).
    cloud_stride_px : int
        Pixel stride of the organised ``/rover/depth/points`` cloud (1 = every pixel).
    images : {"compressed", "raw", "both"}
        Camera images as image_transport's ``.../compressed`` and ``.../compressedDepth``
        ``sensor_msgs/CompressedImage`` topics, as raw ``sensor_msgs/Image``, or both.
    image_codec : {"jpeg", "png"}
        Colour / mono compression: JPEG at ``jpeg_quality`` (image_transport's default) or
        lossless PNG (the run's files, reused as they are).
    jpeg_quality : int
        1 ... 100 (image_transport's default 95).
    depth_cloud : bool, optional
        Write ``/rover/depth/points``; default: only with raw images (``"raw"``, ``"both"``):
        the cloud is the depth image reprojected (``depth_image_proc`` makes it at replay).
    compression : {"zstd", "zstd_fast", "zstd_small", "lz4", "none"}
        MCAP chunk compression (rosbag2 storage presets ``zstd_fast`` / ``zstd_small``); for
        sqlite3 any ``zstd*`` is rosbag2 message compression (:mod:`.bag_writer`).
    ros_distro : {"jazzy", "humble"}
        Message definitions and ``metadata.yaml`` version (9 for Jazzy, 5 for Humble).
    progress : callable, optional
        ``progress(messages_done, messages_total)``.
    jpeg_cache : JpegCache, optional
        JPEGs the drive encoded from its renders (``drive(jpeg_cache=...)``); used for the
        colour frames it holds at ``jpeg_quality``, the same bytes as encoding the PNGs here.
    """
    if storage not in STORAGES:
        raise ExportError(f"storage = {storage!r}; expected one of {', '.join(STORAGES)}")
    if depth_encoding not in DEPTH_ENCODINGS:
        raise ExportError(f"depth_encoding = {depth_encoding!r}; expected 32FC1 or 16UC1")
    if cloud_stride_px < 1:
        raise ExportError(f"cloud_stride_px = {cloud_stride_px}; expected >= 1")
    if images not in IMAGES:
        raise ExportError(f"images = {images!r}; expected one of {', '.join(IMAGES)}")
    if image_codec not in IMAGE_CODECS:
        raise ExportError(f"image_codec = {image_codec!r}; expected png or jpeg")
    if not 1 <= jpeg_quality <= 100:
        raise ExportError(f"jpeg_quality = {jpeg_quality}; expected 1 ... 100")
    check_options(storage, compression, ros_distro)
    unknown = set(sensors or ()) - set(SENSORS)
    if unknown:
        raise ExportError(f"unknown sensor(s) {sorted(unknown)}; expected {', '.join(SENSORS)}")
    run = RunLog(run_dir)
    final = Path(out_dir) if out_dir is not None else run.path / "bag"
    cams = run.camera_streams()
    lidar = run.lidar
    have = {"camera": bool(cams), "stereo": len(cams) > 1, "lidar": lidar is not None}
    wanted = set(sensors) if sensors is not None else {s for s, ok in have.items() if ok}
    for s in sorted(wanted):
        if not have[s]:
            raise RuntimeSimError(f"{run.path} has no {s} logs; drive with --{s} to get "
                                  f"{s} topics" if s != "stereo" else
                                  f"{run.path} has no stereo camera folders (camera/left, "
                                  "camera/right)")
    opts = bt.ImageOptions(
        images=images, codec=image_codec, jpeg_quality=jpeg_quality,
        depth_encoding=depth_encoding, cloud_stride_px=cloud_stride_px,
        depth_cloud=images != "compressed" if depth_cloud is None else depth_cloud,
        jpeg_cache=jpeg_cache,
    )
    bag = MessageBuilder(ros_distro)
    bt.add_state(bag, run, cams, "stereo" in wanted)
    if "camera" in wanted:
        bt.add_camera(bag, cams[0], opts)
    if "stereo" in wanted:
        for cam in cams[1:]:
            bt.add_stereo(bag, cam, opts)
    if "lidar" in wanted and lidar is not None:
        bt.add_lidar(bag, run, *lidar)
    with replacing_dir(final, overwrite=overwrite, create=False) as tmp:
        counts = bag.write(tmp, storage, compression, progress)
    size = sum(p.stat().st_size for p in final.rglob("*") if p.is_file())
    return BagSummary(final, counts, size)
