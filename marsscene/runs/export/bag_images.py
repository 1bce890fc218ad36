"""``sensor_msgs/CompressedImage`` payloads as ROS 2's ``image_transport_plugins`` write them.

``compressed`` (colour / mono): the ``format`` string and the PNG or JPEG bytes of
``compressed_image_transport``'s publisher (``compressed_publisher.cpp``, Humble and Jazzy alike):
``"rgb8; png compressed bgr8"``, ``"rgb8; jpeg compressed bgr8"``, ``"mono8; png compressed "``
(sic: a trailing space) and ``"mono8; jpeg compressed mono8"``. OpenCV writes a ``bgr8`` matrix
as an ordinary RGB PNG / JPEG, so the run folder's RGB PNG files are reused byte for byte.

``compressedDepth``: ``compressed_depth_image_transport``'s ``codec.cpp``: a 12-byte
``ConfigHeader`` (int32 ``compressionFormat`` = 0 ``INV_DEPTH``, float32 ``depthParam[2]``,
little-endian) and a 16-bit grey PNG. For ``16UC1`` the PNG holds the millimetres (values above
``depth_max`` set to 0: none here, see :data:`DEPTH_MAX_M`), i.e. the run's depth PNG itself;
for ``32FC1`` it holds the quantised inverse depth ``q = A / d + B`` (float32 arithmetic,
truncated to uint16; 0 = NaN / beyond ``depth_max``), ``A = z0 (z0 + 1)``,
``B = 1 - A / depth_max``, with ``A, B`` in the header; a decoder returns ``d = A / (q - B)``.
The format string is ``"<enc>; compressedDepth png"`` (Jazzy, since the RVL codec was added)
or ``"<enc>; compressedDepth"`` (Humble); both decoders accept either.
"""

from __future__ import annotations

import io
import shutil
import struct
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.errors import ExportError
from marsscene.runs.export.bag_data import depth_m
from marsscene.runs.export.options import IMAGE_CODECS
from marsscene.runs.logs import png_bytes
from marsscene.runs.runlog import read_image

__all__ = [
    "DEPTH_MAX_M",
    "DEPTH_QUANTIZATION_M",
    "IMAGE_CODECS",
    "JPEG_QUALITY",
    "PNG_LEVEL",
    "JpegCache",
    "compressed_depth",
    "compressed_depth_mm",
    "compressed_image",
    "compressed_image_array",
    "inverse_depth",
]

#: ``compressed_image_transport``'s default ``jpeg_quality``.
JPEG_QUALITY = 95
#: ``png_level`` of both publishers' defaults (zlib level 3).
PNG_LEVEL = 3
#: ``depth_max`` (m): the run's 16-bit depth PNGs hold < 65.535 m, so every logged depth is coded
#: (image_transport's default, 10 m, would drop most of a Mars navcam's view).
DEPTH_MAX_M = 65.535
#: ``depth_quantization`` (m): image_transport's default (depth at which the step is 1 m).
DEPTH_QUANTIZATION_M = 100.0
_INV_DEPTH = 0  # compressionFormat::INV_DEPTH
_PNG_SIG = b"\x89PNG\r\n\x1a\n"


def _png_kind(data: bytes) -> tuple[int, int]:
    """(bit depth, colour type) from a PNG's IHDR (0 grey, 2 RGB, 3 palette, 4/6 + alpha)."""
    if data[:8] != _PNG_SIG or data[12:16] != b"IHDR":
        raise ExportError("not a PNG file (bad signature or no IHDR chunk first)")
    return data[24], data[25]


def _png(arr: NDArray[Any], level: int = PNG_LEVEL) -> bytes:
    """PNG of uint8 RGB / grey or uint16 grey (16-bit) at zlib ``level`` (deterministic)."""
    from PIL import Image

    buf = io.BytesIO()
    dtype = "<u2" if arr.dtype == np.uint16 else np.uint8
    Image.fromarray(np.ascontiguousarray(arr, dtype=dtype)).save(buf, format="PNG",
                                                                 compress_level=level)
    return buf.getvalue()


def _jpeg(arr: NDArray[np.uint8], quality: int) -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(arr)).save(buf, format="JPEG", quality=quality)
    return buf.getvalue()


@dataclass(frozen=True)
class JpegCache:
    """JPEGs of a run's colour frames, encoded from the rendered pixels while it drives.

    A drive that writes a bag right after (``marsscene drive --bag``) encodes each colour frame
    once more beside its PNG (~1 ms on the image writer's thread, where the drive leaves a core
    a third idle), so the bag does not decode the PNGs again (~4.5 ms a frame, 40 % of a
    bag's CPU time): the bytes are those the bag would make from the PNG (PNG is lossless, the
    encoder and settings the same). Files: ``root/jpeg-q{quality}/{stream}/{frame}.jpg``; whoever
    made the cache deletes ``root`` once the bag is written (:meth:`remove`).
    """

    root: Path
    quality: int = JPEG_QUALITY

    def file(self, stream: str, png_name: str) -> Path:
        """The cached JPEG of frame ``png_name`` (``000123.png``) of camera ``stream``."""
        return self.root / f"jpeg-q{self.quality}" / stream / (Path(png_name).stem + ".jpg")

    def encode(self, rgb: NDArray[np.uint8]) -> bytes:
        return _jpeg(rgb, self.quality)

    @classmethod
    def fresh(cls, run_dir: Path, quality: int = JPEG_QUALITY) -> JpegCache:
        """An empty cache in ``run_dir/.bag-cache`` (a killed drive's leftovers removed)."""
        cache = cls(Path(run_dir).absolute() / ".bag-cache", quality)
        cache.remove()
        return cache

    def remove(self) -> None:
        shutil.rmtree(self.root, ignore_errors=True)


def compressed_image(path: Path, codec: str, *, jpeg_quality: int = JPEG_QUALITY,
                     cached: Path | None = None) -> tuple[str, bytes]:
    """``(format, data)`` of a ``CompressedImage`` from an 8-bit RGB or mono PNG of the run.

    An 8-bit RGB or grey PNG is reused as it is (``codec="png"``); any other PNG (palette,
    alpha) is decoded to RGB and re-encoded. ``codec="jpeg"`` encodes at ``jpeg_quality``, or
    reads ``cached`` (a :class:`JpegCache` file of this frame at that quality) if it exists.
    """
    if codec not in IMAGE_CODECS:
        raise ExportError(f"image codec {codec!r}; expected one of {', '.join(IMAGE_CODECS)}")
    if codec == "jpeg" and cached is not None and cached.is_file():
        with path.open("rb") as f:
            head = f.read(32)
        try:
            depth, colour = _png_kind(head)
        except ExportError as err:
            raise ExportError(f"{path}: {err}") from None
        if depth == 8 and colour in (0, 2):
            return ("mono8; jpeg compressed mono8" if colour == 0
                    else "rgb8; jpeg compressed bgr8"), cached.read_bytes()
    data = path.read_bytes()
    try:
        depth, colour = _png_kind(data)
    except ExportError as err:
        raise ExportError(f"{path}: {err}") from None
    mono = colour == 0
    if codec == "png":
        if depth == 8 and colour in (0, 2):
            return ("mono8; png compressed " if mono else "rgb8; png compressed bgr8"), data
        return "rgb8; png compressed bgr8", _png(read_image(path))
    arr = read_image(path)
    if arr.dtype != np.uint8:
        raise ExportError(f"{path}: a {arr.dtype} image cannot be a JPEG (8-bit only)")
    return compressed_image_array(arr, codec, jpeg_quality=jpeg_quality)


def compressed_image_array(arr: NDArray[np.uint8], codec: str, *,
                           jpeg_quality: int = JPEG_QUALITY) -> tuple[str, bytes]:
    """``(format, data)`` of a ``CompressedImage`` from a rendered RGB (H, W, 3) or mono (H, W)
    uint8 image: the bytes :func:`compressed_image` makes from the run's PNG of it (``png``: the
    run folder's own PNG encoding)."""
    mono = arr.ndim == 2
    if codec == "png":
        return ("mono8; png compressed " if mono else "rgb8; png compressed bgr8"), png_bytes(arr)
    fmt = "mono8; jpeg compressed mono8" if mono else "rgb8; jpeg compressed bgr8"
    return fmt, _jpeg(arr, jpeg_quality)


def inverse_depth(depth: NDArray[np.float32], depth_max_m: float = DEPTH_MAX_M,
                  z0_m: float = DEPTH_QUANTIZATION_M) -> tuple[NDArray[np.uint16], float, float]:
    """``codec.cpp``'s inverse-depth quantisation of a 32FC1 image: ``(q, A, B)``.

    ``q = uint16(A / d + B)`` where ``d < depth_max`` (float32, truncated; clipped to 65535
    below ``A / (65535 - B)`` m, where C++ would overflow), else 0 (NaN, +inf, too far).
    """
    a = np.float32(z0_m) * (np.float32(z0_m) + np.float32(1.0))
    b = np.float32(1.0) - a / np.float32(depth_max_m)
    d = np.asarray(depth, dtype=np.float32)
    ok = d < np.float32(depth_max_m)  # False for NaN
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        q = np.where(ok, a / d + b, np.float32(0.0))
    q = np.clip(q, 0.0, 65535.0).astype(np.uint16)  # truncation toward zero, as C++
    return q, float(a), float(b)


def compressed_depth(path: Path, encoding: str, distro: str = "jazzy",
                     depth_max_m: float = DEPTH_MAX_M,
                     z0_m: float = DEPTH_QUANTIZATION_M) -> tuple[str, bytes]:
    """``(format, data)`` of a ``compressedDepth`` message from the run's uint16 mm depth PNG.

    ``encoding`` is the raw image's: ``"16UC1"`` (the PNG is reused when nothing exceeds
    ``depth_max``) or ``"32FC1"`` (metres, :func:`~.bag_data.depth_m`, quantised by
    :func:`inverse_depth`).
    """
    if encoding == "16UC1" and round(depth_max_m * 1000.0) >= 65535:
        fmt = f"{encoding}; compressedDepth" + (" png" if distro != "humble" else "")
        return fmt, struct.pack("<iff", _INV_DEPTH, 0.0, 0.0) + path.read_bytes()
    return compressed_depth_mm(read_image(path), encoding, distro, depth_max_m, z0_m)


def compressed_depth_mm(mm: NDArray[np.uint16], encoding: str, distro: str = "jazzy",
                        depth_max_m: float = DEPTH_MAX_M,
                        z0_m: float = DEPTH_QUANTIZATION_M) -> tuple[str, bytes]:
    """``(format, data)`` of a ``compressedDepth`` message from a uint16 mm depth image: the
    bytes :func:`compressed_depth` makes from the run's PNG of it (``16UC1``: that very PNG,
    :func:`~marsscene.runs.logs.png_bytes`)."""
    fmt = f"{encoding}; compressedDepth" + (" png" if distro != "humble" else "")
    if encoding == "16UC1":
        header = struct.pack("<iff", _INV_DEPTH, 0.0, 0.0)  # params unused for 16UC1
        if round(depth_max_m * 1000.0) >= 65535:
            return fmt, header + png_bytes(np.asarray(mm, dtype=np.uint16))
        mm = np.array(mm, dtype=np.uint16)
        mm[mm > np.uint16(round(depth_max_m * 1000.0))] = 0
        return fmt, header + _png(mm)
    if encoding != "32FC1":
        raise ExportError(f"depth encoding {encoding!r}; expected 32FC1 or 16UC1")
    q, a, b = inverse_depth(depth_m(mm), depth_max_m, z0_m)
    return fmt, struct.pack("<iff", _INV_DEPTH, a, b) + _png(q)

