"""Test-fixture writer for HiRISE-style PDS3 DTMs (GDAL cannot write PDS3).

**The labels written here are ASSEMBLED, not real products.** Keyword order and the IMAGE
object follow ISIS ``hidtmgen``'s ``MroHirisePdsDTMEqui.pft`` template; the identification values
come from the real HiRISE DTM label of DTEEC_008669_1705_009025_1705_A01 (GDAL autotest
``pds_3177.lbl``) and hidtmgen's ``params_equi.pvl``; the IMAGE_MAP_PROJECTION keywords and their
NOTE comments are those of the same real label, with the numbers replaced by the caller's
(centre, radius, scale, projection offsets). Sources: ``/work/shared/data/real/labels`` (see its
README: DOI-USGS/ISIS3 @ 7ca57fa9, OSGeo/gdal @ 2935a95e).

``write_pds3_dtm`` writes a DTEEC-style ``.IMG`` with an attached label (``^IMAGE`` = record
number, ``RECORD_BYTES`` = one line) or, with ``detached=True``, a ``.LBL`` plus a raw ``.IMG``.
``write_hirise_ortho`` writes a HiRISE RDR-style orthoimage (JPEG 2000 plus a detached label).

Public: use it to test your own DEM pipelines (``marsscene.dem.read_dem``, ``marsscene build
--dem``) on a DTM of any size, shape and content without downloading a product. Needs only the
core dependencies (numpy; rasterio with GDAL's JP2OpenJPEG driver for the orthoimage).

Examples
--------
>>> import tempfile
>>> from pathlib import Path
>>> import numpy as np
>>> from marsscene.dem import read_dem
>>> from marsscene.testing.pds3 import write_pds3_dtm
>>> z = np.full((64, 48), -2500.0, np.float32)
>>> path = write_pds3_dtm(Path(tempfile.mkdtemp()) / "DTEEC_TEST.IMG", z, map_scale_m=1.0)
>>> read_dem(path).elevation_m.shape
(64, 48)
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

import numpy as np

__all__ = ["NULL4", "dtm_label", "write_hirise_ortho", "write_pds3_dtm"]

NULL4 = np.array([0xFF7FFFFB], dtype="<u4").view("<f4")[0]
"""HiRISE/ISIS MISSING_CONSTANT 16#FF7FFFFB# as a float32."""

_IDENT = '''/* Identification Information */
DATA_SET_ID               = "MRO-M-HIRISE-5-DTM-V1.0"
DATA_SET_NAME             = "MRO MARS HIGH RESOLUTION IMAGING SCIENCE EXPERIMENT DTM V1.0"
PRODUCER_INSTITUTION_NAME = "UNIVERSITY OF ARIZONA"
PRODUCER_ID               = "UA"
PRODUCER_FULL_NAME        = "ALFRED MCEWEN"
PRODUCT_ID                = "{product_id}"
PRODUCT_VERSION_ID        = "1.0"
INSTRUMENT_HOST_NAME      = "MARS RECONNAISSANCE ORBITER"
INSTRUMENT_HOST_ID        = "MRO"
INSTRUMENT_NAME           = "HIGH RESOLUTION IMAGING SCIENCE EXPERIMENT"
INSTRUMENT_ID             = "HIRISE"
TARGET_NAME               = "MARS"
SOURCE_PRODUCT_ID         = (PSP_008669_1705, PSP_009025_1705)
RATIONALE_DESC            = "ASSEMBLED TEST FIXTURE (marsscene.testing.pds3)"
SOFTWARE_NAME             = "SOCET Set v.5.4.1.20090303"
'''

_PROJ = '''OBJECT = IMAGE_MAP_PROJECTION
  ^DATA_SET_MAP_PROJECTION     = "DSMAP.CAT"
  MAP_PROJECTION_TYPE          = "{proj_type}"
  PROJECTION_LATITUDE_TYPE     = PLANETOCENTRIC
  /* NOTE: The EQUIRECTANGULAR projection is based on the formula  */
  /* for a sphere. To eliminate confusion in the                   */
  /* IMAGE_MAP_PROJECTION object we have set all three radii,      */
  /* A_AXIS_RADIUS, B_AXIS_RADIUS, and C_AXIS_RADIUS to the same   */
  /* number. The value recorded in the three radii is the local    */
  /* radius at the center latitude on the Mars ellipsoid. That is, */
  /* equatorial radius of 3396.190000 km and polar radius of       */
  /* 3376.200000 kilometers. Using the local radius of the         */
  /* ellipsoid implies that the MAP_SCALE and MAP_RESOLUTION are   */
  /* true at the center latitude. */
  A_AXIS_RADIUS                = {radius_km!r} <KM>
  B_AXIS_RADIUS                = {radius_km!r} <KM>
  C_AXIS_RADIUS                = {radius_km!r} <KM>
  COORDINATE_SYSTEM_NAME       = PLANETOCENTRIC
  POSITIVE_LONGITUDE_DIRECTION = EAST
  KEYWORD_LATITUDE_TYPE        = PLANETOCENTRIC
  /* NOTE:  CENTER_LATITUDE and CENTER_LONGITUDE describe the location  */
  /* of the center of projection, which is not necessarily equal to the */
  /* location of the center point of the image.                         */
  CENTER_LATITUDE              = {clat!r} <DEG>
  CENTER_LONGITUDE             = {clon!r} <DEG>
  LINE_FIRST_PIXEL             = 1
  LINE_LAST_PIXEL              = {lines}
  SAMPLE_FIRST_PIXEL           = 1
  SAMPLE_LAST_PIXEL            = {samples}
  MAP_PROJECTION_ROTATION      = 0.0 <DEG>
  MAP_RESOLUTION               = {map_res!r} <PIX/DEG>
  MAP_SCALE                    = {scale!r} <METERS/PIXEL>
  LINE_PROJECTION_OFFSET       = {lpo!r} <PIXEL>
  SAMPLE_PROJECTION_OFFSET     = {spo!r} <PIXEL>
END_OBJECT = IMAGE_MAP_PROJECTION

OBJECT = VIEWING_PARAMETERS
  NORTH_AZIMUTH                = 270.0 <DEG>
END_OBJECT = VIEWING_PARAMETERS
END
'''

_IMAGE = '''OBJECT = IMAGE
  LINES            = {lines}
  LINE_SAMPLES     = {samples}
  BANDS            = 1
  OFFSET           = 0.0
  SCALING_FACTOR   = 1.0
  NOTE             = "ASSEMBLED TEST FIXTURE: elevations in meters above the Mars 2000 areoid"
  SAMPLE_BITS      = 32
  SAMPLE_BIT_MASK  = 2#11111111111111111111111111111111#
  SAMPLE_TYPE      = PC_REAL
  MISSING_CONSTANT = 16#FF7FFFFB#
  VALID_MINIMUM    = {vmin!r}
  VALID_MAXIMUM    = {vmax!r}
END_OBJECT = IMAGE

'''


def dtm_label(
    lines: int, samples: int, *, pointer: str, record_bytes: int, file_records: int,
    map_scale_m: float = 1.0, center_lat: float = 18.0, center_lon: float = 77.0,
    radius_km: float = 3394.8398133163, lpo: float = 1_066_700.5, spo: float = -1_200.5,
    product_id: str = "DTEEC_045994_1985_046060_1985_U01",
    valid_range: tuple[float, float] = (-2700.0, -2400.0), proj_type: str = "EQUIRECTANGULAR",
) -> str:
    """The text of an assembled DTEEC-style PDS3 label (LF line ends; parsers need no CRLF).

    Parameters
    ----------
    lines, samples : int
        Image rows and columns.
    pointer : str
        The whole ``^IMAGE = ...`` line (a record number, or a detached ``.IMG`` file name).
    record_bytes, file_records : int
        ``RECORD_BYTES`` and ``FILE_RECORDS``.
    map_scale_m : float
        Post spacing (m/pixel); ``MAP_RESOLUTION`` follows from it and ``radius_km``.
    center_lat, center_lon : float
        Centre of projection (deg, planetocentric, east-positive).
    radius_km : float
        The three axis radii (km): the local radius at ``center_lat``.
    lpo, spo : float
        ``LINE_PROJECTION_OFFSET`` and ``SAMPLE_PROJECTION_OFFSET`` (pixels).
    product_id : str
        ``PRODUCT_ID``.
    valid_range : tuple of float
        ``VALID_MINIMUM`` and ``VALID_MAXIMUM`` (m).
    proj_type : str
        ``MAP_PROJECTION_TYPE`` (``"EQUIRECTANGULAR"`` or ``"POLAR STEREOGRAPHIC"``).

    Returns
    -------
    str
        The label, ending with ``END``.
    """
    map_res = float(np.pi * radius_km * 1000.0 / 180.0 / map_scale_m)
    head = (f"PDS_VERSION_ID            = PDS3\n\n/* File format and length */\n"
            f"RECORD_TYPE               = FIXED_LENGTH\n"
            f"RECORD_BYTES              = {record_bytes}\n"
            f"FILE_RECORDS              = {file_records}\n{pointer}\n\n")
    return (head + _IMAGE.format(lines=lines, samples=samples, vmin=float(valid_range[0]),
                                 vmax=float(valid_range[1]))
            + _IDENT.format(product_id=product_id) + "\n"
            + _PROJ.format(proj_type=proj_type, radius_km=float(radius_km),
                           clat=float(center_lat), clon=float(center_lon), lines=lines,
                           samples=samples, map_res=map_res, scale=float(map_scale_m),
                           lpo=float(lpo), spo=float(spo)))


def write_pds3_dtm(
    path: Path, z: np.ndarray | None = None, *, detached: bool = False,
    shape: tuple[int, int] | None = None, blocks: Iterable[np.ndarray] | None = None,
    pointer_record: int | None = None, **label_kw: object,
) -> Path:
    """Write an assembled DTEEC-style PDS3 DTM.

    Parameters
    ----------
    path : Path
        The product's path; its suffix is replaced by ``.IMG`` (and ``.LBL`` when detached).
    z : ndarray, optional
        Elevations (rows, cols) in m, written as little-endian float32; NaN and inf become
        ``MISSING_CONSTANT`` (:data:`NULL4`).
    detached : bool
        Write the label to a ``.LBL`` beside a raw ``.IMG`` instead of attaching it.
    shape : tuple of int, optional
        ``(rows, cols)``, with ``blocks`` instead of ``z``.
    blocks : iterable of ndarray, optional
        Row blocks of the image, top first (for files too big to hold in memory).
    pointer_record : int, optional
        Overrides the attached label's ``^IMAGE`` record (to write a deliberately wrong pointer).
    **label_kw
        Passed to :func:`dtm_label` (``map_scale_m``, ``lpo``, ``spo``, ...).

    Returns
    -------
    Path
        The file to open: the ``.IMG`` (attached label) or the ``.LBL`` (detached).
    """
    if z is not None:
        shape = z.shape
        blocks = [z]
    if shape is None or blocks is None:
        raise ValueError("write_pds3_dtm needs z, or shape and blocks")
    lines, samples = shape
    rb = samples * 4
    img_path = path.with_suffix(".IMG")
    if detached:
        lbl = dtm_label(lines, samples, pointer=f'^IMAGE                    = "{img_path.name}"',
                        record_bytes=rb, file_records=lines, **label_kw)  # type: ignore[arg-type]
        path.with_suffix(".LBL").write_text(lbl, encoding="ascii")
        label_bytes = b""
    else:
        n_label = 1
        while True:  # label records depend on the pointer text length: iterate to a fixpoint
            rec = pointer_record if pointer_record is not None else n_label + 1
            lbl = dtm_label(lines, samples, pointer=f"^IMAGE                    = {rec}",
                            record_bytes=rb, file_records=lines + n_label,
                            **label_kw)  # type: ignore[arg-type]
            need = -(-len(lbl) // rb)
            if need == n_label:
                break
            n_label = need
        label_bytes = lbl.encode("ascii").ljust(n_label * rb, b" ")
    with open(img_path, "wb") as fh:
        fh.write(label_bytes)
        for blk in blocks:
            out = np.asarray(blk, dtype="<f4").copy()
            out[~np.isfinite(out)] = NULL4
            fh.write(out.tobytes())
    return path.with_suffix(".LBL") if detached else img_path


def write_hirise_ortho(
    folder: Path, dn: np.ndarray, *, template: Path, x0_m: float, y0_m: float, scale_m: float,
    name: str = "ESP_TEST_RED",
) -> Path:
    """Write ``<name>.JP2`` (lossless, uint16 DN) and an **ASSEMBLED** ``<name>.LBL``.

    The label is the real HiRISE RDR label ``template`` (GDAL's ESP_013951_1955_RED.LBL) with
    the file name, image size, MAP_SCALE and projection offsets replaced so that the upper-left
    pixel corner is at projected ``(x0_m, y0_m)``. Its DN scaling (SCALING_FACTOR, OFFSET) and
    CORE_NULL = 0 are the real label's.

    Parameters
    ----------
    folder : Path
        Where both files are written.
    dn : ndarray
        The image (rows, cols), written as uint16 DN.
    template : Path
        The real RDR label to start from (GDAL autotest's ``ESP_013951_1955_RED.LBL``).
    x0_m, y0_m : float
        Projected coordinates of the upper-left pixel corner (m).
    scale_m : float
        Pixel size (m).
    name : str
        File stem.

    Returns
    -------
    Path
        The ``.LBL`` to open.

    Raises
    ------
    ValueError
        If ``template`` is not that label (a keyword to replace is missing).
    """
    import re
    import warnings

    import rasterio
    import rasterio.errors

    rows, cols = dn.shape
    jp2 = folder / f"{name}.JP2"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", rasterio.errors.NotGeoreferencedWarning)  # label georef
        with rasterio.open(jp2, "w", driver="JP2OpenJPEG", width=cols, height=rows, count=1,
                           dtype="uint16", QUALITY=100, REVERSIBLE="YES") as ds:
            ds.write(dn.astype(np.uint16), 1)
    text = template.read_bytes().decode("ascii").replace("\r\n", "\n")
    spo = -x0_m / scale_m - 0.5
    lpo = y0_m / scale_m - 0.5
    subs = {
        r'FILE_NAME                  = "byte.tif"': f'FILE_NAME                  = "{jp2.name}"',
        r"LINES                      = 67395": f"LINES                      = {rows}",
        r"LINE_SAMPLES               = 19243": f"LINE_SAMPLES               = {cols}",
        r"MAP_SCALE                    = 0.5 <METERS/PIXEL>":
            f"MAP_SCALE                    = {scale_m!r} <METERS/PIXEL>",
        r"LINE_PROJECTION_OFFSET       = 1872006.5 <PIXEL>":
            f"LINE_PROJECTION_OFFSET       = {lpo!r} <PIXEL>",
        r"SAMPLE_PROJECTION_OFFSET     = 12278395.5 <PIXEL>":
            f"SAMPLE_PROJECTION_OFFSET     = {spo!r} <PIXEL>",
    }
    for old, new in subs.items():
        if old not in text:
            raise ValueError(f"{template} is not GDAL's ESP_013951_1955_RED.LBL: no {old!r}")
        text = text.replace(old, new)
    text = re.sub(r"^PDS_VERSION_ID.*$", "PDS_VERSION_ID            = PDS3\n"
                  "/* ASSEMBLED TEST FIXTURE: real HiRISE RDR label with test geometry */",
                  text, count=1, flags=re.M)
    lbl = folder / f"{name}.LBL"
    lbl.write_text(text, encoding="ascii")
    return lbl
