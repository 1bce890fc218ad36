"""What goes into each camera and LiDAR topic, composed once for the bag and the live topics.

One function per message, from one frame's decoded values: the bag (:mod:`.bag_topics`) hands
in what it reads back from the run folder's PNG and PLY files, the live publisher
(:class:`~.sample_messages.SampleMessages`) the very arrays the drive wrote there (PNG is
lossless, the PLY records are :func:`~marsscene.runs.logs.scan_record`'s), so both make the
same messages. Image payloads that differ by source (a PNG file's bytes reused, or pixels
encoded) come from :mod:`.bag_images`. No ``rosbags`` import: the messages come from the
:class:`~.bag_messages.MessageBuilder` passed in.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.runs.export import bag_data as bd
from marsscene.runs.runlog import pinhole_k

__all__ = ["CLOUD_XYZ", "camera_info", "colour_image", "depth_cloud", "depth_image",
           "laser_scan", "lidar_cloud", "pinhole_k", "projection_tx"]

#: Point record of the organised depth cloud (``/rover/depth/points``).
CLOUD_XYZ = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4")])


def projection_tx(stream: str, intrinsics: dict[str, Any]) -> float:
    """``P[0, 3]`` of a view (REP-104): ``-fx * baseline`` for the stereo pair's right view,
    0 for the left one and the navcam (``baseline_m``, or ``stereo_baseline_m``, in m)."""
    if stream != "right":
        return 0.0
    base = intrinsics.get("baseline_m", intrinsics.get("stereo_baseline_m", 0.0))
    return -float(intrinsics["fx"]) * float(base)


def camera_info(b: Any, t_s: float, frame: str, intrinsics: dict[str, Any], tx: float) -> Any:
    """``.../camera_info``: plumb_bob, no distortion, ``P = [K | (tx, 0, 0)]``."""
    return b.camera_info_k(t_s, frame, pinhole_k(intrinsics), int(intrinsics["width"]),
                           int(intrinsics["height"]), tx)


def colour_image(b: Any, t_s: float, frame: str, pixels: NDArray[np.uint8]) -> Any:
    """``.../image_raw`` of a colour (``rgb8``) or grey (``mono8``) frame."""
    return b.image(t_s, frame, pixels, "rgb8" if np.ndim(pixels) == 3 else "mono8")


def depth_image(b: Any, t_s: float, frame: str, depth_mm: NDArray[np.uint16],
                encoding: str) -> Any:
    """``/rover/depth/image_raw``: ``16UC1`` millimetres or ``32FC1`` metres (REP-118)."""
    arr = bd.depth_m(depth_mm) if encoding == "32FC1" else depth_mm.astype("<u2")
    return b.image(t_s, frame, arr, encoding)


def depth_cloud(b: Any, t_s: float, frame: str, depth_mm: NDArray[np.uint16],
                intrinsics: dict[str, Any], stride_px: int) -> Any:
    """``/rover/depth/points``: the organised cloud of every ``stride_px``-th pixel."""
    pts = bd.depth_points(depth_mm, pinhole_k(intrinsics), stride_px)
    return b.cloud(t_s, frame, np.ascontiguousarray(pts).view(CLOUD_XYZ)[..., 0],
                   pts.shape[:2])


def lidar_cloud(b: Any, t_s: float, record: NDArray[Any]) -> Any:
    """``/rover/lidar/points``: one scan's point records, unorganised."""
    return b.cloud(t_s, "lidar_link", record, (1, len(record)))


def laser_scan(b: Any, t_s: float, record: NDArray[Any], lidar: dict[str, Any]) -> Any:
    """``/rover/scan``: the ring nearest to horizontal (:func:`~.bag_data.laser_scan`) of a
    LiDAR of spec ``lidar`` (``run.json``'s ``lidar``)."""
    period = 1.0 / float(lidar.get("rate_hz", 10.0))
    return b.laser_scan(t_s, bd.laser_scan(record, lidar), period,
                        int(lidar["horizontal_samples"]))
