"""Interpret PDS3 labels of HiRISE DTMs and orthoimages (pure: label in, numbers out).

Conventions follow GDAL's PDS driver (``frmts/pds/pdsdataset.cpp``; :doc:`/science/dem`) so that a
file read here and through GDAL lands on the same ground coordinates:

* ``MAP_SCALE`` in m (``<M>``/``<METERS...>``), ``<CM>`` / 100, anything else (incl. no unit) is
  km and x 1000;
* geotransform ``(x0, scale, 0, y0, 0, -scale)`` with
  ``x0 = -(SAMPLE_PROJECTION_OFFSET + 0.5) * scale`` and
  ``y0 = (LINE_PROJECTION_OFFSET + 0.5) * scale`` (upper-left *corner* of pixel (1, 1)), so the
  centre of 1-based (sample s, line l) is ``x = (s - 1 - SPO) * scale``,
  ``y = (LPO - (l - 1)) * scale``;
* ``MISSING_CONSTANT = 16#FF7FFFFB#`` is a float32 bit pattern (ISIS NULL4, -3.4028226550889045e38).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from marsscene.dem.pvl import Based, Label, Quantity
from marsscene.errors import DEMReadError

__all__ = [
    "ISIS_SPECIAL_BITS_F32",
    "NULL4_BITS",
    "ImageLayout",
    "image_layout",
    "label_metadata",
    "map_geotransform",
    "map_projection",
    "number",
]

#: ISIS special pixels as float32 bit patterns: NULL, VALID_MIN-1 (LRS, LIS, HIS, HRS).
NULL4_BITS = 0xFF7FFFFB
ISIS_SPECIAL_BITS_F32 = (0xFF7FFFFA, 0xFF7FFFFB, 0xFF7FFFFC, 0xFF7FFFFD, 0xFF7FFFFE, 0xFF7FFFFF)

_LITTLE = ("PC_", "LSB_", "VAX_")


def number(value: Any) -> float:
    """A label value as a float (units dropped)."""
    if isinstance(value, Quantity):
        value = value.value
    if isinstance(value, Based):
        return float(value.value)
    try:
        return float(value)
    except (TypeError, ValueError):
        raise DEMReadError(f"expected a number in the PDS3 label, got {value!r}") from None


def _dtype(sample_type: str, bits: int) -> np.dtype[Any]:
    st = sample_type.upper().replace(" ", "_")
    order = "<" if st.startswith(_LITTLE) else ">"
    if "REAL" in st or "FLOAT" in st:
        kind = "f"
    elif "UNSIGNED" in st:
        kind = "u"
    elif "INTEGER" in st:
        kind = "i"
    else:
        raise DEMReadError(f"unsupported SAMPLE_TYPE = {sample_type!r}")
    if bits not in (8, 16, 32, 64) or (kind == "f" and bits < 32):
        raise DEMReadError(f"unsupported SAMPLE_BITS = {bits} for SAMPLE_TYPE = {sample_type}")
    return np.dtype(f"{order}{kind}{bits // 8}")


@dataclass(frozen=True)
class ImageLayout:
    """Where and how the ``IMAGE`` object's samples are stored."""

    data_file: str | None
    """Detached data file name from ``^IMAGE`` (``None``: attached to the label)."""
    offset_bytes: int
    """Byte offset of the first sample in the data file."""
    lines: int
    samples: int
    bands: int
    dtype: np.dtype[Any]
    scaling_factor: float
    offset: float
    missing_bits: int | None
    """``MISSING_CONSTANT`` as an unsigned bit pattern of the sample size (``None`` if absent)."""
    missing_value: float | None
    """``MISSING_CONSTANT`` given as a plain number (``None`` if absent or based)."""

    @property
    def data_bytes(self) -> int:
        return self.lines * self.samples * self.bands * self.dtype.itemsize


def _pointer(label: Label, record_bytes: int) -> tuple[str | None, int]:
    ptr = label.find("^IMAGE")
    if ptr is None:
        raise DEMReadError("the label has no ^IMAGE pointer")
    fname: str | None = None
    loc: Any = 1
    if isinstance(ptr, tuple):
        if not ptr or not isinstance(ptr[0], str):
            raise DEMReadError(f"cannot interpret ^IMAGE = {ptr!r}")
        fname = ptr[0]
        loc = ptr[1] if len(ptr) > 1 else 1
    elif isinstance(ptr, str):
        fname = ptr
    else:
        loc = ptr
    if isinstance(loc, Quantity):
        if loc.unit != "BYTES":
            raise DEMReadError(f"^IMAGE unit {loc.unit!r} is not BYTES")
        start = int(number(loc.value)) - 1
    else:
        start = (int(number(loc)) - 1) * record_bytes
    if start < 0:
        raise DEMReadError(f"^IMAGE = {ptr!r} points before the start of the file")
    return fname, start


def image_layout(label: Label) -> ImageLayout:
    """Sample layout of the label's ``IMAGE`` object (DTMs: one band of PC_REAL float32).

    Raises
    ------
    DEMReadError
        No ``IMAGE`` object, a missing keyword or an unsupported sample type.
    """
    img = label.obj("IMAGE")
    if img is None:
        raise DEMReadError("the label has no IMAGE object")
    try:
        lines = int(number(img.find("LINES")))
        samples = int(number(img.find("LINE_SAMPLES")))
        bits = int(number(img.find("SAMPLE_BITS")))
    except DEMReadError:
        raise DEMReadError("the IMAGE object lacks LINES, LINE_SAMPLES or SAMPLE_BITS") from None
    bands = int(number(img.find("BANDS", 1)))
    dtype = _dtype(str(img.find("SAMPLE_TYPE", "")), bits)
    record_bytes = int(number(label.find("RECORD_BYTES", 1)))
    fname, start = _pointer(label, record_bytes)
    missing = img.find("MISSING_CONSTANT", img.find("MISSING"))
    missing_bits = missing_value = None
    if isinstance(missing, Based):
        missing_bits = missing.value
    elif missing is not None:
        missing_value = number(missing)
    if missing is None and dtype.kind == "f" and dtype.itemsize == 4:
        missing_bits = NULL4_BITS  # GDAL's default nodata for float32 PDS3 (NULL3/NULL4)
    return ImageLayout(
        data_file=fname,
        offset_bytes=start,
        lines=lines,
        samples=samples,
        bands=bands,
        dtype=dtype,
        scaling_factor=number(img.find("SCALING_FACTOR", 1.0)),
        offset=number(img.find("OFFSET", 0.0)),
        missing_bits=missing_bits,
        missing_value=missing_value,
    )


def _map_scale_m(value: Any) -> float:
    scale = number(value)
    unit = value.unit if isinstance(value, Quantity) else ""
    head = unit.split("/")[0].strip()
    if head in ("M", "METER", "METERS", "METRE", "METRES"):
        return scale
    if head == "CM":
        return scale / 100.0
    return scale * 1000.0  # GDAL: anything else (incl. no unit) is km


def _proj(label: Label) -> Label:
    proj = label.obj("IMAGE_MAP_PROJECTION")
    if proj is None:
        raise DEMReadError("the label has no IMAGE_MAP_PROJECTION object")
    return proj


def map_geotransform(label: Label) -> tuple[float, float, float, float, float, float]:
    """Affine transform ``(a, b, c, d, e, f)`` (rasterio order) of the label's map projection."""
    proj = _proj(label)
    scale = _map_scale_m(proj.find("MAP_SCALE"))
    spo = number(proj.find("SAMPLE_PROJECTION_OFFSET"))
    lpo = number(proj.find("LINE_PROJECTION_OFFSET"))
    rot = number(proj.find("MAP_PROJECTION_ROTATION", 0.0))
    if rot != 0.0:
        raise DEMReadError(f"MAP_PROJECTION_ROTATION = {rot} is not supported (only 0)")
    x0 = -(spo + 0.5) * scale
    y0 = (lpo + 0.5) * scale
    return (scale, 0.0, x0, 0.0, -scale, y0)


def map_projection(label: Label) -> str:
    """PROJ string of the label's projection on the label sphere (as GDAL builds it).

    Equirectangular: ``+proj=eqc`` with ``lat_ts = CENTER_LATITUDE`` and ``R = A_AXIS_RADIUS``
    (the local radius at the centre latitude for HiRISE); polar stereographic: ``+proj=stere`` on
    the polar-radius sphere for planetocentric labels.
    """
    proj = _proj(label)
    kind = str(proj.find("MAP_PROJECTION_TYPE", "")).upper().replace(" ", "_")
    clat = number(proj.find("CENTER_LATITUDE", 0.0))
    clon = number(proj.find("CENTER_LONGITUDE", 0.0))
    a_m = number(proj.find("A_AXIS_RADIUS")) * 1000.0
    c_m = number(proj.find("C_AXIS_RADIUS", proj.find("A_AXIS_RADIUS"))) * 1000.0
    if kind in ("EQUIRECTANGULAR", "SIMPLE_CYLINDRICAL", "EQUIDISTANT"):
        lat_ts = clat if kind == "EQUIRECTANGULAR" else 0.0
        return (f"+proj=eqc +lat_ts={lat_ts!r} +lat_0=0 +lon_0={clon!r} +x_0=0 +y_0=0 "
                f"+R={a_m!r} +units=m +no_defs")
    if kind == "POLAR_STEREOGRAPHIC":
        pole = 90.0 if clat >= 0 else -90.0
        planetocentric = str(proj.find("COORDINATE_SYSTEM_NAME", "")).upper() == "PLANETOCENTRIC"
        if planetocentric or a_m == c_m:
            shape = f"+R={c_m!r}"
        else:
            shape = f"+a={a_m!r} +b={c_m!r}"
        return (f"+proj=stere +lat_0={pole!r} +lon_0={clon!r} +k=1 +x_0=0 +y_0=0 {shape} "
                "+units=m +no_defs")
    raise DEMReadError(f"MAP_PROJECTION_TYPE = {kind!r} is not supported")


_META_KEYS = (
    "PRODUCT_ID", "DATA_SET_ID", "SOURCE_PRODUCT_ID", "INSTRUMENT_ID", "TARGET_NAME",
    "PRODUCER_ID", "RATIONALE_DESC",
)
_PROJ_KEYS = (
    "MAP_PROJECTION_TYPE", "CENTER_LATITUDE", "CENTER_LONGITUDE", "A_AXIS_RADIUS",
    "C_AXIS_RADIUS", "MAP_SCALE", "MAP_RESOLUTION", "LINE_PROJECTION_OFFSET",
    "SAMPLE_PROJECTION_OFFSET", "MINIMUM_LATITUDE", "MAXIMUM_LATITUDE",
    "WESTERNMOST_LONGITUDE", "EASTERNMOST_LONGITUDE", "POSITIVE_LONGITUDE_DIRECTION",
    "COORDINATE_SYSTEM_NAME",
)


def _plain(value: Any) -> Any:
    if isinstance(value, Quantity):
        return _plain(value.value)
    if isinstance(value, Based):
        return f"{value.radix}#{value.digits}#"
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    return value


def label_metadata(label: Label) -> dict[str, Any]:
    """JSON-friendly label keywords kept on the DEM (product id, projection, radius, ...)."""
    out: dict[str, Any] = {}
    for key in _META_KEYS:
        value = label.find(key)
        if value is not None:
            out[key] = _plain(value)
    proj = label.obj("IMAGE_MAP_PROJECTION")
    if proj is not None:
        for key in _PROJ_KEYS:
            value = proj.find(key)
            if value is not None:
                out[key] = _plain(value)
        if "MAP_SCALE" in out:
            out["MAP_SCALE_M"] = _map_scale_m(proj.find("MAP_SCALE"))
    img = label.obj("IMAGE")
    if img is not None and img.find("MISSING_CONSTANT") is not None:
        out["MISSING_CONSTANT"] = _plain(img.find("MISSING_CONSTANT"))
    return out
