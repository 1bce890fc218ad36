"""What to export from a run folder: ROS 2 bag options and the run exporters to call.

Frozen option types with one set of defaults, read by :func:`~marsscene.runs.export.bag.write_bag`,
by :func:`marsscene.drive` and by the command line (whose option defaults come from here).
Pure data: importing this module loads no ``rosbags``.

Examples
--------
>>> from marsscene.runs.export.options import BagOptions, ExportOptions
>>> ExportOptions.from_dict({"bag": {"storage": "sqlite3"}, "datasets": ["euroc"]}).bag.storage
'sqlite3'
>>> BagOptions(images="raw").depth_cloud_on
True
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any

from marsscene._validate import dataclass_from_mapping, plain
from marsscene.errors import ConfigError, ExportError

__all__ = [
    "BAG_SENSORS",
    "COMPRESSIONS",
    "DATASET_FORMATS",
    "DATASET_IMAGES",
    "DEPTH_ENCODINGS",
    "DISTROS",
    "IMAGES",
    "IMAGE_CODECS",
    "STORAGES",
    "BagOptions",
    "ExportOptions",
]

STORAGES = ("mcap", "sqlite3")
DEPTH_ENCODINGS = ("16UC1", "32FC1")
BAG_SENSORS = ("camera", "stereo", "lidar")
IMAGES = ("compressed", "raw", "both")
IMAGE_CODECS = ("jpeg", "png")
#: MCAP chunk compression presets (rosbag2's names); sqlite3 takes any ``zstd*`` or ``none``.
COMPRESSIONS = ("zstd", "zstd_fast", "zstd_small", "lz4", "none")
DISTROS = ("jazzy", "humble")
#: Dataset folder formats of :func:`~marsscene.runs.export.datasets.export_dataset`.
DATASET_FORMATS = ("tum-rgbd", "euroc")
#: How a dataset folder holds the run's images. ``link``: hard links to the run's PNGs where
#: the format takes them as they are (colour images; one copy on disk), TUM RGB-D depth written
#: at the format's 5000 counts per metre. ``convert``: EuRoC's images as mono8 copies too.
#: ``run-depth``: TUM RGB-D depth hard-linked at the run's 1000 per metre, a scale TUM readers
#: do not expect, so the folder says it (:func:`dataset_folder`).
DATASET_IMAGES = ("link", "convert", "run-depth")
#: The one-line help of that choice (``marsscene drive --dataset-images``, ``export --images``).
DATASET_IMAGES_HELP = ("link: hard links to the run's colour PNGs, TUM depth at the format's 5000 "
                       "per m; convert: EuRoC mono8 copies too; run-depth: TUM depth linked at "
                       "the run's 1000 per m, in RUN_DIR/tum_rgbd_depth1000.")


def dataset_folder(fmt: str, images: str = "link") -> str:
    """The name of a dataset folder inside its run folder: ``tum_rgbd``, ``euroc``, and
    ``tum_rgbd_depth1000`` for TUM RGB-D depth kept at the run's scale."""
    name = fmt.replace("-", "_")
    return name + "_depth1000" if fmt == "tum-rgbd" and images == "run-depth" else name


def _choice(key: str, value: Any, allowed: tuple[str, ...]) -> None:
    if value not in allowed:
        raise ExportError(f"{key} = {plain(value)!r}; expected one of {', '.join(allowed)}")


@dataclass(frozen=True, kw_only=True)
class BagOptions:
    """How a run folder becomes a ROS 2 bag (topics, frames and units: :doc:`/ros`).

    Parameters
    ----------
    storage : {"mcap", "sqlite3"}
        rosbag2 storage plugin.
    sensors : tuple of {"camera", "stereo", "lidar"}, optional
        Sensor topics to write; each must be in the run. Default: every sensor it logged.
    depth_encoding : {"16UC1", "32FC1"}
        Depth images in millimetres (0 = no return; lossless) or metres (NaN = no return).
    cloud_stride_px : int
        Pixel stride of the organised ``/rover/depth/points`` cloud.
    images : {"compressed", "raw", "both"}
        image_transport ``.../compressed`` and ``.../compressedDepth`` topics, raw
        ``sensor_msgs/Image``, or both.
    image_codec : {"jpeg", "png"}
        Compressed colour / mono images: JPEG at ``jpeg_quality`` (image_transport's
        default) or lossless PNG (the run's files).
    jpeg_quality : int
        1 ... 100.
    depth_cloud : bool, optional
        Write ``/rover/depth/points``; default (None): only with raw images.
    compression : {"zstd", "zstd_fast", "zstd_small", "lz4", "none"}
        MCAP chunk compression; for sqlite3 any ``zstd*`` is rosbag2 message compression.
    ros_distro : {"jazzy", "humble"}
        Message definitions and ``metadata.yaml`` version (9 for Jazzy, 5 for Humble).
    """

    storage: str = "mcap"
    sensors: tuple[str, ...] | None = None
    depth_encoding: str = "16UC1"
    cloud_stride_px: int = 4
    images: str = "compressed"
    image_codec: str = "jpeg"
    jpeg_quality: int = 95
    depth_cloud: bool | None = None
    compression: str = "zstd"
    ros_distro: str = "jazzy"

    def __post_init__(self) -> None:
        _choice("storage", self.storage, STORAGES)
        _choice("depth_encoding", self.depth_encoding, DEPTH_ENCODINGS)
        _choice("images", self.images, IMAGES)
        _choice("image_codec", self.image_codec, IMAGE_CODECS)
        _choice("compression", self.compression, COMPRESSIONS)
        _choice("ros_distro", self.ros_distro, DISTROS)
        if isinstance(self.cloud_stride_px, bool) or not isinstance(self.cloud_stride_px, int) \
                or self.cloud_stride_px < 1:
            raise ExportError(f"cloud_stride_px = {plain(self.cloud_stride_px)!r}; "
                              "expected an integer >= 1")
        if isinstance(self.jpeg_quality, bool) or not isinstance(self.jpeg_quality, int) \
                or not 1 <= self.jpeg_quality <= 100:
            raise ExportError(f"jpeg_quality = {plain(self.jpeg_quality)!r}; expected 1 ... 100")
        if self.storage == "sqlite3" and self.compression == "lz4":
            raise ExportError("compression 'lz4' is MCAP chunk compression; sqlite3 bags take "
                              "zstd (rosbag2 message compression) or none")
        if self.sensors is not None:
            sensors = (self.sensors,) if isinstance(self.sensors, str) else tuple(self.sensors)
            unknown = sorted(set(sensors) - set(BAG_SENSORS))
            if unknown:
                raise ExportError(f"unknown sensor(s) {unknown}; expected "
                                  f"{', '.join(BAG_SENSORS)}")
            object.__setattr__(self, "sensors", sensors)

    @property
    def depth_cloud_on(self) -> bool:
        """Whether ``/rover/depth/points`` is written (``depth_cloud`` or its default)."""
        return self.images != "compressed" if self.depth_cloud is None else self.depth_cloud

    @property
    def wants_jpeg(self) -> bool:
        """Whether the bag holds JPEG-compressed colour images of the camera (what a drive's
        JPEG cache can encode while driving)."""
        cameras = self.sensors is None or bool({"camera", "stereo"} & set(self.sensors))
        return cameras and self.images != "raw" and self.image_codec == "jpeg"

    @classmethod
    def from_dict(cls, mapping: Mapping[str, Any]) -> BagOptions:
        """From a TOML/JSON table (unknown keys are a :class:`~marsscene.errors.ConfigError`)."""
        return dataclass_from_mapping(cls, mapping, "bag")

    def to_dict(self) -> dict[str, Any]:
        return {f.name: getattr(self, f.name) for f in fields(self)}


@dataclass(frozen=True, kw_only=True)
class ExportOptions:
    """The run exporters a drive calls once its run folder is complete.

    Parameters
    ----------
    bag : BagOptions, optional
        Write ``RUN/bag`` (a ROS 2 bag); None: no bag.
    datasets : tuple of {"tum-rgbd", "euroc"}
        Dataset folders to write (``RUN/tum_rgbd``, ``RUN/euroc``); they need the camera.
    overwrite : bool
        Replace existing export folders (else they are an error, checked before driving).
    dataset_images : {"link", "convert", "run-depth"}
        ``link``: the dataset folders hard-link the run's colour PNGs (one copy on disk; EuRoC
        images stay RGB, which ORB-SLAM3 converts to grey itself; copied where the file
        system cannot link) and write TUM RGB-D depth at the format's 5000 counts per metre
        (13.1 m at most; farther is 0, no return). ``convert``: EuRoC mono8 copies too, as
        EuRoC's own datasets hold them. ``run-depth``: TUM RGB-D depth hard-linked at the
        run's 1000 per metre (declared in ``depth.txt`` and ``orbslam3_rgbd.yaml``), in
        ``RUN/tum_rgbd_depth1000``.
    keep_lidar_files : bool
        With a bag that holds the LiDAR, also keep the run's ``lidar/*.ply`` (by default they
        are removed once the bag is written: the scans are kept once, in the bag, and
        ``lidar/stamps.csv`` stays).
    lidar_files : bool
        Write each LiDAR scan as ``lidar/NNNNNN.ply`` (default). False: the scans reach only
        the drive's listeners (e.g. a live LiDAR odometry) and are never stored;
        ``lidar/stamps.csv`` keeps their stamps and point counts. Not with a bag that holds
        the LiDAR.
    """

    bag: BagOptions | None = None
    datasets: tuple[str, ...] = field(default=())
    overwrite: bool = False
    dataset_images: str = "link"
    keep_lidar_files: bool = False
    lidar_files: bool = True

    def __post_init__(self) -> None:
        _choice("dataset_images", self.dataset_images, DATASET_IMAGES)
        for key in ("keep_lidar_files", "lidar_files"):
            if not isinstance(getattr(self, key), bool):
                raise ExportError(f"{key} = {plain(getattr(self, key))!r}; expected true or "
                                  "false")
        if not self.lidar_files and self.lidar_into_bag():
            raise ExportError("lidar_files = false stores no LiDAR scans, but the bag takes "
                              "the LiDAR: give BagOptions(sensors=...) without 'lidar'")
        datasets = (self.datasets,) if isinstance(self.datasets, str) else tuple(self.datasets)
        for fmt in datasets:
            _choice("datasets", fmt, DATASET_FORMATS)
        if len(set(datasets)) != len(datasets):
            raise ExportError(f"datasets = {list(datasets)} names a format twice")
        object.__setattr__(self, "datasets", datasets)

    def lidar_into_bag(self) -> bool:
        """Whether the bag takes the run's LiDAR scans (if it logged any)."""
        return self.bag is not None and (self.bag.sensors is None or "lidar" in self.bag.sensors)

    @property
    def folders(self) -> tuple[str, ...]:
        """Names of the folders these exports write inside the run folder."""
        return (*(("bag",) if self.bag is not None else ()),
                *(dataset_folder(fmt, self.dataset_images) for fmt in self.datasets))

    @classmethod
    def from_dict(cls, mapping: Mapping[str, Any]) -> ExportOptions:
        """From a table: ``bag`` (a table of :class:`BagOptions`, ``true`` for the defaults or
        ``false``), ``datasets`` (a list of formats) and ``overwrite``."""
        if not isinstance(mapping, Mapping):
            raise ConfigError(f"export options must be a table, got {plain(mapping)!r}")
        doc = dict(mapping)
        bag = doc.pop("bag", None)
        if bag is True:
            bag = BagOptions()
        elif bag is False or bag is None:
            bag = None
        elif isinstance(bag, Mapping):
            bag = BagOptions.from_dict(bag)
        else:
            raise ConfigError(f"export.bag = {plain(bag)!r}; expected a table, true or false")
        rest = dataclass_from_mapping(cls, doc, "export")
        return dataclasses.replace(rest, bag=bag)
