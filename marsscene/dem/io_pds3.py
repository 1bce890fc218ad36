"""PDS3 side of the raster readers: :class:`RasterSource` and label-vs-file checks.

No rasterio here: the label is parsed (:mod:`marsscene.dem.pvl`) and the data file's size is
checked against it before GDAL is asked for any pixel.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from marsscene.dem import pds3
from marsscene.dem.pvl import Label, label_length, parse_label
from marsscene.errors import DEMReadError

__all__ = ["RasterSource"]


@dataclass
class RasterSource:
    """What a raster file holds, before any pixel is read."""

    open_path: Path
    """File handed to GDAL (the label for PDS3)."""
    source_path: Path
    shape: tuple[int, int]
    count: int
    dtype: str
    transform: tuple[float, float, float, float, float, float]
    crs_wkt: str
    driver: str
    metadata: dict[str, Any] = field(default_factory=dict)
    missing_bits: tuple[int, ...] = ()
    """Raw bit patterns (of the sample size) that mean missing."""
    missing_values: tuple[float, ...] = ()
    scale: float = 1.0
    offset: float = 0.0
    label: Label | None = None


def _is_pds3(head: bytes) -> bool:
    text = head.lstrip()[:64].upper()
    return text.startswith(b"PDS_VERSION_ID") or text.startswith(b"ODL_VERSION_ID")


def _sibling(path: Path, name: str) -> Path | None:
    direct = path.parent / name
    if direct.exists():
        return direct
    low = name.lower()
    for p in path.parent.iterdir():
        if p.name.lower() == low:
            return p
    return None


def _check_pds3_data(label_path: Path, label_bytes: int, layout: pds3.ImageLayout) -> Path:
    """Check the data file holds the label's image; return the data file."""
    if layout.data_file is None:
        data_path, attached = label_path, True
    else:
        found = _sibling(label_path, layout.data_file)
        if found is None:
            raise DEMReadError(f"{label_path}: ^IMAGE points to {layout.data_file!r}, which is "
                               "not beside the label")
        data_path, attached = found, found.resolve() == label_path.resolve()
    size = data_path.stat().st_size
    if attached and layout.offset_bytes < label_bytes:
        raise DEMReadError(
            f"{label_path}: ^IMAGE points to byte {layout.offset_bytes + 1}, inside the "
            f"{label_bytes}-byte label: the ^IMAGE pointer is wrong"
        )
    if layout.offset_bytes >= size:
        raise DEMReadError(f"{data_path}: ^IMAGE points to byte {layout.offset_bytes + 1}, past "
                           f"the end of the {size}-byte file: the ^IMAGE pointer is wrong")
    need = layout.offset_bytes + layout.data_bytes
    if size < need:
        raise DEMReadError(
            f"{data_path}: truncated: the label's {layout.lines} x {layout.samples} x "
            f"{layout.bands} {layout.dtype.name} image at byte {layout.offset_bytes + 1} needs "
            f"{need:,} bytes, the file has {size:,} (or the ^IMAGE pointer is wrong)"
        )
    return data_path


def _pds3_source(path: Path) -> RasterSource:
    blob = path.read_bytes() if path.stat().st_size < 1 << 16 else _head(path, 1 << 16)
    label = parse_label(blob)
    layout = pds3.image_layout(label)
    data_path = _check_pds3_data(path, label_length(blob), layout)
    meta = pds3.label_metadata(label)
    if data_path != path:
        meta["data_file"] = str(data_path)
    missing: tuple[int, ...] = (
        (layout.missing_bits,) if layout.missing_bits is not None else ())
    if layout.dtype.kind == "f" and layout.dtype.itemsize == 4:
        missing = tuple(sorted(set(missing) | set(pds3.ISIS_SPECIAL_BITS_F32)))
    return RasterSource(
        open_path=path, source_path=path, shape=(layout.lines, layout.samples),
        count=layout.bands, dtype=layout.dtype.newbyteorder("=").name,
        transform=pds3.map_geotransform(label), crs_wkt=pds3.map_projection(label),
        driver="PDS", metadata=meta, missing_bits=missing,
        missing_values=(layout.missing_value,) if layout.missing_value is not None else (),
        scale=layout.scaling_factor, offset=layout.offset, label=label,
    )


def _head(path: Path, n: int) -> bytes:
    with open(path, "rb") as fh:
        return fh.read(n)
