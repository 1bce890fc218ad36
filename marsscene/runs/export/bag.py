"""ROS 2 bags from a run folder, with no ROS installation (the only importer of ``rosbags``).

Messages are built from ROS 2 Jazzy message classes of a ``rosbags`` typestore, serialised to
CDR by ``rosbags`` and written by ``rosbags.rosbag2.Writer`` (MCAP storage by default, sqlite3
as an alternative). Topics, frames and units: ``docs/ros.md``.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Collection
from dataclasses import dataclass, field
from pathlib import Path

from marsscene._atomic import replacing_dir
from marsscene.errors import ExportError, RuntimeSimError
from marsscene.runs.export import bag_topics as bt
from marsscene.runs.export.bag_messages import MessageBuilder
from marsscene.runs.runlog import RunLog

__all__ = ["BagSummary", "MessageBuilder", "write_bag"]

STORAGES = ("mcap", "sqlite3")
DEPTH_ENCODINGS = ("32FC1", "16UC1")
SENSORS = ("camera", "stereo", "lidar")


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
    depth_encoding: str = "32FC1",
    cloud_stride_px: int = 4,
    progress: Callable[[int, int], None] | None = None,
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
    depth_encoding : {"32FC1", "16UC1"}
        ``/rover/depth/image_raw`` in metres (NaN = no return) or millimetres (0 = no return).
    cloud_stride_px : int
        Pixel stride of the organised ``/rover/depth/points`` cloud (1 = every pixel).
    progress : callable, optional
        ``progress(messages_done, messages_total)``.
    """
    if storage not in STORAGES:
        raise ExportError(f"storage = {storage!r}; expected one of {', '.join(STORAGES)}")
    if depth_encoding not in DEPTH_ENCODINGS:
        raise ExportError(f"depth_encoding = {depth_encoding!r}; expected 32FC1 or 16UC1")
    if cloud_stride_px < 1:
        raise ExportError(f"cloud_stride_px = {cloud_stride_px}; expected >= 1")
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
    bag = MessageBuilder()
    bt.add_state(bag, run, cams, "stereo" in wanted)
    if "camera" in wanted:
        bt.add_camera(bag, cams[0], depth_encoding, cloud_stride_px)
    if "stereo" in wanted:
        for cam in cams[1:]:
            bt.add_stereo(bag, cam)
    if "lidar" in wanted and lidar is not None:
        bt.add_lidar(bag, run, *lidar)
    with replacing_dir(final, overwrite=overwrite, create=False) as tmp:
        counts = bag.write(tmp, storage, progress)
    size = sum(p.stat().st_size for p in final.rglob("*") if p.is_file())
    return BagSummary(final, counts, size)
