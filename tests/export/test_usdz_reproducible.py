"""``.usdz`` packages are byte-reproducible and still valid usdz (aligned, stored, openable)."""

from __future__ import annotations

import struct
import time
import zipfile
from pathlib import Path

import pytest

import marsscene as ms
from marsscene.errors import ExportError
from marsscene.export.usd.usdz import normalize_zip_times

pxr = pytest.importorskip("pxr")
from pxr import Usd, UsdGeom  # noqa: E402

from marsscene.export.usd import validate_stage  # noqa: E402

EPOCH = (1980, 1, 1, 0, 0, 0)


def _write(scene: ms.Scene, out: Path) -> bytes:
    ms.write_scene(scene, out, formats=("usd",))
    return (out / "scene.usdz").read_bytes()


def test_two_builds_give_identical_usdz_bytes(tmp_path: Path) -> None:
    cfg = ms.SceneConfig.from_dict(
        {"terrain": {"source": "procedural", "size_m": [20.0, 20.0], "post_m": 0.5},
         "rocks": {"k": 0.05, "d_min_m": 0.3}, "craters": {"d_min_m": 1.0},
         "export": {"usd_format": "usdz", "max_tile_posts": 17}}
    )
    scene = ms.build_scene(cfg, seed=5)
    first = _write(scene, tmp_path / "a")
    time.sleep(2.1)  # DOS timestamps have a 2 s resolution: an unpatched package would differ
    second = _write(ms.build_scene(cfg, seed=5), tmp_path / "b")
    assert first == second

    path = tmp_path / "a" / "scene.usdz"
    with zipfile.ZipFile(path) as zf:
        assert zf.testzip() is None  # every CRC still matches
        infos = zf.infolist()
    names = [i.filename for i in infos]
    assert names[0] == "scene.usdc"  # the root layer comes first
    assert {"assets/terrain.usdc", "assets/rocks.usdc", "assets/craters.usdc"} <= set(names)
    raw = path.read_bytes()
    for info in infos:
        assert info.date_time == EPOCH
        assert info.compress_type == zipfile.ZIP_STORED
        name_len, extra_len = struct.unpack_from("<HH", raw, info.header_offset + 26)
        assert (info.header_offset + 30 + name_len + extra_len) % 64 == 0  # usdz alignment

    stage = Usd.Stage.Open(str(path))
    assert stage.GetPrimAtPath("/World/Rocks/Instancer").IsA(UsdGeom.PointInstancer)
    tiles = [p for p in stage.Traverse() if p.GetName().startswith("tile_")]
    assert len(tiles) == 9 and all(p.IsA(UsdGeom.Mesh) for p in tiles)  # 41 posts: 3 x 3 tiles
    assert validate_stage(stage) == []


def test_normalize_zip_times_patches_both_headers(tmp_path: Path) -> None:
    path = tmp_path / "x.zip"
    with zipfile.ZipFile(path, "w") as zf:
        for name, when in (("a.txt", (2020, 5, 6, 7, 8, 10)),
                           ("b/c.bin", (2031, 12, 31, 23, 59, 58))):
            zf.writestr(zipfile.ZipInfo(name, date_time=when), name.encode() * 100)
    assert normalize_zip_times(path) == 2
    with zipfile.ZipFile(path) as zf:
        assert zf.testzip() is None
        assert [i.date_time for i in zf.infolist()] == [EPOCH, EPOCH]  # central directory
        assert zf.read("b/c.bin") == b"b/c.bin" * 100
    raw = path.read_bytes()
    locals_ = [raw.index(b"PK\x03\x04"), raw.index(b"PK\x03\x04", 1)]
    assert [struct.unpack_from("<HH", raw, o + 10) for o in locals_] == [(0, 33), (0, 33)]


def test_normalize_zip_times_refuses_what_it_does_not_handle(tmp_path: Path) -> None:
    path = tmp_path / "comment.zip"
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("a.txt", b"x")
        zf.comment = b"made elsewhere"
    before = path.read_bytes()
    with pytest.raises(ExportError, match="unsupported zip layout"):
        normalize_zip_times(path)
    assert path.read_bytes() == before
    (tmp_path / "tiny.zip").write_bytes(b"PK")
    with pytest.raises(ExportError, match="not a zip"):
        normalize_zip_times(tmp_path / "tiny.zip")
