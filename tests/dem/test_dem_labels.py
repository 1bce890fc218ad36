"""PDS3 label parsing and GDAL's label conventions (docs/science/dem.md), on real labels."""

from __future__ import annotations

import numpy as np
import pytest

from marsscene.dem import pds3
from marsscene.dem.pvl import Based, Quantity, parse_label
from marsscene.errors import DEMReadError
from tests.dem.conftest import real

HIDTMGEN_FIXTURE = """PDS_VERSION_ID = PDS3
RECORD_BYTES = 4
^IMAGE = 2
OBJECT = IMAGE
  LINES = 2
  LINE_SAMPLES = 3
  SAMPLE_BITS = 32
  SAMPLE_TYPE = PC_REAL
  MISSING_CONSTANT = 16#FF7FFFFB#
END_OBJECT = IMAGE
OBJECT = IMAGE_MAP_PROJECTION
  MAP_PROJECTION_TYPE = "EQUIRECTANGULAR"
  A_AXIS_RADIUS = 3396.19 <KM>
  CENTER_LATITUDE = 0.0 <DEG>
  CENTER_LONGITUDE = 180.0 <DEG>
  MAP_SCALE = 1000.0 <METERS/PIXEL>
  LINE_PROJECTION_OFFSET = 760.5 <PIXEL>
  SAMPLE_PROJECTION_OFFSET = -10413.5 <PIXEL>
END_OBJECT = IMAGE_MAP_PROJECTION
END
"""


def test_hidtmgen_fixture_geotransform_matches_science_reference() -> None:
    # docs/science/dem.md: SPO -10413.5, LPO 760.5, 1000 m
    # -> GT (10413000, 1000, 0, 761000, 0, -1000)
    label = parse_label(HIDTMGEN_FIXTURE)
    a, b, c, d, e, f = pds3.map_geotransform(label)
    assert (c, a, b, f, d, e) == (10413000.0, 1000.0, 0.0, 761000.0, 0.0, -1000.0)


def test_half_pixel_convention_hand_computed() -> None:
    # centre of 1-based (sample s, line l): x = (s - 1 - SPO) * scale, y = (LPO - (l - 1)) * scale
    label = parse_label(HIDTMGEN_FIXTURE)
    a, _, c, _, e, f = pds3.map_geotransform(label)
    s, line = 3, 2
    x_centre = c + a * (s - 1 + 0.5)
    y_centre = f + e * (line - 1 + 0.5)
    assert x_centre == (s - 1 - (-10413.5)) * 1000.0 == 10415500.0
    assert y_centre == (760.5 - (line - 1)) * 1000.0 == 759500.0


def test_missing_constant_is_compared_as_float32_bits() -> None:
    layout = pds3.image_layout(parse_label(HIDTMGEN_FIXTURE))
    assert layout.missing_bits == 0xFF7FFFFB
    value = np.array([layout.missing_bits], dtype="<u4").view("<f4")[0]
    assert float(value) == -3.4028226550889045e38  # docs/science/dem.md
    assert np.float32(-3.4028227e38).view(np.uint32) == 0xFF7FFFFB
    # a rounded float64 literal is a different float32: never compare that way
    assert np.float32(-3.40282e38).view(np.uint32) != 0xFF7FFFFB
    assert layout.dtype == np.dtype("<f4") and layout.offset_bytes == 4


def test_real_hirise_dtm_label_pds_3177() -> None:
    label = parse_label(real("labels", "GDAL_pds_3177.lbl").read_bytes())
    meta = pds3.label_metadata(label)
    assert meta["PRODUCT_ID"] == "DTEEC_008669_1705_009025_1705_A01"
    assert meta["SOURCE_PRODUCT_ID"] == ["PSP_008669_1705", "PSP_009025_1705"]
    proj = label.obj("IMAGE_MAP_PROJECTION")
    assert proj is not None
    assert proj.find("A_AXIS_RADIUS") == Quantity(3396.036, "KM")
    a, _, c, _, e, f = pds3.map_geotransform(label)
    assert a == pytest.approx(1.0113804322107) and e == -a
    assert c == pytest.approx(6050329.0 * 1.0113804322107)  # -(SPO + 0.5) * scale
    assert f == pytest.approx(-543510.0 * 1.0113804322107)  # (LPO + 0.5) * scale
    proj_str = pds3.map_projection(label)
    assert "+proj=eqc" in proj_str and "+lat_ts=-5.0" in proj_str and "+R=3396036.0" in proj_str


def test_real_ctx_label_map_scale_without_unit_is_km() -> None:
    # MAP_SCALE = 0.0050001 with no unit: GDAL treats it as km -> 5.0001 m
    label = parse_label(real("labels", "P06_003376_1987_XN_18N283W_070416.LBL").read_bytes())
    assert pds3.map_geotransform(label)[0] == pytest.approx(5.0001)


def test_real_hirise_rdr_label_objects_and_based_values() -> None:
    label = parse_label(real("labels", "GDAL_ESP_013951_1955_RED.LBL").read_bytes())
    unc = label.obj("UNCOMPRESSED_FILE")
    assert unc is not None
    img = unc.obj("IMAGE")
    assert img is not None and img.find("SAMPLE_BIT_MASK") == Based(2, "0000001111111111")
    assert img.find("SCALING_FACTOR") == pytest.approx(1.07543902665525e-04)
    assert label.find("DATA_SET_NAME") == (
        "MRO MARS HIGH RESOLUTION IMAGING SCIENCE EXPERIMENT RDR V1.1")
    assert pds3.map_geotransform(label)[0] == 0.5


def test_polar_stereographic_uses_polar_radius_sphere() -> None:
    text = HIDTMGEN_FIXTURE.replace('"EQUIRECTANGULAR"', '"POLAR STEREOGRAPHIC"').replace(
        "CENTER_LATITUDE = 0.0", "CENTER_LATITUDE = -90.0").replace(
        "A_AXIS_RADIUS = 3396.19 <KM>",
        "A_AXIS_RADIUS = 3396.19 <KM>\n  C_AXIS_RADIUS = 3376.2 <KM>\n"
        "  COORDINATE_SYSTEM_NAME = PLANETOCENTRIC")
    proj = pds3.map_projection(parse_label(text))
    assert "+proj=stere" in proj and "+lat_0=-90.0" in proj and "+R=3376200.0" in proj


def test_not_a_label_is_refused() -> None:
    with pytest.raises(DEMReadError, match="PDS3"):
        parse_label(b"hello world\nEND\n")
