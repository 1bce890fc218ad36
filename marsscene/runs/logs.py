"""Log writers: TUM, CSV, binary PLY point clouds, PNG images (deterministic bytes).

Run folder layout (all stamps in s on the simulation clock, t = 0 after settling)::

    RUN_DIR/
      run.json            config, seed, rates, frames, counts, tracking statistics
      gt.tum              base_link ground truth in the world (map) frame, control rate
      odom.tum            wheel odometry (odom frame = map at t = 0), control rate
      cmd.csv             t, v (m/s), omega (rad/s) sent to the rover
      wheels.csv          t, measured wheel rates (rad/s) x6, steering angles (rad) x4
      imu.csv             t, ax ay az (m/s^2, specific force incl. gravity), gx gy gz (rad/s)
      imu_true.csv        the same without noise and bias
      imu_bias.csv        t, gyro bias xyz (rad/s), accel bias xyz (m/s^2) in each imu.csv row
      lidar/stamps.csv    t, file, points
      lidar/NNNNNN.ply    x y z (m, lidar frame) intensity ring
      camera/stamps.csv   t, rgb file, depth file
      camera/rgb/NNNNNN.png, camera/depth/NNNNNN.png (uint16, mm; 0 = no return)
      camera/intrinsics.json
"""

from __future__ import annotations

import io
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene._atomic import write_atomic

__all__ = ["CsvLog", "TumLog", "depth_mm", "ply_bytes", "png_bytes", "scan_record", "write_file",
           "write_json"]


#: One LiDAR point as the run folder's PLY files and the bag's PointCloud2 hold it.
PLY_DTYPE = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("intensity", "<f4"),
                      ("t", "<u4"), ("ring", "<u2")])


def _num(v: float) -> str:
    s = f"{float(v):.9g}"
    return "0" if s in ("-0", "0") else s


class _Appended:
    """A text file written in order, open while written; :meth:`park` closes it until the next
    write (a batch of thousands of drives holds no files open between its blocks)."""

    def _start(self, path: Path, head: str) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        self.path = path
        self._fh: Any = open(path, "w", encoding="utf-8", newline="\n")
        self._fh.write(head)

    def _file(self) -> Any:
        if self._fh is None:
            self._fh = open(self.path, "a", encoding="utf-8", newline="\n")
        return self._fh

    def park(self) -> None:
        """Close the file (its rows handed to the operating system) until the next write."""
        self.close()

    def flush(self) -> None:
        if self._fh is not None:
            self._fh.flush()

    def close(self) -> None:
        if self._fh is not None:
            self._fh.close()
            self._fh = None


class CsvLog(_Appended):
    """Append rows to a CSV with a header; numbers formatted with 9 significant digits."""

    def __init__(self, path: Path, columns: list[str]) -> None:
        self._start(path, ",".join(columns) + "\n")

    def row(self, t_s: float, values: Any) -> None:
        self._file().write(
            f"{t_s:.6f}," + ",".join(v if isinstance(v, str) else _num(v) for v in values) + "\n"
        )

    def rows(self, t_s: Any, values: Any) -> None:
        """Numeric rows at once: ``t_s`` (R,), ``values`` (R, C); the bytes of R :meth:`row`
        calls (``-0`` written ``0``), one format a row instead of one a number."""
        v = np.asarray(values, dtype=np.float64)
        if not len(v):
            return
        fmt = "%.6f," + ",".join(["%.9g"] * v.shape[1])
        table = np.column_stack([np.asarray(t_s, dtype=np.float64), v + 0.0])  # -0 + 0 = 0
        self._file().write("\n".join(map(fmt.__mod__, map(tuple, table.tolist()))) + "\n")


def _unit(q: NDArray[np.float64]) -> NDArray[np.float64]:
    """Rows of ``q`` (R, 4) scaled to unit length (a zero row kept); elementwise, so a row's
    bits do not depend on R."""
    norm = np.sqrt(q[:, 0] * q[:, 0] + q[:, 1] * q[:, 1] + q[:, 2] * q[:, 2] + q[:, 3] * q[:, 3])
    return q / np.where(norm == 0.0, 1.0, norm)[:, None]


class TumLog(_Appended):
    """Append poses to a TUM file as they happen (the bytes of
    :func:`marsscene.runs.tum.write_tum`), so a long drive holds no trajectory in memory and
    an interrupted one leaves the poses up to the interruption."""

    def __init__(self, path: Path, header: str) -> None:
        self._start(path, "".join(f"# {h}\n" for h in header.splitlines()))

    def row(self, t_s: float, xyz_m: Any, quat_wxyz: Any) -> None:
        q = _unit(np.asarray(quat_wxyz, dtype=np.float64)[None, :])[0]
        x, y, z = (float(v) for v in xyz_m)
        line = f"{t_s:.6f} {x:.6f} {y:.6f} {z:.6f} {q[1]:.9f} {q[2]:.9f} {q[3]:.9f} {q[0]:.9f}"
        self._file().write(line.replace("-0.000000000 ", "0.000000000 ") + "\n")

    def rows(self, t_s: Any, xyz_m: Any, quat_wxyz: Any) -> None:
        """Poses at once: ``t_s`` (R,), ``xyz_m`` (R, 3), ``quat_wxyz`` (R, 4); the bytes of
        R :meth:`row` calls."""
        q = np.asarray(quat_wxyz, dtype=np.float64)
        if not len(q):
            return
        q = _unit(q)
        table = np.column_stack([np.asarray(t_s, dtype=np.float64),
                                 np.asarray(xyz_m, dtype=np.float64), q[:, 1:], q[:, :1]])
        fmt = "%.6f %.6f %.6f %.6f %.9f %.9f %.9f %.9f"
        text = "\n".join(map(fmt.__mod__, map(tuple, table.tolist())))
        self._file().write(text.replace("-0.000000000 ", "0.000000000 ") + "\n")


#: note in a run's ``lidar/`` when its scans went to listeners only (``lidar_files = false``)
LIDAR_NOT_STORED = "scans_not_stored.txt"


def write_file(path: Path, data: bytes) -> None:
    """Write ``path`` whole or not at all, so a killed drive never leaves a truncated image or
    scan behind (:func:`~marsscene._atomic.write_atomic`)."""
    write_atomic(path, data)


def ply_bytes(
    xyz_m: NDArray[np.float32], intensity: NDArray[np.float32], ring: NDArray[np.uint16],
    t_s: NDArray[np.float64] | None = None,
) -> bytes:
    """Binary little-endian PLY of a LiDAR scan: ``x y z intensity`` float32, ``t`` uint32
    (nanoseconds after the scan's stamp, as ``ouster-ros`` names it) and ``ring`` uint16."""
    rec = scan_record(xyz_m, intensity, ring, t_s)
    head = (
        "ply\nformat binary_little_endian 1.0\ncomment marsscene lidar, sensor frame; "
        "t: ns after the scan stamp\n"
        f"element vertex {len(rec)}\nproperty float x\nproperty float y\nproperty float z\n"
        "property float intensity\nproperty uint t\nproperty ushort ring\nend_header\n"
    ).encode("ascii")
    return head + rec.tobytes()


def scan_record(
    xyz_m: NDArray[np.float32], intensity: NDArray[np.float32], ring: NDArray[np.uint16],
    t_s: NDArray[np.float64] | None = None,
) -> NDArray[Any]:
    """A LiDAR scan as the PLY's records (``PLY_DTYPE``): what :func:`ply_bytes` writes and
    :func:`~marsscene.runs.runlog.read_ply` reads back, and the live cloud's points."""
    n = len(xyz_m)
    t_ns = np.zeros(n, dtype=np.uint32) if t_s is None else np.round(
        np.asarray(t_s, dtype=np.float64) * 1e9).astype(np.uint32)
    rec = np.zeros(n, dtype=PLY_DTYPE)
    rec["x"], rec["y"], rec["z"] = xyz_m[:, 0], xyz_m[:, 1], xyz_m[:, 2]
    rec["intensity"], rec["t"], rec["ring"] = intensity, t_ns, ring
    return rec


def depth_mm(depth_m: NDArray[np.float32]) -> NDArray[np.uint16]:
    """A depth image in m as the run's uint16 millimetres (0 = no return, 65535 = too far)."""
    return np.clip(np.round(depth_m * 1000.0), 0, 65535).astype(np.uint16)


#: zlib's ``Z_RLE`` strategy (Pillow's ``compress_type``).
_Z_RLE = 3


def png_bytes(image: NDArray[Any]) -> bytes:
    """PNG of an RGB uint8 (H, W, 3) or a uint16 (H, W) image, tuned for speed on renders.

    Measured on 640 x 480 navcam frames (2 cores, 2026-11): 8-bit images use zlib's run-length
    strategy (13.5 ms, 284 kB; level 1 default strategy: 15.2 ms, 323 kB; level 6: ~4x
    slower); 16-bit depth uses level 4 (8.3 ms, 96 kB; level 1: 5.4 ms, 116 kB), which also
    makes the bag's lossless ``16UC1`` compressedDepth (these very bytes) 17 % smaller.
    """
    from PIL import Image

    buf = io.BytesIO()
    if image.dtype == np.uint16:
        img = Image.fromarray(np.ascontiguousarray(image, dtype="<u2"))
        img.save(buf, format="PNG", compress_level=4)
    else:
        img = Image.fromarray(np.ascontiguousarray(image, dtype=np.uint8))
        img.save(buf, format="PNG", compress_level=1, compress_type=_Z_RLE)
    return buf.getvalue()


class ImageWriter:
    """Encodes and writes images on one background thread (zlib releases the GIL).

    ``submit`` returns at once (at most ``max_pending`` images wait; then it blocks on the
    oldest); ``close`` waits for all and re-raises the first error. Bytes are those of the
    image's encoder (:func:`png_bytes` unless ``submit`` names another, e.g. the bag's JPEG
    cache), whatever the order the files are written in.
    """

    def __init__(self, max_pending: int = 8) -> None:
        from collections import deque
        from concurrent.futures import Future, ThreadPoolExecutor

        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="marsscene-png")
        self._pending: deque[Future[None]] = deque()
        self._max = max_pending

    @staticmethod
    def _write(path: Path, image: NDArray[Any], encode: Callable[[NDArray[Any]], bytes]) -> None:
        write_file(path, encode(image))

    def submit(self, path: Path, image: NDArray[Any],
               encode: Callable[[NDArray[Any]], bytes] | None = None) -> None:
        """Write ``encode(image)`` (default :func:`png_bytes`) to ``path``, in the background."""
        while len(self._pending) >= self._max:
            self._pending.popleft().result()
        self._pending.append(self._pool.submit(self._write, path, np.array(image),
                                               encode or png_bytes))

    def close(self) -> None:
        try:
            while self._pending:
                self._pending.popleft().result()
        finally:
            self._pool.shutdown(wait=True, cancel_futures=True)


def write_json(path: Path, doc: dict[str, Any]) -> None:
    """``doc`` as sorted, indented JSON, written whole or not at all."""
    write_atomic(path, json.dumps(doc, indent=2, sort_keys=True, allow_nan=False) + "\n")
