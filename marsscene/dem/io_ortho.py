"""Read orthoimages (HiRISE JP2 + PDS3 ``.LBL``, GeoTIFF, ISIS3) with rasterio.

GDAL loses a HiRISE RDR's DN scaling and null value when it follows a ``.LBL`` to its JPEG2000
file, so for PDS3 labels this module takes them from the label itself
(``UNCOMPRESSED_FILE/IMAGE``: ``SCALING_FACTOR``, ``OFFSET``, ``CORE_NULL``) and the transform
and CRS from ``IMAGE_MAP_PROJECTION`` (same GDAL convention as the DTM), then reads the pixels
from the JP2 directly. Only the window covering the requested footprint is read, decimated on
read (GDAL average) when the texture needs far fewer pixels than the source has.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from marsscene.dem import pds3
from marsscene.dem.io import missing_mask, open_source, select_band
from marsscene.dem.io_pds3 import RasterSource, _head, _is_pds3, _sibling
from marsscene.dem.model import Ortho
from marsscene.dem.ops import PixelWindow
from marsscene.dem.pvl import Label, parse_label
from marsscene.errors import ConfigError, DEMReadError

__all__ = ["read_ortho"]


def _jp2_source(label_path: Path, label: Label) -> RasterSource:
    import rasterio
    from rasterio.errors import NotGeoreferencedWarning, RasterioError

    comp = label.obj("COMPRESSED_FILE")
    unc = label.obj("UNCOMPRESSED_FILE")
    assert comp is not None
    name = str(comp.find("FILE_NAME", ""))
    data = _sibling(label_path, name) if name else None
    if data is None:
        raise DEMReadError(f"{label_path}: COMPRESSED_FILE {name!r} is not beside the label")
    img = unc.obj("IMAGE") if unc is not None else None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", NotGeoreferencedWarning)  # georef is in the label
            with rasterio.open(data) as ds:
                shape, count, dtype = (ds.height, ds.width), ds.count, ds.dtypes[0]
    except RasterioError as err:
        raise DEMReadError(f"{data}: not a readable image ({err})") from None
    if img is not None:
        want = (int(pds3.number(img.find("LINES"))), int(pds3.number(img.find("LINE_SAMPLES"))))
        if want != shape:
            raise DEMReadError(f"{data}: image is {shape}, the label says {want}")
    null = img.find("CORE_NULL", 0) if img is not None else 0
    meta = {**pds3.label_metadata(label), "data_file": str(data)}
    return RasterSource(
        open_path=data, source_path=label_path, shape=shape, count=count, dtype=dtype,
        transform=pds3.map_geotransform(label), crs_wkt=pds3.map_projection(label),
        driver="PDS3+" + data.suffix.lstrip(".").upper(), metadata=meta,
        missing_values=(pds3.number(null),),
        scale=pds3.number(img.find("SCALING_FACTOR", 1.0)) if img is not None else 1.0,
        offset=pds3.number(img.find("OFFSET", 0.0)) if img is not None else 0.0,
        label=label,
    )


def _source(path: Path) -> RasterSource:
    if _is_pds3(_head(path, 64)):
        label = parse_label(path.read_bytes()[: 1 << 16])
        if label.obj("COMPRESSED_FILE") is not None:
            return _jp2_source(path, label)
    return open_source(path)


def _window(src: RasterSource, bounds_xy_m: tuple[float, float, float, float]) -> PixelWindow:
    a, _, c, _, e, f = src.transform
    x0, y0, x1, y1 = bounds_xy_m
    rows, cols = src.shape
    c0 = max(int(np.floor((x0 - c) / a)) - 2, 0)
    c1 = min(int(np.ceil((x1 - c) / a)) + 2, cols)
    r0 = max(int(np.floor((y1 - f) / e)) - 2, 0)
    r1 = min(int(np.ceil((y0 - f) / e)) + 2, rows)
    if c1 - c0 < 1 or r1 - r0 < 1:
        raise ConfigError(
            f"{src.source_path}: the orthoimage (x {c:.1f}..{c + a * cols:.1f}, y "
            f"{f + e * rows:.1f}..{f:.1f} m) does not overlap the terrain footprint {bounds_xy_m}"
        )
    return PixelWindow(r0, c0, r1 - r0, c1 - c0)


def read_ortho(
    path: str | os.PathLike[str],
    *,
    bounds_xy_m: tuple[float, float, float, float] | None = None,
    pixel_m: float | None = None,
    band: int | None = None,
) -> Ortho:
    """Read an orthoimage, or the window covering ``bounds_xy_m`` (plus a 2-pixel margin).

    Parameters
    ----------
    path : path-like
        HiRISE ``.LBL`` (with its ``.JP2``), GeoTIFF, ISIS3 cube or PDS3 ``.IMG``.
    bounds_xy_m : (x_min, y_min, x_max, y_max), optional
        Footprint in the ortho's projected metres.
    pixel_m : float, optional
        Coarsest pixel size needed (in m); the read is decimated by
        ``floor(pixel_m / native)`` when that is >= 2.
    band : int, optional
        One band; default all bands (1 grey or 3 colour).

    Returns
    -------
    Ortho
        Calibrated values (DN * scale + offset) as float32, NaN where missing.
    """
    import rasterio
    from rasterio.enums import Resampling
    from rasterio.errors import NotGeoreferencedWarning, RasterioError
    from rasterio.windows import Window

    p = Path(path)
    if not p.is_file():
        raise DEMReadError(f"orthoimage not found: {p}")
    src = _source(p)
    bands = [select_band(src, band, "orthoimage")] if band is not None else list(
        range(1, min(src.count, 3) + 1))
    if len(bands) == 2:
        bands = bands[:1]
    win = _window(src, bounds_xy_m) if bounds_xy_m is not None else PixelWindow(0, 0, *src.shape)
    native = abs(src.transform[0])
    k = int(pixel_m // native) if pixel_m else 1
    k = k if k >= 2 else 1
    out_rows, out_cols = max(win.rows // k, 1), max(win.cols // k, 1)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", NotGeoreferencedWarning)
            ds = rasterio.open(src.open_path)
        with ds:
            raw: Any = ds.read(
                bands, window=Window(win.col_off, win.row_off, win.cols, win.rows),
                out_shape=(len(bands), out_rows, out_cols),
                resampling=Resampling.average if k > 1 else Resampling.nearest,
            )
    except RasterioError as err:
        raise DEMReadError(f"{p}: reading failed ({err})") from None
    img = raw.astype(np.float32)
    if src.scale != 1.0 or src.offset != 0.0:
        img = img * np.float32(src.scale) + np.float32(src.offset)
    img[missing_mask(raw, src)] = np.nan
    a, _, c, _, e, f = src.transform
    sx, sy = a * win.cols / out_cols, e * win.rows / out_rows
    transform = (sx, 0.0, c + a * win.col_off, 0.0, sy, f + e * win.row_off)
    meta = {"driver": src.driver, "decimation": k, **src.metadata}
    return Ortho(image=np.moveaxis(img, 0, -1), transform=transform,
                 crs_wkt=src.crs_wkt, source_path=str(p), metadata=meta)
