"""Helpers of the sweep tests: a small scene config and a scene-folder comparison."""

from __future__ import annotations

import json
from pathlib import Path

SMALL_SCENE = """
[terrain]
source = "procedural"
size_m = [40.0, 40.0]
post_m = 0.25
rms_height_m = 0.05
[craters]
d_min_m = 2.0
d_max_m = 8.0
[rocks]
d_min_m = 0.2
"""


def write_sweep(path: Path, sweep: str, drive: str = "") -> Path:
    path.write_text(SMALL_SCENE + "[sweep]\n" + sweep + drive, encoding="utf-8")
    return path


def assert_same_scene(a: Path, b: Path) -> None:
    """Every file byte-identical; manifest.json identical except its timings."""
    files_a = sorted(p.relative_to(a).as_posix() for p in a.rglob("*") if p.is_file())
    files_b = sorted(p.relative_to(b).as_posix() for p in b.rglob("*") if p.is_file())
    assert files_a == files_b
    assert "scene.usda" in files_a and "mjcf/scene.xml" in files_a
    for rel in files_a:
        if rel == "manifest.json":
            ma, mb = (json.loads((d / rel).read_text()) for d in (a, b))
            ma.pop("timings_s"), mb.pop("timings_s")
            assert ma == mb
        else:
            assert (a / rel).read_bytes() == (b / rel).read_bytes(), rel
