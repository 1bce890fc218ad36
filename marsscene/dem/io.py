"""Read DEM rasters with rasterio/GDAL (with :mod:`io_ortho`, the only rasterio importers).

GeoTIFF/COG, ISIS3 cubes, PDS4 and PDS3 ``.IMG`` (attached label) or ``.LBL`` (detached) all
open through GDAL. PDS3 labels are also parsed here (:mod:`marsscene.dem.pvl`) and checked
against the file before any pixel is read (truncated files, wrong ``^IMAGE`` pointers), and the
label — not GDAL — gives the transform and CRS (GDAL's convention, :doc:`/science/dem`). Only the
requested window is read. Missing values become NaN by **bit pattern** on the raw samples:
``MISSING_CONSTANT``, the ISIS special pixels and the dataset nodata.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.dem import pds3
from marsscene.dem.crs import is_projected_metres
from marsscene.dem.io_pds3 import RasterSource, _head, _is_pds3, _pds3_source
from marsscene.dem.model import DEM
from marsscene.dem.ops import (
    Crop,
    PixelWindow,
    _center_lonlat,
    check_memory,
    crop_window,
    window_transform,
)
from marsscene.errors import ConfigError, CRSError, DEMReadError

__all__ = ["RasterSource", "open_source", "read_dem"]

#: ISIS3 NULL of integer cubes by GDAL dtype. The saturation specials (LRS/HRS: 0/255 for
#: 8 bit) are kept as values: for an image they are (saturated) data, not gaps.
_ISIS_INT_SPECIALS = {"uint8": (0,), "int16": (-32768,), "uint16": (0,)}


def _isis_metadata(ds: Any) -> dict[str, Any]:
    tags = ds.tags(ns="json:ISIS3")
    if not tags:
        return {}
    key, value = next(iter(tags.items()))
    for sep in (":", "="):
        try:
            doc = json.loads(key + sep + value)
            break
        except json.JSONDecodeError:
            continue
    else:
        return {}
    mapping = doc.get("IsisCube", {}).get("Mapping", {})
    out = {k: (v["value"] if isinstance(v, dict) and "value" in v else v)
           for k, v in mapping.items() if not k.startswith("_")}
    return {f"ISIS_{k}": v for k, v in out.items()}


def open_source(path: str | os.PathLike[str]) -> RasterSource:
    """Inspect a raster (label, shape, transform, CRS, missing-value rules) without reading it.

    Raises
    ------
    DEMReadError
        Missing file, not a raster, a PDS3 label inconsistent with its data file.
    """
    import rasterio
    from rasterio.errors import RasterioError

    p = Path(path)
    if not p.is_file():
        raise DEMReadError(f"raster file not found: {p}")
    head = _head(p, 64)
    if not _is_pds3(head) and p.suffix.lower() == ".img":
        for ext in (".LBL", ".lbl"):
            if p.with_suffix(ext).is_file():
                p, head = p.with_suffix(ext), _head(p.with_suffix(ext), 64)
                break
    src = _pds3_source(p) if _is_pds3(head) else None
    try:
        with rasterio.open(p) as ds:
            gdal_info = (ds.driver, ds.count, ds.dtypes[0], (ds.height, ds.width),
                         tuple(ds.transform)[:6], ds.crs, ds.nodata, ds.scales[0],
                         ds.offsets[0], dict(ds.tags()), _isis_metadata(ds))
    except RasterioError as err:
        raise DEMReadError(f"{p}: not a raster GDAL can read ({err})") from None
    driver, count, dtype, shape, transform, crs, nodata, scale, offset, tags, isis = gdal_info
    if src is not None:
        if shape != src.shape or count != src.count:
            raise DEMReadError(f"{p}: GDAL sees {shape} x {count} bands, the label says "
                               f"{src.shape} x {src.count}")
        return src
    if crs is None:
        crs_wkt = ""
    elif crs.is_geographic:
        raise CRSError(f"{p}: CRS is geographic (degrees); marsscene needs a projected CRS in "
                       "metres (reproject, e.g. gdalwarp -t_srs '+proj=eqc ...')")
    else:
        crs_wkt = crs.to_wkt()
    bits: tuple[int, ...] = ()
    values: tuple[float, ...] = (float(nodata),) if nodata is not None else ()
    if driver == "ISIS3":
        if dtype == "float32":
            bits = pds3.ISIS_SPECIAL_BITS_F32
        values = tuple(sorted(set(values) | set(map(float, _ISIS_INT_SPECIALS.get(dtype, ())))))
    return RasterSource(
        open_path=p, source_path=Path(path), shape=shape, count=count, dtype=dtype,
        transform=transform, crs_wkt=crs_wkt, driver=driver, metadata={**tags, **isis},
        missing_bits=bits, missing_values=values, scale=float(scale or 1.0),
        offset=float(offset or 0.0),
    )


def missing_mask(raw: NDArray[Any], src: RasterSource) -> NDArray[np.bool_]:
    """True where a raw sample is a missing value (by bit pattern or exact value)."""
    mask = np.zeros(raw.shape, dtype=bool)
    if src.missing_bits and raw.dtype.kind == "f":
        view = raw.view(np.uint32 if raw.dtype.itemsize == 4 else np.uint64)
        mask |= np.isin(view, np.asarray(src.missing_bits, dtype=view.dtype))
    for v in src.missing_values:
        mask |= raw == raw.dtype.type(v)
    if raw.dtype.kind == "f":
        mask |= ~np.isfinite(raw)
    return mask


def read_window(src: RasterSource, band: int, win: PixelWindow | None) -> NDArray[Any]:
    """Raw samples of one band in a window (no scaling, no masking)."""
    import rasterio
    from rasterio.errors import RasterioError
    from rasterio.windows import Window

    w = None if win is None else Window(win.col_off, win.row_off, win.cols, win.rows)
    try:
        with rasterio.open(src.open_path) as ds:
            return np.asarray(ds.read(band, window=w))
    except RasterioError as err:
        raise DEMReadError(f"{src.source_path}: reading failed ({err})") from None


def select_band(src: RasterSource, band: int | None, what: str = "DTM") -> int:
    """Validate ``band`` (1-based); a multi-band file needs it explicitly."""
    if band is None:
        if src.count > 1:
            raise DEMReadError(f"{src.source_path}: the {what} has {src.count} bands; choose "
                               "one with band=N (CLI --band N, config terrain.band)")
        return 1
    if not 1 <= band <= src.count:
        raise DEMReadError(f"{src.source_path}: band {band} does not exist "
                           f"(the file has {src.count})")
    return band


def read_dem(
    path: str | os.PathLike[str],
    *,
    band: int | None = None,
    crop: Crop | None = None,
    window: tuple[int, int, int, int] | None = None,
    max_bytes: float | None = None,
    target_post_m: float | None = None,
) -> DEM:
    """Read an elevation raster, or only the window of ``crop``.

    Parameters
    ----------
    path : path-like
        PDS3 ``.IMG`` (attached label, or a sibling ``.LBL``), ``.LBL``, ISIS3 ``.cub``,
        GeoTIFF/COG, PDS4 ``.xml``.
    band : int, optional
        1-based elevation band; required when the file has several bands.
    crop : Crop, optional
        Pixel window, projected bounds or lon/lat centre + size (see :func:`ops.crop_window`).
    window : (row_off, col_off, rows, cols), optional
        Shorthand for ``crop=Crop(pixels=window)``.
    max_bytes : float, optional
        Refuse (:class:`~marsscene.errors.MemoryBudgetError`) before reading when the estimated
        build memory for this window (resampled to ``target_post_m``) exceeds it.
    target_post_m : float, optional
        The post spacing the build will resample to (in m), for the ``max_bytes`` estimate.

    Returns
    -------
    DEM
        ``elevation_m`` float32 (scaled by the label/GDAL scale and offset), NaN where missing.

    Raises
    ------
    DEMReadError, CRSError, ConfigError, MemoryBudgetError

    Examples
    --------
    A small HiRISE-style PDS3 DTM written by :mod:`marsscene.testing.pds3` (a real one reads
    the same way: ``ms.read_dem("DTEEC_....IMG")``):

    >>> import tempfile
    >>> from pathlib import Path
    >>> import numpy as np
    >>> import marsscene as ms
    >>> from marsscene.testing.pds3 import write_pds3_dtm
    >>> z = np.linspace(-10, 10, 48 * 32, dtype=np.float32).reshape(48, 32)
    >>> path = write_pds3_dtm(Path(tempfile.mkdtemp()) / "dtm.IMG", z)
    >>> dem = ms.read_dem(path)
    >>> dem.shape, dem.post_m
    ((48, 32), 1.0)

    Only a window (row offset, column offset, rows, columns), and a scene from the DEM:

    >>> ms.read_dem(path, window=(0, 0, 16, 16)).shape
    (16, 16)
    >>> cfg = ms.SceneConfig.from_dict({"terrain": {"post_m": 1.0}})
    >>> ms.build_scene(cfg, seed=7, dem=dem).heightfield.shape
    (48, 32)
    """
    if window is not None:
        if crop is not None:
            raise ConfigError("give crop or window, not both")
        crop = Crop(pixels=tuple(int(v) for v in window))  # type: ignore[arg-type]
    src = open_source(path)
    b = select_band(src, band)
    if src.crs_wkt and not is_projected_metres(src.crs_wkt):
        raise CRSError(f"{src.source_path}: CRS is not projected in metres")
    win = crop_window(src.transform, src.shape, src.crs_wkt, crop) if crop is not None else None
    rows, cols = (win.rows, win.cols) if win is not None else src.shape
    if max_bytes is not None:
        post = abs(src.transform[0])
        ratio = (post / target_post_m) ** 2 if target_post_m else 1.0
        check_memory(rows * cols, int(rows * cols * ratio), max_bytes, str(src.source_path))
    raw = read_window(src, b, win)
    z = raw.astype(np.float32)
    if src.scale != 1.0 or src.offset != 0.0:
        z = z * np.float32(src.scale) + np.float32(src.offset)
    z[missing_mask(raw, src)] = np.nan
    transform = src.transform if win is None else window_transform(src.transform, win)
    meta = {"driver": src.driver, "band": b, **src.metadata}
    if win is not None:
        meta["window_rows_cols"] = [win.row_off, win.col_off, win.rows, win.cols]
    dem = DEM(elevation_m=z, transform=transform, crs_wkt=src.crs_wkt,  # type: ignore[arg-type]
              source_path=str(src.source_path), metadata=meta)
    return dem.replace(center_lonlat_deg=_center_lonlat(dem))
