"""Read a run folder written by :func:`marsscene.sim.driver.drive` (numpy + Pillow only).

The bag writer (:mod:`marsscene.runs.export.bag`) and the dataset exports
(:mod:`marsscene.runs.export.datasets`) read runs from disk, not from memory, so they work after the
fact and on runs from other versions of the drive. Camera folders are discovered: ``camera/``
itself (the navcam, RGB + depth) and every sub-folder of it with its own ``stamps.csv``
(``camera/left``, ``camera/right`` for a stereo head; see :func:`camera_streams`).
"""

from __future__ import annotations

import json
import os
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene._atomic import write_atomic
from marsscene.errors import MarsSceneWarning, RuntimeSimError
from marsscene.rover.config import RoverConfig
from marsscene.runs.logs import LIDAR_NOT_STORED
from marsscene.runs.tum import Trajectory, read_tum

__all__ = ["LIDAR_IN_BAG", "CameraStream", "IncompleteRunWarning", "RunLog",
           "move_lidar_into_bag", "pinhole_k", "read_image", "read_numeric_csv",
           "read_ply", "run_rover"]

_REQUIRED = ("run.json", "gt.tum", "odom.tum", "cmd.csv", "wheels.csv", "imu.csv")
#: Marker in ``lidar/`` of a run whose PLY scans were removed once its bag held them.
LIDAR_IN_BAG = "scans_in_bag.txt"


class IncompleteRunWarning(MarsSceneWarning):
    """A run folder whose drive was interrupted or killed: readers use its complete prefix."""


def _read_csv(path: Path, complete_lines: bool = False) -> tuple[list[str], list[list[str]]]:
    text = path.read_text(encoding="utf-8")
    if complete_lines and not text.endswith("\n"):  # the writer was killed mid-line
        text = text[: text.rfind("\n") + 1]
    lines = text.splitlines()
    if not lines:
        raise RuntimeSimError(f"{path}: empty log (no header)")
    return lines[0].split(","), [ln.split(",") for ln in lines[1:] if ln.strip()]


def read_numeric_csv(path: Path, columns: int, *, complete_lines: bool = False
                     ) -> NDArray[np.float64]:
    """A numeric log of ``columns`` columns after its header line, as an (N, columns) array;
    ``complete_lines=True`` ignores a last line without its newline."""
    head, rows = _read_csv(path, complete_lines)
    if len(head) != columns or any(len(r) != columns for r in rows):
        raise RuntimeSimError(f"{path}: expected {columns} columns per row ({','.join(head)})")
    try:
        return np.array(rows, dtype=np.float64).reshape(-1, columns)
    except ValueError:
        raise RuntimeSimError(f"{path}: not a number in the log") from None


@dataclass(frozen=True)
class CameraStream:
    """One camera's images in a run folder.

    ``name`` is ``"navcam"`` for ``camera/`` itself, else the sub-folder name (``left``, ...).
    ``depth_files`` is empty when the camera logged no depth.
    """

    name: str
    folder: Path
    stamps_s: NDArray[np.float64]
    rgb_files: tuple[Path, ...]
    depth_files: tuple[Path, ...]
    intrinsics: dict[str, Any]

    @property
    def k(self) -> NDArray[np.float64]:
        """3 x 3 pinhole matrix (pixels)."""
        return pinhole_k(self.intrinsics)


def pinhole_k(intrinsics: dict[str, Any]) -> NDArray[np.float64]:
    """3 x 3 pinhole matrix (pixels) of a camera's intrinsics (``fx, fy, cx, cy``)."""
    i = intrinsics
    return np.array([[i["fx"], 0.0, i["cx"]], [0.0, i["fy"], i["cy"]], [0.0, 0.0, 1.0]])


def _written_prefix(rows: list[list[str]], folder: Path, columns: int) -> list[list[str]]:
    """Rows of an interrupted drive up to the first whose files were not written yet."""
    for i, r in enumerate(rows):
        if len(r) < columns or not all((folder / f).is_file() for f in r[1:columns] if f):
            return rows[:i]
    return rows


def _camera_stream(name: str, folder: Path, fallback: dict[str, Any] | None,
                   incomplete: bool = False) -> CameraStream:
    head, rows = _read_csv(folder / "stamps.csv", incomplete)
    if head[:2] != ["t", "rgb"]:
        raise RuntimeSimError(f"{folder / 'stamps.csv'}: expected columns t,rgb[,depth]")
    if incomplete:
        rows = _written_prefix(rows, folder, len(head))
    stamps = np.array([float(r[0]) for r in rows], dtype=np.float64)
    rgb = tuple(folder / r[1] for r in rows)
    depth = tuple(folder / r[2] for r in rows if len(r) > 2 and r[2])
    if depth and len(depth) != len(rgb):
        raise RuntimeSimError(f"{folder / 'stamps.csv'}: depth missing for some frames")
    missing = [p for p in (*rgb, *depth) if not p.is_file()]
    if missing:
        raise RuntimeSimError(f"{folder}: {len(missing)} image file(s) missing, e.g. {missing[0]}")
    path = folder / "intrinsics.json"
    if path.is_file():
        intr = json.loads(path.read_text(encoding="utf-8"))
    elif fallback is not None:
        intr = dict(fallback)
    else:
        raise RuntimeSimError(f"{folder}: no intrinsics.json")
    return CameraStream(name, folder, stamps, rgb, depth, intr)


def read_image(path: Path) -> NDArray[Any]:
    """A PNG as an array: (H, W, 3) uint8 RGB, (H, W) uint8 mono or (H, W) uint16."""
    from PIL import Image

    with Image.open(path) as im:
        if im.mode in ("I;16", "I;16B", "I"):
            return np.asarray(im, dtype=np.uint16)
        return np.asarray(im.convert("RGB") if im.mode not in ("RGB", "L") else im)


_PLY_TYPES = {"float": "<f4", "uint": "<u4", "ushort": "<u2", "uchar": "u1", "double": "<f8",
              "int": "<i4", "short": "<i2"}


def read_ply(path: Path) -> NDArray[Any]:
    """A LiDAR scan (binary PLY written by :func:`~marsscene.runs.logs.ply_bytes`).

    Returns a structured array with the file's fields: ``x y z intensity`` (float32), ``t``
    (uint32 ns after the scan's stamp; absent in run folders written before it existed) and
    ``ring`` (uint16).
    """
    raw = path.read_bytes()
    end = raw.find(b"end_header\n")
    if not raw.startswith(b"ply\n") or end < 0:
        raise RuntimeSimError(f"{path}: not a binary PLY scan")
    lines = raw[:end].decode("ascii").splitlines()
    n = int(next(ln.split()[2] for ln in lines if ln.startswith("element vertex")))
    try:
        fields = [(ln.split()[2], _PLY_TYPES[ln.split()[1]]) for ln in lines
                  if ln.startswith("property ")]
    except (KeyError, IndexError):
        raise RuntimeSimError(f"{path}: unsupported PLY property types") from None
    return np.frombuffer(raw, dtype=np.dtype(fields), count=n, offset=end + len(b"end_header\n"))


def run_rover(meta: dict[str, Any]) -> RoverConfig:
    """The rover a run drove, from its ``run.json`` (``meta``); keys of other versions
    ignored."""
    rover = {k: v for k, v in meta.get("rover", {}).items()
             if k in RoverConfig.__dataclass_fields__}
    return RoverConfig(**rover)


class RunLog:
    """The logs of one run folder (see :mod:`marsscene.runs.logs` for the layout).

    Raises :class:`~marsscene.errors.RuntimeSimError` naming the missing files when the folder
    is not a complete run.
    """

    def __init__(self, run_dir: str | os.PathLike[str]) -> None:
        self.path = Path(run_dir)
        if not self.path.is_dir():
            raise RuntimeSimError(f"{self.path} is not a run folder (no such directory)")
        missing = [f for f in _REQUIRED if not (self.path / f).is_file()]
        if missing:
            raise RuntimeSimError(
                f"{self.path} is not a complete run folder: missing {', '.join(missing)}"
            )
        self.meta: dict[str, Any] = json.loads((self.path / "run.json").read_text("utf-8"))
        self.rover = run_rover(self.meta)
        #: "complete", "interrupted" (Ctrl-C: finished up to there) or "running" (killed)
        self.status: str = str((self.meta.get("summary") or {}).get("status", "complete"))
        cut = self.incomplete = self.status != "complete"
        gt = read_tum(self.path / "gt.tum", complete_lines=cut)
        odom = read_tum(self.path / "odom.tum", complete_lines=cut)
        self.cmd = read_numeric_csv(self.path / "cmd.csv", 3, complete_lines=cut)
        wheels = read_numeric_csv(self.path / "wheels.csv", 11, complete_lines=cut)
        # one row each per control step: a cut run may end between the files
        n = min(len(gt), len(odom), len(wheels))
        self.gt: Trajectory = gt.head(n)
        self.odom: Trajectory = odom.head(n)
        self.wheels = wheels[:n]
        self.imu = read_numeric_csv(self.path / "imu.csv", 7, complete_lines=cut)
        true = self.path / "imu_true.csv"
        self.imu_true = (read_numeric_csv(true, 7, complete_lines=cut) if true.is_file()
                         else None)
        soil = self.path / "soil.csv"  # t, slip x6, sinkage_m x6, load_n x6 (runs on soil)
        self.soil = (read_numeric_csv(soil, 19, complete_lines=cut)[:n] if soil.is_file()
                     else None)
        bias = self.path / "imu_bias.csv"  # t, gyro bias xyz, accel bias xyz (newer runs)
        self.imu_bias = (read_numeric_csv(bias, 7, complete_lines=cut) if bias.is_file()
                         else None)
        if cut:
            how = ("was interrupted" if self.status == "interrupted"
                   else "stopped without finishing (killed?)")
            warnings.warn(f"{self.path}: the drive {how}; using the "
                          f"{float(self.gt.timestamps_s[-1]):.1f} sim s it logged",
                          IncompleteRunWarning, stacklevel=2)

    @property
    def lidar_stamps_s(self) -> NDArray[np.float64] | None:
        """LiDAR scan stamps (s), also of a run whose scans were moved into its bag; None
        when the run has no LiDAR."""
        stamps = self.path / "lidar" / "stamps.csv"
        if not stamps.is_file():
            return None
        _, rows = _read_csv(stamps, self.incomplete)
        return np.array([float(r[0]) for r in rows], dtype=np.float64)

    @property
    def lidar(self) -> tuple[NDArray[np.float64], tuple[Path, ...]] | None:
        """LiDAR stamps (s) and PLY files, or None when the run has no LiDAR."""
        stamps = self.path / "lidar" / "stamps.csv"
        if not stamps.is_file():
            return None
        if (stamps.parent / LIDAR_IN_BAG).is_file():
            raise RuntimeSimError(f"{stamps.parent}: the scans were moved into the run's bag "
                                  f"({self.path / 'bag'}, topic /rover/lidar/points); drive with "
                                  "keep_lidar_files (--keep-lidar-files) to keep the PLYs too")
        if (stamps.parent / LIDAR_NOT_STORED).is_file():
            raise RuntimeSimError(f"{stamps.parent}: the scans were not stored (the drive ran "
                                  "with lidar_files = false)")
        _, rows = _read_csv(stamps, self.incomplete)
        if self.incomplete:
            rows = _written_prefix(rows, stamps.parent, 2)
        files = tuple(self.path / "lidar" / r[1] for r in rows)
        missing = [p for p in files if not p.is_file()]
        if missing:
            raise RuntimeSimError(f"{stamps.parent}: {len(missing)} scan(s) missing, e.g. "
                                  f"{missing[0]}")
        return np.array([float(r[0]) for r in rows], dtype=np.float64), files

    def camera_streams(self) -> list[CameraStream]:
        """The navcam (``camera/``) first, then extra camera folders in name order."""
        root = self.path / "camera"
        if not (root / "stamps.csv").is_file():
            return []
        main = _camera_stream("navcam", root, None, self.incomplete)
        extra = [
            _camera_stream(p.name, p, main.intrinsics, self.incomplete)
            for p in sorted(root.iterdir())
            if p.is_dir() and (p / "stamps.csv").is_file()
        ]
        base = (self.meta.get("camera") or {}).get("stereo_baseline_m")
        for cam in extra:  # the run's camera config may carry the stereo baseline
            if base is not None and "baseline_m" not in cam.intrinsics:
                cam.intrinsics.setdefault("stereo_baseline_m", base)
        return [main, *extra]


def move_lidar_into_bag(run_dir: str | os.PathLike[str]) -> int:
    """Remove a run's ``lidar/*.ply`` once its bag holds the scans (one copy of the stream on
    disk); ``lidar/stamps.csv`` stays, with a :data:`LIDAR_IN_BAG` note. Returns the number
    of files removed."""
    folder = Path(run_dir) / "lidar"
    if not (folder / "stamps.csv").is_file():
        return 0
    scans = sorted(folder.glob("*.ply"))
    write_atomic(folder / LIDAR_IN_BAG,
                 f"The {len(scans)} LiDAR scans of this run are in ../bag (topic "
                 "/rover/lidar/points, the same points as the PLYs were); stamps.csv lists "
                 "them.\n")
    for p in scans:
        p.unlink()
    return len(scans)
